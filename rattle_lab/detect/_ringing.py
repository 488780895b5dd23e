"""The test for ringing: the local fits' residual after the impacts against before them,
which decides where ``velocity_model = "auto"`` runs the flight model."""

from __future__ import annotations

import numpy as np

from ._local_fits import _fit_windows, _LocalFit


#: ``velocity_model = "auto"`` runs the flight model where the local fits' median residual
#: after the impacts is at least this many times that before them (the plate's higher
#: modes ring after each impact; noise, hum and the forced motion are alike on both sides).
RINGING_RESIDUAL_RATIO = 1.2
#: The plate's higher modes ring in the vibrometer where the local fits' residual before the
#: impacts exceeds this share of the median jump (:func:`_residual_level`; measured on the
#: independent generator: 2e-4 to 6e-4 without ringing, 5e-3 to 0.05 with 2 % damping; heavily
#: damped modes die within a flight and are seen by the ratio instead).
QUIET_LEVEL = 2e-3
#: Fewest flight-model impacts for a run's ringing share.
MIN_SHARE_IMPACTS = 8
#: The residual ratio's windows are this many times the velocity fits' (a window as short
#: as the fits' absorbs a few milliseconds of ringing into its envelope).
RESIDUAL_WINDOW_FACTOR = 2
#: Impacts sampled for the residual ratio.
_RESIDUAL_SAMPLE = 40


def _ringing_residual_ratio(v: np.ndarray, spans: list[tuple[int, int, int, int]],
                            keep: np.ndarray, n_fit: int, n_guard: int, degree: int,
                            omega: float | None) -> float:
    """Median over (at most :data:`_RESIDUAL_SAMPLE`) impacts of the RMS residual of the
    local fit after the impact over that before it (NaN with fewer than 8 impacts)."""
    idx = np.flatnonzero(keep)
    if idx.size < 8:
        return float("nan")
    idx = idx[np.unique(np.linspace(0, idx.size - 1, min(idx.size, _RESIDUAL_SAMPLE))
                        .round().astype(int))]
    ratios = []
    n_fit = RESIDUAL_WINDOW_FACTOR * n_fit
    for i in idx:
        j_lo, j_hi, lo_lim, hi_lim = spans[i]
        pre_lo, pre_hi, post_lo, post_hi = _fit_windows(j_lo, j_hi, lo_lim, hi_lim, n_fit,
                                                        n_guard)
        rms = []
        for lo, hi in ((pre_lo, pre_hi), (post_lo, post_hi)):
            if hi - lo + 1 < n_fit:
                break
            k = np.arange(lo, hi + 1.0)
            fit = _LocalFit(k, v[lo:hi + 1], degree, omega)
            rms.append(float(np.sqrt(np.mean((v[lo:hi + 1] - fit(k)) ** 2))))
        if len(rms) == 2 and rms[0] > 0:
            ratios.append(rms[1] / rms[0])
    return float(np.median(ratios)) if len(ratios) >= 8 else float("nan")


def _residual_level(v: np.ndarray, spans: list[tuple[int, int, int, int]], keep: np.ndarray,
                    jumps: np.ndarray, n_fit: int, n_guard: int, degree: int,
                    omega: float | None) -> float:
    """Median over (at most :data:`_RESIDUAL_SAMPLE`) impacts of the RMS residual of the
    local fit before the impact (the windows of :func:`_ringing_residual_ratio`), over the
    median velocity jump (NaN with fewer than 8 impacts).  Noise alone leaves ~1e-3; the
    plate's higher modes ringing in the vibrometer, even where their tails fill every
    flight alike (a steady dwell, which the ratio cannot tell), leave a few per cent."""
    idx = np.flatnonzero(keep & np.isfinite(jumps))
    if idx.size < 8:
        return float("nan")
    scale = float(np.median(np.abs(jumps[idx])))
    idx = idx[np.unique(np.linspace(0, idx.size - 1, min(idx.size, _RESIDUAL_SAMPLE))
                        .round().astype(int))]
    n_fit = RESIDUAL_WINDOW_FACTOR * n_fit
    rms = []
    for i in idx:
        j_lo, j_hi, lo_lim, hi_lim = spans[i]
        lo, hi, _, _ = _fit_windows(j_lo, j_hi, lo_lim, hi_lim, n_fit, n_guard)
        if hi - lo + 1 < n_fit:
            continue
        k = np.arange(lo, hi + 1.0)
        fit = _LocalFit(k, v[lo:hi + 1], degree, omega)
        rms.append(float(np.sqrt(np.mean((v[lo:hi + 1] - fit(k)) ** 2))))
    return float(np.median(rms)) / scale if len(rms) >= 8 and scale > 0 else float("nan")
