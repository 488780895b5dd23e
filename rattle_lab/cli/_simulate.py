"""``rattle-lab simulate SCENE -o raw.h5``: a thin layer over :func:`rattle_lab.rig.write_synthetic`.

Prints one line per run (impacts, thresholds) and the output path on stdout; a bad
scene exits 2 with one line on stderr.  The record is written atomically.
"""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "simulate", help="synthesise a rattle record from a scene (synthetic rig)",
        description="Run the exact SDF simulator through a scene's protocol and write a "
                    "synthetic rattle record with its ground truth (/truth). SCENE is a TOML "
                    "file (see synthetic/) or 'default' for the embedded demo scene.")
    parser.add_argument("scene", metavar="SCENE",
                        help="scene TOML file, or the name of a shipped scene "
                             "('default', 'thesis_cfcf_1p3mm', ...; see synthetic/)")
    parser.add_argument("-o", "--output", required=True, metavar="RAW.h5", help="record to write")
    parser.add_argument("--seed", type=int, help="override the scene's seed")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab._atomic import check_output_path

    check_output_path(args.output)  # a bad output is refused before anything is imported
    from rattle_lab.rig import load_scene

    scene = load_scene(args.scene)  # refused (SceneError) before the simulator is imported
    from rattle_lab.rig import write_synthetic

    result = write_synthetic(scene, args.output, seed=args.seed, quiet=args.quiet)
    for run in result.runs:
        print(run.line())
    print(args.output)
    return 0
