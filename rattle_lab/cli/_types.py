"""Argument types shared by every ``rattle-lab`` command.

Each is an ``argparse`` ``type=`` callable: it turns the option's text into a
value or raises :class:`argparse.ArgumentTypeError`, which argparse reports
as ``rattle-lab <command>: error: argument --x: ...`` with exit status 2.

* :func:`cycles` -- a number of forcing periods, finite and >= 1;
* :func:`positive` -- a finite number > 0 (frequencies, amplitudes, lengths);
* :func:`non_negative` -- a finite number >= 0 (damping ratios);
* :func:`probability` -- a number in [0, 1] (coefficient of restitution, fractions);
* :func:`finite` -- any finite number (initial conditions, phases);
* :func:`positive_int` -- an integer >= 1.

Examples
--------
>>> cycles("20")
20.0
>>> probability("0.6")
0.6
"""

from __future__ import annotations

import argparse
import math


def finite(text: str) -> float:
    """A finite number."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"must be a number, was {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, was {text!r}")
    return value


def positive(text: str) -> float:
    """A finite number > 0 (a frequency, an amplitude, a length)."""
    value = finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be > 0, was {text!r}")
    return value


def non_negative(text: str) -> float:
    """A finite number >= 0 (a damping ratio)."""
    value = finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, was {text!r}")
    return value


def probability(text: str) -> float:
    """A number in [0, 1] (a coefficient of restitution, a fraction)."""
    value = finite(text)
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in [0, 1], was {text!r}")
    return value


def cycles(text: str) -> float:
    """A number of forcing periods: finite and >= 1."""
    value = finite(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1 (forcing periods), was {text!r}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1."""
    try:
        value = int(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"must be an integer, was {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, was {text!r}")
    return value


__all__ = ["finite", "positive", "non_negative", "probability", "cycles", "positive_int"]
