"""``rattle-lab model modal-impact``: the multi-mode plate impact model and its sound.

A thin layer over :func:`rattle_lab.model.modal.modal_channels`.  Defaults run the thesis's
FEM plate (section 5.1: CFCF, 0.254 x 0.2286 x 0.001 m aluminium, striker at the centre
1 mm behind it, 285 Pa at 99.8 Hz, 2 zeta = 0.1).
"""

from __future__ import annotations

import argparse
import math
from typing import Any

from ._model_plate import _EDGE_HELP, _emit_json, _plate_from_args, _table


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``modal-impact`` command to the ``model`` group."""
    p = sub.add_parser(
        "modal-impact", help="N plate modes against a point striker: impacts, e of mode 1, sound",
        description="Multi-mode plate impact model: N modes of the plate (Rayleigh-Ritz), modal "
                    "damping, uniform pressure P cos(2 pi f t), a striker at (x_s, y_s) behind a gap; "
                    "exact event-driven solution with a rigid (restitution), Kelvin-Voigt or Hertz "
                    "contact. Impacts are contact episodes (first touch to final separation); e_mode1 "
                    "is -q1'(after)/q1'(before); mic is the peak Rayleigh-integral pressure per impact. "
                    "Defaults: the thesis's FEM plate (section 5.1). Edges: " + _EDGE_HELP + ".")
    p.add_argument("--a", type=float, default=0.254, metavar="A_M", help="side along x [m] (default 0.254)")
    p.add_argument("--b", type=float, default=0.2286, metavar="B_M", help="side along y [m] (default 0.2286)")
    p.add_argument("--h", type=float, default=1e-3, metavar="H_P_M", help="thickness [m] (default 0.001)")
    p.add_argument("--E", type=float, default=7e10, metavar="E_PA", help="Young's modulus [Pa] (default 7e10)")
    p.add_argument("--nu", type=float, default=0.34, help="Poisson's ratio (default 0.34)")
    p.add_argument("--rho", type=float, default=2710.0, metavar="RHO_KG_M3", help="density (default 2710)")
    p.add_argument("--edges", default="CFCF", metavar="EDGES", help="edge conditions (default CFCF)")
    p.add_argument("--gap", type=float, default=1e-3, metavar="GAP_M", help="plate-striker gap [m] (default 0.001)")
    p.add_argument("--striker", type=float, nargs=2, default=None, metavar=("X_M", "Y_M"),
                   help="striker position on the plate [m] (default: the centre)")
    p.add_argument("--pressure", type=float, default=285.0, metavar="PRESSURE_PA",
                   help="pressure amplitude P_e [Pa] (default 285: F = 0.3 at 1 mm)")
    p.add_argument("--freq", type=float, default=99.8, metavar="FREQ_HZ",
                   help="forcing frequency [Hz] (default 99.8: omega = 0.95)")
    p.add_argument("--zeta", type=float, default=0.05, help="modal damping ratio of every mode (default 0.05)")
    p.add_argument("--modes", type=int, default=64,
                   help="number of modes N (default 64: with the omitted modes' element the thesis "
                        "plate's contact episodes change by about 2 %% or less from 64 to 128 modes)")
    p.add_argument("--all-modes", action="store_true",
                   help="keep modes that neither the pressure nor a centred striker excite (default: skip them)")
    p.add_argument("--no-omitted-modes", dest="omitted_modes", action="store_false",
                   help="leave out the omitted modes' element at the contact point (the infinite-plate "
                        "impedance 8 sqrt(D m'') with their residual flexibility; default: on for the "
                        "compliant contacts, which it makes converge in N; the rigid contact never has it)")
    p.add_argument("--contact", choices=["rigid", "kelvin-voigt", "hertz"], default="kelvin-voigt",
                   help="contact law (default kelvin-voigt)")
    p.add_argument("--e", type=float, default=0.8, help="restitution of the rigid contact (default 0.8)")
    p.add_argument("--stiffness", type=float, default=None, metavar="K_N_M",
                   help="Kelvin-Voigt striker stiffness [N/m] (default: thesis truss E A / L = 4.4e8)")
    p.add_argument("--contact-damping", type=float, default=0.0, metavar="C_N_S_M",
                   help="Kelvin-Voigt striker damping [N s/m] (default 0)")
    p.add_argument("--hertz", type=float, default=None, metavar="K_N_M15",
                   help="Hertz constant [N/m^1.5] (default: 5 mm steel ball on aluminium)")
    p.add_argument("--cycles", type=float, default=30.0, help="forcing periods to simulate (default 30)")
    p.add_argument("--mic", type=float, nargs=3, default=None, metavar=("X_M", "Y_M", "Z_M"),
                   help="microphone position [m] (default 0.3 m in front of the centre)")
    p.add_argument("--fs", type=float, default=50000.0, metavar="FS_HZ",
                   help="sample rate of the microphone signal [Hz] (default 50000)")
    p.add_argument("--json", action="store_true", help="JSON on stdout instead of tables")
    p.set_defaults(func=_run_modal_impact)


def _run_modal_impact(args: argparse.Namespace) -> int:
    import numpy as np

    from rattle_lab.exceptions import ParameterError
    from rattle_lab.model.modal import contact_from_name, modal_channels, plate_system

    plate = _plate_from_args(args, args.b, args.edges)
    if not (args.cycles > 0 and math.isfinite(args.cycles)):
        raise ParameterError(f"`--cycles` must be > 0, was {args.cycles}")
    if not (args.fs > 0 and math.isfinite(args.fs)):
        raise ParameterError(f"`--fs` must be > 0, was {args.fs}")
    system = plate_system(plate, n_modes=args.modes, gap_m=args.gap,
                          striker_xy_m=None if args.striker is None else tuple(args.striker),
                          pressure_pa=args.pressure, freq_hz=args.freq, zeta=args.zeta,
                          skip_unexcited=not args.all_modes,
                          omitted_modes=args.omitted_modes and args.contact != "rigid")
    contact = contact_from_name(args.contact, e=args.e, stiffness_n_m=args.stiffness,
                                damping_n_s_m=args.contact_damping, hertz_n_m15=args.hertz)
    duration = args.cycles / args.freq
    n = max(2, int(round(duration * args.fs)))
    t = np.arange(n) / args.fs
    ch = modal_channels(system, contact, t, mic_xyz_m=None if args.mic is None else tuple(args.mic))
    from rattle_lab.model.modal import measured_peak, microphone
    from rattle_lab.model.modal import C_AIR_M_S, peak_per_impact

    mic_xyz = (0.5 * plate.a_m, 0.5 * plate.b_m, 0.3) if args.mic is None else tuple(args.mic)
    delay = math.dist(mic_xyz, (system.striker_xi * plate.a_m, system.striker_eta * plate.b_m, 0.0)) / C_AIR_M_S
    heard = peak_per_impact(microphone(ch.mic_pa, args.fs), t, ch.impacts.t_s, delay)
    _, fast_db = measured_peak(ch.mic_pa, args.fs)
    modes = [{"mode": k + 1, "f_hz": float(w / (2 * math.pi)), "zeta": float(z), "modal_mass_kg": float(m),
              "load_m2": float(L), "shape_at_striker": float(b)}
             for k, (w, z, m, L, b) in enumerate(zip(system.omega_rad_s, system.zeta, system.modal_mass_kg,
                                                      system.load_m2, system.shape_at_striker))]
    impacts = ch.impacts.to_dicts()
    out: dict[str, Any] = {
        "plate": {"a_m": plate.a_m, "b_m": plate.b_m, "h_p_m": plate.h_p_m, "edges": plate.edges},
        "gap_m": system.gap_m, "striker_xy_m": [system.striker_xi * plate.a_m, system.striker_eta * plate.b_m],
        "pressure_pa": system.pressure_pa, "freq_hz": system.freq_hz, "contact": contact.name,
        "effective_mass_kg": system.effective_mass_kg, "modes": modes, "impacts": impacts,
        "n_contacts": len(ch.result.contacts), "mic": [float(x) for x in ch.mic_peak_pa],
        "mic_measured": [float(x) for x in heard], "mic_fast_max_db": fast_db,
        "omitted_modes": ({"local_impedance_n_s_m": system.local_impedance_n_s_m,
                           "residual_compliance_m_n": system.residual_compliance_m_n,
                           "residual_volume_m2_kg": system.residual_volume_m2_kg} if system.corrected else None),
    }
    if args.json:
        _emit_json(out)
        return 0
    print(f"plate {plate.a_m:g} x {plate.b_m:g} x {plate.h_p_m:g} m {plate.edges}, gap {system.gap_m:g} m, "
          f"{system.pressure_pa:g} Pa at {system.freq_hz:g} Hz, {contact.name} contact, "
          f"N = {system.n_modes} (m_eff at the striker {system.effective_mass_kg:.4g} kg)")
    print("omitted modes: " + (f"Z = {system.local_impedance_n_s_m:.4g} N s/m in parallel with "
                               f"1/k_r = {system.residual_compliance_m_n:.4g} m/N at the contact point"
                               if system.corrected else "left out (plain truncated sum)"))
    print(f"microphone: 2nd-order low-pass at 20 kHz; Fast level max {fast_db:.1f} dB re 20 uPa")
    print(_table(["mode", "f [Hz]", "L [m^2]", "W(striker)"],
                 [[m["mode"], m["f_hz"], m["load_m2"], m["shape_at_striker"]] for m in modes]))
    print()
    print(_table(["impact", "t [s]", "v_in [m/s]", "v_out [m/s]", "e_mode1", "contacts", "mic peak [Pa]",
                  "measured [Pa]"],
                 [[i + 1, r["t_s"], r["v_in_m_s"], r["v_out_m_s"], r["e_mode1"], r["n_contacts"], pk, hk]
                  for i, (r, pk, hk) in enumerate(zip(impacts, out["mic"], out["mic_measured"]))]))
    return 0
