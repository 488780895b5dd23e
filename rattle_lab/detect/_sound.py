"""Sound peaks after impacts, and delays by cross-correlation.

For each impact, the pressure in ``[t_impact, t_impact + window_s]`` (cut at
the next impact) gives the first peak (the first local maximum of ``|p|`` that
reaches ``first_fraction`` of the window's largest) -- the *impact sound
pressure* -- and the largest peak -- the *maximum sound pressure* (thesis
Fig. 6-6).  Peak times are refined by a 3-point parabola, except at an onset (the
sample before the peak below half of it), where the signal is not a smooth maximum and
the parabola would overshoot.  With the excitation frequency, the low-frequency sound of
the vibrating plate (at the forcing frequency) is fitted over ``baseline_s`` before each
impact and subtracted, so that the peaks are those of the impact sound alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._common import as_signal, n_samples_of, parabolic_peak
from ._spl import spl_db


#: Each window opens this many samples before the predicted arrival (impact time plus
#: ``delay_s``), and the baseline fit ends before them.  The arrival is predicted from an
#: impact time good to a fraction of a sample and a declared distance: a sound whose onset is
#: sharp (one sample) and lands a sample early would otherwise be fitted into the baseline and
#: missed by the window, and the first peak would follow the impact time's rounding.
ARRIVAL_GUARD_SAMPLES = 2


@dataclass(frozen=True)
class SoundPeaks:
    """Sound peaks paired with impacts (one entry per impact; NaN when the window is empty).

    Attributes
    ----------
    t_first_s, t_max_s : ndarray
        Times of the first and the largest peak of ``|p|``, s.
    p_first_pa, p_max_pa : ndarray
        ``|p|`` at those peaks (impact and maximum sound pressure), Pa.
    delay_first_s, delay_max_s : ndarray
        Peak time minus impact time, s.
    spl_first_db, spl_max_db : ndarray
        ``20 log10(p / 20 uPa)`` of the peaks, dB.
    p_rms_pa : ndarray
        RMS pressure over the window after the impact, Pa.
    """

    t_first_s: np.ndarray
    t_max_s: np.ndarray
    p_first_pa: np.ndarray
    p_max_pa: np.ndarray
    delay_first_s: np.ndarray
    delay_max_s: np.ndarray
    spl_first_db: np.ndarray
    spl_max_db: np.ndarray
    p_rms_pa: np.ndarray


def sound_peaks(pressure_pa: object, fs_hz: float, impact_t_s: object, *, window_s: float = 5e-3,
                first_fraction: float = 0.5, start_time_s: float = 0.0,
                excitation_freq_hz: float | None = None, baseline_s: float = 3e-3,
                delay_s: float = 0.0, guard_samples: int = ARRIVAL_GUARD_SAMPLES) -> SoundPeaks:
    """First and largest pressure peaks in a bounded window after each impact.

    Each window opens ``delay_s`` after its impact (the declared propagation delay,
    microphone distance over the speed of sound), less ``guard_samples`` samples (see
    :data:`ARRIVAL_GUARD_SAMPLES`), and closes ``window_s`` later or when the next impact's
    sound can arrive: each sound is paired with its own impact even when it arrives after
    the next impact (a distant microphone).  Peak times and delays are from the impact.

    With ``excitation_freq_hz``, the pressure over ``baseline_s`` before each impact
    (cut at the previous impact's window) is fitted by a forced-mode sinusoid at that
    frequency (constant, ``cos`` and ``sin``: bounded when extrapolated), which is extrapolated
    over the window and subtracted: the plate's own low-frequency radiation is then not
    counted in the impact's peaks.

    Examples
    --------
    >>> import numpy as np
    >>> p = np.zeros(100); p[12] = 0.6; p[20] = -1.0
    >>> pk = sound_peaks(p, 1000.0, [0.010], window_s=0.05)
    >>> float(pk.p_first_pa[0]), float(pk.p_max_pa[0]), float(pk.delay_max_s[0])
    (0.6, 1.0, 0.01)
    """
    p_signed = as_signal(pressure_pa, "pressure_pa")
    omega = None
    if excitation_freq_hz is not None:
        if not (np.isfinite(excitation_freq_hz) and 0 < excitation_freq_hz < fs_hz / 2):
            raise ParameterError(f"`excitation_freq_hz` must be in (0, fs_hz/2 = {fs_hz / 2}), "
                                 f"was {excitation_freq_hz}")
        omega = 2.0 * np.pi * excitation_freq_hz / fs_hz
    n_base = n_samples_of(baseline_s, fs_hz, name="baseline_s")
    t_imp = np.atleast_1d(np.asarray(impact_t_s, dtype=float))
    if not np.all(np.isfinite(t_imp)):
        bad = int(np.flatnonzero(~np.isfinite(t_imp))[0])
        raise ParameterError(f"`impact_t_s` must be finite, has NaN/Inf at impact {bad}")
    if not 0 < first_fraction <= 1:
        raise ParameterError(f"`first_fraction` must be in (0, 1], was {first_fraction}")
    n_win = n_samples_of(window_s, fs_hz, name="window_s")
    out = {k: np.full(t_imp.size, np.nan) for k in ("tf", "tm", "pf", "pm", "rms")}
    if not (np.isfinite(delay_s) and delay_s >= 0):
        raise ParameterError(f"`delay_s` must be >= 0, was {delay_s}")
    if int(guard_samples) != guard_samples or guard_samples < 0:
        raise ParameterError(f"`guard_samples` must be a whole number >= 0, was {guard_samples}")
    from ._jump_kernels import readonly, sound_windows

    res = sound_windows(readonly(p_signed), np.ascontiguousarray(t_imp, dtype=float), float(start_time_s),
                        float(fs_hz), float(delay_s), n_win, n_base,
                        0.0 if omega is None else float(omega), omega is not None,
                        float(first_fraction), int(guard_samples))
    for j, key in enumerate(("tf", "tm", "pf", "pm", "rms")):
        out[key] = res[:, j]
    return SoundPeaks(out["tf"], out["tm"], out["pf"], out["pm"], out["tf"] - t_imp,
                      out["tm"] - t_imp, spl_db(out["pf"]), spl_db(out["pm"]), out["rms"])


def cross_correlation_delay(cause: object, response: object, fs_hz: float, *,
                            max_lag_s: float, min_lag_s: float = 0.0,
                            envelope: bool = True) -> float:
    """Delay of ``response`` after ``cause`` by cross-correlation, with parabolic refinement, s.

    With ``envelope`` the correlation is of ``|x - mean|`` (robust to the sign
    and ringing of the response); otherwise of the mean-removed signals.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.zeros(200); x[50] = 1.0
    >>> y = np.zeros(200); y[57] = 0.5; y[58] = 0.5
    >>> bool(np.isclose(cross_correlation_delay(x, y, 1000.0, max_lag_s=0.02), 0.0075))
    True
    """
    x = as_signal(cause, "cause")
    y = as_signal(response, "response")
    if x.size != y.size or x.size == 0:
        raise ParameterError(f"`cause` and `response` must be non-empty and of equal length, "
                             f"had {x.size} and {y.size} samples")
    if envelope:
        x, y = np.abs(x - np.mean(x)), np.abs(y - np.mean(y))
    x, y = x - np.mean(x), y - np.mean(y)
    from scipy import signal   # here: scipy.signal costs about 1 s to import

    corr = signal.correlate(y, x, mode="full", method="fft")
    lags = signal.correlation_lags(y.size, x.size, mode="full")
    k_lo = n_samples_of(min_lag_s, fs_hz, name="min_lag_s")
    k_hi = n_samples_of(max_lag_s, fs_hz, name="max_lag_s")
    sel = np.flatnonzero((lags >= k_lo) & (lags <= k_hi))
    if sel.size == 0:
        raise ParameterError(f"no lag in [`min_lag_s`, `max_lag_s`] = [{min_lag_s}, {max_lag_s}] s")
    k = int(sel[np.argmax(corr[sel])])
    loc, _ = parabolic_peak(corr, k)
    return float(lags[k] + (loc - k)) / fs_hz


def impulse_train(t_s: object, n_samples: int, fs_hz: float, start_time_s: float = 0.0) -> np.ndarray:
    """Unit impulses at sub-sample times, each split linearly between its two neighbours."""
    out = np.zeros(n_samples)
    for t in np.atleast_1d(np.asarray(t_s, dtype=float)):
        x = (t - start_time_s) * fs_hz
        k = int(np.floor(x))
        w = x - k
        if 0 <= k < n_samples:
            out[k] += 1.0 - w
        if 0 <= k + 1 < n_samples:
            out[k + 1] += w
    return out
