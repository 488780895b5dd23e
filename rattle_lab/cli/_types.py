"""Argument types shared by every ``rattle-lab`` command.

Each factory takes the quantity's name and returns an ``argparse`` ``type=``
callable that turns the option's text into a value or raises
:class:`argparse.ArgumentTypeError` with the library's wording (``"`e` must
be in [0, 1], was 2.0"``); the parser prints it on one line, exit status 2.

* :func:`cycles` -- a number of forcing periods, finite and >= 1;
* :func:`positive` -- finite and > 0 (frequencies, amplitudes, lengths);
* :func:`non_negative` -- finite and >= 0 (damping ratios, forcing amplitudes);
* :func:`probability` -- in [0, 1] (coefficient of restitution, fractions);
* :func:`finite` -- any finite number (initial conditions, phases);
* :func:`positive_int` -- an integer >= 1.

Examples
--------
>>> cycles("cycles")("20")
20.0
>>> probability("e")("0.6")
0.6
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable


def _number(name: str, text: str) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"`{name}` must be a number, was {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"`{name}` must be finite, was {value}")
    return value


def _checked(name: str, ok: Callable[[float], bool], rule: str) -> Callable[[str], float]:
    def parse(text: str) -> float:
        value = _number(name, text)
        if not ok(value):
            raise argparse.ArgumentTypeError(f"`{name}` must be {rule}, was {value}")
        return value

    parse.__name__ = name  # argparse names the type in some messages
    return parse


def finite(name: str) -> Callable[[str], float]:
    """Any finite number."""
    return _checked(name, lambda v: True, "finite")


def positive(name: str) -> Callable[[str], float]:
    """A finite number > 0 (a frequency, an amplitude, a length)."""
    return _checked(name, lambda v: v > 0, "finite and > 0")


def non_negative(name: str) -> Callable[[str], float]:
    """A finite number >= 0 (a damping ratio, a forcing amplitude)."""
    return _checked(name, lambda v: v >= 0, ">= 0")


def probability(name: str) -> Callable[[str], float]:
    """A number in [0, 1] (a coefficient of restitution, a fraction)."""
    return _checked(name, lambda v: 0.0 <= v <= 1.0, "in [0, 1]")


def cycles(name: str = "cycles") -> Callable[[str], float]:
    """A number of forcing periods: finite and >= 1."""
    return _checked(name, lambda v: v >= 1, "finite and >= 1")


def positive_int(name: str) -> Callable[[str], int]:
    """An integer >= 1."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except (TypeError, ValueError):
            raise argparse.ArgumentTypeError(f"`{name}` must be an integer, was {text!r}") from None
        if value < 1:
            raise argparse.ArgumentTypeError(f"`{name}` must be >= 1, was {value}")
        return value

    parse.__name__ = name
    return parse


class OneLineParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line, exit status 2, with the prefix every
    command's errors have: ``rattle-lab: error: fit: message (see rattle-lab fit --help)``."""

    def error(self, message: str) -> None:  # type: ignore[override]
        program, *command = self.prog.split()
        where = f"{' '.join(command)}: " if command else ""
        self.exit(2, f"{program}: error: {where}{' '.join(message.split())} "
                     f"(see {self.prog} --help)\n")


__all__ = ["finite", "positive", "non_negative", "probability", "cycles", "positive_int",
           "OneLineParser"]
