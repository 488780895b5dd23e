"""``rattle-lab demo``: the main job on the embedded default scene (see :mod:`rattle_lab.workflow.demo`)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "demo", help="run the main job on the embedded default scene",
        description="Simulate the embedded default scene (synthetic rig with known truth; or "
                    "another scene, --scene), then "
                    "ingest, detect, fit and report through the pipeline of `rattle-lab run`. "
                    "Prints the fitted values against the rig's truth and, last, the path of "
                    "the PDF report. Writes OUT/raw.h5, OUT/store.h5 and OUT/report.pdf.")
    parser.add_argument("--out", default="demo_out", help="output folder (default: demo_out)")
    parser.add_argument("--scene", default="default", metavar="SCENE",
                        help="the scene to simulate: a scene TOML file or a shipped scene's "
                             "name (see `rattle-lab simulate --help`; default: the embedded "
                             "default scene)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.workflow.demo import run_demo

    return run_demo(args.out, quiet=args.quiet, scene=args.scene)
