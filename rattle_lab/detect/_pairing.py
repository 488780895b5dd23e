"""Bringing two channels of one run onto one time base before they are paired.

A channel's samples are at ``t_k = start_time_s + k / fs - group_delay_s`` in physical
time: the filters of a vibrometer decoder or an anti-alias stage show every event
``group_delay_s`` late.  :func:`onto_grid` resamples one channel (rational polyphase
resampling, then a fractional delay applied in the frequency domain, both band-limited)
onto the sample grid of another, so that a velocity jump and a contact pulse that
happened together are paired at the same sample.

:func:`base_velocity_at` gives the shaker base's velocity at given instants from the
base accelerometer (a local least-squares sine at the excitation frequency, integrated
in closed form): what an absolute vibrometer adds to the panel's motion relative to the
striker, which sits on the base.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from rattle_lab.exceptions import ParameterError

#: Largest numerator/denominator of the rational rate ratio of :func:`onto_grid`.
MAX_RATIO_TERMS = 1000


def fractional_delay(x: np.ndarray, fs_hz: float, delay_s: float) -> np.ndarray:
    """``x`` delayed by ``delay_s`` (may be negative or fractional), band-limited.

    The record is extended by its mirror image before the FFT so that the circular
    shift wraps no edge step into the other end.
    """
    x = np.asarray(x, dtype=np.float64)
    if delay_s == 0.0 or x.size < 2:
        return x.copy()
    n = x.size
    ext = np.concatenate([x, x[::-1]])
    f = np.fft.rfftfreq(ext.size, 1.0 / fs_hz)
    y = np.fft.irfft(np.fft.rfft(ext) * np.exp(-2j * np.pi * f * delay_s), ext.size)
    return y[:n]


def onto_grid(x: np.ndarray, fs_hz: float, t0_s: float, fs_target_hz: float, t0_target_s: float,
              n_target: int) -> np.ndarray:
    """Samples of ``x`` (rate ``fs_hz``, first sample at ``t0_s``) at ``t0_target_s + k / fs_target_hz``.

    ``k = 0 .. n_target - 1``; samples the record does not cover are NaN.

    Raises
    ------
    ParameterError
        If the rate ratio is not a ratio of integers up to :data:`MAX_RATIO_TERMS`.
    """
    x = np.asarray(x, dtype=np.float64)
    ratio = Fraction(fs_target_hz / fs_hz).limit_denominator(MAX_RATIO_TERMS)
    if abs(float(ratio) - fs_target_hz / fs_hz) > 1e-9 * fs_target_hz / fs_hz:
        raise ParameterError(f"sample rates {fs_hz} Hz and {fs_target_hz} Hz are not in a ratio of "
                             f"integers up to {MAX_RATIO_TERMS}: cannot pair the channels")
    from scipy import signal  # here: importing detect stays light

    y = x if ratio == 1 else signal.resample_poly(x, ratio.numerator, ratio.denominator,
                                                  padtype="line")
    # y[k] is at t0_s + k / fs_target; advance it by the fraction of a sample that puts
    # its samples on the target grid, first sample at or after t0_s (none invented before
    # the record starts; the last one, past its end, is dropped)
    offset = (t0_s - t0_target_s) * fs_target_hz
    whole = math.ceil(offset - 1e-9)
    if whole - offset > 1e-9:
        y = fractional_delay(y, fs_target_hz, (offset - whole) / fs_target_hz)[:-1]
    out = np.full(n_target, np.nan)
    lo = max(0, whole)
    hi = min(n_target, whole + y.size)
    if hi > lo:
        out[lo:hi] = y[lo - whole:hi - whole]
    return out


def base_motion_at(base_ms2: np.ndarray, fs_hz: float, t0_s: float, freq_hz: float,
                   t_s: np.ndarray, periods: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Base displacement [m] and velocity [m/s] at ``t_s``: the excitation-frequency part.

    Over ``+-periods / 2`` forcing periods around each instant the acceleration is fitted
    by ``c + a cos(W t) + b sin(W t)`` and integrated twice: ``x = -a / W**2`` and
    ``v = -b / W`` at the instant (the shaker moves at the excitation frequency; a constant
    offset has no velocity).  Near the ends of the record the window is cut to the record;
    NaN where less than one forcing period remains.
    """
    base = np.asarray(base_ms2, dtype=np.float64)
    w = 2.0 * math.pi * freq_hz
    half = int(round(0.5 * periods * fs_hz / freq_hz))
    x = np.full(np.size(t_s), np.nan)
    v = np.full(np.size(t_s), np.nan)
    for i, t in enumerate(np.atleast_1d(t_s)):
        k = int(round((t - t0_s) * fs_hz))
        lo, hi = max(0, k - half), min(base.size, k + half + 1)
        if (hi - lo) * freq_hz < fs_hz:
            continue
        tt = t0_s + np.arange(lo, hi) / fs_hz - t
        design = np.column_stack([np.ones_like(tt), np.cos(w * tt), np.sin(w * tt)])
        _, a, b = np.linalg.lstsq(design, base[lo:hi], rcond=None)[0]
        x[i] = -a / (w * w)
        v[i] = -b / w     # at tt = 0: (a sin 0 - b cos 0) / W
    return x, v


def base_velocity_at(base_ms2: np.ndarray, fs_hz: float, t0_s: float, freq_hz: float,
                     t_s: np.ndarray, periods: float = 2.0) -> np.ndarray:
    """Base velocity [m/s] at ``t_s`` from the base acceleration: the excitation-frequency
    part (:func:`base_motion_at`'s velocity)."""
    return base_motion_at(base_ms2, fs_hz, t0_s, freq_hz, t_s, periods)[1]


__all__ = ["base_velocity_at", "fractional_delay", "onto_grid"]
