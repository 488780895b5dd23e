"""``rattle-lab explore``: open the interactive explorer (the thesis's applet, Appendix A).

A thin layer over :class:`rattle_lab.explorer.Explorer`.  Without a display
(matplotlib resolved a file-only backend such as Agg) it prints one line on
stderr and exits 2, unless ``--save-png FILE`` asks for the initial state
rendered to an image.
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from ._types import cycles, positive


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "explore", help="interactive explorer of the SDF impact oscillator (the thesis's applet)",
        description=(
            "Open a window with sliders for F (or the base acceleration in m/s^2), omega, "
            "zeta, e and the gap; time histories of x, v, a with forced, transient and "
            "excitation parts; the phase portrait; the impacts; sweeps of the impact "
            "velocity against omega, the amplitude or e; and a save-data button "
            "(CSV/HDF5). Model quantities are nondimensional (thesis eq. 2.28-2.33)."))
    amp = parser.add_mutually_exclusive_group()
    amp.add_argument("--F", type=float, default=None,
                     help="forcing amplitude F (nondimensional; default 0.2)")
    amp.add_argument("--accel-ms2", type=float, default=None,
                     help="base-acceleration amplitude A_e [m/s^2] instead of F (sets F "
                          "through --gap-m, --f-s-hz, --participation; the slider shows A_e)")
    parser.add_argument("--omega", type=float, default=1.0,
                        help="forcing frequency / modal frequency (nondimensional; default 1)")
    parser.add_argument("--zeta", type=float, default=0.05,
                        help="damping ratio (nondimensional; default 0.05)")
    parser.add_argument("--e", type=float, default=0.6,
                        help="coefficient of restitution, 0..1 (default 0.6)")
    parser.add_argument("--gap-m", type=float, default=1e-3, help="gap h [m] (default 0.001)")
    parser.add_argument("--f-s-hz", type=positive("f_s_hz"), default=100.0,
                        help="modal frequency f_s [Hz] (default 100)")
    parser.add_argument("--participation", type=float, default=1.0,
                        help="modal participation Q1/Q2 (eq. 2.27; default 1: an SDF "
                             "oscillator on a shaken base)")
    parser.add_argument("--cycles", type=cycles(), default=20.0,
                        help="forcing periods shown per run (default 20)")
    parser.add_argument("--save-png", metavar="FILE",
                        help="render the initial state to FILE (png/pdf/svg) and exit; "
                             "needs no display")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.explorer import Explorer, display_available
    from rattle_lab.plot import check_figure_path
    from rattle_lab.model.scaling import F_from_accel
    from rattle_lab.model.sdf import SDFParams

    if args.save_png:
        check_figure_path(args.save_png)
    elif not display_available():
        return _no_display()
    mode = "F"
    F = 0.2 if args.F is None else args.F
    if args.accel_ms2 is not None:  # F_from_accel validates, naming the argument
        mode = "accel"
        F = float(F_from_accel(args.accel_ms2, args.participation,
                               2.0 * math.pi * args.f_s_hz, args.gap_m))
    params = SDFParams(F=F, omega=args.omega, zeta=args.zeta, e=args.e)
    options: dict[str, Any] = dict(params=params, gap_m=args.gap_m, f_s_hz=args.f_s_hz,
                                   participation=args.participation, cycles=args.cycles,
                                   amplitude_mode=mode)
    if args.save_png:
        path = Explorer(**options).save_png(args.save_png)
        print(f"rattle-lab: wrote {path}", file=sys.stderr)
        return 0
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(16, 10))
    if not display_available():  # pyplot fell back to a file-only backend
        plt.close(fig)
        return _no_display()
    fig.canvas.manager.set_window_title("rattle-lab explorer")  # type: ignore[union-attr]
    explorer = Explorer(figure=fig, **options)
    plt.show()  # ``explorer`` holds the widgets: it must live as long as the window
    del explorer
    return 0


def _no_display() -> int:
    import matplotlib

    print(f"rattle-lab: error: no display for the explorer window (matplotlib backend "
          f"{matplotlib.get_backend()!r}); set DISPLAY, or use --save-png FILE to render it "
          f"to an image", file=sys.stderr)
    return 2
