"""Damping from the onset thresholds of finite-rate ramps (the ramp model of the grazing fit).

The grazing fit (eq. 3.4, :func:`~rattle_lab.fit.fit_grazing`) treats every onset as
quasi-static.  On a ramp the plate's amplitude lags the level by about the ramp's
change over one modal time constant ``1 / (zeta omega_s)``; near resonance, where the
onset is set by ``zeta``, the lag is read as extra damping (7 % on the default scene's
3 s ramps).  Here ``zeta`` is refitted to the same onsets with every ramp replayed through
the exact simulator (:func:`rattle_lab.fit._ramp_model.model_threshold`), the gap,
``f_s`` and the participation held at the grazing fit's values (they are set by the
thresholds away from resonance, where the lag is small).  The onset is the first impact
of a linear motion, so ``e`` hardly matters (only through the confirming impacts).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import optimize

from rattle_lab.exceptions import ConvergenceError, ParameterError
from rattle_lab.detect.thresholds import Threshold
from ._common import check_positive
from ._estimates import RampDamping
from ._ramp_model import RampSpec, model_threshold, threshold_sigma_ms2


def fit_zeta_ramp(thresholds: Sequence[Threshold], *, gap_m: float, f_s_hz: float, zeta0: float,
                  participation: float = 1.0, e: float = 0.6,
                  zeta_bounds_rel: tuple[float, float] = (0.5, 1.5), n_phases: int = 4,
                  n_confirm: int = 3, max_gap_cycles: float = 100.0,
                  edge_cycles: float = 2.0, level_hold_periods: int = 1) -> RampDamping:
    """Fit ``zeta`` to the onset thresholds of upward ramps, each replayed through the simulator.

    Parameters
    ----------
    thresholds : sequence of Threshold
        Measured thresholds with their ramps; the finite upward ones are used.
    gap_m, f_s_hz, participation : float
        Held fixed (m, Hz, ``Q1/Q2``), e.g. from :func:`fit_grazing`.
    zeta0 : float
        Centre of the search, e.g. the grazing fit's ``zeta``.
    e : float
        Restitution used for the replays' confirming impacts.
    zeta_bounds_rel : (float, float)
        Search interval as multiples of ``zeta0``.
    n_phases, n_confirm, max_gap_cycles, edge_cycles, level_hold_periods
        As in :func:`rattle_lab.fit._ramp_model.model_threshold`.

    Returns
    -------
    RampDamping
        ``zeta`` (nondimensional) with ``stderr`` linearised, ``sqrt(s2 / sum((g /
        sigma)^2))`` with ``g = dA/dzeta`` by central differences at ``+-2 %``, and
        ``ci_low``, ``ci_high`` = ``value -+ 2 stderr``; ``n`` thresholds and their
        ``residuals_ms2`` (model minus data, m/s^2); ``notes``: warnings (an estimate at a
        bound of the search).  Working fields (not stored): ``run_ids``, ``freq_hz``,
        ``accel_ms2``, ``sigma_ms2``, ``model_ms2`` per threshold used, ``chi2`` at the fit
        and ``chi2_scale`` ``s2 = max(1, chi2 / (n - 1))`` (1 with one point).

    Notes
    -----
    Minimises ``chi2(zeta) = sum(((A_model - A) / sigma)^2)`` (``sigma``:
    :func:`~rattle_lab.fit._ramp_model.threshold_sigma_ms2`) with bounded Brent; a replay
    that sees no onset counts at the ramp's end level.  The model is smooth in ``zeta`` to
    well below ``sigma`` (the replays average out the one-cycle staircase).

    Raises
    ------
    ParameterError
        With no finite upward threshold, one without its measured ramp, or a parameter
        out of range.
    ConvergenceError
        If no replay sees an onset at the estimate.

    Examples
    --------
    >>> from rattle_lab.detect.thresholds import Threshold
    >>> up = Threshold("up_096", 96.0, "up", 6.92, 1.68, ramp_start_ms2=3.0, ramp_end_ms2=10.0,
    ...                ramp_duration_s=3.0, ramp_rms_ms2=0.001)
    >>> fit = fit_zeta_ramp([up], gap_m=1.3e-3, f_s_hz=96.0, zeta0=0.0091, participation=1.2442)
    >>> bool(abs(fit.value / 0.0085 - 1) < 0.01)
    True
    """
    check_positive(gap_m=gap_m, f_s_hz=f_s_hz, zeta0=zeta0, participation=participation)
    lo_rel, hi_rel = zeta_bounds_rel
    if not 0 < lo_rel < 1 < hi_rel:
        raise ParameterError(f"`zeta_bounds_rel` must satisfy 0 < low < 1 < high, was "
                             f"{zeta_bounds_rel}")
    points = [t for t in thresholds if isinstance(t, Threshold) and t.direction == "up"
              and np.isfinite(t.accel_ms2) and t.accel_ms2 > 0 and np.isfinite(t.freq_hz)]
    if not points:
        raise ParameterError("no finite upward threshold to fit zeta to")
    ramps = [RampSpec.from_threshold(t) for t in points]
    acc = np.array([t.accel_ms2 for t in points])
    sigma = np.array([threshold_sigma_ms2(r, t.ramp_rms_ms2, level_hold_periods)
                      for r, t in zip(ramps, points)])
    common: dict[str, Any] = dict(e=e, gap_m=gap_m, f_s_hz=f_s_hz, participation=participation,
                  n_phases=n_phases, n_confirm=n_confirm, max_gap_cycles=max_gap_cycles,
                  edge_cycles=edge_cycles, level_hold_periods=level_hold_periods)

    def model(z: float) -> np.ndarray:
        out = np.array([model_threshold(r, zeta=z, anchor_ms2=a, **common).mean_ms2
                        for r, a in zip(ramps, acc)])
        return np.where(np.isfinite(out), out, [r.level_end_ms2 for r in ramps])

    def chi2(z: float) -> float:
        return float(np.sum(((model(z) - acc) / sigma) ** 2))

    bounds = (lo_rel * zeta0, hi_rel * zeta0)
    res = optimize.minimize_scalar(chi2, bounds=bounds, method="bounded",
                                   options={"xatol": 1e-4 * zeta0})
    z = float(res.x)
    notes = []
    if min(z - bounds[0], bounds[1] - z) < 1e-3 * zeta0:
        notes.append(f"zeta at a bound of its search {bounds}: widen `zeta_bounds_rel`")
    raw = np.array([model_threshold(r, zeta=z, anchor_ms2=a, **common).mean_ms2
                    for r, a in zip(ramps, acc)])
    if not np.isfinite(raw).any():
        raise ConvergenceError(f"no replay sees an onset at zeta = {z:.6g}")
    best = model(z)
    c2 = float(np.sum(((best - acc) / sigma) ** 2))
    n = acc.size
    s2 = max(1.0, c2 / (n - 1)) if n > 1 else 1.0
    dz = 0.02 * z
    g = (model(z + dz) - model(z - dz)) / (2 * dz)
    info = float(np.sum((g / sigma) ** 2))
    stderr = float(np.sqrt(s2 / info)) if info > 0 else float("nan")
    return RampDamping(z, stderr, "1", z - 2 * stderr, z + 2 * stderr, notes=tuple(notes),
                       method=METHOD, n=len(points), residuals_ms2=tuple((best - acc).tolist()),
                       run_ids=tuple(t.run_id for t in points),
                       freq_hz=np.array([t.freq_hz for t in points]), accel_ms2=acc,
                       sigma_ms2=sigma, model_ms2=best, chi2=c2, chi2_scale=s2)


#: :attr:`RampDamping.method` of :func:`fit_zeta_ramp`
METHOD = "ramp replay of the upward thresholds"
