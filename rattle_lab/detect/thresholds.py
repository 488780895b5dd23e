"""Impact onset thresholds from amplitude-ramp runs (thesis Fig. 6-3).

The excitation amplitude is measured, not taken from the nominal command: the
base acceleration is demodulated at the run's excitation frequency (lock-in:
``z(t) = lowpass(x(t) exp(-2 pi i f t))``, amplitude ``2 |z|``), with a
zero-phase Butterworth low-pass.  On an upward ramp the threshold is the
amplitude at the first impact of the first sustained group (``n_confirm``
further impacts, each within ``max_gap_cycles`` forcing periods of the last);
on a downward ramp, at the last impact of the last sustained group.  A threshold whose
impact lies within ``edge_cycles`` forcing periods of the record's start (up) or end (down)
is *censored*: impact was already there when the record began, or still there when it
ended, so the level where it appears or disappears was not seen (NaN, ``censored=True``).

The ramp itself is measured too: a straight line fitted to the envelope gives the levels at
the record's start and end and the RMS deviation from the line (fan beats, noise, a ramp
that is not straight).  The ramp-model fits of :mod:`rattle_lab.fit` replay that measured
ramp through the exact simulator.

Below resonance the impacting near grazing is intermittent: an impact takes energy out
of the mode, which regrows over a few time constants ``1 / (zeta omega_s)`` (~20 forcing
cycles at ``zeta = 0.0085``) before it reaches the gap again, so impacts that belong
together can be tens of cycles apart.  The group criterion is there to reject isolated
false triggers, not to wait for impacts in every cycle: the default gap is 100 cycles.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from rattle_lab.detect._common import as_signal
from rattle_lab.exceptions import ParameterError

__all__ = ["Direction", "Threshold", "ThresholdCurve", "GAP_IMPACTS", "fundamental_amplitude",
           "sustained_impact_time", "ramp_line", "ramp_threshold", "impact_gap_cycles",
           "threshold_uncertainty_ms2", "crossing_level_ms2", "tabulate_thresholds"]

Direction = Literal["up", "down"]


def fundamental_amplitude(x: object, fs_hz: float, freq_hz: float, *,
                          lowpass_hz: float | None = None, order: int = 4) -> np.ndarray:
    """Amplitude envelope of ``x`` at ``freq_hz`` by quadrature demodulation (lock-in).

    ``lowpass_hz`` defaults to ``freq_hz / 20``: narrow enough to reject a tone a few Hz
    away (a fan at 88 Hz beats at 8 Hz against 96 Hz and moved the amplitude by its own
    0.05 m/s^2 with ``freq_hz / 5``), and free on ramps: the zero-phase filter passes a
    linear ramp unchanged, so only level changes faster than ``lowpass_hz`` are smoothed.
    Units as ``x``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(20000) / 10000.0
    >>> amp = fundamental_amplitude(3.0 * np.sin(2 * np.pi * 100 * t) + np.sin(2 * np.pi * 300 * t),
    ...                             10000.0, 100.0)
    >>> bool(np.allclose(amp[5000:15000], 3.0, rtol=1e-3))
    True
    """
    xs = as_signal(x, "x")
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ParameterError(f"`fs_hz` must be > 0, was {fs_hz}")
    if not (np.isfinite(freq_hz) and 0 < freq_hz < fs_hz / 2):
        raise ParameterError(f"`freq_hz` must be in (0, fs_hz/2 = {fs_hz / 2}), was {freq_hz}")
    cutoff = freq_hz / 20.0 if lowpass_hz is None else lowpass_hz
    if not 0 < cutoff < fs_hz / 2:
        raise ParameterError(f"`lowpass_hz` must be in (0, fs_hz/2), was {cutoff}")
    t = np.arange(xs.size) / fs_hz
    z = xs * np.exp(-2j * np.pi * freq_hz * t)
    from scipy import signal   # here: scipy.signal costs about 1 s to import

    sos = signal.butter(order, cutoff, fs=fs_hz, output="sos")
    if xs.size <= 3 * (2 * sos.shape[0] + 1):
        raise ParameterError(f"`x` has {xs.size} samples, too few for the low-pass")
    # the straight-line trend of z is taken out before the filter and put back after (a
    # zero-phase filter passes a line unchanged); the rest is padded by even extension over
    # a few filter time constants, so a ramp does not ring at the ends of the record
    pad = min(xs.size - 1, 3 * round(fs_hz / cutoff))
    u = np.linspace(-1.0, 1.0, xs.size)
    trend = np.polynomial.polynomial.polyfit(u, np.column_stack([z.real, z.imag]), 1)
    line = trend[0] + np.outer(u, trend[1])
    rest = np.column_stack([z.real, z.imag]) - line
    filt = signal.sosfiltfilt(sos, rest, axis=0, padtype="even", padlen=pad) + line
    zf = filt[:, 0] + 1j * filt[:, 1]
    return 2.0 * np.abs(zf)


def sustained_impact_time(impact_t_s: object, freq_hz: float, direction: Direction, *,
                          n_confirm: int = 3, max_gap_cycles: float = 100.0) -> float:
    """Time of the first (``"up"``) / last (``"down"``) impact of a sustained group; NaN if none.

    A group is ``n_confirm + 1`` impacts, each within ``max_gap_cycles`` forcing periods of
    the previous one.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.r_[0.05, np.arange(2.0, 2.1, 0.01)]   # a stray hit 195 cycles early, then a group
    >>> float(sustained_impact_time(t, 100.0, "up"))
    2.0
    >>> t = np.r_[1.0, 1.3, 1.5, 1.55, np.arange(1.6, 1.7, 0.01)]   # intermittent, then every cycle
    >>> float(sustained_impact_time(t, 100.0, "up"))
    1.0
    """
    if direction not in ("up", "down"):
        raise ParameterError(f"`direction` must be 'up' or 'down', was {direction!r}")
    t = np.sort(np.atleast_1d(np.asarray(impact_t_s, dtype=float)))
    if direction == "down":
        t = -t[::-1]
    gap = max_gap_cycles / freq_hz
    for i in range(t.size - n_confirm):
        if np.all(np.diff(t[i:i + n_confirm + 1]) <= gap):
            return float(abs(t[i]))
    return float("nan")


@dataclass(frozen=True)
class Threshold:
    """The measured threshold of one ramp run.

    Attributes
    ----------
    run_id : str
    freq_hz : float
        Excitation frequency, Hz.
    direction : {"up", "down"}
        Ramp direction: appearance (up) or disappearance (down) of impact.
    accel_ms2 : float
        Base-acceleration amplitude at the fundamental at that instant, m/s^2
        (NaN when impact never appeared / never stopped in the run).
    t_s : float
        Time of the threshold impact, s (NaN when censored or not seen).
    ramp_start_ms2, ramp_end_ms2 : float
        The measured ramp: a least-squares line through the base-acceleration envelope,
        evaluated at the record's start and end, m/s^2 (NaN when not measured).
    ramp_duration_s : float
        Record length ``n_samples / fs_hz`` over which the line runs, s.
    ramp_rms_ms2 : float
        RMS deviation of the envelope from that line, m/s^2 (away from the filter's edges).
    censored : bool
        True when the threshold impact lies within ``edge_cycles`` forcing periods of the
        record's start (up) or end (down): the level where impact appears or disappears
        lies outside the ramp, and ``accel_ms2`` is NaN.
    impact_gap_cycles : float
        Mean interval between the impacts next to the threshold (up to
        :data:`GAP_IMPACTS` of them, after the onset or before the disappearance), in
        forcing periods: 1 where the motion impacts once a cycle, more where it is
        intermittent (an irregular regime).  NaN when not measured.
    """

    run_id: str
    freq_hz: float
    direction: Direction
    accel_ms2: float
    t_s: float
    ramp_start_ms2: float = float("nan")
    ramp_end_ms2: float = float("nan")
    ramp_duration_s: float = float("nan")
    ramp_rms_ms2: float = float("nan")
    censored: bool = False
    impact_gap_cycles: float = float("nan")

    @property
    def ramp_rate_ms2_s(self) -> float:
        """Slope of the measured ramp, m/s^3: ``(ramp_end - ramp_start) / ramp_duration_s``."""
        return (self.ramp_end_ms2 - self.ramp_start_ms2) / self.ramp_duration_s


def ramp_line(envelope_ms2: object, fs_hz: float, *, edge_s: float = 0.0
              ) -> tuple[float, float, float, float]:
    """Straight line through a ramp's envelope: ``(start, end, duration_s, rms)``.

    The line is fitted (least squares) to the samples at least ``edge_s`` from either end
    (all of them when the record is shorter than ``4 edge_s``), away from the lock-in
    filter's edge transients; ``start`` and ``end`` are its values at the first sample and
    at ``n / fs_hz`` (the end of the record), units of the envelope; ``rms`` is the RMS
    deviation of those samples from it.

    Raises
    ------
    ParameterError
        With fewer than 2 samples or ``fs_hz <= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> start, end, dur, rms = ramp_line(16.0 - 4.0 * np.arange(3000) / 1000.0, 1000.0)
    >>> bool(np.allclose([start, end, dur], [16.0, 4.0, 3.0]) and rms < 1e-9)
    True
    """
    env = np.asarray(envelope_ms2, dtype=float).ravel()
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ParameterError(f"`fs_hz` must be > 0, was {fs_hz}")
    if env.size < 2:
        raise ParameterError(f"`envelope_ms2` needs >= 2 samples, had {env.size}")
    t = np.arange(env.size) / fs_hz
    duration = env.size / fs_hz
    n_edge = round(edge_s * fs_hz)
    core = slice(n_edge, env.size - n_edge) if env.size > 4 * n_edge else slice(None)
    slope, intercept = np.polyfit(t[core], env[core], 1)
    rms = float(np.sqrt(np.mean((env[core] - (intercept + slope * t[core])) ** 2)))
    return float(intercept), float(intercept + slope * duration), float(duration), rms


def ramp_threshold(run_id: str, base_accel_ms2: object, fs_hz: float, freq_hz: float,
                   impact_t_s: object, direction: Direction, *, start_time_s: float = 0.0,
                   n_confirm: int = 3, max_gap_cycles: float = 100.0,
                   lowpass_hz: float | None = None, edge_cycles: float = 2.0) -> Threshold:
    """Threshold of one ramp run from its base acceleration and detected impacts.

    Parameters
    ----------
    run_id : str
        Name carried into the result.
    base_accel_ms2 : array
        Base acceleration, m/s^2, sampled at ``fs_hz`` from ``start_time_s``.
    fs_hz, freq_hz : float
        Sample rate and excitation frequency, Hz.
    impact_t_s : array
        Detected impact times, s (same clock as ``start_time_s``).
    direction : {"up", "down"}
        Ramp direction.
    n_confirm, max_gap_cycles
        The sustained-group criterion of :func:`sustained_impact_time`.
    lowpass_hz : float, optional
        Lock-in low-pass (:func:`fundamental_amplitude`).
    edge_cycles : float
        A threshold impact within this many forcing periods of the record's start (up) or
        end (down) is censored (NaN, ``censored=True``).

    Returns
    -------
    Threshold
        With the measured ramp (:func:`ramp_line` of the envelope) whenever impacts were
        found.

    Raises
    ------
    ParameterError
        For an invalid signal, rate, frequency or direction.
    """
    t_thr = sustained_impact_time(impact_t_s, freq_hz, direction, n_confirm=n_confirm,
                                  max_gap_cycles=max_gap_cycles)
    if not np.isfinite(t_thr):
        return Threshold(run_id, float(freq_hz), direction, float("nan"), float("nan"))
    amp = fundamental_amplitude(base_accel_ms2, fs_hz, freq_hz, lowpass_hz=lowpass_hz)
    cutoff = freq_hz / 20.0 if lowpass_hz is None else lowpass_hz
    start, end, duration, rms = ramp_line(amp, fs_hz, edge_s=1.0 / cutoff)
    ramp: dict[str, Any] = dict(ramp_start_ms2=start, ramp_end_ms2=end, ramp_duration_s=duration,
                ramp_rms_ms2=rms)
    cycles_from_edge = ((t_thr - start_time_s) if direction == "up"
                        else (start_time_s + duration - t_thr)) * freq_hz
    if cycles_from_edge < edge_cycles:
        return Threshold(run_id, float(freq_hz), direction, float("nan"), float("nan"),
                         censored=True, **ramp)
    x = (t_thr - start_time_s) * fs_hz
    value = float(np.interp(x, np.arange(amp.size), amp))
    return Threshold(run_id, float(freq_hz), direction, value, t_thr, **ramp,
                     impact_gap_cycles=impact_gap_cycles(impact_t_s, t_thr, freq_hz, direction))


#: Impacts next to a threshold whose mean interval measures how regular the motion is there.
GAP_IMPACTS = 10


def impact_gap_cycles(impact_t_s: object, t_threshold_s: float, freq_hz: float,
                      direction: Direction) -> float:
    """Mean interval, in forcing periods, between the :data:`GAP_IMPACTS` impacts from the
    threshold impact on (up) or up to it (down); NaN with fewer than two.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.r_[np.arange(1.0, 1.2, 0.01), np.arange(1.2, 2.0, 0.05)]   # 100 Hz: 1 then 5 cycles
    >>> round(float(impact_gap_cycles(t, 1.0, 100.0, "up")), 6)
    1.0
    >>> round(float(impact_gap_cycles(t, t[-1], 100.0, "down")), 6)
    5.0
    """
    t = np.sort(np.atleast_1d(np.asarray(impact_t_s, dtype=float)))
    side = t[t >= t_threshold_s][:GAP_IMPACTS] if direction == "up" \
        else t[t <= t_threshold_s][-GAP_IMPACTS:]
    if side.size < 2:
        return float("nan")
    return float((side[-1] - side[0]) / (side.size - 1) * freq_hz)


@dataclass(frozen=True)
class ThresholdCurve:
    """Thresholds against frequency, with the hysteresis (thesis Fig. 6-3).

    Attributes
    ----------
    freq_hz : ndarray
        Sorted unique excitation frequencies, Hz.
    up_ms2, down_ms2 : ndarray
        Appearance / disappearance thresholds (mean over runs at that frequency), m/s^2; NaN if none.
    hysteresis_ms2 : ndarray
        ``up_ms2 - down_ms2``, m/s^2.
    up_se_ms2, down_se_ms2 : ndarray
        Standard uncertainties of ``up_ms2`` and ``down_ms2``, m/s^2
        (:func:`threshold_uncertainty_ms2`, combined over the runs at a frequency); NaN where
        not known.  Empty when built without them.
    """

    freq_hz: np.ndarray
    up_ms2: np.ndarray
    down_ms2: np.ndarray
    hysteresis_ms2: np.ndarray
    up_se_ms2: np.ndarray = field(default_factory=lambda: np.zeros(0))
    down_se_ms2: np.ndarray = field(default_factory=lambda: np.zeros(0))


def threshold_uncertainty_ms2(th: Threshold) -> float:
    """Standard uncertainty of one ramp's threshold level, m/s^2 (NaN without a measured ramp).

    Two independent parts, added in quadrature:

    * *which cycle*: impacts come at most once a forcing period, so the threshold impact
      fixes the crossing only to within the interval to its neighbours, and near a
      threshold in an irregular (chaotic) regime the first (up) or last (down) impact of
      the sustained group moves by such intervals with last-bit differences of the
      simulated or measured record (another libm, another BLAS).  The level change over
      that interval, ``max(1, impact_gap_cycles) |rate| / f``, is taken as the standard
      uncertainty (a uniform instant within one period alone would give
      ``|rate| / (f sqrt 12)``);
    * *the level*: the envelope's RMS scatter about the measured ramp line
      (:attr:`Threshold.ramp_rms_ms2`).

    Examples
    --------
    >>> th = Threshold("r", 100.0, "up", 10.0, 1.0, ramp_start_ms2=5.0, ramp_end_ms2=15.0,
    ...                ramp_duration_s=2.0, ramp_rms_ms2=0.03)
    >>> round(threshold_uncertainty_ms2(th), 6)   # hypot(5 m/s^3 / 100 Hz, 0.03)
    0.05831
    """
    rate = th.ramp_rate_ms2_s
    if not (np.isfinite(th.accel_ms2) and np.isfinite(rate) and th.freq_hz > 0):
        return float("nan")
    rms = th.ramp_rms_ms2 if np.isfinite(th.ramp_rms_ms2) else 0.0
    gap = max(1.0, th.impact_gap_cycles) if np.isfinite(th.impact_gap_cycles) else 1.0
    return float(np.hypot(gap * abs(rate) / th.freq_hz, rms))


def crossing_level_ms2(th: Threshold) -> float:
    """The level at which a ramp crossed its threshold, from the impact that showed it.

    Impacts come at most once a forcing period: the first impact of an upward ramp shows
    that the threshold was crossed at some instant of the period before it, and the last
    impact of a downward ramp that it is crossed in the period after it.  Without more
    information that instant is uniform over the period, so its expected level is half a
    period's ramp change before (up) or after (down) the impact's: ``accel_ms2 -+ rate /
    (2 f)``.  The impact's own level is biased by that much (up to a few % on a fast ramp).
    NaN without a measured ramp.
    """
    if not (np.isfinite(th.accel_ms2) and np.isfinite(th.ramp_start_ms2)
            and np.isfinite(th.ramp_end_ms2) and th.ramp_duration_s > 0 and th.freq_hz > 0):
        return float("nan")
    rate = (th.ramp_end_ms2 - th.ramp_start_ms2) / th.ramp_duration_s
    sign = -1.0 if th.direction == "up" else 1.0
    return float(th.accel_ms2 + sign * 0.5 * rate / th.freq_hz)


def tabulate_thresholds(thresholds: Sequence[Threshold]) -> ThresholdCurve:
    """Collect ramp thresholds into a curve against frequency.

    Several runs at one frequency and direction are averaged; the mean's standard
    uncertainty is the larger of the runs' own (:func:`threshold_uncertainty_ms2`, root sum
    of squares over ``n``) and their scatter (sample standard deviation over ``sqrt(n)``),
    either where the other is not known, NaN where neither is.
    """
    freqs = np.unique([t.freq_hz for t in thresholds]) if thresholds else np.zeros(0)
    up, down = np.full(freqs.size, np.nan), np.full(freqs.size, np.nan)
    up_se, down_se = np.full(freqs.size, np.nan), np.full(freqs.size, np.nan)
    for i, f in enumerate(freqs):
        for arr, se, d in ((up, up_se, "up"), (down, down_se, "down")):
            runs = [t for t in thresholds if t.freq_hz == f and t.direction == d
                    and np.isfinite(t.accel_ms2)]
            if runs:
                vals = np.array([t.accel_ms2 for t in runs])
                arr[i] = float(np.mean(vals))
                own = np.array([threshold_uncertainty_ms2(t) for t in runs])
                parts = [float(np.sqrt(np.sum(own**2)) / vals.size),
                         float(np.std(vals, ddof=1) / np.sqrt(vals.size)) if vals.size > 1
                         else float("nan")]
                known = [p for p in parts if np.isfinite(p)]
                se[i] = max(known) if known else float("nan")
    return ThresholdCurve(freqs, up, down, up - down, up_se, down_se)
