"""``rattle-lab model plate | scale | grazing``: plate modal data, scaling, grazing curve.

Thin layers over :func:`rattle_lab.model.plate.ritz_modes` (and the closed form for SSSS),
:class:`rattle_lab.model.scaling.SDFScaling` and :mod:`rattle_lab.model.linear`.  A human table
goes to stdout by default, JSON with ``--json``.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from typing import Any

_EDGE_HELP = (
    "four letters C (clamped), S (simply supported), F (free) for the edges "
    "y=0, x=a, y=b, x=0 in that order (counter-clockwise from the bottom edge); "
    "CFCF clamps the two sides of length a and frees the two of length b "
    "(the thesis's Table 2.1 plate), CCCC is Table 2.2"
)


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``plate``, ``scale`` and ``grazing`` commands to the ``model`` group."""
    p = sub.add_parser(
        "plate", help="modal data (lambda, f, Q1, Q2) of a thin rectangular plate",
        description="Modes of a thin rectangular plate 0<=x<=a, 0<=y<=b by Rayleigh-Ritz with "
                    "beam functions (closed form for SSSS): lambda = omega a^2 sqrt(rho h/D) "
                    "(thesis eq. 2.25), f [Hz], Q1, Q2 (eq. 2.18, 2.19; W = 1 at the centre, or "
                    "at max |W| where the centre is a node). Edges: " + _EDGE_HELP + ".")
    _add_plate_args(p, need_shape=True)
    p.add_argument("--modes", type=int, default=6, help="number of modes (default: 6)")
    p.add_argument("--terms", type=int, default=None,
                   help="beam functions per side in the Ritz solver (default: the library's)")
    p.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    p.set_defaults(func=_run_plate)

    s = sub.add_parser(
        "scale", help="physical excitation -> nondimensional F, omega of one plate mode",
        description="Scales of one plate mode (thesis eq. 2.3, 2.25, 2.27, 2.28, 2.31): omega_s, "
                    "f_s, the participation factor Q1/Q2, F_es, F and omega. The modal data come "
                    "from the Ritz solver (--b, --edges, --mode) or are given (--lam, --Q1, --Q2). "
                    "Edges: " + _EDGE_HELP + ".")
    _add_plate_args(s, need_shape=False)
    s.add_argument("--mode", type=int, default=1, help="1-based Ritz mode number (default: 1)")
    s.add_argument("--lam", type=float, default=None, help="give lambda instead of solving")
    s.add_argument("--Q1", type=float, default=None, help="give Q1 instead of solving")
    s.add_argument("--Q2", type=float, default=None, help="give Q2 instead of solving")
    s.add_argument("--gap", type=float, required=True, metavar="GAP_M", help="plate-striker gap h [m]")
    amp = s.add_mutually_exclusive_group(required=True)
    amp.add_argument("--accel", type=float, metavar="ACCEL_MS2", help="base-acceleration amplitude [m/s^2]")
    amp.add_argument("--pressure", type=float, metavar="PRESSURE_PA", help="pressure amplitude P_e [Pa]")
    s.add_argument("--freq", type=float, default=None, metavar="FREQ_HZ", help="excitation frequency [Hz]")
    s.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    s.set_defaults(func=_run_scale)

    g = sub.add_parser(
        "grazing", help="linear grazing curve F(omega) = sqrt((1-omega^2)^2 + (2 zeta omega)^2)",
        description="The linear grazing curve (thesis eq. 3.4), nondimensional. With --F: the two "
                    "frequencies where F grazes (impact in between). With --omega: F_graze there. "
                    "With neither: F_graze on omega = 0.5, 0.55, ..., 1.5.")
    g.add_argument("--zeta", type=float, required=True, help="damping ratio (nondimensional)")
    g.add_argument("--F", type=float, default=None, help="forcing amplitude (nondimensional)")
    g.add_argument("--omega", type=float, nargs="+", default=None, help="forcing frequencies (nondimensional)")
    g.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    g.set_defaults(func=_run_grazing)


def _add_plate_args(p: argparse.ArgumentParser, *, need_shape: bool) -> None:
    p.add_argument("--a", type=float, required=True, metavar="A_M", help="side along x [m] (lambda uses a)")
    p.add_argument("--b", type=float, required=need_shape, default=None, metavar="B_M", help="side along y [m]")
    p.add_argument("--h", type=float, required=True, metavar="H_P_M", help="thickness h_p [m]")
    p.add_argument("--E", type=float, required=True, metavar="E_PA", help="Young's modulus [Pa]")
    p.add_argument("--nu", type=float, required=True, help="Poisson's ratio (-1 < nu < 0.5)")
    p.add_argument("--rho", type=float, required=True, metavar="RHO_KG_M3", help="density [kg/m^3]")
    p.add_argument("--edges", default=None if not need_shape else "CFCF", metavar="EDGES",
                   help=_EDGE_HELP + " (default: CFCF)")


# --------------------------------------------------------------------------- output helpers
def _clean(value: Any) -> Any:
    """JSON-safe copy: numpy scalars to Python, NaN/inf to None."""
    import numpy as np  # here, not at the top: `rattle-lab --help` must not import numpy

    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_clean(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _emit_json(payload: dict[str, Any]) -> None:
    print(json.dumps(_clean(payload), indent=2, allow_nan=False))


def _fmt(v: Any) -> str:
    if v is None:
        return "-"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else f"{v:.6g}"
    return str(v)


def _fixed(v: float) -> str:
    """Five decimals, without the "-0.00000" that rounding noise of a zero would print."""
    text = f"{v:.5f}"
    return text[1:] if text == "-0.00000" else text


def _table(headers: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    cells = [list(headers)] + [[_fmt(v) for v in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


# --------------------------------------------------------------------------- commands
def _plate_from_args(args: argparse.Namespace, b_m: float, edges: str) -> Any:
    from rattle_lab.model.plate import Plate

    return Plate(a_m=args.a, b_m=b_m, h_p_m=args.h, E_pa=args.E, nu=args.nu, rho_kg_m3=args.rho, edges=edges)


def _solve(plate: Any, n_modes: int, n_terms: int | None) -> tuple[str, list[dict[str, Any]]]:
    from rattle_lab.model.plate import simply_supported_modes

    if plate.edges == "SSSS":
        modes = list(simply_supported_modes(plate.aspect_ratio, n_modes))
        method = "closed form (eq. 2.20-2.25)"
    else:
        result = plate.modes(n_modes, n_terms)
        modes = [result[k] for k in range(len(result))]
        method = f"Rayleigh-Ritz, {result.n_terms[0]}x{result.n_terms[1]} beam functions"
    rows = [
        {"mode": k + 1, "lambda": m.lam, "f_hz": float(plate.frequency_hz(m.lam)), "Q1": m.Q1, "Q2": m.Q2,
         "normalised_at_max": m.at_max, "m": m.m, "n": m.n}
        for k, m in enumerate(modes)
    ]
    return method, rows


def _run_plate(args: argparse.Namespace) -> int:
    plate = _plate_from_args(args, args.b, args.edges)
    method, rows = _solve(plate, args.modes, args.terms)
    if args.json:
        _emit_json({"edges": plate.edges, "edge_order": ["y=0", "x=a", "y=b", "x=0"],
                    "aspect_ratio": plate.aspect_ratio, "nu": plate.nu,
                    "flexural_rigidity_nm": plate.flexural_rigidity_nm, "method": method, "modes": rows})
        return 0
    print(f"plate {plate.a_m:g} m x {plate.b_m:g} m x {plate.h_p_m:g} m, edges {plate.edges} "
          f"(y=0, x=a, y=b, x=0), b/a = {plate.aspect_ratio:.4g}, D = {plate.flexural_rigidity_nm:.5g} N m")
    print(f"method: {method}; * = W normalised at max |W| (centre is a node)")
    print(_table(["mode", "lambda", "f [Hz]", "Q1", "Q2", "*", "m", "n"],
                 [[r["mode"], r["lambda"], r["f_hz"], _fixed(r["Q1"]), _fixed(r["Q2"]),
                   "*" if r["normalised_at_max"] else "",
                   r["m"], r["n"]] for r in rows]))
    return 0


def _run_scale(args: argparse.Namespace) -> int:
    from rattle_lab.model import scaling
    from rattle_lab.exceptions import ParameterError

    given = [args.lam, args.Q1, args.Q2]
    if any(v is not None for v in given):
        if any(v is None for v in given):
            raise ParameterError(
                f"give all of --lam, --Q1, --Q2 or none, was lam={args.lam}, Q1={args.Q1}, Q2={args.Q2}")
        lam, q1, q2 = float(args.lam), float(args.Q1), float(args.Q2)
        source = "given"
        # Validates a, h, E, nu, rho through the same Plate checks (b, edges unused).
        _plate_from_args(args, args.a if args.b is None else args.b, args.edges or "CFCF")
    else:
        if args.b is None or args.edges is None:
            raise ParameterError(
                f"--b and --edges are needed to solve for the mode (or give --lam, --Q1, --Q2), "
                f"was b={args.b}, edges={args.edges}")
        if args.mode < 1:
            raise ParameterError(f"`--mode` must be >= 1, was {args.mode}")
        plate = _plate_from_args(args, args.b, args.edges)
        _, rows = _solve(plate, args.mode, None)
        row = rows[args.mode - 1]
        lam, q1, q2 = row["lambda"], row["Q1"], row["Q2"]
        source = f"mode {args.mode} of {plate.edges}, b/a = {plate.aspect_ratio:.4g}"
    sc = scaling.SDFScaling.from_modal_data(lam=lam, Q1=q1, Q2=q2, gap_m=args.gap, a_m=args.a, h_p_m=args.h,
                                            E_pa=args.E, nu=args.nu, rho_kg_m3=args.rho)
    if args.accel is not None:
        accel = float(args.accel)
        pressure = float(scaling.pressure_pa_from_accel(accel, args.rho, args.h))
    else:
        pressure = float(args.pressure)
        accel = float(scaling.accel_ms2_from_pressure(pressure, args.rho, args.h))
    F = float(scaling.F_from_accel(accel, sc.participation, sc.omega_s_rad_s, sc.gap_m))
    omega = None if args.freq is None else float(scaling.omega_from_freq(args.freq, sc.f_s_hz))
    out = {
        "modal_data": source, "lambda": lam, "Q1": q1, "Q2": q2, "participation": sc.participation,
        "omega_s_rad_s": sc.omega_s_rad_s, "f_s_hz": sc.f_s_hz, "gap_m": sc.gap_m,
        "accel_ms2": accel, "pressure_pa": pressure,
        "F_es_ms2": float(scaling.F_es_from_accel(accel, sc.participation)),
        "F": F, "freq_hz": args.freq, "omega": omega,
    }
    if args.json:
        _emit_json(out)
        return 0
    units = {"omega_s_rad_s": "rad/s", "f_s_hz": "Hz", "gap_m": "m", "accel_ms2": "m/s^2", "pressure_pa": "Pa",
             "F_es_ms2": "m/s^2", "freq_hz": "Hz"}
    print(_table(["quantity", "value", "unit"], [[k, v, units.get(k, "")] for k, v in out.items()]))
    return 0


def _run_grazing(args: argparse.Namespace) -> int:
    import numpy as np

    from rattle_lab.model import linear

    out: dict[str, Any] = {"zeta": args.zeta}
    if args.F is not None:
        lo, hi = linear.grazing_omegas(args.F, args.zeta)
        out.update({"F": args.F, "omega_low": float(lo), "omega_high": float(hi)})
    omegas = args.omega
    if omegas is None and args.F is None:
        omegas = list(np.round(np.arange(0.5, 1.5 + 1e-9, 0.05), 10))
    if omegas is not None:
        f_graze = np.atleast_1d(linear.grazing_F(np.asarray(omegas, dtype=float), args.zeta))
        out["curve"] = [{"omega": float(w), "F_graze": float(f)} for w, f in zip(omegas, f_graze)]
    if args.json:
        _emit_json(out)
        return 0
    print(f"grazing curve (eq. 3.4), zeta = {args.zeta:g}")
    if args.F is not None:
        print(_table(["F", "omega_low", "omega_high"], [[args.F, out["omega_low"], out["omega_high"]]]))
        print("linear theory: impact for omega_low <= omega <= omega_high (nan: no root)")
    if "curve" in out:
        print(_table(["omega", "F_graze"], [[r["omega"], r["F_graze"]] for r in out["curve"]]))
    return 0
