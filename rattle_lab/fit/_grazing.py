"""Grazing fit: the dimensional form of eq. (3.4) fitted to upward thresholds (thesis Fig. 6-2).

Model, :func:`rattle_lab.model.linear.threshold_accel_ms2`::

    A_up(f) = h omega_s^2 sqrt((1 - (f/f_s)^2)^2 + (2 zeta f/f_s)^2) / q

with the gap ``h`` (fitted in mm for conditioning), the modal frequency
``f_s``, the damping ratio ``zeta`` and the participation ``q = Q1/Q2``.
Only ``h / q`` enters: with both free, the covariance is singular and the
pair is reported as not identifiable.

Steps: (1) a robust fit (``least_squares``, ``loss="soft_l1"``) of relative
residuals ``(A_model - A)/A``; (2) points whose relative residual exceeds
``outlier_k`` robust standard deviations are rejected (and reported);
(3) an ordinary least-squares fit of the inliers gives standard errors, the
correlation matrix and profile confidence intervals (``lmfit.conf_interval``).
"""

from __future__ import annotations

import warnings

import lmfit
import numpy as np

from rattle_lab.detect import robust_sigma
from rattle_lab.exceptions import ConvergenceError, ParameterError
from rattle_lab.model.linear import threshold_accel_unchecked
from ._common import correlation_matrix
from ._estimates import GrazingParameter, GrazingSummary

#: unit of each parameter of the fit
_UNITS = {"gap_m": "m", "f_s_hz": "Hz", "zeta": "1", "participation": "1"}

_CORR_LIMIT = 0.995

#: Smallest relative scatter of measured thresholds assumed by the outlier test.
REL_SCATTER_FLOOR = 0.01


def _model_ms2(freq_hz: np.ndarray, gap_mm: float, f_s_hz: float, zeta: float,
               participation: float) -> np.ndarray:
    """lmfit's model: eq. (3.4) with the gap in mm (conditioning); the formula is the linear module's."""
    return threshold_accel_unchecked(freq_hz, 1e-3 * gap_mm, f_s_hz, zeta, participation)


def _initial(freq: np.ndarray, acc: np.ndarray, q: float) -> tuple[float, float, float]:
    k = int(np.argmin(acc))
    fs0 = float(freq[k])
    w = freq / fs0
    far = int(np.argmax(np.abs(1.0 - w**2)))
    gap0_m = acc[far] * q / ((2 * np.pi * fs0) ** 2 * abs(1.0 - w[far] ** 2))
    zeta0 = float(np.clip(acc[k] * q / (2.0 * gap0_m * (2 * np.pi * fs0) ** 2), 1e-4, 0.5))
    return 1e3 * float(gap0_m), fs0, zeta0


def fit_grazing(freq_hz: object, accel_ms2: object, *, participation: float = 1.0,
                vary_participation: bool = False, gap_m: float | None = None,
                vary_gap: bool = True, outlier_k: float = 5.0,
                conf_interval: bool = True) -> GrazingSummary:
    """Fit eq. (3.4) to appearance thresholds ``accel_ms2`` against ``freq_hz``.

    Parameters
    ----------
    freq_hz, accel_ms2 : array
        Thresholds (NaNs are dropped); at least 4 finite points.
    participation : float
        ``Q1/Q2`` (from the plate model), held fixed unless ``vary_participation``.
    gap_m : float, optional
        Starting (or, with ``vary_gap=False``, fixed) gap, m.
    outlier_k : float
        Rejection level in robust standard deviations of the relative residuals.
    conf_interval : bool
        Compute 95 % profile confidence intervals.

    Returns
    -------
    GrazingSummary
        ``gap_m`` (m), ``f_s_hz`` (Hz), ``zeta``, ``participation`` (``vary`` False when
        held) with standard errors and 2-sigma profile intervals; ``residuals_ms2``: model
        minus data at every point given (None where a point was not finite);
        ``outliers_hz``: the points rejected by the robust step; the correlation of the
        varied parameters, ``unidentifiable`` notes and the reduced chi-square.  The class
        the store keeps.

    Raises
    ------
    ParameterError
        With fewer than 4 finite points or non-positive values.
    ConvergenceError
        If the fit fails.
    """
    f = np.asarray(freq_hz, dtype=float)
    a = np.asarray(accel_ms2, dtype=float)
    if f.shape != a.shape or f.ndim != 1:
        raise ParameterError(f"`freq_hz` and `accel_ms2` must be 1-D of equal length, "
                             f"had shapes {f.shape} and {a.shape}")
    ok = np.isfinite(f) & np.isfinite(a)
    if ok.sum() < 4:
        raise ParameterError(f"the grazing fit needs >= 4 finite thresholds, had {int(ok.sum())}")
    if np.any(a[ok] <= 0) or np.any(f[ok] <= 0):
        raise ParameterError("`freq_hz` and `accel_ms2` must be > 0")
    if not participation > 0:
        raise ParameterError(f"`participation` must be > 0, was {participation}")
    fo, ao = f[ok], a[ok]
    gap0_mm, fs0, zeta0 = _initial(fo, ao, participation)
    if gap_m is not None:
        gap0_mm = 1e3 * gap_m
    model = lmfit.Model(_model_ms2, independent_vars=["freq_hz"])
    pars = model.make_params(gap_mm=dict(value=gap0_mm, min=0.0, vary=vary_gap),
                             f_s_hz=dict(value=fs0, min=0.0),
                             zeta=dict(value=zeta0, min=0.0, max=1.0),
                             participation=dict(value=participation, min=0.0,
                                                vary=vary_participation))
    weights = 1.0 / ao
    # an unidentifiable pair (gap and participation both varied) leaves a singular
    # covariance whose square roots lmfit takes anyway: said below as a note, not as
    # numpy's "invalid value in sqrt" warnings
    with np.errstate(invalid="ignore"):
        robust = model.fit(ao, pars, freq_hz=fo, weights=weights, method="least_squares",
                           fit_kws={"loss": "soft_l1", "f_scale": 0.05})
    rel = (robust.eval(freq_hz=fo) - ao) / ao
    # Measured thresholds do not repeat to better than about 1 % (envelope noise, one
    # forcing period's level change, the ramp lag that eq. 3.4 leaves out); with few points
    # the robust scale of near-exact residuals can be far smaller, and would then make a
    # 2 % deviation an "outlier".  The scale is floored at that 1 %.
    scale = max(robust_sigma(rel), REL_SCATTER_FLOOR)
    inlier = np.abs(rel - np.median(rel)) <= outlier_k * scale
    if inlier.sum() < 4:
        raise ConvergenceError(f"the grazing fit kept only {int(inlier.sum())} inliers")
    with np.errstate(invalid="ignore"):  # as above
        final = model.fit(ao[inlier], robust.params, freq_hz=fo[inlier],
                          weights=weights[inlier], method="leastsq")
    if not final.success:
        raise ConvergenceError(f"the grazing fit did not converge: {final.message}")
    varied = tuple(final.var_names)
    shown = [n.replace("gap_mm", "gap_m") for n in varied]
    corr = correlation_matrix(final, list(varied))
    notes: list[str] = []
    if vary_gap and vary_participation:
        notes.append("gap_m and participation: only gap/participation enters eq. (3.4); "
                     "the data identify the ratio, not each")
    if not final.errorbars:
        notes.append("singular covariance: " + ", ".join(varied) + " are not all identifiable")
    for i in range(len(varied)):
        for j in range(i + 1, len(varied)):
            if np.isfinite(corr[i, j]) and abs(corr[i, j]) > _CORR_LIMIT:
                notes.append(f"{shown[i]} and {shown[j]} are correlated at {corr[i, j]:+.4f}")
    ci: dict[str, tuple[float, float]] = {}
    if conf_interval and final.errorbars and not notes:
        try:
            with warnings.catch_warnings():  # lmfit warns when a profile is flat; NaN-ed below
                warnings.simplefilter("ignore", UserWarning)
                table = lmfit.conf_interval(final, final, sigmas=[2])  # type: ignore[arg-type]
            for name, rows in table.items():
                vals = [v for _, v in rows]
                lo, hi = float(min(vals)), float(max(vals))
                ci[name] = (lo if np.isfinite(lo) else np.nan, hi if np.isfinite(hi) else np.nan)
        except (lmfit.minimizer.MinimizerException, ValueError, RuntimeError) as exc:
            notes.append(f"profile confidence intervals failed: {exc}")
    params = {}
    for src, dst, scale_to in (("gap_mm", "gap_m", 1e-3), ("f_s_hz", "f_s_hz", 1.0),
                               ("zeta", "zeta", 1.0), ("participation", "participation", 1.0)):
        p = final.params[src]
        lo, hi = ci.get(src, (np.nan, np.nan))
        std = p.stderr if (p.stderr is not None and p.vary) else np.nan
        params[dst] = GrazingParameter(scale_to * float(p.value), scale_to * float(std),
                                       _UNITS[dst], scale_to * lo, scale_to * hi,
                                       vary=bool(p.vary))
    resid = np.full(f.shape, np.nan)
    resid[ok] = final.eval(params=final.params, freq_hz=fo) - ao
    outliers = f[np.flatnonzero(ok)[~inlier]]
    return GrazingSummary(**params, unidentifiable=tuple(notes),
                          outliers_hz=tuple(outliers.tolist()),
                          residuals_ms2=tuple(resid.tolist()), correlation_names=tuple(shown),
                          correlation=tuple(map(tuple, corr.tolist())),
                          redchi=float(final.redchi))
