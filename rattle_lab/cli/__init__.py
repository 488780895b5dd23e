"""The ``rattle-lab`` command line.

Each command lives in its own module under :mod:`rattle_lab.cli` and is a thin
call into one library function (no logic lives only in the CLI).  A module
exposes ``register(subparsers)`` which adds its parser and sets
``func=callable(args) -> int`` as the parser default.

Errors: a :class:`~rattle_lab.exceptions.RattleLabError`, or an ``OSError``
(a directory given as the output, a read-only folder, a full disk), becomes
one line on stderr and exit status 2, never a traceback.  Ctrl-C (also when it
lands inside compiled numba code, which reports it as a ``SystemError``) prints
``interrupted`` and exits 130; SIGTERM prints ``terminated`` and exits 143.
Either way the temporary files of the writer are removed and no partial output
is left (outputs are written atomically).  Data go to stdout or ``--output``;
messages go to stderr.  Option values are checked by the shared types of
:mod:`rattle_lab.cli._types`.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import os
import signal
import sys
from collections.abc import Iterator, Sequence
from types import FrameType

from rattle_lab._version import __version__
from rattle_lab.exceptions import RattleLabError
from ._types import OneLineParser

__all__ = ["COMMAND_MODULES", "build_parser", "main"]

#: Modules that register top-level commands, in the order ``--help`` lists them.
COMMAND_MODULES: tuple[str, ...] = (
    "rattle_lab.cli._model",
    "rattle_lab.cli._demo",
    "rattle_lab.cli._ingest",
    "rattle_lab.cli._verify",
    "rattle_lab.cli._fit",
    "rattle_lab.cli._explore",
    "rattle_lab.cli._simulate",
    "rattle_lab.cli._report",
    "rattle_lab.cli._export",
    "rattle_lab.cli._run",
)


def build_parser() -> argparse.ArgumentParser:
    """Build the full argument parser (used by :func:`main` and the docs)."""
    parser = OneLineParser(
        prog="rattle-lab",
        description="Rattle-noise engineering: exact impact-oscillator models and shaker-lab data.",
    )
    parser.add_argument("--version", action="version", version=f"rattle-lab {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised in the main thread so that writers clean up as for Ctrl-C."""


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    raise Terminated()


@contextlib.contextmanager
def _sigterm_raises() -> Iterator[None]:
    """Turn SIGTERM into :class:`Terminated` while a command runs (main thread only)."""
    try:
        previous = signal.signal(signal.SIGTERM, _on_sigterm)
    except ValueError:  # not the main thread: leave the handler alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _interrupt_in(exc: BaseException) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt behind ``exc`` (numba turns one into a SystemError), if any."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, KeyboardInterrupt):
            return cur
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return None


def _os_error_line(exc: OSError) -> str:
    where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
    if exc.errno == errno.ENOSPC:
        why = "no space left on the device"
    elif exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        why = "permission denied"
    else:
        why = exc.strerror or str(exc) or type(exc).__name__
    return " ".join(f"{where}{why}".split())


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``rattle-lab`` console script; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help(sys.stderr)
        return 2
    try:
        with _sigterm_raises():
            return int(func(args) or 0)
    except RattleLabError as exc:
        message = " ".join(str(exc).split())  # exactly one line
        print(f"rattle-lab: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        return _interrupted(exc)
    except SystemError as exc:
        interrupt = _interrupt_in(exc)
        if interrupt is None:
            raise
        return _interrupted(interrupt)
    except BrokenPipeError:
        # the reader went away (e.g. `rattle-lab ... | head`): stop quietly
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except OSError as exc:  # an output or input the system refused: the user's to fix
        print(f"rattle-lab: error: {_os_error_line(exc)}", file=sys.stderr)
        return 2


def _interrupted(exc: KeyboardInterrupt) -> int:
    if isinstance(exc, Terminated):
        print("rattle-lab: terminated", file=sys.stderr)
        return 143
    print("rattle-lab: interrupted", file=sys.stderr)
    return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
