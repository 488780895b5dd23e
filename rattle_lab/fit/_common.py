"""Helpers shared by the fits: argument checks, the correlation matrix of an lmfit result."""

from __future__ import annotations

from typing import Any

import math

import numpy as np

from rattle_lab.exceptions import ParameterError


def check_positive(**values: float) -> None:
    """Raise :class:`ParameterError` naming the first of ``values`` that is not finite and > 0.

    Examples
    --------
    >>> check_positive(gap_m=1.3e-3, f_s_hz=96.0)
    >>> check_positive(gap_m=1.3e-3, zeta=float("nan"))
    Traceback (most recent call last):
    ...
    rattle_lab.exceptions.ParameterError: `zeta` must be finite and > 0, was nan
    """
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise ParameterError(f"`{name}` must be finite and > 0, was {value}")


def correlation_matrix(result: Any, names: list[str]) -> np.ndarray:
    """Correlation matrix of the varied parameters ``names`` (NaN without a covariance)."""
    n = len(names)
    corr = np.full((n, n), np.nan)
    covar = getattr(result, "covar", None)
    var_names = list(getattr(result, "var_names", []))
    if covar is None:
        return corr
    idx = [var_names.index(nm) for nm in names]
    sub = np.asarray(covar)[np.ix_(idx, idx)]
    d = np.sqrt(np.diag(sub))
    with np.errstate(divide="ignore", invalid="ignore"):
        return sub / np.outer(d, d)
