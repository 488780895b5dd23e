"""Profile-likelihood helpers of the fits of ``e``: intervals on a grid and the coarse search.

Split from :mod:`rattle_lab.fit._restitution` (module size, issue 12):
:func:`profile_interval` and :func:`profile_parabola` read an interval off a ``chi2``
profile on a grid, and :func:`_search_coarse` evaluates only the part of a coarse grid of
``e`` that the ramp fit's profile needs.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np


def profile_interval(grid: np.ndarray, chi2: np.ndarray, cut: float) -> tuple[float, float]:
    """Outermost extent of ``{x : chi2(x) <= cut}`` on a grid, edges interpolated linearly.

    NaN on a side where the set reaches the end of the grid (the profile does not rise
    to ``cut`` there: the bound is not determined).  Non-finite ``chi2`` counts as above.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.linspace(0.0, 1.0, 11)
    >>> lo, hi = profile_interval(x, (x - 0.5) ** 2 / 0.01, 1.0)
    >>> bool(np.allclose([lo, hi], [0.4, 0.6]))
    True
    >>> profile_interval(x, x / 0.1, 1.0)[0]
    nan
    """
    c = np.where(np.isfinite(chi2), chi2, np.inf)
    inside = np.flatnonzero(c <= cut)
    if inside.size == 0:
        return float("nan"), float("nan")
    i, j = int(inside[0]), int(inside[-1])

    def cross(a: int, b: int) -> float:   # a inside, b outside
        if not np.isfinite(c[b]):
            return float(grid[b])
        return float(grid[a] + (grid[b] - grid[a]) * (cut - c[a]) / (c[b] - c[a]))

    lo = cross(i, i - 1) if i > 0 else float("nan")
    hi = cross(j, j + 1) if j < grid.size - 1 else float("nan")
    return lo, hi


def profile_parabola(grid: np.ndarray, chi2: np.ndarray, cut: float) -> tuple[float, float]:
    """``(vertex, a)`` of ``chi2 ~ a (x - vertex)^2 + c`` fitted to the points below ``cut``.

    The profile of a threshold replayed at one impact per cycle is a fine staircase; the
    least-squares parabola through its points within ``cut`` smooths it (through the
    minimum and its two neighbours when fewer than 3 points are within ``cut``).  NaN
    when the parabola opens downwards or its vertex lies outside the points used.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.linspace(0.0, 1.0, 21)
    >>> v, a = profile_parabola(x, 5.0 + 400.0 * (x - 0.42) ** 2, 30.0)
    >>> bool(np.isclose(v, 0.42) and np.isclose(a, 400.0))
    True
    """
    sel = np.isfinite(chi2) & (chi2 <= cut)
    if sel.sum() < 3:
        k = int(np.argmin(np.where(np.isfinite(chi2), chi2, np.inf)))
        sel = np.zeros(grid.size, dtype=bool)
        sel[max(k - 1, 0):k + 2] = True
        sel &= np.isfinite(chi2)
    if sel.sum() >= 3:
        a, b, _ = np.polyfit(grid[sel], chi2[sel], 2)
        if a > 0:
            x = -b / (2 * a)
            if grid[sel].min() <= x <= grid[sel].max():
                return float(x), float(a)
    return float("nan"), float("nan")


def _search_coarse(size: int, rows: Callable[[int], np.ndarray], data: np.ndarray,
                   sigma: np.ndarray) -> None:
    """Evaluate (through ``rows``) the part of a coarse grid of ``e`` the profile fit needs.

    ``rows(k)`` evaluates the model thresholds at grid point ``k`` (once; later calls are
    free).  The profile ``chi2 = sum(((rows(k) - data) / sigma)^2)`` is then known on a
    contiguous block ``[L, R]`` of the grid holding its minimum, plus a few isolated probes,
    such that every grid point left out has ``chi2 > cut``, the 2-sigma level
    ``min + 4 s2`` of the fit: the estimate, its standard error and its interval come out
    exactly as from the whole grid (they use the points below the cut and the first point
    beyond it on each side), while the model runs at about half of the grid points or less.

    How: probes every ``ceil(sqrt(size))`` points, a walk downhill from the lowest probe to
    a local minimum, then the block grows from there until at each end (or at the grid's
    end) ``chi2 > cut`` and every residual ``r_i = model_i - data_i`` has one sign ``s``,
    moving away from the data: ``s (r_i(end) - r_i(other end)) > 0`` for every ``i``.  The
    model threshold of a downward ramp is monotone in ``e`` (the 1/1 orbit's fold level
    falls as ``e`` rises, eq. 3.11; the replay's mean is a staircase of it, of steps
    ``|dA/dt| / (f n_phases)``, far finer than its change over a grid step), so beyond such
    an end each ``|r_i|`` only grows and ``chi2`` stays above the cut, which only falls as
    the block finds lower points.  A residual that is not finite (no threshold seen) or a
    flat one never lets an end stop there: at worst the whole grid is evaluated.  The
    monotonicity is an assumption about the model, not checked beyond the ends: a model
    threshold that turned back there by more than its staircase steps could hide a second
    basin.  The whole-grid profile stays available (``_FULL_GRID``) and the tests compare
    the two.
    """
    c2 = np.full(size, np.nan)

    def chi2(k: int) -> float:
        if np.isnan(c2[k]):
            with np.errstate(invalid="ignore"):
                value = float(np.sum(((rows(k) - data) / sigma) ** 2))
            c2[k] = value if math.isfinite(value) else math.inf
        return float(c2[k])

    n = data.size
    stride = max(1, math.ceil(math.sqrt(size)))
    k = min(sorted(set(range(0, size, stride)) | {size - 1}), key=chi2)
    while True:   # downhill to a local minimum (ties: stay)
        step = min((j for j in (k - 1, k + 1) if 0 <= j < size), key=chi2, default=k)
        if chi2(step) >= chi2(k):
            break
        k = step
    lo = hi = k

    def cut() -> float:
        best = float(np.nanmin(c2))
        return best + 4.0 * (max(1.0, best / (n - 1)) if n > 1 else 1.0)

    def stops(end: int, other: int) -> bool:
        if chi2(end) <= cut():
            return False
        r_end, r_other = rows(end) - data, rows(other) - data
        if not (np.all(np.isfinite(r_end)) and np.all(np.isfinite(r_other))):
            return False
        s = np.sign(r_end)
        return bool(np.all(s == s[0]) and s[0] != 0 and np.all(s * (r_end - r_other) > 0))

    while True:
        while lo > 0 and chi2(lo) <= cut():
            lo -= 1
        while hi < size - 1 and chi2(hi) <= cut():
            hi += 1
        left_ok = lo == 0 or stops(lo, hi)
        right_ok = hi == size - 1 or stops(hi, lo)
        if left_ok and right_ok:
            return
        if not left_ok:
            lo -= 1
        if not right_ok:
            hi += 1


__all__ = ["profile_interval", "profile_parabola"]
