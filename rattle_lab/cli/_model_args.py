"""Argument parsing and output shared by the ``rattle-lab model`` analysis commands.

Used by :mod:`rattle_lab.cli._model_orbits` (``orbits``, ``bifsets``) and
:mod:`rattle_lab.cli._model_sweep` (``sweep``, ``map``).  Options arrive as
text; every invalid value raises :class:`~rattle_lab.exceptions.ParameterError`
naming the option and the value (the CLI prints it on one line, exit status 2).
"""

from __future__ import annotations

import argparse
import json
import math
import sys

from rattle_lab.exceptions import ParameterError

#: Damping ratio and coefficient of restitution used when the command line gives none.
DEFAULT_ZETA = "0.05"
DEFAULT_E = "0.6"


def add_damping_restitution(parser: argparse.ArgumentParser) -> None:
    """Add ``--zeta`` and ``--e`` (nondimensional, as text) with the model's defaults.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser; the options keep their text until :func:`parse_float`.
    """
    parser.add_argument("--zeta", default=DEFAULT_ZETA,
                        help=f"damping ratio (default: {DEFAULT_ZETA})")
    parser.add_argument("--e", default=DEFAULT_E,
                        help=f"coefficient of restitution (default: {DEFAULT_E})")


def parse_float(option: str, text: str) -> float:
    """The finite number an option gives.

    Parameters
    ----------
    option : str
        The option's name as typed (``"--zeta"``), for the message.
    text : str
        Its value.

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        If ``text`` is not a finite number.
    """
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise ParameterError(f"`{option}` must be a number, was {text!r}") from None
    if not math.isfinite(value):
        raise ParameterError(f"`{option}` must be finite, was {text!r}")
    return value


def parse_int(option: str, text: str) -> int:
    """The integer an option gives.

    Parameters
    ----------
    option : str
        The option's name as typed, for the message.
    text : str
        Its value.

    Returns
    -------
    int

    Raises
    ------
    ParameterError
        If ``text`` is not an integer.
    """
    try:
        return int(text)
    except (TypeError, ValueError):
        raise ParameterError(f"`{option}` must be an integer, was {text!r}") from None


def parse_range(option: str, text: str) -> tuple[float, float]:
    """``"0.6:1.5"`` -> ``(0.6, 1.5)``; requires ``lo < hi``.

    Parameters
    ----------
    option : str
        The option's name as typed, for the message.
    text : str
        Its value, ``lo:hi``.

    Returns
    -------
    lo, hi : float

    Raises
    ------
    ParameterError
        If ``text`` is not two finite numbers with ``lo < hi``.
    """
    parts = text.split(":")
    if len(parts) != 2:
        raise ParameterError(f"`{option}` must be a range lo:hi, was {text!r}")
    lo, hi = parse_float(option, parts[0]), parse_float(option, parts[1])
    if not lo < hi:
        raise ParameterError(f"`{option}` must have lo < hi, was {text!r}")
    return lo, hi


def dump_json(doc: object, indent: int | None = None) -> None:
    """Write ``doc`` as JSON and a newline to stdout.

    Parameters
    ----------
    doc : object
        JSON-serialisable document.
    indent : int or None, optional
        Indentation as in :func:`json.dump`; None writes one line.
    """
    json.dump(doc, sys.stdout, indent=indent)
    sys.stdout.write("\n")
