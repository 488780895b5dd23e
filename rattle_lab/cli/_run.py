"""``rattle-lab run PIPELINE INPUT...``: a thin layer over
:func:`rattle_lab.workflow.pipeline.run_pipeline`.
"""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "run", help="run a pipeline (simulate, ingest, detect, thresholds, fit, report)",
        description="Run the stages a pipeline TOML asks for, lazily: a stage runs only if a "
                    "requested output needs it, and a stage whose inputs and parameters are "
                    "unchanged is not rerun (content hashes are kept in the store under "
                    "/pipeline_cache). INPUT is a record file, or a scene (.toml, 'default' or "
                    "the name of a shipped scene) which is simulated first.")
    parser.add_argument("pipeline", metavar="PIPELINE",
                        help="pipeline TOML file, or the name of a shipped pipeline "
                             "('full_campaign', ...; see pipelines/)")
    parser.add_argument("inputs", nargs="+", metavar="INPUT", help="record files or scenes")
    parser.add_argument("--store", metavar="STORE.h5",
                        help="the store (default: OUT/<pipeline name>.h5)")
    parser.add_argument("--out", default=".", metavar="DIR",
                        help="directory for simulated records and the report (default: .)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="dask.distributed scheduler address for per-run detection; "
                             "'local' or 'local:N': a cluster of a worker process per core (or "
                             "N) started on this machine (default: serial, in this process)")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress lines or bars on stderr")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.workflow.pipeline import load_pipeline_file, run_pipeline

    def say(line: str) -> None:
        if not args.quiet:
            print(f"rattle-lab: {line}", file=sys.stderr)

    result = run_pipeline(load_pipeline_file(args.pipeline), args.inputs, store=args.store,
                          out_dir=args.out, scheduler=args.scheduler, log=say,
                          quiet=args.quiet)
    for name, path in result.outputs.items():
        print(f"{name}\t{path}")
    return 0
