"""Helpers shared by the fits: argument checks, parameter summaries of lmfit results."""

from __future__ import annotations

from dataclasses import dataclass
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


@dataclass(frozen=True)
class ParamEstimate:
    """One fitted parameter.

    Attributes
    ----------
    name : str
        Parameter name (carries its unit, e.g. ``gap_m``).
    value : float
        Best-fit value.
    stderr : float
        Standard error from the covariance matrix (NaN when not identifiable).
    ci_low, ci_high : float
        2-sigma (95.4 %) profile confidence interval (``lmfit.conf_interval``); NaN when not computed.
    vary : bool
        False for a parameter held fixed.
    """

    name: str
    value: float
    stderr: float
    ci_low: float
    ci_high: float
    vary: bool

    def as_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-ready)."""
        return {"name": self.name, "value": self.value, "stderr": self.stderr,
                "ci_low": self.ci_low, "ci_high": self.ci_high, "vary": self.vary}


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
