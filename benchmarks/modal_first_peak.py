"""The sound of one impact of the multi-mode model, converged in N (issue 24, ask 3).

Thesis plate (CFCF 0.254 x 0.2286 x 0.001 m aluminium) with the omitted modes' element,
centre striker, 1 mm gap, Kelvin-Voigt striker 4.4e8 N/m, no forcing: mode 1 moving at 1 m/s
into the striker (what :func:`rattle_lab.model.modal.predicted_spl_slope` simulates), one
48-term Ritz basis for every N.  Microphone 0.3 m in front of the centre, 50 kHz, sample means
(Rayleigh integral of the retained modes plus the element's point source).  Printed per N:

* the episode's peak per m/s, raw and through the microphone model (``microphone``: flat,
  2nd-order roll-off at 20 kHz);
* the peak within 200 us of the direct sound's arrival, through the microphone, and the part
  of it from the element's point source alone;
* the largest element force ``k_r r + Z r'`` [N];

then each quantity's relative change from N to 2N, and the infinite-plate first-peak bound
``rho_0 Z / (2 pi m'' r)`` for comparison.

Then, at one N (``--sweep-modes``, default 64), the early peak for impact velocities 0.5, 1, 2
and 4 m/s, split into what does and does not scale with the velocity (:func:`sweep`): the
slope ``dp/dv`` against the infinite-plate pressure of the model's own contact force
``rho_0 F_max / (2 pi m'' r v)``, and the intercept against the sound of the plate's own
elastic deceleration at the gap, ``rho_0 / (2 pi) sum dA w1^2 q1 phi_1 / R`` (mode 1 held at
the gap: the benchmark starts its run there, so that sound starts with the impact).

Run: ``python benchmarks/modal_first_peak.py [--modes 8,16,32,64,128,256] [--sweep-modes 64]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from rattle_lab.model.modal import (THESIS_PLATE, KelvinVoigtContact, ModalState, microphone,
                                    plate_system, simulate_modal)
from rattle_lab.model.modal._sound import (C_AIR_M_S, RHO_AIR_KG_M3, plate_surface,
                                           rayleigh_pressure, residual_pressure)

FS_HZ = 50000.0
N_TERMS = 48
R_MIC_M = 0.3
EARLY_S = 200e-6


def thesis_system(n: int) -> object:
    return plate_system(THESIS_PLATE, n_modes=n, skip_unexcited=True, omitted_modes=True,
                        pressure_pa=0.0, n_terms=N_TERMS)


def one_impact(n: int, speed_m_s: float = 1.0, system: object = None) -> dict[str, float]:
    t0 = time.perf_counter()
    system = thesis_system(n) if system is None else system
    b1 = float(system.beta[0])
    p0, v0 = np.zeros(n), np.zeros(n)
    p0[0] = system.gap_m * (1 - 1e-9) / b1
    v0[0] = speed_m_s / b1
    span = 4.0 / float(system.omega_rad_s[0])
    res = simulate_modal(system, KelvinVoigtContact(), duration_s=span,
                         state=ModalState(0.0, p0, v0), dense=True, episode_gap_s=span)
    plate = system.plate
    assert plate is not None
    mic = (0.5 * plate.a_m, 0.5 * plate.b_m, R_MIC_M)
    t = np.arange(0.0, span, 1.0 / FS_HZ)

    def clip(tt: np.ndarray) -> np.ndarray:
        return np.clip(tt, 0.0, span)

    p_modes = rayleigh_pressure(plate_surface(system, 30),
                                lambda tt: res.modal_velocity_m_s(clip(tt)), t, mic)
    p_point = residual_pressure(system, lambda tt: res.residual_deflection_m(clip(tt)), t, mic)
    p = p_modes + p_point
    t_hit = float(res.contacts.t_start_s[0])
    v_in = float(res.contacts.u_in_m_s[0])
    arrive = t_hit + R_MIC_M / C_AIR_M_S
    after = t >= arrive - 2.0 / FS_HZ
    early = after & (t <= arrive + EARLY_S)
    heard, heard_point = microphone(p, FS_HZ), microphone(p_point, FS_HZ)
    # the element's force over the contact, on a 1 MHz grid
    t_end = float(res.contacts.t_end_s[0])
    tf = np.linspace(t_hit, t_end, max(int((t_end - t_hit) * 1e6), 50))
    r = res.residual_deflection_m(tf)
    force = system.local_impedance_n_s_m * np.gradient(r, tf) + r / system.residual_compliance_m_n
    k_early = np.flatnonzero(early)[np.argmax(np.abs(heard[early]))]
    return {"n": n, "s": time.perf_counter() - t0, "v_in": v_in,
            "early_signed_pa": float(heard[k_early]),
            "raw": float(np.max(np.abs(p[after]))) / v_in,
            "mic": float(np.max(np.abs(heard[after]))) / v_in,
            "early": float(np.max(np.abs(heard[early]))) / v_in,
            "early_point": float(np.max(np.abs(heard_point[early]))) / v_in,
            "force": float(np.max(np.abs(force))),
            "contacts": float(len(res.contacts)),
            "bound": RHO_AIR_KG_M3 * system.local_impedance_n_s_m
            / (2 * math.pi * plate.rho_kg_m3 * plate.h_p_m * R_MIC_M)}


def static_sound_pa(system: object) -> float:
    """Pressure [Pa] at the microphone of the plate held in mode 1 at the gap: its elastic
    deceleration ``w1^2 q1 phi_1`` over the plate, through the Rayleigh sum (each element
    at its distance ``R``; all of it arrives within 150 us of the direct sound)."""
    surf = plate_surface(system, 30)
    plate = system.plate
    pts = surf.points_m
    dist = np.sqrt((pts[:, 0] - 0.5 * plate.a_m) ** 2 + (pts[:, 1] - 0.5 * plate.b_m) ** 2
                   + R_MIC_M**2)
    q1 = system.gap_m / float(system.beta[0]) / math.sqrt(float(system.modal_mass_kg[0]))
    w1 = float(system.omega_rad_s[0])
    return float(RHO_AIR_KG_M3 / (2 * math.pi)
                 * np.sum(surf.area_m2 * surf.shapes[0] * w1**2 * q1 / dist))


def sweep(n: int, speeds: tuple[float, ...] = (0.5, 1.0, 2.0, 4.0)) -> dict[str, object]:
    """The early peak (signed, through the microphone) against the impact velocity at ``n``
    modes: least-squares line ``p = S v + c``, and what explains ``S`` and ``c``."""
    system = thesis_system(n)
    runs = [one_impact(n, v, system) for v in speeds]
    v = np.array([r["v_in"] for r in runs])
    p = np.array([abs(r["early_signed_pa"]) for r in runs])
    slope, intercept = np.polyfit(v, p, 1)
    episode = np.array([r["mic"] * r["v_in"] for r in runs])
    ep_slope, ep_intercept = np.polyfit(v, episode, 1)
    plate = system.plate
    per_force = RHO_AIR_KG_M3 / (2 * math.pi * plate.rho_kg_m3 * plate.h_p_m * R_MIC_M)
    force_slope = float(np.polyfit(v, [r["force"] for r in runs], 1)[0]) * per_force
    return {"n": n, "v": v, "p": p, "slope": float(slope), "intercept": float(intercept),
            "fit_residual": float(np.max(np.abs(p - (slope * v + intercept)))),
            "episode": episode, "episode_slope": float(ep_slope),
            "episode_intercept": float(ep_intercept),
            "force_slope": force_slope, "static": static_sound_pa(system),
            "force_over_zv": [r["force"] / (system.local_impedance_n_s_m * r["v_in"])
                              for r in runs], "bound": runs[0]["bound"]}


ROWS = [("raw", "episode peak [Pa/(m/s)], raw"), ("mic", "episode peak through the microphone"),
        ("early", "peak within 200 us of arrival, through the microphone"),
        ("early_point", "of which the omitted modes' point source alone"),
        ("force", "largest element force [N]"), ("contacts", "contacts")]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", default="8,16,32,64,128,256")
    ap.add_argument("--sweep-modes", type=int, default=64)
    args = ap.parse_args()
    ns = [int(x) for x in args.modes.split(",")]
    out = [one_impact(n) for n in ns]
    print("| N | " + " | ".join(str(n) for n in ns) + " |")
    print("|---|" + "---|" * len(ns))
    for key, name in ROWS:
        print(f"| {name} | " + " | ".join(f"{o[key]:.4g}" for o in out) + " |")
    print("| run [s] | " + " | ".join(f"{o['s']:.1f}" for o in out) + " |")
    print("\nN -> 2N, relative change:")
    for lo, hi in zip(out, out[1:]):
        if hi["n"] == 2 * lo["n"]:
            print(f"  {lo['n']} -> {hi['n']}: " + ", ".join(
                f"{key} {100 * abs(hi[key] / lo[key] - 1):.2f} %" for key, _ in ROWS[:5]))
    print(f"\ninfinite-plate first-peak bound rho_0 Z / (2 pi m'' r) = {out[0]['bound']:.3f} "
          f"Pa/(m/s) at {R_MIC_M} m")
    sw = sweep(args.sweep_modes)
    print(f"\nearly peak against the impact velocity, N = {sw['n']}:")
    print("  v_in [m/s]: " + ", ".join(f"{x:.3f}" for x in sw["v"]))
    print("  |p| [Pa]:   " + ", ".join(f"{x:.3f}" for x in sw["p"]))
    print(f"  line p = S v + c: S = {sw['slope']:.3f} Pa/(m/s), c = {sw['intercept']:.3f} Pa "
          f"(largest residual {sw['fit_residual']:.3f} Pa)")
    print(f"  S against the infinite plate driven by the model's own contact force "
          f"rho_0 dF_max/dv / (2 pi m'' r) = {sw['force_slope']:.3f} Pa/(m/s) "
          f"(F_max / (Z v) = " + ", ".join(f"{x:.3f}" for x in sw["force_over_zv"]) + ")")
    print(f"  S against the bound rho_0 Z / (2 pi m'' r) = {sw['bound']:.3f}: "
          f"{sw['slope'] / sw['bound']:.3f} times")
    print(f"  c against the plate's elastic deceleration at the gap: {sw['static']:.3f} Pa")
    print("  the whole episode's peak [Pa]: " + ", ".join(f"{x:.3f}" for x in sw["episode"])
          + f": p = {sw['episode_slope']:.3f} v + {sw['episode_intercept']:.3f}")


if __name__ == "__main__":
    main()
