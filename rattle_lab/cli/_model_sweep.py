"""``rattle-lab model sweep`` and ``rattle-lab model map``: slow sweeps, regime maps, basins.

Thin layers over :func:`rattle_lab.model.analysis._sweep.sweep_up_down` /
:func:`~rattle_lab.model.analysis._sweep.sweep` and the study functions of
:mod:`rattle_lab.model.analysis.maps`.  Every invalid argument raises
:class:`~rattle_lab.exceptions.ParameterError` naming the option and the value
(the CLI prints it on one line, exit status 2).  Data go to stdout (a table,
or JSON with ``--json``) or to ``--csv`` / ``--plot`` files; messages go to
stderr and are silenced by ``--quiet``.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from rattle_lab.exceptions import ParameterError

from ._model_args import add_damping_restitution, dump_json, parse_float, parse_int, parse_range

_GAP_HELP = ("gap: the gap h in units of the static deflection F_es / omega_s^2, i.e. "
             "gap = 1/F (eq. 2.31); the dimensional forcing amplitude F_es and omega, zeta, e "
             "are held fixed, so each value sets F = 1/gap, and the results are presented as "
             "v_im/F (proportional to the dimensional impact velocity, eq. 4.5) against 1/F "
             "(thesis Fig. 4-4)")


class _Formatter(argparse.ArgumentDefaultsHelpFormatter):
    """Shows ``(default: X)`` unless there is none or the help already says it."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        if action.default in (None, False) or "default" in text:
            return text
        return super()._get_help_string(action)


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    sw = sub.add_parser(
        "sweep", help="slow parameter sweep: impact velocities, regimes, Lyapunov exponents",
        description="Slow sweep of one parameter of the SDF impact oscillator (thesis 4.2-4.3, "
                    "Fig. 4-3 to 4-5): at each value the exact simulator runs --cycles forcing "
                    "periods from the previous value's final state (forcing phase continuous), "
                    "discards the first --discard, and records the impact velocities, the "
                    "upward x = 0 crossing velocities, the average impact velocity per cycle, "
                    "the regime (no impact, m/n periodic, aperiodic, or 'unsettled': a periodic "
                    "match still converging after 1000 extra periods, never a wrong m/n) and, "
                    "for aperiodic motion, the largest Lyapunov exponent.  " + _GAP_HELP + ".",
        formatter_class=_Formatter)
    sw.add_argument("--param", default="omega", help="swept parameter: omega, F, e or gap "
                    "(see the description for gap)")
    sw.add_argument("--start", required=True, help="first value")
    sw.add_argument("--stop", required=True, help="last value (included)")
    sw.add_argument("--step", required=True, help="step; must divide stop - start")
    sw.add_argument("--F", default=None, help="forcing amplitude, nondimensional (default 0.2; "
                    "not with --param F or gap)")
    sw.add_argument("--omega", default=None,
                    help="forcing frequency, nondimensional (default 1.0; not with --param omega)")
    sw.add_argument("--zeta", default="0.05", help="damping ratio")
    sw.add_argument("--e", default=None,
                    help="coefficient of restitution (default 0.6; not with --param e)")
    sw.add_argument("--direction", default="both", help="up, down, or both (up, then down "
                    "from the up-sweep's final state)")
    sw.add_argument("--cycles", default="100", help="forcing periods per value (thesis: 100)")
    sw.add_argument("--discard", default="70", help="of which discarded (thesis: 70)")
    sw.add_argument("--n-max", default="12", help="largest period (in forcing periods) detected")
    sw.add_argument("--rtol", default="1e-4", help="relative tolerance of the period detection")
    sw.add_argument("--lyapunov", default="aperiodic",
                    help="where to compute the largest Lyapunov exponent: aperiodic, all, none")
    sw.add_argument("--lyapunov-cycles", default="300",
                    help="forcing periods of the Lyapunov side run (50 of them warm-up)")
    out = sw.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    out.add_argument("--csv", metavar="FILE", help="write one CSV row per direction and value")
    sw.add_argument("--plot", metavar="FILE", help="write the figure (.png, .pdf or .svg)")
    sw.add_argument("--quiet", action="store_true", help="no progress bar, no messages")
    sw.set_defaults(func=_run_sweep)

    mp = sub.add_parser(
        "map", help="regime maps, basins of attraction and the disturbance study (Dask-parallel)",
        description="Studies of many independent simulations, run serially, on a local Dask "
                    "cluster (--workers N) or on a running dask.distributed cluster "
                    "(--scheduler ADDRESS).  --kind regime: the attractor at every point of an "
                    "(F, omega) grid; --kind basin: the attractor reached from every initial "
                    "state (x0, v0) at one (F, omega); --kind disturbance: the smallest "
                    "velocity kick at the upward x = 0 crossing that turns the impact-free "
                    "response into sustained impact, over (F, omega) (thesis 4.3.3, Fig. 4-7).",
        formatter_class=_Formatter)
    mp.add_argument("--kind", required=True, help="regime, basin or disturbance")
    mp.add_argument("--F", default=None, help="regime/disturbance: range lo:hi (default "
                    "0.02:0.6 / 0.05:0.3); basin: one value (default 0.2)")
    mp.add_argument("--omega", default=None, help="regime/disturbance: range lo:hi (default "
                    "0.6:1.5 / 1.0:1.3); basin: one value (default 1.15)")
    mp.add_argument("--n-F", default="41", help="F grid points (regime, disturbance)")
    mp.add_argument("--n-omega", default="41", help="omega grid points (regime, disturbance)")
    mp.add_argument("--x0", default="-2:1", help="basin: initial displacement range lo:hi")
    mp.add_argument("--v0", default="-2:2", help="basin: initial velocity range lo:hi")
    mp.add_argument("--n-x0", default="41", help="basin: x0 grid points")
    mp.add_argument("--n-v0", default="41", help="basin: v0 grid points")
    mp.add_argument("--theta0", default="0", help="basin: initial forcing phase")
    add_damping_restitution(mp)
    mp.add_argument("--cycles", default=None,
                    help="forcing periods per run (default 150; disturbance: 200)")
    mp.add_argument("--discard", default="100", help="regime/basin: periods discarded")
    mp.add_argument("--n-max", default="12", help="regime/basin: largest period detected")
    mp.add_argument("--rtol", default="1e-4", help="regime/basin: period-detection tolerance")
    mp.add_argument("--no-lyapunov", action="store_true",
                    help="regime/basin: skip the Lyapunov exponent of aperiodic points")
    mp.add_argument("--kick-max", default="2.0", help="disturbance: largest kick tried")
    mp.add_argument("--kick-tol", default="1e-3", help="disturbance: bisection tolerance")
    mp.add_argument("--n-scan", default="20", help="disturbance: kicks of the coarse scan")
    mp.add_argument("--check-cycles", default="20",
                    help="disturbance: final periods that must contain an impact")
    mp.add_argument("--levels", default="0.1,0.2,0.4",
                    help="disturbance: kick levels of the demarcation curves on the plot")
    mp.add_argument("--workers", default="1", help="local worker processes (1: serial)")
    mp.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="address of a running dask.distributed scheduler (tcp://host:8786)")
    mp.add_argument("--chunk-size", default=None,
                    help="points per chunk of work (default 256; disturbance: 16)")
    mp.add_argument("--json", action="store_true", help="JSON on stdout instead of a table")
    mp.add_argument("--plot", metavar="FILE", help="write the figure (.png, .pdf or .svg)")
    mp.add_argument("--quiet", action="store_true", help="no progress bar, no messages")
    mp.set_defaults(func=_run_map)


# ---------------------------------------------------------------------------
# Helpers
# ---------------------------------------------------------------------------

def _choice(option: str, text: str, choices: tuple[str, ...]) -> str:
    if text not in choices:
        raise ParameterError(f"`{option}` must be one of {', '.join(choices)}, was {text!r}")
    return text


def _message(args: argparse.Namespace, text: str) -> None:
    if not args.quiet:
        print(f"rattle-lab: {text}", file=sys.stderr)


def _fmt(x: float) -> str:
    return f"{x:.4g}" if math.isfinite(x) else str(x)


# ---------------------------------------------------------------------------
# model sweep
# ---------------------------------------------------------------------------

def _run_sweep(args: argparse.Namespace) -> int:
    from rattle_lab.model.analysis import (
        LYAPUNOV_MODES,
        SWEEP_PARAMS,
        sweep,
        sweep_up_down,
        sweep_values,
        write_sweeps_csv,
    )
    from rattle_lab.model.sdf import SDFParams
    from rattle_lab.plot import check_figure_path, plot_sweeps

    param = _choice("--param", args.param, SWEEP_PARAMS)
    direction = _choice("--direction", args.direction, ("up", "down", "both"))
    lyap = _choice("--lyapunov", args.lyapunov, LYAPUNOV_MODES)
    forbidden = {"omega": "omega", "F": "F", "e": "e", "gap": "F"}[param]
    if getattr(args, forbidden) is not None:
        raise ParameterError(f"`--{forbidden}` must not be given with --param {param}, "
                             f"was {getattr(args, forbidden)!r}")
    defaults = {"F": "0.2", "omega": "1.0", "e": "0.6"}
    values = {k: parse_float(f"--{k}", getattr(args, k) if getattr(args, k) is not None else d)
              for k, d in defaults.items()}
    values["zeta"] = parse_float("--zeta", args.zeta)
    grid = sweep_values(parse_float("--start", args.start), parse_float("--stop", args.stop),
                        parse_float("--step", args.step))
    if param == "gap":
        values["F"] = 1.0 / float(grid[0]) if grid[0] > 0 else 1.0
    # the swept parameter's base value is a placeholder: replaced at every grid value
    base = SDFParams(**{**values, **({param: float(grid[0])} if param != "gap" else {})})
    if args.plot:
        check_figure_path(args.plot)  # fail before the computation, not after
    options: dict[str, Any] = dict(
        cycles=parse_int("--cycles", args.cycles), discard=parse_int("--discard", args.discard),
        n_max=parse_int("--n-max", args.n_max), rtol=parse_float("--rtol", args.rtol),
        lyapunov=lyap, lyapunov_cycles=parse_float("--lyapunov-cycles", args.lyapunov_cycles),
        quiet=args.quiet)
    if direction == "both":
        sweeps = list(sweep_up_down(param, grid, base=base, **options))  # type: ignore[arg-type]
    else:
        sweeps = [sweep(param, grid, base=base, direction=direction, **options)]  # type: ignore[arg-type]
    if args.plot:
        plot_sweeps(sweeps, args.plot)
        _message(args, f"wrote {args.plot}")
    if args.csv:
        write_sweeps_csv(sweeps, args.csv)
        _message(args, f"wrote {args.csv}")
        return 0
    if args.json:
        dump_json({"sweeps": [s.to_dict() for s in sweeps]})
        return 0
    for s in sweeps:
        b = s.base
        # [issue 17] only the parameters that are held fixed (not the swept one, nor F for
        # a gap sweep, which sweeps 1/F)
        held = {"F": b.F, "omega": b.omega, "zeta": b.zeta, "e": b.e}
        fixed = " ".join(f"{k}={v:g}" for k, v in held.items()
                         if k != param and not (param == "gap" and k == "F"))
        print(f"{s.direction}-sweep of {param} over {grid[0]:g}..{grid[-1]:g} step "
              f"{float(args.step):g} ({grid.size} values; fixed: {fixed}; {s.cycles} periods, "
              f"first {s.discard} discarded)")
        print(f"  {'from':>10} {'to':>10} {'between':>21}")
        for tr in s.transitions():
            print(f"  {tr['from']:>10} {tr['to']:>10} {tr['before']:>10.6g} {tr['after']:>10.6g}")
        ap = [p for p in s.points if p.lyapunov is not None and p.regime.kind == "aperiodic"]
        if ap:
            pos = sum(1 for p in ap if p.lyapunov is not None and p.lyapunov.exponent > 0)
            print(f"  aperiodic values: {len(ap)}, with positive Lyapunov exponent: {pos}")
        unsettled = [p.value for p in s.points if p.regime.kind == "unsettled"]
        longer = [p for p in s.points if p.settle_cycles > 0 and p.regime.kind != "unsettled"]
        if unsettled or longer:
            print(f"  run longer to settle the period: {len(longer)} values; still unsettled "
                  f"after that: {len(unsettled)}"
                  + (f" ({', '.join(f'{v:g}' for v in unsettled[:8])}"
                     f"{', ...' if len(unsettled) > 8 else ''})" if unsettled else ""))
    return 0


# ---------------------------------------------------------------------------
# model map
# ---------------------------------------------------------------------------

def _grid(option: str, text: str, n_option: str, n_text: str) -> Any:
    import numpy as np

    lo, hi = parse_range(option, text)
    n = parse_int(n_option, n_text)
    if not 1 <= n <= 100_000:
        raise ParameterError(f"`{n_option}` must be in 1..100000, was {n_text!r}")
    return np.linspace(lo, hi, n)


def _run_map(args: argparse.Namespace) -> int:
    from rattle_lab.plot import check_figure_path

    kind = _choice("--kind", args.kind, ("regime", "basin", "disturbance"))
    if args.plot:
        check_figure_path(args.plot)
    workers = parse_int("--workers", args.workers)
    common: dict[str, Any] = dict(workers=workers, scheduler=args.scheduler, quiet=args.quiet)
    zeta, e = parse_float("--zeta", args.zeta), parse_float("--e", args.e)
    if kind == "disturbance":
        return _run_disturbance(args, zeta, e, common)
    from rattle_lab.model.analysis.maps import basin_map, regime_map
    from rattle_lab.model.sdf import SDFParams
    from rattle_lab.plot import check_figure_path, plot_attractor_map

    opts: dict[str, Any] = dict(
        cycles=parse_int("--cycles", args.cycles or "150"),
        discard=parse_int("--discard", args.discard),
        n_max=parse_int("--n-max", args.n_max), rtol=parse_float("--rtol", args.rtol),
        lyapunov=not args.no_lyapunov,
        chunk_size=parse_int("--chunk-size", args.chunk_size or "256"), **common)
    if kind == "regime":
        amap = regime_map(_grid("--F", args.F or "0.02:0.6", "--n-F", args.n_F),
                          _grid("--omega", args.omega or "0.6:1.5", "--n-omega", args.n_omega),
                          zeta=zeta, e=e, **opts)
    else:
        params = SDFParams(F=parse_float("--F", args.F or "0.2"),
                           omega=parse_float("--omega", args.omega or "1.15"), zeta=zeta, e=e)
        amap = basin_map(params, _grid("--x0", args.x0, "--n-x0", args.n_x0),
                         _grid("--v0", args.v0, "--n-v0", args.n_v0),
                         theta0=parse_float("--theta0", args.theta0), **opts)
    if args.plot:
        plot_attractor_map(amap, args.plot)
        _message(args, f"wrote {args.plot}")
    if args.json:
        dump_json(amap.to_dict())
        return 0
    total = amap.code.size
    print(f"{amap.kind} map over {amap.y_name} x {amap.x_name} = {amap.y.size} x {amap.x.size} "
          f"points ({amap.cycles} periods, last {amap.cycles - amap.discard} classified)")
    print(f"  {'regime':>10} {'points':>7} {'share':>7}")
    for label, count in amap.counts().items():
        print(f"  {label:>10} {count:>7} {100.0 * count / total:>6.1f}%")
    return 0


def _run_disturbance(args: argparse.Namespace, zeta: float, e: float,
                     common: dict[str, Any]) -> int:
    import numpy as np

    from rattle_lab.model.analysis import disturbance_map
    from rattle_lab.plot import plot_disturbance_map

    levels = tuple(parse_float("--levels", t) for t in args.levels.split(","))
    if any(v <= 0 for v in levels):
        raise ParameterError(f"`--levels` must be positive numbers, was {args.levels!r}")
    dmap = disturbance_map(
        _grid("--F", args.F or "0.05:0.3", "--n-F", args.n_F),
        _grid("--omega", args.omega or "1.0:1.3", "--n-omega", args.n_omega), zeta=zeta, e=e,
        kick_max=parse_float("--kick-max", args.kick_max),
        kick_tol=parse_float("--kick-tol", args.kick_tol),
        n_scan=parse_int("--n-scan", args.n_scan),
        cycles=parse_int("--cycles", args.cycles or "200"),
        check_cycles=parse_int("--check-cycles", args.check_cycles),
        chunk_size=parse_int("--chunk-size", args.chunk_size or "16"), **common)
    if args.plot:
        plot_disturbance_map(dmap, args.plot, levels=levels)
        _message(args, f"wrote {args.plot}")
    if args.json:
        dump_json(dmap.to_dict())
        return 0
    th = dmap.threshold
    print(f"disturbance thresholds over F x omega = {dmap.F.size} x {dmap.omega.size} points "
          f"(kick at the upward x = 0 crossing; impact sustained over the last "
          f"{dmap.check_cycles} of {dmap.cycles} periods)")
    print(f"  above grazing (no impact-free response): {int(np.isnan(th).sum())}")
    print(f"  no sustained impact up to kick {dmap.kick_max:g}: {int(np.isinf(th).sum())}")
    finite = th[np.isfinite(th)]
    if finite.size:
        print(f"  threshold found: {finite.size} points, kick {_fmt(float(finite.min()))} .. "
              f"{_fmt(float(finite.max()))}")
    for level in levels:
        print(f"  kick {level:g} sustains impact at {int(np.sum(np.isfinite(th) & (th <= level)))} "
              "points")
    return 0
