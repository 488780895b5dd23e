"""``rattle-lab model run``: simulate the nondimensional SDF impact oscillator."""

from __future__ import annotations

import argparse
import json
import sys

from ._types import cycles, finite, non_negative, positive, probability


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "run", help="simulate the SDF impact oscillator and print its impacts",
        description=(
            "Simulate x'' + 2 zeta x' + x = F cos(omega t + phi) for x < 1 with v -> -e v at "
            "x = 1 (thesis eq. 2.33; all quantities nondimensional) with the exact "
            "event-driven solver, and print the impacts."))
    parser.add_argument("--F", type=non_negative("F"), required=True, help="forcing amplitude F (nondimensional)")
    parser.add_argument("--omega", type=positive("omega"), required=True,
                        help="forcing frequency / modal frequency (nondimensional)")
    parser.add_argument("--zeta", type=non_negative("zeta"), required=True, help="damping ratio")
    parser.add_argument("--e", type=probability("e"), required=True, help="coefficient of restitution, 0..1")
    parser.add_argument("--cycles", type=cycles(), default=20.0,
                        help="forcing periods to simulate (default 20)")
    parser.add_argument("--x0", type=finite("x0"), default=0.0, help="initial displacement (default 0)")
    parser.add_argument("--v0", type=finite("v0"), default=0.0, help="initial velocity (default 0)")
    parser.add_argument("--phase", type=finite("phase"), default=0.0,
                        help="initial forcing phase phi in rad (default 0)")
    parser.add_argument("--method", choices=("exact", "exact-python", "rk4-thesis"),
                        default="exact", help="solver (default: exact)")
    parser.add_argument("--json", action="store_true", help="print JSON on stdout")
    parser.add_argument("--plot", metavar="FILE",
                        help="write time histories and the phase portrait (png/pdf/svg)")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import numpy as np

    from rattle_lab.model.sdf import SDFParams, SDFState, simulate

    params = SDFParams(F=args.F, omega=args.omega, zeta=args.zeta, e=args.e)
    state = SDFState(x=args.x0, v=args.v0, theta=args.phase)
    if args.plot:
        from rattle_lab.plot import check_figure_path

        check_figure_path(args.plot)
    dense_t = None
    if args.plot:
        n = max(int(200 * args.cycles), 2)
        dense_t = np.linspace(0.0, args.cycles * params.period, n + 1)
    res = simulate(params, cycles=args.cycles, state=state, method=args.method,
                   dense_t=dense_t, crossings=False,
                   dense_fields=("x", "v", "a", "forced", "transient", "excitation"))
    if args.plot:
        from rattle_lab.plot import plot_time_history

        plot_time_history(res, args.plot)
    imp = res.impacts
    if args.json:
        doc = {
            "params": {"F": params.F, "omega": params.omega, "zeta": params.zeta, "e": params.e},
            "method": res.method,
            "impacts": [{"t": float(t), "phase": float(ph), "v_in": float(vi), "v_out": float(vo)}
                        for t, ph, vi, vo in zip(imp.t, imp.phase, imp.v_in, imp.v_out)],
            "accumulations": [float(t) for t in res.accumulations],
            "sticking": [[float(a), float(b)] for a, b in res.sticking],
            "t_end": res.state.t,
            "x_end": res.state.x,
            "v_end": res.state.v,
            "stuck_end": res.state.stuck,
        }
        # json writes floats with repr(): the shortest string that round-trips exactly
        json.dump(doc, sys.stdout, indent=1)
        sys.stdout.write("\n")
        return 0
    out = sys.stdout
    out.write(f"SDF run: F={params.F:g} omega={params.omega:g} zeta={params.zeta:g} "
              f"e={params.e:g}, {args.cycles:g} cycles, method {res.method} (nondimensional)\n")
    out.write(f"{'#':>5} {'t':>14} {'phase [rad]':>12} {'v_in':>12} {'v_out':>12}\n")
    for i, (t, ph, vi, vo) in enumerate(zip(imp.t, imp.phase, imp.v_in, imp.v_out)):
        out.write(f"{i:5d} {t:14.8f} {ph:12.8f} {vi:12.8f} {vo:12.8f}\n")
    out.write(f"{len(imp)} impacts, {len(res.accumulations)} chatter accumulations, "
              f"{len(res.sticking)} sticking intervals; end state x={res.state.x:.10g} "
              f"v={res.state.v:.10g}\n")
    return 0
