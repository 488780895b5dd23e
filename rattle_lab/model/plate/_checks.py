"""Argument checks of the plate solvers and of :class:`~rattle_lab.model.plate.Plate`."""

from __future__ import annotations

import math
import operator

from rattle_lab.exceptions import ParameterError


def check_aspect_ratio(aspect_ratio: float) -> float:
    r = float(aspect_ratio)
    if not (r > 0 and math.isfinite(r)):
        raise ParameterError(f"`aspect_ratio` (b/a) must be finite and > 0, was {aspect_ratio}")
    return r


def check_count(name: str, value: int, minimum: int = 1) -> int:
    try:
        as_int = operator.index(value)
    except TypeError:
        raise ParameterError(f"`{name}` must be an integer >= {minimum}, was {value!r}") from None
    if as_int < minimum:
        raise ParameterError(f"`{name}` must be an integer >= {minimum}, was {value!r}")
    return as_int


def positive_float(name: str, value: float) -> float:
    v = float(value)
    if not (v > 0 and math.isfinite(v)):
        raise ParameterError(f"`{name}` must be finite and > 0, was {value}")
    return v
