"""Progress bars for long work: shown on a terminal, quiet otherwise."""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

from tqdm.auto import tqdm

T = TypeVar("T")


def progress_enabled(quiet: bool = False) -> bool:
    """True when a progress bar should be drawn: not ``quiet`` and stderr is a TTY."""
    return (not quiet) and sys.stderr.isatty()


def progress(iterable: Iterable[T], *, total: int | None = None, desc: str = "",
             quiet: bool = False, unit: str = "it") -> Iterator[T]:
    """Wrap ``iterable`` in a tqdm bar on stderr when :func:`progress_enabled`."""
    return iter(tqdm(iterable, total=total, desc=desc, unit=unit, file=sys.stderr,
                     disable=not progress_enabled(quiet), leave=False))
