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


def progress_bar(total: int, *, desc: str = "", quiet: bool = False, unit: str = "it",
                 unit_scale: bool = False) -> tqdm:
    """A tqdm bar on stderr to :meth:`~tqdm.tqdm.update` by hand (a no-op unless
    :func:`progress_enabled`); use it as a context manager so that it is closed.

    The bar shows the count done of ``total``, the rate (``unit``/s, with k/M/G prefixes
    when ``unit_scale``) and the time elapsed and left: ``[00:12<01:40, 21.3Msample/s]``."""
    return tqdm(total=total, desc=desc, unit=unit, unit_scale=unit_scale, file=sys.stderr,
                disable=not progress_enabled(quiet), leave=False)
