"""The trigger of impact detection: characteristic functions in robust noise units, on/off
with merging (ObsPy's trigger design), half-height regions and their centroids
(:func:`~rattle_lab.detect.detect_impacts`, steps 1-3)."""

from __future__ import annotations

import numpy as np

from ._common import detrended_abs, robust_sigma


def characteristic(x: np.ndarray, sigma_floor: float, n_detrend: int, *, jump: bool) -> np.ndarray:
    """Characteristic function in robust noise units (``jump``: of the first difference)."""
    if jump:
        d = np.diff(x)
        cf = np.concatenate([[0.0], detrended_abs(d, n_detrend)])
    else:
        cf = detrended_abs(x, n_detrend)
    sigma = max(robust_sigma(cf), sigma_floor)
    if sigma == 0.0:
        return np.zeros_like(cf)
    return cf / sigma


def trigger_onsets(cf: np.ndarray, on: float, off: float, n_min_sep: int
                   ) -> list[tuple[int, int, int]]:
    """``(onset, peak, end)`` sample indices of the triggers of ``cf`` (inclusive end).

    Examples
    --------
    >>> import numpy as np
    >>> cf = np.array([0, 1, 5, 20, 6, 1, 0, 0, 0, 0, 30, 2, 0], dtype=float)
    >>> trigger_onsets(cf, 10.0, 3.0, 2)
    [(2, 3, 4), (10, 10, 10)]
    """
    above_on = np.flatnonzero(cf > on)
    out: list[tuple[int, int, int]] = []
    i = 0
    while i < above_on.size:
        k = int(above_on[i])
        start = k
        while start > 0 and cf[start - 1] > off:  # back-track to the onset
            start -= 1
        end = k
        while end + 1 < cf.size and cf[end + 1] > off:
            end += 1
        peak = start + int(np.argmax(cf[start:end + 1]))
        if out and peak - out[-1][1] < n_min_sep:
            prev = out[-1]
            merged_peak = prev[1] if cf[prev[1]] >= cf[peak] else peak
            out[-1] = (prev[0], merged_peak, max(end, prev[2]))
        else:
            out.append((start, peak, end))
        i = int(np.searchsorted(above_on, end + 1))
    return out


def _half_region(cf: np.ndarray, peak: int) -> tuple[int, int]:
    """The contiguous samples around ``peak`` above half its height (inclusive)."""
    half = 0.5 * cf[peak]
    lo = peak
    while lo > 0 and cf[lo - 1] > half:
        lo -= 1
    hi = peak
    while hi + 1 < cf.size and cf[hi + 1] > half:
        hi += 1
    return lo, hi


def _centroid(cf: np.ndarray, peak: int, offset: float) -> float:
    """Centroid index of the samples around ``peak`` above half its height."""
    lo, hi = _half_region(cf, peak)
    idx = np.arange(lo, hi + 1, dtype=float)
    w = cf[lo:hi + 1]
    return float(np.sum(idx * w) / np.sum(w)) + offset
