"""Argument checks and shared types of the model's functions (scaling, linear)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError

FloatOrArray = float | npt.NDArray[np.float64]


# --------------------------------------------------------------------------- validation
def _as_checked(name: str, value: npt.ArrayLike, *, strict: bool) -> FloatOrArray:
    """Return ``value`` as float (scalar input) or float array; reject NaN and values <= 0 / < 0."""
    arr = np.asarray(value, dtype=float)
    bad = ~(arr > 0) if strict else ~(arr >= 0)
    if np.any(bad):
        first = arr[bad].flat[0] if arr.ndim else float(arr)
        rel = "> 0" if strict else ">= 0"
        raise ParameterError(f"`{name}` must be {rel}, was {first}")
    return float(arr) if arr.ndim == 0 else arr


def _positive(name: str, value: npt.ArrayLike) -> FloatOrArray:
    return _as_checked(name, value, strict=True)


def _nonnegative(name: str, value: npt.ArrayLike) -> FloatOrArray:
    return _as_checked(name, value, strict=False)


def _poisson(nu: float) -> float:
    nu_f = float(nu)
    if not (-1.0 < nu_f < 0.5):
        raise ParameterError(f"`nu` must satisfy -1 < nu < 0.5, was {nu}")
    return nu_f


def _finite(name: str, value: npt.ArrayLike) -> FloatOrArray:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        first = arr[~np.isfinite(arr)].flat[0] if arr.ndim else float(arr)
        raise ParameterError(f"`{name}` must be finite, was {first}")
    return float(arr) if arr.ndim == 0 else arr


def _excited_participation(participation: npt.ArrayLike) -> FloatOrArray:
    """``participation`` (``Q1 / Q2``) checked finite and != 0: a mode with Q1 = 0 is not excited.

    Parameters
    ----------
    participation : float
        ``Q1 / Q2`` of the mode.

    Returns
    -------
    float
        ``participation`` as a float.

    Raises
    ------
    ParameterError
        If it is not finite or is 0.
    """
    q = _finite("participation", participation)
    if q == 0.0:
        raise ParameterError("`participation` must be != 0 (a mode with Q1 = 0 is not excited), was 0.0")
    return q


