"""Coefficient of restitution: from per-impact velocity ratios, and from downward thresholds.

Above resonance the stable 1/1 orbit is lost at its saddle-node (eq. 3.11), below the
grazing level (eq. 3.4): that hysteresis is why the disappearance threshold of a
downward ramp carries ``e`` and the onset does not.  Two models of that threshold:

``method="ramp"`` (default)
    The measured ramp replayed through the exact simulator at candidate ``e``
    (:func:`rattle_lab.fit._ramp_model.model_threshold`), the threshold read off as
    :mod:`rattle_lab.detect.thresholds` reads it off the data.  Valid at any ramp rate.
``method="quasi-static"``
    The fold itself, dimensionally ``A_down(f) = h omega_s^2 F_sn(f / f_s, zeta, e) / q``
    with ``F_sn`` from :func:`rattle_lab.model.analysis.saddle_node_forcing`.  Valid only when
    the ramp passes the fold slowly: the plate lags a ramp by about ``|dA/dt|`` times its
    time constant ``1 / (zeta omega_s)``, and a fold is left with the delay of a slow
    passage, whose level lag grows like ``|dA/dt|^(2/3)``.  For the thesis plate
    (``1 / (zeta omega_s) = 0.2 s``) at 98 Hz and ``e = 0.3`` the lag is 0.04 m/s^2 at
    0.05 m/s^2/s (a 30 s pass over 1.5 m/s^2) and 0.54 m/s^2 on the default scene's
    3 s ramps (8 m/s^2/s), more than the whole change of ``A_down`` between ``e = 0.3``
    and ``e = 0.9`` (0.48 m/s^2): with seconds-long ramps it fits ``e`` near 1.

Only thresholds above the upper half-power frequency ``f_s (1 + zeta)`` are used:
there the 1/1 orbit folds well below grazing; at and below resonance impacting stops
by irregular, intermittent grazing whose level scatters by several cycles of the ramp.
In both methods ``h, f_s, q`` (and ``zeta``) are held; the downward thresholds near
resonance depend on ``zeta`` more than on ``e`` (7 % in zeta moves them by 0.5 m/s^2 on
the thesis plate), so give the ramp-model damping of :func:`fit_zeta_ramp` and its
standard error: it is propagated into the uncertainty of ``e``.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import lmfit
import numpy as np
from scipy import stats

from rattle_lab.detect import RINGING_RESIDUAL_RATIO
from rattle_lab.exceptions import ConvergenceError, ParameterError
from rattle_lab.detect.thresholds import Threshold
from ._common import check_positive
from ._estimates import DownRestitution, RatioRestitution
from ._params import METHODS
from ._profile import _search_coarse, profile_interval, profile_parabola
from ._ramp_model import RampSpec, model_threshold, threshold_sigma_ms2


@dataclass(frozen=True)
class RestitutionStats:
    """``e`` from per-impact ratios ``-v_out/v_in``.

    Attributes
    ----------
    mean, std, median : float
        Of the finite ratios in (0, 1.5); nondimensional.
    n : int
        Number of ratios used.
    stderr : float
        Standard error of ``mean``: ``std / sqrt(n)``, or, with the runs the ratios came
        from (``groups``), the larger of that and the run-clustered standard error with the
        few-runs t factor (:func:`restitution_from_ratios`).
    n_groups : int
        Number of runs with a ratio (0 when no groups were given).
    """

    mean: float
    std: float
    median: float
    n: int
    stderr: float
    n_groups: int = 0


def clustered_stderr(values: np.ndarray, groups: np.ndarray) -> float:
    """Run-clustered standard error of ``mean(values)`` (Liang-Zeger sandwich, CR1).

    ``sqrt(G / (G - 1) sum_g (sum_{i in g} (x_i - mean))^2) / n`` over the ``G`` groups:
    errors shared by all the values of a group (one run's frequency, level, impact speed
    and ringing) count once per group, not once per value.  With equal group sizes it is
    the standard error of the group means, ``std(means, ddof=1) / sqrt(G)``.  NaN with
    fewer than 2 groups.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.array([1.0, 1.0, 3.0, 3.0])
    >>> float(clustered_stderr(x, np.array([0, 0, 1, 1])))     # means 1, 3: std sqrt(2) / sqrt(2)
    1.0
    """
    x = np.asarray(values, dtype=float)
    g = np.asarray(groups)
    labels, inv = np.unique(g, return_inverse=True)
    n_g = labels.size
    if n_g < 2 or x.size == 0:
        return float("nan")
    sums = np.bincount(inv, weights=x - x.mean(), minlength=n_g)
    return float(np.sqrt(n_g / (n_g - 1) * np.sum(sums**2)) / x.size)


def restitution_from_ratios(e_values: object, groups: object = None) -> RestitutionStats:
    """Statistics of per-impact restitution ratios (non-finite or implausible ones dropped).

    Parameters
    ----------
    e_values : array
        Per-impact ratios ``-v_out / v_in``.
    groups : array, optional
        The run (any hashable label) of each ratio, same length as ``e_values``.  The
        ratios of one run share an error that is not noise: the velocity fits either side
        of a jump extrapolate the forced motion and the higher modes' ringing across the
        contact, and what they leave out depends on the run's frequency, level and impact
        speed, so it repeats from impact to impact (on the rig's default scene the run means
        scatter by +-0.5 % while a run's own standard error is 0.2 %).  ``std / sqrt(n)``
        then treats thousands of impacts as independent and its interval is far too narrow;
        with ``groups`` the standard error is the larger of that and the run-clustered one
        (:func:`clustered_stderr`), which measures the run-to-run scatter of that error,
        times ``t_{0.975, G-1} / 1.96`` (``G`` runs: with few runs the clustered error is
        itself uncertain, and ``mean +- 1.96 stderr`` is then the Student-t 95 % interval;
        x1.12 for 12 runs).  A bias common to every run is not in it.

    Examples
    --------
    >>> s = restitution_from_ratios([0.7, 0.8, 0.9, float("nan")])
    >>> round(s.mean, 12), s.n
    (0.8, 3)
    """
    e = np.asarray(e_values, dtype=float).ravel()
    if groups is not None:
        g = np.asarray(groups).ravel()
        if g.shape != e.shape:
            raise ParameterError(f"`groups` must have one label per ratio: {g.size} labels "
                                 f"for {e.size} ratios")
    keep = np.isfinite(e) & (e > 0) & (e < 1.5)
    e = e[keep]
    if e.size == 0:
        return RestitutionStats(np.nan, np.nan, np.nan, 0, np.nan)
    std = float(np.std(e, ddof=1)) if e.size > 1 else np.nan
    se = std / np.sqrt(e.size) if e.size > 1 else np.nan
    n_groups = 0
    if groups is not None:
        gk = g[keep]
        n_groups = int(np.unique(gk).size)
        # few runs: the sandwich is itself uncertain (G - 1 degrees of freedom); users take
        # mean +- 1.96 stderr, so the t quantile is folded in: stderr = cl t_{G-1} / 1.96
        cl = clustered_stderr(e, gk)
        if np.isfinite(cl):
            cl *= float(stats.t.ppf(0.975, n_groups - 1)) / float(stats.norm.ppf(0.975))
            se = max(se, cl) if np.isfinite(se) else cl
    return RestitutionStats(float(np.mean(e)), std, float(np.median(e)), int(e.size), se,
                            n_groups)


@dataclass(frozen=True)
class RingingShare:
    """The higher modes' share of the measured velocity jumps, pooled over runs.

    Attributes
    ----------
    value : float
        Median of the runs' shares (NaN without any).
    stderr : float
        ``1.2533 sigma / sqrt(n)``, the median's standard error, with ``sigma`` the runs'
        robust spread (1.4826 MAD: one run whose model failed does not widen it; NaN with
        fewer than 2 runs).
    n_runs : int
        Runs with a share.
    """

    value: float
    stderr: float
    n_runs: int


def pooled_ringing_share(shares: Iterable[float]) -> RingingShare:
    """Pool the runs' ringing shares (:attr:`~rattle_lab.detect.ImpactLog.ringing_share`).

    The share is a property of the plate and of where the contact and the beam are: the
    impulse that reverses the fundamental excites each higher mode in fixed proportion,
    the same in every run.  One run's flight model can miss a mode or trade it against
    the free response (on the realistic lab scene 2 of 10 runs came out at 0.18 and
    -0.02 around 0.09), so the median of the runs is taken.

    Examples
    --------
    >>> r = pooled_ringing_share([0.09, 0.1, float("nan"), 0.5, 0.095])
    >>> round(r.value, 4), r.n_runs
    (0.0975, 4)
    """
    s = np.asarray([x for x in shares if x is not None], dtype=float)
    s = s[np.isfinite(s)]
    if s.size == 0:
        return RingingShare(float("nan"), float("nan"), 0)
    sigma = 1.4826 * float(np.median(np.abs(s - np.median(s))))
    se = 1.2533 * sigma / np.sqrt(s.size) if s.size > 1 else float("nan")
    return RingingShare(float(np.median(s)), se, int(s.size))


def ringing_corrected_ratios(v_in: object, v_out: object, share: float) -> np.ndarray:
    """Per-impact ``e`` with the higher modes' ``share`` of each velocity jump taken off.

    The velocity fits either side of an impact read the jump of every mode the impact
    excites; the fundamental's is ``(1 - share) (v_out - v_in)``, so its rebound is
    ``v_in + (1 - share) (v_out - v_in)`` and ``e = -(v_in + (1 - share) (v_out - v_in)) / v_in``.

    Examples
    --------
    >>> round(float(ringing_corrected_ratios([-0.1], [0.076], 0.0)[0]), 6)
    0.76
    >>> round(float(ringing_corrected_ratios([-0.1], [0.076], 1 / 11)[0]), 6)   # 1 in 11 of the jump
    0.6
    """
    vi = np.asarray(v_in, dtype=float)
    vo = np.asarray(v_out, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -(vi + (1.0 - share) * (vo - vi)) / vi


#: Data-quality flag: the vibrometer rings after the impacts and no run measured the share.
FLAG_RINGING_UNCORRECTED = "e_ratio_ringing_uncorrected"
#: Data-quality flag: the lightly damped ringing modes were found from one run only.
FLAG_RING_MODES_ONE_RUN = "e_ratio_ring_modes_one_run"


def ratios_of_runs(logs: Sequence[Any]) -> RatioRestitution:
    """e from the velocity ratios of several runs' impact logs, as ``rattle-lab fit`` reports it.

    ``logs``: :class:`~rattle_lab.detect.ImpactLog` (or anything with ``v_in_m_s``,
    ``v_out_m_s``, ``e``, ``ringing_share`` and, optionally, ``ringing_ratio``), one per
    run, velocities relative to the striker.  The runs' ringing shares are pooled
    (:func:`pooled_ringing_share`) and taken off every ratio
    (:func:`ringing_corrected_ratios`).  Without any share, the logs' own ratios; a run
    whose local fits showed ringing (``ringing_ratio`` at or above the detector's
    threshold) is then counted in ``ringing_runs_unmeasured``: its ratios read the higher
    modes too, and the fit says so; unless its velocities came from the flight model with
    the campaign's ringing modes (``ring_modes``, tails carried on).

    Returns
    -------
    RatioRestitution
        ``value``, ``std``, ``median``, ``n`` of the per-impact ratios (the share taken
        off), ``n_runs`` with a ratio; ``stderr``: the run-clustered one
        (:func:`restitution_from_ratios`) combined in quadrature with the pooled share's
        error moving every ratio alike (``|d e / d share| = |v_out - v_in| / |v_in|``,
        median over impacts); ``ringing_share``, ``ringing_share_stderr``,
        ``ringing_runs``: the pooled share (``ringing_runs == 0``: none, nothing taken
        off); working field ``ringing_runs_unmeasured``.  No notes: the store's summary
        (:func:`~rattle_lab.fit.summarise_fits`) adds them, and the vibrometer's
        systematics to ``stderr``.

    Examples
    --------
    >>> from types import SimpleNamespace as Log
    >>> vi = np.array([-0.1, -0.2])
    >>> runs = [Log(v_in_m_s=vi, v_out_m_s=-0.76 * vi, e=np.array([0.76, 0.76]),
    ...             ringing_share=s) for s in (1 / 11, float("nan"), 1 / 11)]
    >>> r = ratios_of_runs(runs)
    >>> round(r.value, 6), r.ringing_runs
    (0.6, 2)
    """
    ring = pooled_ringing_share(log.ringing_share for log in logs)
    if ring.n_runs:
        e_logs = [ringing_corrected_ratios(log.v_in_m_s, log.v_out_m_s, ring.value)
                  for log in logs]
    else:
        e_logs = [np.asarray(log.e, dtype=float) for log in logs]
    e_all = np.concatenate(e_logs or [np.zeros(0)])
    # a run's impacts share its frequency, level and ringing: the stderr is clustered by run
    groups = np.concatenate([np.full(e.size, i) for i, e in enumerate(e_logs)] or [np.zeros(0)])
    st = restitution_from_ratios(e_all, groups=groups)
    se = st.stderr
    if ring.n_runs and np.isfinite(ring.stderr) and st.n:
        vi = np.concatenate([np.asarray(log.v_in_m_s, dtype=float) for log in logs])
        vo = np.concatenate([np.asarray(log.v_out_m_s, dtype=float) for log in logs])
        with np.errstate(divide="ignore", invalid="ignore"):
            d = np.abs((vo - vi) / vi)[(e_all > 0) & (e_all < 1.5)]   # the ratios kept
        slope = float(np.median(d)) if d.size else float("nan")
        se = float(np.hypot(se, slope * ring.stderr))
    unmeasured = 0 if ring.n_runs else sum(
        1 for log in logs if getattr(log, "ringing_ratio", np.nan) >= RINGING_RESIDUAL_RATIO
        and not getattr(log, "ring_modes", ()))
    nan = float("nan")
    return RatioRestitution(st.mean, se, "1", std=st.std, median=st.median, n=st.n,
                            n_runs=st.n_groups,
                            ringing_share=ring.value if ring.n_runs else nan,
                            ringing_share_stderr=ring.stderr if ring.n_runs else nan,
                            ringing_runs=ring.n_runs, ringing_runs_unmeasured=unmeasured)


def saddle_node_threshold_ms2(freq_hz: np.ndarray, e: float, gap_m: float, f_s_hz: float,
                              zeta: float, participation: float) -> np.ndarray:
    """Quasi-static disappearance threshold: the 1/1 saddle-node (eq. 3.11), dimensional, m/s^2.

    ``A = h omega_s^2 F_sn(f / f_s, zeta, e) / q`` (eq. 2.27, 2.31 for the scaling).

    Examples
    --------
    >>> import numpy as np
    >>> a = saddle_node_threshold_ms2(np.array([100.0]), 0.6, 1.3e-3, 96.0, 0.0085, 1.2442)
    >>> bool(np.isclose(a[0], 7.636, atol=1e-3))
    True
    """
    with np.errstate(invalid="ignore"):
        from rattle_lab.model.analysis import saddle_node_forcing  # lazy: start-up

        F_sn, _ = saddle_node_forcing(1, np.asarray(freq_hz, dtype=float) / f_s_hz, zeta, e)
    return gap_m * (2 * np.pi * f_s_hz) ** 2 * F_sn / participation


Method = Literal["ramp", "quasi-static"]


def _down_points(thresholds: Sequence[Threshold], f_s_hz: float, zeta: float
                 ) -> list[Threshold]:
    """Finite downward thresholds above the upper half-power frequency ``f_s (1 + zeta)``."""
    f_min = f_s_hz * (1.0 + zeta)
    use = [t for t in thresholds if isinstance(t, Threshold) and t.direction == "down"
           and np.isfinite(t.freq_hz) and np.isfinite(t.accel_ms2) and t.accel_ms2 > 0
           and t.freq_hz > f_min]
    if not use:
        raise ParameterError(f"no finite downward threshold above the half-power frequency "
                             f"f_s (1 + zeta) = {f_min:.6g} Hz to fit e to")
    return use


#: Evaluate the whole coarse grid of the ramp fit's profile (the reference the coarse search
#: of :func:`_search_coarse` is tested against); False: only the part the fit needs.
_FULL_GRID = False


def _quasi_static(points: list[Threshold], *, gap_m: float, f_s_hz: float, zeta: float,
                  participation: float, e0: float) -> DownRestitution:
    fu = np.array([t.freq_hz for t in points])
    au = np.array([t.accel_ms2 for t in points])
    model = lmfit.Model(saddle_node_threshold_ms2, independent_vars=["freq_hz"])
    pars = model.make_params(e=dict(value=e0, min=1e-3, max=0.999),
                             gap_m=dict(value=gap_m, vary=False), f_s_hz=dict(value=f_s_hz, vary=False),
                             zeta=dict(value=zeta, vary=False),
                             participation=dict(value=participation, vary=False))
    res = model.fit(au, pars, freq_hz=fu, weights=1.0 / au, nan_policy="omit")
    if not res.success or not np.isfinite(res.params["e"].value):
        raise ConvergenceError(f"the restitution fit did not converge: {res.message}")
    p = res.params["e"]
    std = float(p.stderr) if p.stderr is not None else np.nan
    notes = []
    tau_s = 1.0 / (zeta * 2 * np.pi * f_s_hz)
    for t in points:
        if np.isfinite(t.ramp_duration_s):
            lag = abs(t.ramp_rate_ms2_s) * tau_s
            if lag > 0.01 * t.accel_ms2:
                notes.append(f"{t.run_id}: the ramp moves {lag:.3g} m/s^2 per modal time constant "
                             f"({100 * lag / t.accel_ms2:.2g} % of the threshold): the quasi-static "
                             f"fold lags; use method='ramp'")
    model_ms2 = res.eval(freq_hz=fu)
    return DownRestitution(float(p.value), std, "1", float(p.value) - 2 * std,
                           float(p.value) + 2 * std, notes=tuple(notes), method="quasi-static",
                           n=len(points), residuals_ms2=tuple((model_ms2 - au).tolist()),
                           run_ids=tuple(t.run_id for t in points), zeta_used=float(zeta),
                           stderr_from_zeta=0.0, freq_hz=fu, accel_ms2=au,
                           sigma_ms2=np.full(fu.size, np.nan), model_ms2=model_ms2)


def fit_restitution_down(thresholds: Sequence[Threshold], *, gap_m: float, f_s_hz: float,
                         zeta: float, participation: float = 1.0, method: Method = "ramp",
                         zeta_stderr: float = 0.0, e_bounds: tuple[float, float] = (0.05, 0.95),
                         e_step: float = 0.025, n_phases: int = 4, n_confirm: int = 3,
                         max_gap_cycles: float = 100.0, edge_cycles: float = 2.0,
                         level_hold_periods: int = 1, e0: float = 0.7) -> DownRestitution:
    """Fit ``e`` to the disappearance thresholds of downward ramps above resonance.

    Parameters
    ----------
    thresholds : sequence of Threshold
        Measured thresholds (:func:`rattle_lab.detect.thresholds.ramp_threshold`); the finite
        downward ones above ``f_s (1 + zeta)`` are used, others ignored.  The ramp method
        needs their measured ramp (``ramp_start_ms2`` ...).
    gap_m, f_s_hz, zeta, participation : float
        Modal model (m, Hz, nondimensional, ``Q1/Q2``), e.g. from :func:`fit_grazing` and
        :func:`fit_zeta_ramp`; held fixed.
    method : {"ramp", "quasi-static"}
        Threshold model (module docstring).
    zeta_stderr : float
        Standard error of ``zeta``, propagated into that of ``e`` (ramp method).
    e_bounds, e_step : float
        Grid of the profile ``chi2(e)`` (ramp method), nondimensional.
    n_phases, n_confirm, max_gap_cycles, edge_cycles, level_hold_periods
        Replays per threshold, the threshold criterion used on the data and how the drive
        steps its level (:func:`rattle_lab.fit._ramp_model.model_threshold`).
    e0 : float
        Start value of the quasi-static fit.

    Returns
    -------
    DownRestitution
        ``e`` with its standard error and 2-sigma interval (see the class), ``method``,
        ``run_ids`` of the thresholds used (in the order of the working arrays), ``n``,
        ``zeta_used``, ``stderr_from_zeta``, ``residuals_ms2`` (model minus data) and
        ``notes`` (what the data could not determine, and warnings such as the ramp lag
        for quasi-static); working fields (not stored): ``freq_hz``, ``accel_ms2``,
        ``sigma_ms2``, ``model_ms2`` per threshold, the profile ``e_grid``, ``chi2`` (ramp
        method: the part of the coarse grid the fit needs -- the points left out lie
        above the 2-sigma cut -- and the refinement; empty otherwise) and ``chi2_scale``
        ``s2 = max(1, min(chi2) / (n - 1))`` (the Birge ratio that widens the interval).

    Notes
    -----
    Ramp method: for every ``e`` on the grid each threshold is replayed and
    ``chi2(e) = sum(((A_model(e) - A) / sigma)^2)`` formed with the measurement's own
    standard deviation ``sigma`` (quantisation over one cycle's level change, envelope
    scatter).  A grid rather than a local optimiser: ``A_model(e)`` is a fine staircase
    (one impact per cycle), can be flat (no information), and the profile shows it.  The
    grid is refined (11 more points) across the 2-sigma region when it holds fewer than 7
    grid points.  The estimate and its standard error come from the parabola through the
    profile points within ``4 s2`` of its minimum (:func:`profile_parabola`: the curvature
    smooths the staircase, where the width of a ``+1`` cut would follow its notches); the 2-sigma
    interval is where ``chi2 <= min + 4 s2``, as for a one-parameter likelihood ratio with
    the variance scaled by ``s2 = max(1, min chi2 / (n - 1))``.  The part from ``zeta`` is
    ``|de/dzeta| zeta_stderr`` with ``de/dzeta = -sum(g h / sigma^2) / sum(g^2 / sigma^2)``,
    ``g = dA/de`` (slope of the model over the grid near the estimate) and ``h = dA/dzeta``
    (central difference at ``zeta +- max(zeta_stderr, 0.01 zeta)``).

    The coarse grid is not evaluated everywhere (:func:`_search_coarse`): probes, a walk
    down to the minimum, and the block around it grown until, at each end, ``chi2`` is above
    the 2-sigma cut and every residual has one sign and moves away from the data.  Since the
    model threshold is monotone in ``e``, the points left out lie above the cut, and the
    estimate, its standard error and interval are those of the whole grid, bit for bit
    (tested), at about half of the coarse grid or fewer (16 -> 8 coarse points on the
    thesis scene's ramps with ``e_step = 0.05``; ``benchmarks/speed_goals.py``).

    Raises
    ------
    ParameterError
        With no usable threshold, a threshold without its measured ramp (ramp method),
        an unknown method or a parameter out of range.
    ConvergenceError
        If the quasi-static fit fails, or no ``e`` on the grid reproduces every threshold.

    Examples
    --------
    >>> from rattle_lab.detect.thresholds import Threshold
    >>> down = Threshold("down_100", 100.0, "down", 6.90, 5.5, ramp_start_ms2=50.0,
    ...                  ramp_end_ms2=3.0, ramp_duration_s=6.0, ramp_rms_ms2=0.005)
    >>> fit = fit_restitution_down([down], gap_m=1.3e-3, f_s_hz=96.0, zeta=0.0085,
    ...                            participation=1.2442, e_bounds=(0.4, 0.8), e_step=0.05)
    >>> bool(abs(fit.value - 0.6) < 0.05), fit.method
    (True, 'ramp')
    """
    if method not in METHODS:
        raise ParameterError(f"`method` must be one of {METHODS}, was {method!r}")
    check_positive(gap_m=gap_m, f_s_hz=f_s_hz, zeta=zeta, participation=participation)
    if zeta_stderr is None or not (np.isfinite(zeta_stderr) and zeta_stderr >= 0):
        raise ParameterError(f"`zeta_stderr` must be finite and >= 0, was {zeta_stderr}")
    points = _down_points(thresholds, f_s_hz, zeta)
    if method == "quasi-static":
        return _quasi_static(points, gap_m=gap_m, f_s_hz=f_s_hz, zeta=zeta,
                             participation=participation, e0=e0)
    lo_e, hi_e = e_bounds
    if not (0.0 <= lo_e < hi_e <= 1.0):
        raise ParameterError(f"`e_bounds` must satisfy 0 <= low < high <= 1, was {e_bounds}")
    if not (np.isfinite(e_step) and 0 < e_step <= hi_e - lo_e):
        raise ParameterError(f"`e_step` must be in (0, {hi_e - lo_e:g}], was {e_step}")
    ramps = [RampSpec.from_threshold(t) for t in points]
    acc = np.array([t.accel_ms2 for t in points])
    sigma = np.array([threshold_sigma_ms2(r, t.ramp_rms_ms2, level_hold_periods)
                      for r, t in zip(ramps, points)])
    common: dict[str, Any] = dict(gap_m=gap_m, f_s_hz=f_s_hz, participation=participation, n_phases=n_phases,
                  n_confirm=n_confirm, max_gap_cycles=max_gap_cycles, edge_cycles=edge_cycles,
                  level_hold_periods=level_hold_periods)

    def model(e: float, z: float = zeta) -> np.ndarray:
        return np.array([model_threshold(r, e=e, zeta=z, anchor_ms2=a, **common).mean_ms2
                         for r, a in zip(ramps, acc)])

    n = acc.size
    known: dict[float, np.ndarray] = {}       # e -> model thresholds (n,), m/s^2

    def evaluate(es: Iterable[float]) -> None:
        for e in es:
            if float(e) not in known:
                known[float(e)] = model(float(e))

    def profile() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The grid evaluated so far (ascending), its model table (n_grid, n) and chi2."""
        es = np.array(sorted(known))
        tab = np.array([known[e] for e in es]).reshape(es.size, n)
        with np.errstate(invalid="ignore"):
            c2 = np.sum(((tab - acc) / sigma) ** 2, axis=1)
        return es, tab, np.where(np.isfinite(c2), c2, np.inf)

    coarse = np.linspace(lo_e, hi_e, round((hi_e - lo_e) / e_step) + 1)
    if _FULL_GRID:
        evaluate(coarse)
    else:
        def at(k: int) -> np.ndarray:
            evaluate([coarse[k]])
            return known[float(coarse[k])]

        _search_coarse(coarse.size, at, acc, sigma)
    grid, table, chi2 = profile()
    if not np.isfinite(chi2).any():
        raise ConvergenceError("no e in the grid reproduces every downward threshold "
                               "(the replays saw no disappearance)")
    for refine in (True, False):
        chi2_min = float(np.min(chi2))
        s2 = max(1.0, chi2_min / (n - 1)) if n > 1 else 1.0
        lo2, hi2 = profile_interval(grid, chi2, chi2_min + 4 * s2)
        inside = int(np.sum(chi2 <= chi2_min + 4 * s2))
        if not (refine and np.isfinite(lo2) and np.isfinite(hi2) and inside < 7):
            break
        # a sharp minimum: 11 more points across the 2-sigma region and a step beyond it
        # (a point of the coarse grid among them is that grid point, evaluated if it was not)
        fine = np.linspace(max(lo_e, lo2 - e_step), min(hi_e, hi2 + e_step), 11)
        on_coarse = np.isin(fine, coarse)
        evaluate(fine[~on_coarse])
        evaluate(coarse[np.isin(coarse, fine)])
        grid, table, chi2 = profile()
    value, curvature = profile_parabola(grid, chi2, chi2_min + 4 * s2)
    if np.isfinite(value):
        stat = float(np.sqrt(s2 / curvature))
    else:
        value = float(grid[int(np.argmin(chi2))])
        lo1, hi1 = profile_interval(grid, chi2, chi2_min + s2)
        stat = (hi1 - lo1) / 2.0
    notes: list[str] = []
    if not (np.isfinite(lo2) and np.isfinite(hi2)):
        notes.append(f"e not identified: the profile chi2(e) stays within its 2-sigma level up "
                     f"to the end of e_bounds = {e_bounds} (thresholds insensitive to e)")
    from_zeta = 0.0
    if zeta_stderr > 0 and np.isfinite(stat):
        # the slope g over every point of the coarse grid near the estimate, as on the
        # whole grid (the coarse search may have left some of them out)
        evaluate(coarse[np.abs(coarse - value) <= max(0.1, 2 * stat)])
        grid, table, chi2 = profile()
        near = np.abs(grid - value) <= max(0.1, 2 * stat)
        ok_rows = near & np.all(np.isfinite(table), axis=1)
        if ok_rows.sum() >= 2:
            g = np.array([np.polyfit(grid[ok_rows], table[ok_rows, i], 1)[0] for i in range(n)])
            dz = max(zeta_stderr, 0.01 * zeta)
            h = (model(value, zeta + dz) - model(value, zeta - dz)) / (2 * dz)
            w = 1.0 / sigma**2
            denom = float(np.sum(w * g * g))
            if denom > 0 and np.all(np.isfinite(h)):
                from_zeta = abs(float(np.sum(w * g * h)) / denom) * zeta_stderr
    stderr = float(np.hypot(stat, from_zeta))
    ci_low = value - float(np.hypot(value - lo2, 2 * from_zeta))
    ci_high = value + float(np.hypot(hi2 - value, 2 * from_zeta))
    best = model(value)
    return DownRestitution(value, stderr, "1", ci_low, ci_high, notes=tuple(notes),
                           method="ramp", n=len(points), residuals_ms2=tuple((best - acc).tolist()),
                           run_ids=tuple(t.run_id for t in points), zeta_used=float(zeta),
                           stderr_from_zeta=from_zeta,
                           freq_hz=np.array([t.freq_hz for t in points]), accel_ms2=acc,
                           sigma_ms2=sigma, model_ms2=best, e_grid=grid, chi2=chi2,
                           chi2_scale=s2)
