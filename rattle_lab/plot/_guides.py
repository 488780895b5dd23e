"""Guide lines drawn through measured points: a law's slope, anchored at the points' median."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def _grid(x: np.ndarray, n: int) -> np.ndarray:
    return np.geomspace(x.min() / 1.2, x.max() * 1.2, n)


def db_slope_guide(x: npt.ArrayLike, level_db: npt.ArrayLike, db_per_decade: float = 20.0, *,
                   n: int = 50) -> tuple[np.ndarray, np.ndarray]:
    """A line of ``db_per_decade`` on a log-x axis through the median of the points.

    Anchored at ``(exp(median log x), median level)`` (NaN levels ignored) and spanning
    the points' ``x`` range widened by 1.2 each side.

    Parameters
    ----------
    x : array_like
        Positive abscissae (e.g. impact velocities, m/s); at least one.
    level_db : array_like
        Levels, dB, one per ``x``; at least one finite.
    db_per_decade : float
        The slope (20 for a pressure proportional to ``x``).
    n : int
        Points on the line.

    Returns
    -------
    (ndarray, ndarray)
        ``x`` and level of the line.
    """
    xa = np.asarray(x, dtype=float)
    grid = _grid(xa, n)
    x_mid, l_mid = np.exp(np.nanmedian(np.log(xa))), np.nanmedian(np.asarray(level_db, float))
    return grid, l_mid + db_per_decade * np.log10(grid / x_mid)


def power_law_guide(x: npt.ArrayLike, y: npt.ArrayLike, exponent: float, *, n: int = 50
                    ) -> tuple[np.ndarray, np.ndarray]:
    """A line ``y proportional to x**exponent`` through the (geometric) median of the points.

    Parameters
    ----------
    x, y : array_like
        Positive coordinates of the points, at least one.
    exponent : float
        The power.
    n : int
        Points on the line.

    Returns
    -------
    (ndarray, ndarray)
        ``x`` and ``y`` of the line, spanning the points' ``x`` widened by 1.2 each side.
    """
    xa, ya = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    grid = _grid(xa, n)
    x_mid, y_mid = np.exp(np.median(np.log(xa))), np.exp(np.median(np.log(ya)))
    return grid, y_mid * (grid / x_mid) ** exponent
