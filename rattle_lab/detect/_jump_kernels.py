"""Compiled loops over a run's impacts: the local fits either side of every impact in one pass
(:func:`jump_fits_batch`), the same arithmetic as :func:`rattle_lab.detect._local_fits._jump_fits`
called impact by impact, the fits' values at given instants (:func:`fits_at`), and the
sound peaks after each impact (:func:`sound_windows`, for :func:`~rattle_lab.detect.sound_peaks`).

A fit is stored as one row: ``[k0, scale, degree, periodic, w, coef...]`` (``k0`` NaN: no
fit, a side without samples); the coefficients are :func:`local_lstsq`'s.
Sums run in index order, where numpy's pairwise sums of the Python path may differ in the
last bits.  A window holding a non-finite sample is left to the Python path (status 1).
Division follows numpy (a zero divisor gives inf or NaN, as in the Python path, not an
exception).  numba compiles these on first use and caches them on disk.
"""

from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def local_design(k: np.ndarray, k0: float, scale: float, degree: int, w: float,
                 periodic: bool) -> np.ndarray:  # pragma: no cover - compiled
    """The design matrix of :class:`rattle_lab.detect._local_fits._LocalFit` at samples ``k``:
    ``[u^degree .. u^0]`` (polynomial), or ``[1, u^j cos(w tau), u^j sin(w tau)]_j``
    (``periodic``), ``tau = k - k0``, ``u = tau / scale``."""
    n = k.size
    if not periodic:
        out = np.empty((n, degree + 1))
        for i in range(n):
            u = (k[i] - k0) / scale
            x = 1.0
            for j in range(degree, -1, -1):
                out[i, j] = x
                x *= u
        return out
    out = np.empty((n, 1 + 2 * (degree + 1)))
    for i in range(n):
        tau = k[i] - k0
        u = tau / scale
        c, s_ = math.cos(w * tau), math.sin(w * tau)
        out[i, 0] = 1.0
        x = 1.0
        for j in range(degree + 1):
            out[i, 1 + 2 * j] = x * c
            out[i, 2 + 2 * j] = x * s_
            x *= u
    return out


@numba.njit(cache=True, nogil=True)
def local_lstsq(k: np.ndarray, v: np.ndarray, k0: float, scale: float, degree: int, w: float,
                periodic: bool) -> np.ndarray:  # pragma: no cover - compiled
    """Least-squares coefficients of :func:`local_design` for ``v`` (LAPACK ``gelsd``, as
    :func:`numpy.linalg.lstsq`)."""
    a = local_design(k, k0, scale, degree, w, periodic)
    rcond = np.finfo(np.float64).eps * max(a.shape[0], a.shape[1])   # numpy's rcond=None
    return np.linalg.lstsq(a, v, rcond)[0]


@numba.njit(cache=True, nogil=True)
def local_eval(k: np.ndarray, k0: float, scale: float, degree: int, w: float, periodic: bool,
               coef: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The fit with coefficients ``coef`` at samples ``k``."""
    return local_design(k, k0, scale, degree, w, periodic) @ coef


def readonly(x: np.ndarray) -> np.ndarray:
    """``x`` as a contiguous float64 read-only view (one compiled variant for samples read
    from a file, which come read-only, and for samples computed here)."""
    out = np.ascontiguousarray(x, dtype=np.float64).view()
    out.flags.writeable = False
    return out


#: Columns of a fit row before its coefficients.
FIT_HEAD = 5
#: Columns of :func:`jump_fits_batch`'s scalars: t_v, t_a, t_half, t_s, a_lo, a_hi, a_sign,
#: status (0: done here; 1: a window holds a non-finite sample, the Python path decides).
N_SCALARS = 8


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _fit(x: np.ndarray, lo: int, hi: int, degree: int, w: float, periodic: bool,
         row: np.ndarray) -> bool:  # pragma: no cover - compiled
    """:class:`~rattle_lab.detect._local_fits._LocalFit` of ``x[lo:hi + 1]`` into ``row``.
    False where the window holds a non-finite sample."""
    n = hi - lo + 1
    y = np.empty(n)
    k = np.empty(n)
    for i in range(n):
        y[i] = x[lo + i]
        if not math.isfinite(y[i]):
            return False
        k[i] = lo + i
    k0 = 0.5 * (lo + hi)           # the mean of consecutive integers, exactly
    scale = max(1.0, 0.5 * (hi - lo))
    n_par = 3 + 2 * degree if periodic else degree + 1
    if n < n_par:
        periodic = False
        degree = max(0, min(degree, n - 1))
    coef = local_lstsq(k, y, k0, scale, degree, w, periodic)
    row[:] = np.nan
    row[0], row[1], row[2] = k0, scale, degree
    row[3] = 1.0 if periodic else 0.0
    row[4] = w
    row[FIT_HEAD:FIT_HEAD + coef.size] = coef
    return True


@numba.njit(cache=True, nogil=True, error_model="numpy")
def fit_value(row: np.ndarray, t: float) -> float:  # pragma: no cover - compiled
    """A fit row's value at the fractional sample ``t`` (NaN: no fit)."""
    k0 = row[0]
    if math.isnan(k0):
        return np.nan
    scale, degree, w = row[1], int(row[2]), row[4]
    tau = t - k0
    u = tau / scale
    if row[3] == 0.0:              # polynomial, highest power first
        acc = 0.0
        x = 1.0
        for j in range(degree, -1, -1):
            acc += row[FIT_HEAD + j] * x
            x *= u
        return acc
    c, s_ = math.cos(w * tau), math.sin(w * tau)
    acc = row[FIT_HEAD]
    x = 1.0
    for j in range(degree + 1):
        acc += row[FIT_HEAD + 1 + 2 * j] * (x * c) + row[FIT_HEAD + 2 + 2 * j] * (x * s_)
        x *= u
    return acc


@numba.njit(cache=True, nogil=True, error_model="numpy")
def fits_at(fits: np.ndarray, t: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """``out[i, s]``: fit ``s`` (0 before, 1 after) of impact ``i`` at ``t[i]`` (NaN where
    ``t[i]`` is NaN or the fit is missing)."""
    n = t.size
    out = np.full((n, 2), np.nan)
    for i in range(n):
        if math.isfinite(t[i]):
            out[i, 0] = fit_value(fits[i, 0], t[i])
            out[i, 1] = fit_value(fits[i, 1], t[i])
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def half_region(r: np.ndarray, peak: int) -> tuple[int, int]:  # pragma: no cover - compiled
    """The contiguous samples around ``peak`` above half its height (inclusive)."""
    half = 0.5 * r[peak]
    lo = peak
    while lo > 0 and r[lo - 1] > half:
        lo -= 1
    hi = peak
    while hi + 1 < r.size and r[hi + 1] > half:
        hi += 1
    return lo, hi


@numba.njit(cache=True, nogil=True)
def pulse_peak(r: np.ndarray) -> int:  # pragma: no cover - compiled
    """The contact pulse's peak in the residual ``r`` of the acceleration from its smooth
    fit extrapolated over the search window: the largest ``|r|`` that falls below half its
    height on both sides inside the window, if it is at least half the largest ``|r|``.
    An extrapolation drifting away from a steep acceleration grows towards the window's end
    without falling again, and may outgrow a pulse that clips (seen on the independent
    generator's start-up impacts: 1283 against a clipped pulse's 1262 m/s^2, the impact
    timed 8.8 samples late).  Otherwise the largest ``|r|``: a bump of the noise far under
    the drift is no pulse (the trigger had none; its time stays undecided)."""
    m = r.size
    top = 0.0
    for i in range(m):
        top = max(top, abs(r[i]))
    best = -1
    for i in range(m):
        ai = abs(r[i])
        if ai == 0.0 or (best >= 0 and ai <= abs(r[best])):
            continue
        half = 0.5 * ai
        lo = i
        while lo > 0 and abs(r[lo - 1]) > half and r[lo - 1] * r[i] > 0:
            lo -= 1
        hi = i
        while hi + 1 < m and abs(r[hi + 1]) > half and r[hi + 1] * r[i] > 0:
            hi += 1
        if lo > 0 and hi + 1 < m and ai >= 0.5 * top:
            best = i
    if best < 0:
        best = 0
        for i in range(1, m):
            if abs(r[i]) > abs(r[best]):
                best = i
    return best


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _step_centroid(v: np.ndarray, p: np.ndarray, q: np.ndarray, pre_hi: int, post_lo: int
                   ) -> float:  # pragma: no cover - compiled
    """Centroid of the normalised step between fits ``p`` and ``q`` (NaN if not finite)."""
    total = 0.0
    first = last = 0.0
    for kk in range(pre_hi, post_lo + 1):
        pk, qk = fit_value(p, float(kk)), fit_value(q, float(kk))
        s = (v[kk] - pk) / (qk - pk)
        if not math.isfinite(s):
            return np.nan
        if kk == pre_hi:
            first = s
        last = s
        total += s
    t = post_lo - (total - 0.5 * (first + last))
    return min(max(t, float(pre_hi)), float(post_lo))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _contact_pulse(a: np.ndarray, k_c: int, n_half: int, lo_lim: int, n_fit: int, degree: int,
                   w: float, periodic: bool, row: np.ndarray
                   ) -> tuple[float, float, float, float, bool]:  # pragma: no cover - compiled
    """:func:`~rattle_lab.detect._local_fits.contact_pulse`; the last value False where a
    window holds a non-finite sample."""
    nan = np.nan
    lo, hi = k_c - n_half, k_c + n_half
    f_hi = lo - 1
    f_lo = max(lo_lim, f_hi - n_fit + 1)
    if lo < 0 or hi >= a.size or f_hi - f_lo + 1 < 3:
        return nan, nan, nan, 0.0, True
    if not _fit(a, f_lo, f_hi, degree, w, periodic, row):
        return nan, nan, nan, 0.0, False
    m = hi - lo + 1
    r = np.empty(m)
    for i in range(m):
        r[i] = a[lo + i] - fit_value(row, float(lo + i))
        if not math.isfinite(r[i]):
            return nan, nan, nan, 0.0, False
    pk = pulse_peak(r)
    sign = 1.0 if r[pk] > 0 else (-1.0 if r[pk] < 0 else 0.0)
    for i in range(m):
        r[i] *= sign
    r_lo, r_hi = half_region(r, pk)
    widen = int(math.ceil(0.25 * (r_hi - r_lo + 1)))
    r_lo, r_hi = max(0, r_lo - widen), min(m - 1, r_hi + widen)
    sw = swk = 0.0
    for i in range(r_lo, r_hi + 1):
        sw += r[i]
        swk += (lo + i) * r[i]
    if not sw > 0:
        return nan, nan, nan, 0.0, True
    t1 = swk / sw
    # the higher modes' ringing just after the pulse, a x + b x**2 (see contact_pulse)
    width = r_hi - r_lo + 1
    a_end = min(m, r_hi + 1 + 2 * width)
    n_after = a_end - (r_hi + 1)
    if n_after >= 3:
        x = np.empty((n_after, 2))
        y = np.empty(n_after)
        for j in range(n_after):
            xj = (lo + r_hi + 1 + j) - t1
            x[j, 0], x[j, 1] = xj, xj * xj
            y[j] = r[r_hi + 1 + j]
        rcond = np.finfo(np.float64).eps * max(n_after, 2)
        coef = np.linalg.lstsq(x, y, rcond)[0]
        sw = swk = 0.0
        for i in range(r_lo, r_hi + 1):
            xc = max((lo + i) - t1, 0.0)
            wi = r[i] - (coef[0] * xc + coef[1] * xc * xc)
            sw += wi
            swk += (lo + i) * wi
        if sw > 0:
            t1 = swk / sw
    return t1, (lo + r_lo) - 0.5, (lo + r_hi) + 0.5, sign, True


@numba.njit(cache=True, nogil=True, error_model="numpy")
def jump_fits_batch(v: np.ndarray, a: np.ndarray, has_a: bool, spans: np.ndarray, n_fit: int,
                    n_guard: int, degree: int, w: float, periodic: bool, n_short_min: int,
                    short_widths: int, short_pads: float, short_degree: int
                    ) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """Every impact's :func:`~rattle_lab.detect._local_fits._jump_fits` at once.

    ``spans[i] = (j_lo, j_hi, lo_lim, hi_lim)``.  Returns ``scalars`` (n, :data:`N_SCALARS`)
    and ``fits`` (n, 2, :data:`FIT_HEAD` + coefficients): the fits before and after.
    """
    n = spans.shape[0]
    n_coef = max(3 + 2 * degree, degree + 1, short_degree + 1)
    scal = np.full((n, N_SCALARS), np.nan)
    fits = np.full((n, 2, FIT_HEAD + n_coef), np.nan)
    work = np.empty(FIT_HEAD + n_coef)
    ps = np.empty(FIT_HEAD + n_coef)
    qs = np.empty(FIT_HEAD + n_coef)
    for i in range(n):
        j_lo, j_hi, lo_lim, hi_lim = spans[i, 0], spans[i, 1], spans[i, 2], spans[i, 3]
        n_pad = (j_hi - j_lo + 1) + n_guard
        pre_hi = j_lo - 1 - n_pad
        post_lo = j_hi + n_pad
        pre_lo, post_hi = max(lo_lim, pre_hi - n_fit + 1), min(hi_lim, post_lo + n_fit - 1)
        scal[i, 2] = 0.5 * (j_lo + j_hi) - 0.5
        scal[i, 6] = 0.0
        scal[i, 7] = 0.0
        ok = True
        for side in range(2):
            lo, hi = (pre_lo, pre_hi) if side == 0 else (post_lo, post_hi)
            if hi < lo:
                continue
            deg = degree if (hi - lo + 1 >= n_fit or not periodic) else 0
            if not _fit(v, lo, hi, deg, w, periodic, fits[i, side]):
                ok = False
        if not ok:
            scal[i, 7] = 1.0
            continue
        if math.isnan(fits[i, 0, 0]) or math.isnan(fits[i, 1, 0]):
            continue
        t = _step_centroid(v, fits[i, 0], fits[i, 1], pre_hi, post_lo)
        if math.isnan(t):
            scal[i, 7] = 1.0   # a fit that is not finite: numpy decides
            continue
        scal[i, 0] = t
        # the short flanks' centroid (_short_flank_centroid)
        t_s = t
        n_s = max(n_short_min, short_widths * (j_hi - j_lo + 1),
                  int(short_pads * (post_lo - j_hi)))
        s_lo, s_hi = max(lo_lim, pre_hi - n_s + 1), min(hi_lim, post_lo + n_s - 1)
        if pre_hi - s_lo + 1 >= 3 and s_hi - post_lo + 1 >= 3:
            if not (_fit(v, s_lo, pre_hi, short_degree, 0.0, False, ps)
                    and _fit(v, post_lo, s_hi, short_degree, 0.0, False, qs)):
                scal[i, 7] = 1.0
                continue
            ts = _step_centroid(v, ps, qs, pre_hi, post_lo)
            if not math.isnan(ts):
                t_s = ts
        scal[i, 3] = t_s
        if has_a:
            # a centroid away from the jump's region measured nothing: the region centres
            # the search (see _jump_fits)
            t_c = t if abs(t - scal[i, 2]) <= j_hi - j_lo + 1 else scal[i, 2]
            t_a, a_lo, a_hi, a_sign, fine = _contact_pulse(
                a, int(np.rint(t_c)), (post_lo - j_hi) + (j_hi - j_lo + 1) // 2, lo_lim, n_fit,
                degree, w, periodic, work)
            if not fine:
                scal[i, 7] = 1.0
                continue
            if math.isfinite(t_a) and pre_hi <= t_a <= post_lo:
                scal[i, 1], scal[i, 4], scal[i, 5], scal[i, 6] = t_a, a_lo, a_hi, a_sign
    return scal, fits


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _refined(y: np.ndarray, k: int) -> tuple[float, float]:  # pragma: no cover - compiled
    """:func:`rattle_lab.detect._sound._refined`: the 3-point parabola's peak at ``k``,
    unless ``k`` is an onset or an edge or not a strict maximum."""
    if 0 < k and y[k - 1] < 0.5 * y[k]:
        return float(k), y[k]
    if k <= 0 or k >= y.size - 1:
        return float(k), y[k]
    a, b, c = y[k - 1], y[k], y[k + 1]
    den = a - 2.0 * b + c
    if den >= 0.0:
        return float(k), b
    delta = 0.5 * (a - c) / den
    return k + delta, b - 0.25 * (a - c) * delta


@numba.njit(cache=True, nogil=True, error_model="numpy")
def sound_windows(p: np.ndarray, t_imp: np.ndarray, start_time_s: float, fs_hz: float,
                  delay_s: float, n_win: int, n_base: int, w: float, periodic: bool,
                  first_fraction: float, n_guard: int) -> np.ndarray:  # pragma: no cover - compiled
    """:func:`~rattle_lab.detect.sound_peaks`' loop over the impacts of finite samples ``p``:
    ``out[i] = (t_first, t_max, p_first, p_max, rms)`` (NaN where the window is empty).
    Each window opens ``n_guard`` samples before the first sample at or after the arrival."""
    n = t_imp.size
    out = np.full((n, 5), np.nan)
    row = np.empty(FIT_HEAD + 3)
    prev_hi = 0
    for i in range(n):
        lo = int(math.ceil((t_imp[i] + delay_s - start_time_s) * fs_hz - 1e-9)) - n_guard
        hi = lo + n_guard + n_win
        if i + 1 < n:
            hi = min(hi, int(math.ceil((t_imp[i + 1] + delay_s - start_time_s) * fs_hz - 1e-9))
                     - n_guard)
        lo, hi = max(lo, 0), min(hi, p.size)
        if hi - lo < 1:
            continue
        seg = np.empty(hi - lo)
        fitted = False
        if periodic:
            b_lo = max(0, lo - n_base, prev_hi)
            if lo - b_lo >= 9:
                fitted = _fit(p, b_lo, lo - 1, 0, w, True, row)
        for k in range(hi - lo):
            seg[k] = abs(p[lo + k] - fit_value(row, float(lo + k))) if fitted else abs(p[lo + k])
        prev_hi = hi
        ss = 0.0
        k_max = 0
        for k in range(seg.size):
            ss += seg[k] * seg[k]
            if seg[k] > seg[k_max]:
                k_max = k
        out[i, 4] = math.sqrt(ss / seg.size)
        if seg[k_max] == 0.0:
            continue
        level = first_fraction * seg[k_max]
        k_first = k_max
        for k in range(seg.size):   # the first local maximum reaching `level`
            if seg[k] >= level and (k + 1 == seg.size or seg[k] >= seg[k + 1]):
                k_first = k
                break
        loc, height = _refined(seg, k_first)
        out[i, 0], out[i, 2] = start_time_s + (lo + loc) / fs_hz, height
        loc, height = _refined(seg, k_max)
        out[i, 1], out[i, 3] = start_time_s + (lo + loc) / fs_hz, height
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def step_rows(v: np.ndarray, t_eval: np.ndarray, fits: np.ndarray, limits: np.ndarray,
              span: int) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """The rows of :func:`~rattle_lab.detect._timing.step_error`: per impact the normalised
    step less the ideal one at ``tau = k - t_eval`` (``-span..span``), and whether the
    impact has a row (finite ``t_eval``, both fits, a sample within its limits)."""
    n = t_eval.size
    out = np.full((n, 2 * span + 1), np.nan)
    has = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        te = t_eval[i]
        if not math.isfinite(te) or math.isnan(fits[i, 0, 0]) or math.isnan(fits[i, 1, 0]):
            continue
        k_lo = max(limits[i, 0], int(math.ceil(te - span)))
        k_hi = min(limits[i, 1], int(math.floor(te + span)))
        if k_hi < k_lo:
            continue
        has[i] = True
        for kk in range(k_lo, k_hi + 1):
            pk, qk = fit_value(fits[i, 0], float(kk)), fit_value(fits[i, 1], float(kk))
            r = ((v[kk] - pk) if kk < te else (v[kk] - qk)) / (qk - pk)
            out[i, int(np.rint(kk - te)) + span] = r
    return out, has


@numba.njit(cache=True, nogil=True)
def onsets(cf: np.ndarray, on: float, off: float, n_min_sep: int
            ) -> np.ndarray:  # pragma: no cover - compiled
    """The rows of :func:`~rattle_lab.detect._trigger.trigger_onsets`, ``(m, 3)``."""
    n = cf.size
    out = np.empty((16, 3), dtype=np.int64)
    m = 0
    k = 0
    while k < n:
        if not cf[k] > on:
            k += 1
            continue
        start = k
        while start > 0 and cf[start - 1] > off:    # back-track to the onset
            start -= 1
        end = k
        while end + 1 < n and cf[end + 1] > off:
            end += 1
        peak = start
        for j in range(start + 1, end + 1):
            if cf[j] > cf[peak]:
                peak = j
        if m > 0 and peak - out[m - 1, 1] < n_min_sep:
            prev_peak = out[m - 1, 1]
            out[m - 1, 1] = prev_peak if cf[prev_peak] >= cf[peak] else peak
            out[m - 1, 2] = max(end, out[m - 1, 2])
        else:
            if m == out.shape[0]:
                grown = np.empty((2 * m, 3), dtype=np.int64)
                grown[:m] = out
                out = grown
            out[m, 0], out[m, 1], out[m, 2] = start, peak, end
            m += 1
        k = end + 1          # the next sample above `on` after this trigger
    return out[:m].copy()


@numba.njit(cache=True, nogil=True, error_model="numpy")
def lag_correlation(x: np.ndarray, y: np.ndarray, max_lag: int
                    ) -> np.ndarray:  # pragma: no cover - compiled
    """``sum_k x[k] y[k + lag]`` for the lags ``0..max_lag, -max_lag..-1`` (that order:
    :func:`~rattle_lab.detect._timing.coarse_lag`), over the samples where ``x`` is not
    zero."""
    n = x.size
    out = np.zeros(2 * max_lag + 1)
    for k in range(n):
        xk = x[k]
        if xk == 0.0:
            continue
        for lag in range(-max_lag, max_lag + 1):
            j = k + lag
            if 0 <= j < n:
                out[lag if lag >= 0 else 2 * max_lag + 1 + lag] += xk * y[j]
    return out
