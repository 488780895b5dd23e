"""The ``rattle-lab`` command line.

Each command lives in its own module under :mod:`rattle_lab.cli` and is a thin
call into one library function (no logic lives only in the CLI).  A module
exposes ``register(subparsers)`` which adds its parser and sets
``func=callable(args) -> int`` as the parser default.

Errors: a :class:`~rattle_lab.exceptions.RattleLabError`, or an ``OSError``
(a directory given as the output, a read-only folder, a full disk), becomes
one line on stderr and exit status 2, never a traceback.  Ctrl-C (also when it
lands inside compiled numba code, which reports it as a ``SystemError``) prints
``interrupted`` and exits 130; SIGTERM prints ``terminated`` and exits 143.  A signal
counts even where compiled code swallowed its exception and raised another.
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
from collections.abc import Callable, Iterator, Sequence
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


@contextlib.contextmanager
def _signals_raise(received: list[KeyboardInterrupt]) -> Iterator[None]:
    """Turn SIGTERM into :class:`Terminated` and SIGINT into ``KeyboardInterrupt``.

    Each exception raised is also appended to ``received``: a handler runs at whatever
    Python line is current, and code called from C (h5py's type-conversion callbacks
    log through Python) can swallow the exception and raise another one in its place
    (a ``TypeError`` from h5py, a ``SystemError`` from numba).  :func:`main` then still
    knows that the command was stopped by a signal.  SIGINT is left alone where it is
    ignored (a command started by ``nohup`` or in the background by a shell) or has a
    handler of its own.  Main thread only; elsewhere nothing is changed.
    """

    def on_sigterm(signum: int, frame: FrameType | None) -> None:
        received.append(Terminated())
        raise received[-1]

    def on_sigint(signum: int, frame: FrameType | None) -> None:
        received.append(KeyboardInterrupt())
        raise received[-1]

    try:
        previous_term = signal.signal(signal.SIGTERM, on_sigterm)
    except ValueError:  # not the main thread: leave the handlers alone
        yield
        return
    previous_int = signal.getsignal(signal.SIGINT)
    if previous_int is signal.default_int_handler:
        signal.signal(signal.SIGINT, on_sigint)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous_term)
        if previous_int is signal.default_int_handler:
            signal.signal(signal.SIGINT, previous_int)


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
    return _run_command(func, args)


def _run_command(func: Callable[[argparse.Namespace], int | None], args: argparse.Namespace) -> int:
    """Run one command; map its failure to a message and an exit status."""
    from ._first_use import compile_if_cold

    received: list[KeyboardInterrupt] = []
    try:
        with _signals_raise(received):
            compile_if_cold(getattr(args, "command", None), getattr(args, "model_command", None))
            return int(func(args) or 0)
    except BaseException as exc:  # noqa: BLE001 - each kind is mapped below or re-raised
        interrupt = _interrupt_in(exc) or (received[0] if received else None)
        if interrupt is not None:  # a signal stopped it, whatever exception came out
            return _interrupted(interrupt)
        if isinstance(exc, RattleLabError):
            message = " ".join(str(exc).split())  # exactly one line
            print(f"rattle-lab: error: {message}", file=sys.stderr)
            return 2
        if isinstance(exc, BrokenPipeError):
            # the reader went away (e.g. `rattle-lab ... | head`): stop quietly
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
            return 1
        if isinstance(exc, OSError):  # an output or input the system refused: the user's to fix
            print(f"rattle-lab: error: {_os_error_line(exc)}", file=sys.stderr)
            return 2
        raise


def _interrupted(exc: KeyboardInterrupt) -> int:
    if isinstance(exc, Terminated):
        print("rattle-lab: terminated", file=sys.stderr)
        return 143
    print("rattle-lab: interrupted", file=sys.stderr)
    return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
