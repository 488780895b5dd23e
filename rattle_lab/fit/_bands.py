"""Uncertainty bands and intervals of fitted laws, for tables and plots of the fit results.

* :func:`grazing_band_ms2`: eq. (3.4) at the fitted parameters with its 95 % band
  (delta method, Student t with the fit's degrees of freedom, :func:`band_quantile`).
* :func:`linear_law_band`: the 95 % band of the mean of an OLS line (the SPL laws).
* :func:`student_t_ci`: ``value +/- t(0.975, dof) stderr``.
* :func:`threshold_hysteresis`: onset less disappearance, and where it is negative.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import numpy.typing as npt

from ._estimates import GrazingSummary

__all__ = ["band_quantile", "grazing_band_ms2", "linear_law_band", "student_t_ci",
           "threshold_hysteresis", "negative_hysteresis",
           "hysteresis_uncertainty_ms2", "SIGNIFICANCE_K"]


def _pval(g: GrazingSummary, name: str, default: float = float("nan")) -> float:
    value = g.params[name].value
    return default if value is None else value


def band_quantile(g: GrazingSummary) -> tuple[float, int | None]:
    """The 97.5 % quantile for the 95 % band of the eq. (3.4) fit, and its degrees of freedom.

    Student t with ``n - p`` degrees of freedom (``n`` thresholds fitted, the
    outliers left out; ``p`` varied parameters), as the profile intervals of the
    fit are; 1.96 (normal, ``None``) when the fit does not say how many points it used
    (no residuals).
    ``nan`` when ``n <= p``: an exactly determined fit has no band.
    """
    from scipy import stats

    if not g.residuals_ms2:
        return 1.96, None
    n = sum(1 for r in g.residuals_ms2 if r is not None)
    n -= len(g.outliers_hz)
    dof = n - len(g.correlation_names)
    return (float(stats.t.ppf(0.975, dof)) if dof >= 1 else float("nan")), dof


def grazing_band_ms2(freq_hz: np.ndarray, g: GrazingSummary) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (3.4) at the fitted parameters and the half-width of its 95 % band, m/s^2.

    Delta method: the covariance is ``stderr_i stderr_j corr_ij`` of the varied
    parameters (as stored by the fit), the gradient is by central differences,
    and the quantile is :func:`band_quantile` (Student t with the fit's degrees
    of freedom).

    Parameters
    ----------
    freq_hz : ndarray
        Excitation frequencies, Hz.
    g : GrazingSummary
        The grazing fit of the fit summary.

    Returns
    -------
    (ndarray, ndarray)
        The threshold and the half-width of the band, m/s^2 (NaN without a covariance).
    """
    from rattle_lab.model.linear import threshold_accel_ms2

    names = ("gap_m", "f_s_hz", "zeta", "participation")
    p0 = {n: _pval(g, n, 1.0 if n == "participation" else float("nan")) for n in names}

    def model(p: Mapping[str, float]) -> np.ndarray:
        return np.asarray(threshold_accel_ms2(freq_hz, p["gap_m"], p["f_s_hz"], abs(p["zeta"]),
                                              p["participation"]), dtype=float)

    y = model(p0)
    varied = list(g.correlation_names)
    matrix = np.array([[np.nan if c is None else c for c in row] for row in g.correlation],
                      dtype=float).reshape(len(g.correlation), -1)
    err = np.array([g.params[n].stderr or np.nan for n in varied]) if varied \
        else np.zeros(0)
    if not varied or matrix.shape != (len(varied), len(varied)) or not np.isfinite(err).all():
        return y, np.full_like(y, np.nan)
    cov = matrix * np.outer(err, err)
    jac = np.empty((len(varied), y.size))
    for i, n in enumerate(varied):
        h = 1e-6 * max(abs(p0[n]), 1e-12)
        hi, lo = dict(p0), dict(p0)
        hi[n] += h
        lo[n] -= h
        jac[i] = (model(hi) - model(lo)) / (2 * h)
    var = np.einsum("ik,ij,jk->k", jac, cov, jac)
    return y, band_quantile(g)[0] * np.sqrt(np.maximum(var, 0.0))


def student_t_ci(value: Any, stderr: Any, dof: int) -> tuple[float | None, float | None]:
    """Student-t 95 % interval ``value +/- t(0.975, dof) stderr`` (None where undefined).

    Parameters
    ----------
    value, stderr : float or None
        The estimate and its standard error.
    dof : int
        Degrees of freedom (``n - 1`` for a mean of ``n``).

    Returns
    -------
    (float or None, float or None)
        The interval; ``(None, None)`` for ``dof < 1`` or a missing or non-finite input.
    """
    from scipy import stats

    try:
        v, e = float(value), float(stderr)
    except (TypeError, ValueError):
        return None, None
    if dof < 1 or not (math.isfinite(v) and math.isfinite(e)):
        return None, None
    half = float(stats.t.ppf(0.975, dof)) * e
    return v - half, v + half


def linear_law_band(v: npt.ArrayLike, p: npt.ArrayLike, slope: float, intercept: float,
                    grid: npt.ArrayLike) -> np.ndarray | None:
    """Half-width of the 95 % band of the mean of the line ``p = slope v + intercept`` (OLS).

    ``t(0.975, n - 2) s sqrt(1/n + (x - mean v)^2 / Sxx)`` at ``grid``, with ``s`` the
    residual standard deviation of the points ``(v, p)`` about the given line.

    Returns
    -------
    ndarray or None
        The half-width at each grid point; None with fewer than 3 points or all ``v`` equal.
    """
    from scipy import stats

    v_a, p_a = np.asarray(v, dtype=float), np.asarray(p, dtype=float)
    if v_a.size <= 2:
        return None
    resid = p_a - (slope * v_a + intercept)
    s = math.sqrt(float(np.sum(resid**2)) / (v_a.size - 2))
    sxx = float(np.sum((v_a - v_a.mean()) ** 2))
    if not sxx > 0:
        return None
    x = np.asarray(grid, dtype=float)
    return np.asarray(stats.t.ppf(0.975, v_a.size - 2) * s * np.sqrt(
        1.0 / v_a.size + (x - v_a.mean()) ** 2 / sxx), dtype=float)


def threshold_hysteresis(up_ms2: npt.ArrayLike, down_ms2: npt.ArrayLike) -> np.ndarray:
    """Onset less disappearance threshold, m/s^2 (NaN where either is not measured)."""
    return np.asarray(up_ms2, dtype=float) - np.asarray(down_ms2, dtype=float)


#: A hysteresis is called negative only when it lies below zero by more than this many
#: standard uncertainties (about the two-sided 95 % level of a normal error).
SIGNIFICANCE_K = 2.0


def hysteresis_uncertainty_ms2(up_se_ms2: npt.ArrayLike, down_se_ms2: npt.ArrayLike) -> np.ndarray:
    """Standard uncertainty of ``up - down`` from the thresholds' own (independent ramps), m/s^2."""
    return np.hypot(np.asarray(up_se_ms2, dtype=float), np.asarray(down_se_ms2, dtype=float))


def negative_hysteresis(freq_hz: npt.ArrayLike, up_ms2: npt.ArrayLike, down_ms2: npt.ArrayLike,
                        up_se_ms2: npt.ArrayLike | None = None,
                        down_se_ms2: npt.ArrayLike | None = None) -> list[tuple[float, float]]:
    """``(freq_hz, onset - disappearance)`` where the disappearance lies significantly above
    the onset.

    Significant: ``onset - disappearance < -SIGNIFICANCE_K * u`` with ``u`` the hysteresis's
    standard uncertainty (:func:`hysteresis_uncertainty_ms2` of the thresholds' standard
    uncertainties, :func:`rattle_lab.detect.thresholds.threshold_uncertainty_ms2`).  A
    hysteresis within its uncertainty of zero is not flagged whatever its sign; where the
    uncertainty is not known (NaN, or not given) nothing is flagged: the sign of a difference
    alone decides nothing.

    Examples
    --------
    >>> negative_hysteresis([95.0, 96.0], [10.0, 10.0], [10.3, 10.05], [0.1, 0.1], [0.1, 0.1])
    [(95.0, -0.3...)]
    """
    h = threshold_hysteresis(up_ms2, down_ms2)
    if up_se_ms2 is None or down_se_ms2 is None:
        return []
    u = hysteresis_uncertainty_ms2(up_se_ms2, down_se_ms2)
    if u.shape != h.shape:
        return []
    return [(float(a), float(b)) for a, b, s in zip(np.asarray(freq_hz, dtype=float), h, u)
            if math.isfinite(b) and math.isfinite(s) and b < -SIGNIFICANCE_K * s]
