"""Channel timing and the vibrometer's measurand, identified from the record (issue 28).

Every impact is a sharp event on the plate accelerometer (its contact pulse) and a step on
the vibrometer.  For any linear filter ``h`` the centroid of its impulse response,
``int t h(t) dt / int h(t) dt``, is its group delay at zero frequency (the first moment is
``-d phase / d omega`` at 0).  The centroid of a filtered step's derivative is therefore the
impact time plus the filter's low-frequency delay, whatever the filter (Butterworth,
Bessel, FIR, a pure fractional delay), and the forced motion (~100 Hz against a decoder's
kHz band) is delayed by exactly that.  So the difference between the velocity step's
centroid and the contact pulse's centroid, impact by impact, measures the vibrometer's
delay relative to the accelerometer: the median over a run's impacts is good to a few
thousandths of a sample.  :func:`channel_delay` estimates it; the velocity fits are then
evaluated at the impact time plus it (:func:`rattle_lab.detect.detect_impacts`).

The same steps give the filter's step response (the normalised step around each impact,
pooled): :func:`step_settling` measures how long it rings, and the velocity fits stay
clear of that.

The measurand: between two impacts a vibrometer relative to the striker integrates to the
plate's displacement relative to the striker, which is the gap at every impact; an absolute
one integrates to that plus the base's displacement, which differs from impact to impact
where the impacts fall at different phases of the base motion.  :func:`measurand_share`
regresses the integrated velocity at the impacts on the base displacement there (with a
constant and the sensor offset's drift): the coefficient is 0 for a relative vibrometer and
1 for an absolute one, with its standard error from the residuals.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._pairing import base_motion_at

#: A declared delay is contradicted where the measured residual exceeds both this many
#: standard errors and :data:`DELAY_CHECK_FLOOR_SAMPLES`.
DELAY_CHECK_SIGMAS = 4.0
#: Least residual delay, samples, named a contradiction: the centroid estimator truncates a
#: slow or ringing decoder's step to its window and was off by up to 0.56 sample on the
#: independent generator's chains (8th-order Butterworth at 3 kHz, 25.6 kHz sampling), so
#: only a whole sample is beyond doubt.
DELAY_CHECK_FLOOR_SAMPLES = 1.0
#: Fewest impacts with both centroids for a delay estimate.
MIN_DELAY_IMPACTS = 5


@dataclass(frozen=True)
class DelayEstimate:
    """The vibrometer's delay relative to the accelerometer, samples.

    Attributes
    ----------
    value : float
        Median over the impacts of ``t_velocity - t_accelerometer``, samples (NaN with fewer
        than :data:`MIN_DELAY_IMPACTS`).
    stderr : float
        ``1.2533 * 1.4826 MAD / sqrt(n)``, samples.
    n : int
        Impacts used.
    resolved : bool
        False where the per-impact delays spread by :data:`UNRESOLVED_SPREAD` or more (steps
        whose timing the sampling limits: the estimate is only known to the sample, and
        ``stderr`` includes that, ``1/sqrt(12)`` sample).
    """

    value: float
    stderr: float
    n: int
    resolved: bool = True


#: Per-impact delays whose 10-90 % range reaches this many samples mark steps whose timing
#: the sampling limits (an unfiltered jump is seen at the next sample whatever its phase, a
#: contact pulse shorter than a sample at the nearest: per-impact errors up to half a
#: sample each, clustered where the impacts repeat a few sampling phases, so that the median
#: is off by up to half a sample while the spread about it looks small).  A decoder's
#: filtered step measures to a few hundredths of a sample per impact.
UNRESOLVED_SPREAD = 0.8


def channel_delay(t_velocity: object, t_accel: object) -> DelayEstimate:
    """Delay of the velocity steps after the contact pulses (fractional samples).

    The centroid of a step that a decoder or an anti-aliasing filter spread over samples
    is exact at any sampling phase; an unfiltered jump sampled as it comes is seen at the
    next sample whatever its phase.  Where the per-impact delays spread by
    :data:`UNRESOLVED_SPREAD` or more the estimate is marked unresolved and its standard
    error includes the sample's ``1/sqrt(12)``.

    Examples
    --------
    >>> import numpy as np
    >>> ta = np.arange(10) * 100.0
    >>> d = channel_delay(ta + 0.46 + 0.001 * np.cos(np.arange(10)), ta)
    >>> round(d.value, 2), d.n
    (0.46, 10)
    """
    ta = np.asarray(t_accel, dtype=float)
    d = np.asarray(t_velocity, dtype=float) - ta
    ok = np.isfinite(d)
    d, ta = d[ok], ta[ok]
    if d.size < MIN_DELAY_IMPACTS:
        return DelayEstimate(float("nan"), float("nan"), int(d.size))
    med = float(np.median(d))
    sigma = 1.4826 * float(np.median(np.abs(d - med)))
    se = 1.2533 * sigma / math.sqrt(d.size)
    lo, hi = np.percentile(d, [10.0, 90.0])
    if hi - lo >= UNRESOLVED_SPREAD:
        return DelayEstimate(med, math.hypot(se, 1 / math.sqrt(12.0)), int(d.size), False)
    return DelayEstimate(med, se, int(d.size))


#: Largest lag, s, looked for between the velocity's and the accelerometer's events.
MAX_COARSE_LAG_S = 2e-3


def coarse_lag(cf_velocity: np.ndarray, cf_accel: np.ndarray, max_lag: int, floor: float) -> int:
    """Whole samples by which the velocity's events follow the accelerometer's.

    The cross-correlation of the two characteristic functions (in noise units, each with
    ``floor`` subtracted and clipped at 0 so that only events count), largest over
    ``|lag| <= max_lag``: a low-pass decoder can delay the velocity by many samples (an
    8th-order 2 kHz Butterworth by ~0.4 ms), more than the trigger's span, and the two
    channels' events must be brought together before they are paired impact by impact.

    Examples
    --------
    >>> import numpy as np
    >>> a = np.zeros(1000); a[[100, 400, 700]] = 50.0
    >>> coarse_lag(np.roll(a, 13), a, 40, 4.0)
    13
    """
    x = np.clip(np.asarray(cf_accel, dtype=float) - floor, 0.0, None)
    y = np.clip(np.asarray(cf_velocity, dtype=float) - floor, 0.0, None)
    n = min(x.size, y.size)
    if n == 0 or max_lag <= 0:
        return 0
    from ._jump_kernels import lag_correlation   # here: importing detect stays light

    # summed directly over the accelerometer's event samples (the clipped function is zero
    # elsewhere): the same sums as the FFT's, without its rounding of the zeros
    max_lag = min(int(max_lag), n - 1)
    vals = lag_correlation(np.ascontiguousarray(x[:n]), np.ascontiguousarray(y[:n]), max_lag)
    lags = np.r_[np.arange(0, max_lag + 1), np.arange(-max_lag, 0)]
    if not np.max(vals) > 0:
        return 0
    return int(lags[int(np.argmax(vals))])


def shift_earlier(x: np.ndarray, lag: int) -> np.ndarray:
    """``x`` moved ``lag`` samples earlier (``y[k] = x[k + lag]``), the ends held."""
    if lag == 0:
        return x
    if lag > 0:
        return np.concatenate([x[lag:], np.full(min(lag, x.size), x[-1])])
    return np.concatenate([np.full(min(-lag, x.size), x[0]), x[:lag]])


#: A step has settled where the pooled normalised step error stays within this fraction of
#: the jump (or within 4 of its own noise units, whichever is larger).
SETTLED_WITHIN = 0.005
#: Most extra guard, s, the settling adds on each side of a jump (a step that has not
#: settled by then is taken for the plate's higher modes ringing in the vibrometer, and
#: no guard is added).
MAX_EXTRA_GUARD_S = 1e-3


def step_error(v: np.ndarray, t_eval: np.ndarray, fits: np.ndarray,
               limits: list[tuple[int, int]], span: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pooled step response's error around the impacts: ``(tau, median, noise)``.

    For each impact the normalised step ``(v - p) / (q - p)`` (``p``, ``q``: the fits
    before and after, rows ``fits[i, 0]`` and ``fits[i, 1]`` of
    :func:`rattle_lab.detect._local_fits._fit_rows`) less the ideal step at
    ``t_eval``, over ``|k - t_eval| <= span`` within the impact's ``limits``; pooled in
    whole-sample bins of ``tau = k - t_eval``, the median and its noise
    (``1.2533 * 1.4826 MAD / sqrt(n)``) per bin (bins with fewer than 5 impacts: NaN).
    This is the chain's step response as the record shows it (a decoder's overshoot and
    ringing) less the ideal step.
    """
    from ._jump_kernels import readonly, step_rows

    taus = np.arange(-span, span + 1)
    out, has = step_rows(readonly(v),
                         np.ascontiguousarray(t_eval, dtype=float), np.ascontiguousarray(fits),
                         np.asarray(limits, dtype=np.int64).reshape(-1, 2), int(span))
    rows = out[has]
    nan = np.full(taus.size, np.nan)
    if len(rows) < MIN_DELAY_IMPACTS:
        return taus, nan, nan.copy()
    m = np.asarray(rows)
    n = np.sum(np.isfinite(m), axis=0)
    with np.errstate(all="ignore"):
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            med = np.nanmedian(m, axis=0)
            mad = np.nanmedian(np.abs(m - med), axis=0)
    noise = 1.2533 * 1.4826 * mad / np.sqrt(np.maximum(n, 1))
    med[n < MIN_DELAY_IMPACTS] = np.nan
    return taus, med, noise


def settled_span(taus: np.ndarray, med: np.ndarray, noise: np.ndarray) -> tuple[float, float]:
    """``(first, last)``: the earliest and latest ``tau`` where the step has not settled.

    Unsettled: ``|median| > max(SETTLED_WITHIN, 4 noise)``.  ``(0, 0)`` where every bin
    has settled (or none is known).
    """
    tol = np.maximum(SETTLED_WITHIN, 4 * noise)
    bad = np.isfinite(med) & (np.abs(med) > tol)
    if not bad.any():
        return 0.0, 0.0
    return float(min(taus[bad].min(), 0)), float(max(taus[bad].max(), 0))


#: An undeclared delay is applied where the measurement exceeds this many standard errors
#: (a record without a decoder measures 0.005 +- 0.012 samples on the rig's default scene;
#: every decoder of issue 28's ranges delays by more than 0.3 sample, measured to 0.01-0.05).
DELAY_APPLIED_SIGMAS = 4.0


def delay_significant(estimate: DelayEstimate) -> bool:
    """Whether a measured delay is beyond :data:`DELAY_APPLIED_SIGMAS` standard errors.

    Examples
    --------
    >>> delay_significant(DelayEstimate(0.005, 0.012, 43)), delay_significant(DelayEstimate(0.71, 0.02, 43))
    (False, True)
    """
    return bool(np.isfinite(estimate.value) and np.isfinite(estimate.stderr)
                and abs(estimate.value) > DELAY_APPLIED_SIGMAS * estimate.stderr)


def delay_contradicted(residual: DelayEstimate) -> bool:
    """Whether a residual delay (after the declared one) is beyond its uncertainty."""
    return bool(np.isfinite(residual.value)
                and abs(residual.value) > DELAY_CHECK_SIGMAS * residual.stderr
                and abs(residual.value) > DELAY_CHECK_FLOOR_SAMPLES)


def integral_at(v: np.ndarray, k: np.ndarray) -> np.ndarray:
    """``int_0^k v`` (sample units, trapezoid, linear between samples) at fractional ``k``."""
    vv = np.asarray(v, dtype=float)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (vv[1:] + vv[:-1]))])
    i0 = np.clip(np.floor(k).astype(int), 0, vv.size - 2)
    frac = np.asarray(k, dtype=float) - i0
    return cum[i0] + frac * vv[i0] + 0.5 * frac**2 * (vv[i0 + 1] - vv[i0])


#: The measurand is decided where the base-displacement coefficient's 95 % interval
#: (``+-1.96 stderr``) lies within this distance of 0 (relative) or 1 (absolute) and
#: excludes the other.
MEASURAND_DECIDED_WITHIN = 0.5

#: ... or where its 95 % interval holds one reading and the other lies more than this many
#: standard errors away (a wide interval that still excludes the other reading by far: light
#: ringing left 1.20 +- 0.23 on an absolute vibrometer of the independent generator, 5.2
#: standard errors from relative and undecided by the first rule).
MEASURAND_EXCLUDED_SIGMAS = 4.0


@dataclass(frozen=True)
class MeasurandShare:
    """How much of the base's motion the vibrometer sees (0: relative, 1: absolute).

    Attributes
    ----------
    value, stderr : float
        The coefficient of the base displacement in the integrated velocity at the impacts
        and its standard error (NaN where not estimable).
    n : int
        Impacts used.
    spread_m : float
        Standard deviation of the base displacement over those impacts, m (what the
        regression sees: impacts at one phase of the base motion give it nothing).
    verdict : str
        ``"relative"``, ``"absolute"`` or ``"undetermined"``.
    """

    value: float
    stderr: float
    n: int
    spread_m: float
    verdict: str


def _integrated_tails(t: np.ndarray, jump: np.ndarray, p: complex) -> np.ndarray:
    """``sum_{j<i} jump_j (exp(p (t_i - t_j)) - 1) / p`` for each ``i`` (``t`` sorted): the
    tails ``S_i = sum_{j<i} jump_j exp(p (t_i - t_j))`` by ``S_i = exp(p (t_i - t_{i-1}))
    (S_{i-1} + jump_{i-1})``, which never forms a growing exponential."""
    tails = np.zeros(t.size, dtype=complex)
    for i in range(1, t.size):
        tails[i] = np.exp(p * (t[i] - t[i - 1])) * (tails[i - 1] + jump[i - 1])
    before = np.concatenate([[0.0], np.cumsum(jump[:-1])])
    return (tails - before) / p


def measurand_share(v_m_s: np.ndarray, fs_hz: float, t0_s: float, t_imp_s: np.ndarray,
                    base_ms2: np.ndarray, fs_base_hz: float, t0_base_s: float,
                    freq_hz: float, jumps_m_s: np.ndarray | None = None,
                    ring_modes: tuple[tuple[float, float], ...] = ()) -> MeasurandShare:
    """Regress the vibrometer's integral at the impacts on the base displacement there.

    ``D_i = int v dt`` from the first impact to impact ``i`` (``t_imp_s`` in the velocity's
    own time, i.e. with its delay) is modelled as ``c0 + c1 (t_i - t_1) + beta x_b(t_i)``:
    the gap (constant), the sensor's DC offset integrated (drift) and the base displacement
    ``x_b`` that an absolute vibrometer sees; with ``jumps_m_s`` also ``gamma jump_i`` (the
    part of the chain-spread step the integral ends in) and ``delta sum_{j<i} jump_j
    (phi_j - 1/2)`` (the trapezoid's error across each sharp step it crossed, ``phi_j`` the
    step's sample phase), and, for each of ``ring_modes`` (the plate's higher modes, ``(f_hz,
    s_1_s)``, carried on over the flights) that rings on past a forcing period, its tails
    integrated up to each impact, ``sum_{j<i} jump_j (exp(p (t_i - t_j)) - 1) / p`` with ``p =
    -s + i 2 pi f`` (real and imaginary parts: its amplitude and phase are the
    regression's).  Without them, light ringing put the coefficient 3 standard errors off
    on the independent generator's steady dwell (0.57 +- 0.18 for 0, 1.56 +- 0.18 for 1; with
    them 0.10 and 1.09 +- 0.28).  ``beta`` with its ordinary least-squares standard
    error (residual scatter: noise, hum and ringing integrated); decided as relative or
    absolute where its 95 % interval is within :data:`MEASURAND_DECIDED_WITHIN` of one and
    excludes the other, or holds one and lies :data:`MEASURAND_EXCLUDED_SIGMAS` standard
    errors from the other.

    Examples
    --------
    >>> import numpy as np
    >>> fs, f = 10000.0, 20.0
    >>> t = np.arange(40000) / fs
    >>> a_b = 5.0 * np.sin(2 * np.pi * f * t)
    >>> x_b = -a_b / (2 * np.pi * f) ** 2
    >>> t_imp = np.sort(np.random.default_rng(1).uniform(0.2, 3.8, 60))
    >>> v_abs = np.gradient(x_b, 1 / fs)            # an absolute vibrometer, plate at rest
    >>> measurand_share(v_abs + 1e-3, fs, 0.0, t_imp, a_b, fs, 0.0, f).verdict
    'absolute'
    >>> measurand_share(0 * v_abs + 1e-3, fs, 0.0, t_imp, a_b, fs, 0.0, f).verdict
    'relative'
    """
    t = np.asarray(t_imp_s, dtype=float)
    jump = np.zeros(t.size) if jumps_m_s is None else np.asarray(jumps_m_s, dtype=float)
    ok = np.isfinite(t) & np.isfinite(jump)
    order = np.argsort(t[ok])
    t, jump = t[ok][order], jump[ok][order]
    k = (t - t0_s) * fs_hz
    ok = (k >= 0) & (k <= np.size(v_m_s) - 1)
    t, k, jump = t[ok], k[ok], jump[ok]
    nan = float("nan")
    if t.size < 8:
        return MeasurandShare(nan, nan, int(t.size), nan, "undetermined")
    xb, _ = base_motion_at(base_ms2, fs_base_hz, t0_base_s, freq_hz, t)
    good = np.isfinite(xb)
    t, k, xb, jump = t[good], k[good], xb[good], jump[good]
    if t.size < 10:
        return MeasurandShare(nan, nan, int(t.size), nan, "undetermined")
    # from the first impact on; each step that the integral crosses adds its sampling
    # error (the trapezoid across a jump at fraction phi of a sample: jump (phi - 1/2) / fs),
    # a regressor of its own, as is the part of the last step the integral ends in
    d = integral_at(v_m_s, k) / fs_hz
    d = d - d[0]
    phi = k - np.floor(k)
    cross = np.concatenate([[0.0], np.cumsum((jump * (phi - 0.5))[:-1])]) / fs_hz
    cols = [np.ones_like(t), t - t[0], xb]
    if jumps_m_s is not None:
        cols += [jump / fs_hz, cross]
        for f_m, s_m in ring_modes:
            if not s_m < freq_hz:
                # gone within a forcing period (decayed by more than e): what it leaves in
                # the integral is its whole integral, the same share of every jump, which
                # the drift and the jumps' own terms take up
                continue
            # the mode's ringing after each earlier impact, integrated up to this one:
            # sum_{j<i} jump_j (exp(p (t_i - t_j)) - 1) / p, p = -s + i w (its amplitude and
            # phase, the same at every impact, are the regression's), by recursion over the
            # impacts (linear in their number: thousands in a long run)
            c_m = _integrated_tails(t, jump, complex(-s_m, 2.0 * math.pi * f_m))
            cols += [c_m.real, c_m.imag]
    design = np.column_stack(cols)
    coef, *_ = np.linalg.lstsq(design, d, rcond=None)
    resid = d - design @ coef
    dof = d.size - design.shape[1]
    s2 = float(resid @ resid) / dof
    try:
        cov = s2 * np.linalg.inv(design.T @ design)
        se = float(math.sqrt(max(cov[2, 2], 0.0)))
    except np.linalg.LinAlgError:
        se = nan
    beta = float(coef[2])
    return MeasurandShare(beta, se, int(t.size), float(np.std(xb)), measurand_verdict(beta, se))


def measurand_verdict(beta: float, se: float) -> str:
    """``"relative"``, ``"absolute"`` or ``"undetermined"`` from the base-displacement
    coefficient ``beta`` and its standard error (see :data:`MEASURAND_DECIDED_WITHIN` and
    :data:`MEASURAND_EXCLUDED_SIGMAS`).

    Examples
    --------
    >>> measurand_verdict(1.20, 0.231), measurand_verdict(0.05, 0.1)
    ('absolute', 'relative')
    >>> measurand_verdict(4.57, 2.02), measurand_verdict(0.57, 0.18)
    ('undetermined', 'undetermined')
    """
    if not (math.isfinite(beta) and math.isfinite(se) and se > 0):
        return "undetermined"
    half = 1.96 * se
    far = MEASURAND_EXCLUDED_SIGMAS * se
    for value, other, name in ((0.0, 1.0, "relative"), (1.0, 0.0, "absolute")):
        near = abs(beta - value)
        if (near + half <= MEASURAND_DECIDED_WITHIN and abs(beta - other) - half > 0) or (
                near <= half and abs(beta - other) > far):
            return name
    return "undetermined"


__all__ = ["DelayEstimate", "MeasurandShare", "base_motion_at", "channel_delay", "coarse_lag",
           "settled_span", "shift_earlier", "step_error",
           "delay_contradicted", "delay_significant", "DELAY_APPLIED_SIGMAS", "integral_at", "measurand_share"]
