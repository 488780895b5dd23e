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

    A trigger starts where ``cf`` exceeds ``on``: its onset is found back to where ``cf``
    was last at or below ``off``, its end forward to the same, its peak is the first
    largest value between; a trigger whose peak is within ``n_min_sep`` samples of the
    previous one's is merged into it (the higher peak, the later end).  One compiled pass
    (:func:`rattle_lab.detect._jump_kernels.onsets`).

    Examples
    --------
    >>> import numpy as np
    >>> cf = np.array([0, 1, 5, 20, 6, 1, 0, 0, 0, 0, 30, 2, 0], dtype=float)
    >>> trigger_onsets(cf, 10.0, 3.0, 2)
    [(2, 3, 4), (10, 10, 10)]
    """
    from ._jump_kernels import onsets   # here: importing detect stays light (no numba)

    rows = onsets(np.ascontiguousarray(cf, dtype=np.float64), float(on), float(off),
                  int(n_min_sep))
    return [(int(a), int(b), int(c)) for a, b, c in rows.tolist()]


def _half_region(cf: np.ndarray, peak: int) -> tuple[int, int]:
    """The contiguous samples around ``peak`` above half its height (inclusive); the
    compiled impact loops' own rule (:func:`rattle_lab.detect._jump_kernels.half_region`)."""
    from ._jump_kernels import half_region   # here: importing detect stays light (no numba)

    lo, hi = half_region(np.ascontiguousarray(cf, dtype=np.float64), int(peak))
    return int(lo), int(hi)


def _centroid(cf: np.ndarray, peak: int, offset: float) -> float:
    """Centroid index of the samples around ``peak`` above half its height."""
    lo, hi = _half_region(cf, peak)
    idx = np.arange(lo, hi + 1, dtype=float)
    w = cf[lo:hi + 1]
    return float(np.sum(idx * w) / np.sum(w)) + offset
