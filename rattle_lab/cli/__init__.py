"""The ``rattle-lab`` command line.

Each command lives in its own module under :mod:`rattle_lab.cli` and is a thin
call into one library function (no logic lives only in the CLI).  A module
exposes ``register(subparsers)`` which adds its parser and sets
``func=callable(args) -> int`` as the parser default.

Errors: a :class:`~rattle_lab.exceptions.RattleLabError` becomes one line on
stderr and exit status 2, never a traceback.  Data go to stdout or
``--output``; messages go to stderr.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence

from .._version import __version__
from ..exceptions import RattleLabError

#: Modules that register top-level commands, in the order ``--help`` lists them.
COMMAND_MODULES: tuple[str, ...] = (
    "rattle_lab.cli._model",
    "rattle_lab.cli._demo",
    "rattle_lab.cli._ingest",
    "rattle_lab.cli._fit",
    "rattle_lab.cli._explore",
    "rattle_lab.cli._simulate",
    "rattle_lab.cli._report",
    "rattle_lab.cli._export",
    "rattle_lab.cli._run",
)


def build_parser() -> argparse.ArgumentParser:
    """Build the full argument parser (used by :func:`main` and the docs)."""
    parser = argparse.ArgumentParser(
        prog="rattle-lab",
        description="Rattle-noise engineering: exact impact-oscillator models and shaker-lab data.",
    )
    parser.add_argument("--version", action="version", version=f"rattle-lab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rattle-lab`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(func(args) or 0)
    except RattleLabError as exc:
        message = " ".join(str(exc).split())  # exactly one line
        print(f"rattle-lab: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("rattle-lab: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader went away (e.g. `rattle-lab ... | head`): stop quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
