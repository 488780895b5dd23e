"""The local fits either side of an impact: the velocities before and after a jump, the
jump's centroid and the contact pulse's centroid (:func:`~rattle_lab.detect.detect_impacts`,
steps 4-5)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._trigger import _half_region

_KERNELS: Any = None


def _kernels() -> Any:
    """:mod:`rattle_lab.detect._jump_kernels`, imported on first use (it imports numba:
    ``import rattle_lab.detect`` stays light) and kept (the fits are made by the thousand)."""
    global _KERNELS
    if _KERNELS is None:
        from . import _jump_kernels

        _KERNELS = _jump_kernels
    return _KERNELS


class _LocalFit:
    """Least-squares fit of one side of a jump, evaluable at (fractional) sample indices.

    Without ``omega_per_sample``: a polynomial of degree ``degree``.  With it (the excitation
    frequency in rad/sample): the local solution of a lightly damped mode forced near its
    resonance, ``sum_k tau**k (a_k cos(w tau) + b_k sin(w tau))``, ``k <= degree``, plus a
    constant: a free response at ``w_s = w + d`` is ``cos(w tau) - d tau sin(w tau) + ...``,
    so the envelope polynomial absorbs the detuning and the damping, and the fit extrapolates
    across the excluded contact without the bias a polynomial has on a signal whose
    amplitude (~ omega_s h) is many times the impact speed.
    """

    def __init__(self, k: np.ndarray, v: np.ndarray, degree: int, omega_per_sample: float | None):
        self.k0 = float(k.mean())
        self.scale = max(1.0, float(np.abs(k - self.k0).max(initial=1.0)))
        self.degree = degree
        self.w = omega_per_sample
        n_par = degree + 1 if omega_per_sample is None else 3 + 2 * degree
        if k.size < n_par:   # too few samples: fall back to a low-degree polynomial
            self.w = None
            self.degree = max(0, min(degree, k.size - 1))
        # compiled where every sample is finite (numba's lstsq refuses NaN; numpy's path
        # keeps what it gives there)
        self.compiled = bool(np.all(np.isfinite(v)))
        if self.compiled:
            self.coef = _kernels().local_lstsq(np.ascontiguousarray(k, float),
                                    np.ascontiguousarray(v, float), self.k0, self.scale,
                                    self.degree, 0.0 if self.w is None else float(self.w),
                                    self.w is not None)
        else:
            self.coef = np.linalg.lstsq(self._design(k), v, rcond=None)[0]
        self.row = np.r_[self.k0, self.scale, self.degree, float(self.w is not None),
                         0.0 if self.w is None else float(self.w), self.coef]

    @classmethod
    def of_row(cls, row: np.ndarray) -> _LocalFit:
        """The fit a compiled row holds (see :mod:`rattle_lab.detect._jump_kernels`)."""
        head = _kernels().FIT_HEAD
        fit = cls.__new__(cls)
        fit.k0, fit.scale, fit.degree = float(row[0]), float(row[1]), int(row[2])
        fit.w = float(row[4]) if row[3] else None
        n_coef = 3 + 2 * fit.degree if fit.w is not None else fit.degree + 1
        fit.compiled = True
        fit.row = row[:head + n_coef]      # views of the run's rows
        fit.coef = fit.row[head:]
        return fit

    def _design(self, k: np.ndarray) -> np.ndarray:
        tau = np.asarray(k, dtype=float) - self.k0
        scale = self.scale
        if self.w is None:
            return np.vander(tau / scale, self.degree + 1)
        c, s_ = np.cos(self.w * tau), np.sin(self.w * tau)
        cols = [np.ones_like(tau)]
        for j in range(self.degree + 1):
            u = (tau / scale) ** j
            cols += [u * c, u * s_]
        return np.column_stack(cols)

    def __call__(self, k: np.ndarray | float) -> np.ndarray:
        if isinstance(k, float) and self.compiled:
            return np.array([_kernels().fit_value(self.row, k)])
        kk = np.atleast_1d(np.asarray(k, dtype=float))
        if self.compiled:
            return _kernels().local_eval(np.ascontiguousarray(kk), self.k0, self.scale, self.degree,
                              0.0 if self.w is None else float(self.w), self.w is not None,
                              self.coef)
        return self._design(kk) @ self.coef


def contact_pulse(a: np.ndarray, k_c: int, n_half: int, lo_lim: int, *, n_fit: int, degree: int,
                  omega_per_sample: float | None = None) -> tuple[float, float, float, float]:
    """Centroid, first and last sample and sign of the contact pulse of the plate
    acceleration near ``k_c`` (sample units; sign +-1 of the pulse).

    The smooth acceleration is fitted (:class:`_LocalFit`) over ``n_fit`` samples ending
    ``n_half`` samples before ``k_c`` and extrapolated; in the residual over
    ``k_c +- n_half`` the pulse is the half-height region around the largest ``|residual|``
    that falls below half its height on both sides inside that span, if it is at least half
    the largest (:func:`~rattle_lab.detect._jump_kernels.pulse_peak`), widened by a quarter
    of its width on each side (a half-sine is 1.5 times as long as its half-height width).
    A contact pulse is short and large, so its centroid is a far less noisy impact time
    than the velocity step (``sigma_a / peak`` against ``sigma_v / jump``); point sampling a
    half-sine of 4 samples moves its centroid by at most 0.01 sample.  The widened region is
    the contact's extent (first touch to separation of a half-sine force).  Returns NaNs
    (sign 0) without room for the fit.
    """
    nan = float("nan")
    lo, hi = k_c - n_half, k_c + n_half
    f_hi = lo - 1
    f_lo = max(lo_lim, f_hi - n_fit + 1)
    if lo < 0 or hi >= a.size or f_hi - f_lo + 1 < 3:
        return nan, nan, nan, 0.0
    smooth = _LocalFit(np.arange(f_lo, f_hi + 1.0), a[f_lo:f_hi + 1], degree, omega_per_sample)
    k = np.arange(lo, hi + 1.0)
    r = a[lo:hi + 1] - smooth(k)
    from ._jump_kernels import pulse_peak   # here: importing detect stays light (no numba)

    pk = int(pulse_peak(np.ascontiguousarray(r, dtype=np.float64)))
    sign = float(np.sign(r[pk]))
    r = r * sign
    r_lo, r_hi = _half_region(r, pk)
    widen = int(np.ceil(0.25 * (r_hi - r_lo + 1)))
    r_lo, r_hi = max(0, r_lo - widen), min(r.size - 1, r_hi + widen)
    w = r[r_lo:r_hi + 1]
    if not np.sum(w) > 0:
        return nan, nan, nan, 0.0
    t1 = float(np.sum(k[r_lo:r_hi + 1] * w) / np.sum(w))
    # ringing of the higher modes starts at the impact, ~ sin(omega_j (t - t_i)): its start,
    # a ramp with its curvature (a x + b x**2, x = t - t1) fitted over twice the pulse's
    # length just after it, is removed (it would pull the centroid late).  On the default
    # scene the impact time was 0.0028 samples early with a straight ramp over one pulse
    # length, 0.0015 with the curvature, 0.0011 with it over two (issue 15)
    m = r_hi - r_lo + 1
    after = np.arange(r_hi + 1, min(r.size, r_hi + 1 + 2 * m))
    if after.size >= 3:
        x = k[after] - t1
        coef = np.linalg.lstsq(np.column_stack([x, x * x]), r[after], rcond=None)[0]
        xc = np.clip(k[r_lo:r_hi + 1] - t1, 0.0, None)
        w = w - (coef[0] * xc + coef[1] * xc * xc)
        if np.sum(w) > 0:
            t1 = float(np.sum(k[r_lo:r_hi + 1] * w) / np.sum(w))
    # the extent: half a sample beyond the first and last samples of the pulse
    return t1, float(k[r_lo]) - 0.5, float(k[r_hi]) + 0.5, sign


def _fit_windows(j_lo: int, j_hi: int, lo_lim: int, hi_lim: int, n_fit: int, n_guard: int
                 ) -> tuple[int, int, int, int]:
    """``(pre_lo, pre_hi, post_lo, post_hi)``: the fit windows either side of a jump's
    half-height region ``j_lo..j_hi``, ``n_pad = width + n_guard`` clear of it, at most
    ``n_fit`` samples each, within ``lo_lim..hi_lim`` (see :func:`jump_velocities`)."""
    n_pad = (j_hi - j_lo + 1) + n_guard
    pre_hi = j_lo - 1 - n_pad
    post_lo = j_hi + n_pad
    return max(lo_lim, pre_hi - n_fit + 1), pre_hi, post_lo, min(hi_lim, post_lo + n_fit - 1)


def jump_velocities(v: np.ndarray, j_lo: int, j_hi: int, lo_lim: int, hi_lim: int, *,
                    n_fit: int, n_guard: int, degree: int,
                    omega_per_sample: float | None = None,
                    accel: np.ndarray | None = None) -> tuple[float, float, float]:
    """Time (sample units) and velocities before/after one velocity jump.

    ``j_lo..j_hi`` is the half-height region of the jump's characteristic function (index
    ``k``: the difference ``v[k] - v[k-1]``).  A finite contact and a band-limited
    vibrometer spread the jump over more samples than that, so each fit stops
    ``n_pad = j_hi - j_lo + 1 + n_guard`` samples clear of the region: ``p`` (see
    :class:`_LocalFit`) over ``n_fit`` samples before and ``q`` over ``n_fit`` after.
    The jump time is the centroid of the transition's derivative, from the normalised
    step ``s = (v - p) / (q - p)`` between the two windows (``t = b - sum s``,
    trapezoidal), which a symmetric contact pulse and a zero-phase band limit both keep
    at the rigid impact time; ``v_in = p(t)``, ``v_out = q(t)``.  Evaluating the fits at
    the centroid matters: the relative velocity changes by up to ``omega_s**2 h`` per second
    (~470 m/s^2 on a 1.3 mm gap at 96 Hz), so a tenth of a sample at 20 kHz is 2 mm/s.
    With ``accel`` the time is the contact pulse's centroid (:func:`contact_pulse`), and
    the velocities are evaluated there: right only where the two channels are on one time
    base (:func:`detect_impacts` measures and removes what remains between them).

    Returns ``(t, v_in, v_out)``; ``t`` is NaN where a side has no samples (the
    velocities are then the fits at the middle of the region, NaN on the empty side).
    """
    jf = _jump_fits(v, j_lo, j_hi, lo_lim, hi_lim, n_fit=n_fit, n_guard=n_guard,
                    degree=degree, omega_per_sample=omega_per_sample, accel=accel)
    t = jf.t_a if np.isfinite(jf.t_a) else jf.t_v
    vi, vo = jf.at(t if np.isfinite(t) else jf.t_half)
    return t, vi, vo


@dataclass(frozen=True)
class _JumpFits:
    """The fits either side of one jump and its two centroids (sample units)."""

    t_v: float                 # the velocity step's centroid (NaN: a side without samples)
    t_a: float                 # the contact pulse's centroid (NaN: none or not found)
    t_half: float              # middle of the half-height region
    p: _LocalFit | None
    q: _LocalFit | None
    t_s: float = float("nan")   # the step's centroid between short local flanks (see below)
    a_lo: float = float("nan")  # the contact pulse's extent (NaN: no pulse)
    a_hi: float = float("nan")
    a_sign: float = 0.0         # the pulse's sign (+-1; 0: no pulse)

    def at(self, t: float) -> tuple[float, float]:
        nan = float("nan")
        t = float(t)
        return (float(self.p(t)[0]) if self.p is not None else nan,
                float(self.q(t)[0]) if self.q is not None else nan)


def _fit_rows(jfits: list[_JumpFits]) -> np.ndarray:
    """The fits before and after every impact as rows (n, 2, width) for :func:`_fits_at`
    (NaN rows where a side has no fit)."""
    width = max([f.row.size for jf in jfits for f in (jf.p, jf.q) if f is not None],
                default=1)
    rows = np.full((len(jfits), 2, width), np.nan)
    for i, jf in enumerate(jfits):
        for side, f in enumerate((jf.p, jf.q)):
            if f is not None:
                rows[i, side, :f.row.size] = f.row
    return rows


def _fits_at(rows: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``(n, 2)``: each impact's fits before and after at ``t[i]`` (NaN where ``t[i]`` is
    not finite or a side has no fit)."""
    from ._jump_kernels import fits_at

    return fits_at(np.ascontiguousarray(rows), np.ascontiguousarray(t, dtype=float))


def _jump_fits_all(v: np.ndarray, spans: list[tuple[int, int, int, int]], *, n_fit: int,
                   n_guard: int, degree: int, omega_per_sample: float | None = None,
                   accel: np.ndarray | None = None) -> list[_JumpFits]:
    """:func:`_jump_fits` of every span ``(j_lo, j_hi, lo_lim, hi_lim)`` in one compiled
    pass (:func:`rattle_lab.detect._jump_kernels.jump_fits_batch`); an impact whose windows
    hold a non-finite sample goes through :func:`_jump_fits` itself."""
    from ._jump_kernels import jump_fits_batch, readonly

    if not spans:
        return []
    scal, fits = jump_fits_batch(
        readonly(v), readonly(accel if accel is not None else np.zeros(0)), accel is not None,
        np.asarray(spans, dtype=np.int64).reshape(-1, 4), int(n_fit), int(n_guard),
        int(degree), 0.0 if omega_per_sample is None else float(omega_per_sample),
        omega_per_sample is not None, SHORT_FLANK_MIN, SHORT_FLANK_WIDTHS,
        float(SHORT_FLANK_PADS), SHORT_FLANK_DEGREE)
    out = []
    for i, (j_lo, j_hi, lo_lim, hi_lim) in enumerate(spans):
        t_v, t_a, t_half, t_s, a_lo, a_hi, a_sign, status = scal[i].tolist()
        if status:
            out.append(_jump_fits(v, j_lo, j_hi, lo_lim, hi_lim, n_fit=n_fit, n_guard=n_guard,
                                  degree=degree, omega_per_sample=omega_per_sample,
                                  accel=accel))
            continue
        p = None if np.isnan(fits[i, 0, 0]) else _LocalFit.of_row(fits[i, 0])
        q = None if np.isnan(fits[i, 1, 0]) else _LocalFit.of_row(fits[i, 1])
        out.append(_JumpFits(t_v, t_a, t_half, p, q, t_s, a_lo, a_hi, a_sign))
    return out


def _jump_fits(v: np.ndarray, j_lo: int, j_hi: int, lo_lim: int, hi_lim: int, *,
               n_fit: int, n_guard: int, degree: int, omega_per_sample: float | None = None,
               accel: np.ndarray | None = None) -> _JumpFits:
    pre_lo, pre_hi, post_lo, post_hi = _fit_windows(j_lo, j_hi, lo_lim, hi_lim, n_fit, n_guard)
    nan = float("nan")
    fits = []
    for lo, hi in ((pre_lo, pre_hi), (post_lo, post_hi)):
        # a window cut short (record edge, neighbouring impact) gets a stiffer envelope
        deg = degree if hi - lo + 1 >= n_fit or omega_per_sample is None else 0
        fits.append(_LocalFit(np.arange(lo, hi + 1.0), v[lo:hi + 1], deg, omega_per_sample)
                    if hi >= lo else None)
    p, q = fits
    t_half = 0.5 * (j_lo + j_hi) - 0.5
    if p is None or q is None:
        return _JumpFits(nan, nan, t_half, p, q)
    k = np.arange(pre_hi, post_lo + 1.0)
    pk, qk = p(k), q(k)
    step = (v[pre_hi:post_lo + 1] - pk) / (qk - pk)
    # centroid of ds over [a, b]: b - integral of s (trapezoid; s(a) ~ 0, s(b) ~ 1)
    t = float(post_lo - (np.sum(step) - 0.5 * (step[0] + step[-1])))
    t = min(max(t, float(pre_hi)), float(post_lo))
    t_s = _short_flank_centroid(v, j_lo, j_hi, lo_lim, hi_lim, pre_hi, post_lo, t)
    t_a, a_lo, a_hi, a_sign = nan, nan, nan, 0.0
    if accel is not None:
        n_pad = post_lo - j_hi
        # a step's centroid further from the jump's half-height region than the region is
        # wide (fits that read the plate's ringing, not the approach and rebound; one held
        # at a window's edge) measured nothing, and a pulse search centred there can miss
        # the pulse (the independent generator's light ringing: impacts timed 6.7-8.4
        # samples early): the region centres it instead
        t_c = t if abs(t - t_half) <= j_hi - j_lo + 1 else t_half
        t_a, a_lo, a_hi, a_sign = contact_pulse(
            accel, int(round(t_c)), n_pad + (j_hi - j_lo + 1) // 2, lo_lim,
            n_fit=n_fit, degree=degree, omega_per_sample=omega_per_sample)
        if not (np.isfinite(t_a) and pre_hi <= t_a <= post_lo):
            t_a, a_lo, a_hi, a_sign = nan, nan, nan, 0.0
    return _JumpFits(t, t_a, t_half, p, q, t_s, a_lo, a_hi, a_sign)


#: Length of the short flanks of :func:`_short_flank_centroid`: the most of
#: :data:`SHORT_FLANK_WIDTHS` half-height widths of the jump, :data:`SHORT_FLANK_PADS` times
#: the gap between the flank and the jump (a quadratic extrapolated much further than its own
#: length amplifies the noise) and :data:`SHORT_FLANK_MIN` samples.
SHORT_FLANK_WIDTHS = 4
SHORT_FLANK_MIN = 6
SHORT_FLANK_PADS = 1.0
SHORT_FLANK_DEGREE = 2


def _short_flank_centroid(v: np.ndarray, j_lo: int, j_hi: int, lo_lim: int, hi_lim: int,
                          pre_hi: int, post_lo: int, t_long: float) -> float:
    """The step's centroid between quadratics fitted over short flanks (sample units).

    The same normalised-step centroid as the long fits' (:func:`_jump_fits`), between
    quadratics over short flanks (see :data:`SHORT_FLANK_WIDTHS`) just outside the same
    guard.  The plate's higher modes ringing in the vibrometer after an impact (a few hundred
    Hz) are a smooth curve over so short a flank, where the long forced-mode fits cannot
    follow them and put the centroid late alike at every impact.  Used for the vibrometer's
    delay (:func:`~rattle_lab.detect._timing.channel_delay`).  Measured on the independent
    generator (``benchmarks/chain_timing.py``, 29 Nov 2026; the detector alone, two dwells):
    with the plate's ringing in the vibrometer and the delay undeclared, the delay's error
    fell from -0.2 to +6.9 samples to -1.0 to +3.5 (6 chains x 2 runs); over the 168 decoders
    of ``--grid`` (no ringing) its median absolute error rose from 0.014 to 0.025 sample and
    144 chains met e within 3 % and v_in within 1 %, against 143.  High-order Butterworth
    decoders, whose step rings on past a short flank, lose most (``--coverage-detect``: e
    within 3 % in 39 of 50 random chains, against 42).  ``t_long`` where a flank has under 3
    samples.
    """
    n_s = max(SHORT_FLANK_MIN, SHORT_FLANK_WIDTHS * (j_hi - j_lo + 1),
              int(SHORT_FLANK_PADS * (post_lo - j_hi)))
    a_lo, b_hi = max(lo_lim, pre_hi - n_s + 1), min(hi_lim, post_lo + n_s - 1)
    if pre_hi - a_lo + 1 < 3 or b_hi - post_lo + 1 < 3:
        return t_long
    ps = _LocalFit(np.arange(a_lo, pre_hi + 1.0), v[a_lo:pre_hi + 1], SHORT_FLANK_DEGREE, None)
    qs = _LocalFit(np.arange(post_lo, b_hi + 1.0), v[post_lo:b_hi + 1], SHORT_FLANK_DEGREE, None)
    k = np.arange(pre_hi, post_lo + 1.0)
    pk, qk = ps(k), qs(k)
    with np.errstate(divide="ignore", invalid="ignore"):
        step = (v[pre_hi:post_lo + 1] - pk) / (qk - pk)
    if not np.all(np.isfinite(step)):
        return t_long
    t = float(post_lo - (np.sum(step) - 0.5 * (step[0] + step[-1])))
    return min(max(t, float(pre_hi)), float(post_lo))
