"""Shared helpers of the detectors: seconds to samples, robust noise, sub-sample peaks."""

from __future__ import annotations

import numpy as np

from rattle_lab.exceptions import ParameterError


def n_samples_of(duration_s: float, fs_hz: float, *, name: str = "duration_s") -> int:
    """Samples in ``duration_s`` at ``fs_hz``: ``round(duration_s * fs_hz)`` (never truncated).

    Examples
    --------
    >>> n_samples_of(1.5e-3, 1000.0), n_samples_of(1.4e-3, 1000.0)
    (2, 1)
    """
    if not np.isfinite(fs_hz) or fs_hz <= 0:
        raise ParameterError(f"`fs_hz` must be > 0, was {fs_hz}")
    if not np.isfinite(duration_s) or duration_s < 0:
        raise ParameterError(f"`{name}` must be >= 0, was {duration_s}")
    return int(round(duration_s * fs_hz))


def as_signal(x: object, name: str) -> np.ndarray:
    """A finite 1-D float64 copy of ``x``; raises :class:`ParameterError` naming ``name``."""
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 1:
        raise ParameterError(f"`{name}` must be 1-D, had shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise ParameterError(f"`{name}` must be finite, has NaN/Inf at sample {bad}")
    return arr


def robust_sigma(x: np.ndarray) -> float:
    """Noise scale 1.4826 * MAD (the standard deviation for Gaussian noise)."""
    if x.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def detrended_abs(x: np.ndarray, n_window: int) -> np.ndarray:
    """``|x - local cubic fit|`` (Savitzky-Golay, ``n_window`` samples, odd, >= 5).

    A cubic follows the smooth forced response (a moving median would leave
    its curvature, which on a large sine exceeds the noise), while a spike of
    one or two samples stays mostly in the residual.
    """
    n_window = max(5, n_window | 1)
    if x.size < n_window:
        return np.abs(x - np.median(x)) if x.size else x.copy()
    from scipy.signal import savgol_filter  # here: `import rattle_lab.detect` stays light

    return np.abs(x - savgol_filter(x, n_window, 3, mode="interp"))


def parabolic_peak(y: np.ndarray, k: int) -> tuple[float, float]:
    """Sub-sample location and height of the peak of ``y`` at index ``k`` (3-point parabola).

    Returns ``(k + delta, height)``, ``|delta| <= 0.5``; at an edge, ``(k, y[k])``.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.arange(7.0)
    >>> loc, h = parabolic_peak(-(x - 3.3) ** 2, 3)
    >>> bool(np.isclose(loc, 3.3) and np.isclose(h, 0.0))
    True
    """
    if k <= 0 or k >= y.size - 1:
        return float(k), float(y[k])
    a, b, c = float(y[k - 1]), float(y[k]), float(y[k + 1])
    den = a - 2.0 * b + c
    if den >= 0.0:  # not a strict maximum: no refinement
        return float(k), b
    delta = 0.5 * (a - c) / den  # |delta| <= 0.5 because b >= a and b >= c
    return k + delta, b - 0.25 * (a - c) * delta
