"""Content of the model pages: bifurcation sets and F sweeps of the SDF model at the fit.

The measured thresholds are converted to ``(omega, F)`` by
:mod:`rattle_lab.model.scaling` (eq. 2.28, 2.31), the regions are computed by
:func:`rattle_lab.model.analysis.bifurcation_sets` (and smoothed for drawing by
:func:`rattle_lab.plot.smooth_region`), the model thresholds by
:func:`rattle_lab.model.analysis.sweep_thresholds`; the report's page only draws.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.model import analysis
from rattle_lab.model.scaling import (F_from_accel, accel_ms2_from_F, angular_rad_s_from_freq,
                                      omega_from_freq)
from rattle_lab.plot import smooth_region
from rattle_lab.report import Field, ModelContent, SweepComparison
from ._content import Missing, fits_of, not_fitted, pval, require_results
from ._gather import ReportData
from ._summary import threshold_arrays


def _F_of(accel_ms2: np.ndarray, q: float, w_s: float, gap_m: float) -> np.ndarray:
    """``F`` of each finite acceleration (eq. 2.31); NaN stays NaN."""
    out = np.full(accel_ms2.shape, np.nan)
    ok = np.isfinite(accel_ms2)
    out[ok] = F_from_accel(accel_ms2[ok], q, w_s, gap_m)
    return out


def _omega_of(freq_hz: np.ndarray, f_s_hz: float) -> np.ndarray:
    """``omega = f / f_s`` (eq. 2.28) of each finite frequency; NaN elsewhere."""
    out = np.full(freq_hz.shape, np.nan)
    ok = np.isfinite(freq_hz)
    out[ok] = omega_from_freq(freq_hz[ok], f_s_hz)
    return out


def _accel_of(F: np.ndarray, q: float, w_s: float, gap_m: float) -> np.ndarray:
    out = np.full(F.shape, np.nan)
    ok = np.isfinite(F)
    out[ok] = accel_ms2_from_F(F[ok], q, w_s, gap_m)
    return out


def _field(sets: Any, mask: np.ndarray) -> Field | None:
    return smooth_region(sets.omega, sets.F, mask) if mask.any() else None


def model_content(data: ReportData, *, n_sweep: int = 40, max_freqs: int = 6,
                  quiet: bool = True) -> ModelContent:
    """Bifurcation sets and F sweeps of the SDF model at the fitted parameters (coarse grids).

    Page 1: the 1/1 and 1/2 existence and stability regions (``bifurcation_sets``)
    in the (omega, F) plane with the measured thresholds converted by eq. (2.28),
    (2.31).  Page 2: at each measured frequency (up to ``max_freqs``), a slow F
    sweep up and back down (``sweep_thresholds``, ``n_sweep`` amplitudes, 60
    forcing periods each): the model's onset and disappearance against the measured
    ones, each with the sweep step as its resolution.  ``quiet``: no progress bar.
    """
    require_results(data)
    fits = fits_of(data)
    g = fits.grazing
    if g is None:
        raise Missing("needs the grazing fit (gap, f_s, zeta): "
                      + not_fitted(data, "grazing", "absent"))
    e_fit = fits.restitution_ratio
    if e_fit is None or e_fit.value is None:
        raise Missing("needs a fitted coefficient of restitution e")
    # zeta from replaying the ramps when the fit made it (free of the ramp lag), else eq. (3.4)'s
    ramp = fits.damping_ramp
    ramp_zeta = ramp.value if ramp is not None and ramp.value else None
    zeta = ramp_zeta if ramp_zeta is not None else abs(pval(g, "zeta"))
    zeta_src = "ramp model" if ramp_zeta is not None else "eq. (3.4) fit"
    e = e_fit.value
    if not 0.0 < e <= 1.0:  # the bifurcation sets need e > 0 (a plastic impact has no orbit)
        raise Missing(f"fitted e = {e:.4g} is outside (0, 1]")
    if not (math.isfinite(zeta) and zeta > 0 and math.isfinite(pval(g, "gap_m"))):
        raise Missing(f"fitted zeta {zeta} or gap unusable for the model")
    f_s, gap, q = pval(g, "f_s_hz"), pval(g, "gap_m"), pval(g, "participation", 1.0)
    f, up, down = threshold_arrays(data)
    try:  # eq. (2.28), (2.31); a fit the scaling rejects (f_s or gap <= 0, Q1 = 0) is unusable
        w_s = float(angular_rad_s_from_freq(f_s))
        w_up, F_up = _omega_of(f, f_s), _F_of(up, q, w_s, gap)
        w_dn, F_dn = _omega_of(f, f_s), _F_of(down, q, w_s, gap)
        accel_ms2_from_F(1.0, q, w_s, gap)
    except ParameterError as exc:
        raise Missing(f"fitted parameters unusable for the model: {exc}") from None
    finite_w = w_up[np.isfinite(w_up)]
    w_lo = float(finite_w.min() - 0.05) if finite_w.size else 0.8
    w_hi = float(max(1.2, finite_w.max() + 0.05)) if finite_w.size else 1.2
    F_all = np.concatenate([F_up[np.isfinite(F_up)], F_dn[np.isfinite(F_dn)]])
    F_hi = float(max(1.6 * F_all.max(), 4 * zeta)) if F_all.size else 0.2
    sets = analysis.bifurcation_sets((1, 2), omega_range=(max(w_lo, 0.05), w_hi),
                                     F_range=(0.0, F_hi), zeta=zeta, e=e, n_omega=61, n_F=41,
                                     n_v=31)
    exists = tuple(_field(sets, sets.exists[k]) for k in range(len(sets.ns)))
    stable = tuple(_field(sets, sets.stable[k]) for k in range(len(sets.ns)))
    both = _field(sets, sets.exists[0] & sets.exists[1]) if len(sets.ns) >= 2 else None
    sweeps = None
    sel = np.flatnonzero(np.isfinite(w_up) | np.isfinite(w_dn))[:max_freqs]
    if sel.size:
        from rattle_lab._progress import progress

        grid = np.linspace(F_hi / n_sweep, F_hi, n_sweep)
        on_F, off_F = np.full(sel.size, np.nan), np.full(sel.size, np.nan)
        step = float(grid[1] - grid[0]) if grid.size > 1 else float(grid[0])
        for i, j in enumerate(progress(sel, total=sel.size, desc="model sweeps", quiet=quiet,
                                       unit="freq")):
            res = analysis.sweep_thresholds(float(w_up[j]), grid, zeta=zeta, e=e)
            on_F[i], off_F[i], step = res.onset_F, res.disappearance_F, res.step_F
        sweeps = SweepComparison(
            f[sel], _accel_of(on_F, q, w_s, gap), _accel_of(off_F, q, w_s, gap),
            float(accel_ms2_from_F(step / 2, q, w_s, gap)),
            float(accel_ms2_from_F(F_hi, q, w_s, gap)), n_sweep, f, up, down)
    return ModelContent(sets, exists, stable, both, w_up, F_up, w_dn, F_dn, zeta, zeta_src, e,
                        sweeps)

