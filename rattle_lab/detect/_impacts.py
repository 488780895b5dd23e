"""Impact detection (ObsPy trigger design: characteristic function, on/off, back-track).

1. Characteristic functions, each in units of its own robust noise (1.4826 MAD):
   the velocity jump ``|dv - smooth(dv)|`` (smooth: a local cubic) between consecutive samples of the
   vibrometer, placed at the later sample, and the spike ``|a - smooth(a)|``
   of the plate accelerometer.  With both channels the mean of the two is
   used (a true impact shows in both; a glitch in one channel is halved).
2. Trigger on where the function exceeds ``on``, off where it falls below
   ``off``; a trigger closer than ``min_separation_s`` to the previous peak
   is merged into it.
3. Back-track from the peak to the onset (the last sample above ``off``).
4. Sub-sample time: the centroid of the velocity jump (or of the spike when
   there is no velocity) over the samples above half the peak.
5. Incoming and rebound velocities: polynomial fits (degree ``poly_degree``)
   to the velocity over ``fit_window_s`` before and after the jump (its
   half-height region, widened by ``guard_s``), each evaluated at the impact
   time; ``e = -v_out / v_in``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..exceptions import ParameterError
from ._common import as_signal, detrended_abs, n_samples_of, robust_sigma


@dataclass(frozen=True)
class ImpactParams:
    """Parameters of :func:`detect_impacts` (seconds and SI units).

    Attributes
    ----------
    on, off : float
        Trigger on / off levels of the characteristic function, in robust
        noise units (``on > off > 0``).
    min_separation_s : float
        Triggers closer than this to the previous peak belong to it, s.
    detrend_window_s : float
        Window of the local cubic (Savitzky-Golay) removed from the characteristic
        functions, s; must span several samples more than a contact pulse.
    fit_window_s : float
        Length of the velocity fits on either side of an impact, s.
    guard_s : float
        Extra time left out between the trigger and each fit window, s.
    poly_degree : int
        Degree of the velocity fits (0 to 3).
    sigma_floor_rel : float
        Lower bound of the noise unit, relative to the largest ``|sample|`` of the
        channel, so that noiseless records do not trigger on rounding and
        curvature residue (>= 0).
    """

    on: float = 12.0
    off: float = 4.0
    min_separation_s: float = 2e-3
    detrend_window_s: float = 1e-3
    fit_window_s: float = 1e-3
    guard_s: float = 0.0
    poly_degree: int = 2
    sigma_floor_rel: float = 1e-4

    def __post_init__(self) -> None:
        if not (np.isfinite(self.off) and self.off > 0):
            raise ParameterError(f"`off` must be > 0, was {self.off}")
        if not (np.isfinite(self.on) and self.on > self.off):
            raise ParameterError(f"`on` must be > `off` ({self.off}), was {self.on}")
        for name in ("min_separation_s", "detrend_window_s", "fit_window_s", "guard_s",
                     "sigma_floor_rel"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"`{name}` must be >= 0, was {value}")
        if self.poly_degree not in (0, 1, 2, 3):
            raise ParameterError(f"`poly_degree` must be 0, 1, 2 or 3, was {self.poly_degree}")


@dataclass(frozen=True)
class ImpactLog:
    """Impacts found in one run (arrays of equal length, one entry per impact).

    Attributes
    ----------
    t_s : ndarray
        Impact time (sub-sample), s from the first sample of the input (plus ``start_time_s``).
    onset_s : ndarray
        Back-tracked onset (first sample above ``off``), s.
    v_in_m_s : ndarray
        Incoming velocity: velocity fit before the impact evaluated at ``t_s``, m/s (NaN without velocity).
    v_out_m_s : ndarray
        Rebound velocity: fit after the impact at ``t_s``, m/s (NaN without velocity).
    e : ndarray
        Coefficient of restitution per impact, ``-v_out / v_in``, nondimensional.
    strength : ndarray
        Peak of the characteristic function, in noise units.
    channels : tuple of str
        Channels used: ``("velocity",)``, ``("acceleration",)`` or both.
    params : ImpactParams
        The parameters used.
    fs_hz : float
        Sample rate, Hz.
    """

    t_s: np.ndarray
    onset_s: np.ndarray
    v_in_m_s: np.ndarray
    v_out_m_s: np.ndarray
    e: np.ndarray
    strength: np.ndarray
    channels: tuple[str, ...]
    params: ImpactParams = field(default_factory=ImpactParams)
    fs_hz: float = float("nan")

    @property
    def n_impacts(self) -> int:
        """Number of impacts."""
        return int(self.t_s.size)


def characteristic(x: np.ndarray, sigma_floor: float, n_detrend: int, *, jump: bool) -> np.ndarray:
    """Characteristic function in robust noise units (``jump``: of the first difference)."""
    if jump:
        d = np.diff(x)
        cf = np.concatenate([[0.0], detrended_abs(d, n_detrend)])
    else:
        cf = detrended_abs(x, n_detrend)
    sigma = max(robust_sigma(cf), sigma_floor)
    if sigma == 0.0:
        return np.zeros_like(cf)
    return cf / sigma


def trigger_onsets(cf: np.ndarray, on: float, off: float, n_min_sep: int
                   ) -> list[tuple[int, int, int]]:
    """``(onset, peak, end)`` sample indices of the triggers of ``cf`` (inclusive end).

    Examples
    --------
    >>> import numpy as np
    >>> cf = np.array([0, 1, 5, 20, 6, 1, 0, 0, 0, 0, 30, 2, 0], dtype=float)
    >>> trigger_onsets(cf, 10.0, 3.0, 2)
    [(2, 3, 4), (10, 10, 10)]
    """
    above_on = np.flatnonzero(cf > on)
    out: list[tuple[int, int, int]] = []
    i = 0
    while i < above_on.size:
        k = int(above_on[i])
        start = k
        while start > 0 and cf[start - 1] > off:  # back-track to the onset
            start -= 1
        end = k
        while end + 1 < cf.size and cf[end + 1] > off:
            end += 1
        peak = start + int(np.argmax(cf[start:end + 1]))
        if out and peak - out[-1][1] < n_min_sep:
            prev = out[-1]
            merged_peak = prev[1] if cf[prev[1]] >= cf[peak] else peak
            out[-1] = (prev[0], merged_peak, max(end, prev[2]))
        else:
            out.append((start, peak, end))
        i = int(np.searchsorted(above_on, end + 1))
    return out


def _half_region(cf: np.ndarray, peak: int) -> tuple[int, int]:
    """The contiguous samples around ``peak`` above half its height (inclusive)."""
    half = 0.5 * cf[peak]
    lo = peak
    while lo > 0 and cf[lo - 1] > half:
        lo -= 1
    hi = peak
    while hi + 1 < cf.size and cf[hi + 1] > half:
        hi += 1
    return lo, hi


def _centroid(cf: np.ndarray, peak: int, offset: float) -> float:
    """Centroid index of the samples around ``peak`` above half its height."""
    lo, hi = _half_region(cf, peak)
    idx = np.arange(lo, hi + 1, dtype=float)
    w = cf[lo:hi + 1]
    return float(np.sum(idx * w) / np.sum(w)) + offset


def _fit_at(t: np.ndarray, v: np.ndarray, t0: float, degree: int) -> float:
    if t.size == 0:
        return float("nan")
    deg = min(degree, t.size - 1)
    coef = np.polyfit(t - t0, v, deg)
    return float(coef[-1])


def detect_impacts(fs_hz: float, *, velocity_m_s: object = None, accel_ms2: object = None,
                   params: ImpactParams | None = None, start_time_s: float = 0.0) -> ImpactLog:
    """Find impacts in a vibrometer velocity and/or plate acceleration record.

    Parameters
    ----------
    fs_hz : float
        Sample rate of both channels, Hz.
    velocity_m_s : array, optional
        Plate velocity, m/s.
    accel_ms2 : array, optional
        Plate acceleration, m/s^2 (same length as ``velocity_m_s`` when both are given).
    params : ImpactParams, optional
        Detector parameters.
    start_time_s : float
        Time of the first sample, s.

    Returns
    -------
    ImpactLog
        Possibly empty (a run without impacts is a valid result).

    Raises
    ------
    ParameterError
        Without any channel, with channels of different lengths, or non-finite samples.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.r_[np.full(100, -0.1), np.full(100, 0.08)]
    >>> log = detect_impacts(10000.0, velocity_m_s=v)
    >>> log.n_impacts, bool(np.isclose(log.t_s[0], 0.00995)), bool(np.isclose(log.e[0], 0.8))
    (1, True, True)
    """
    params = params if params is not None else ImpactParams()
    if velocity_m_s is None and accel_ms2 is None:
        raise ParameterError("detect_impacts needs `velocity_m_s` or `accel_ms2` (got neither)")
    n_detrend = n_samples_of(params.detrend_window_s, fs_hz, name="detrend_window_s")
    cfs: list[np.ndarray] = []
    names: list[str] = []
    v = a = None
    if velocity_m_s is not None:
        v = as_signal(velocity_m_s, "velocity_m_s")
        floor = params.sigma_floor_rel * float(np.max(np.abs(v), initial=0.0))
        cfs.append(characteristic(v, floor, n_detrend, jump=True))
        names.append("velocity")
    if accel_ms2 is not None:
        a = as_signal(accel_ms2, "accel_ms2")
        if v is not None and a.size != v.size:
            raise ParameterError(f"`accel_ms2` has {a.size} samples, `velocity_m_s` {v.size}")
        floor = params.sigma_floor_rel * float(np.max(np.abs(a), initial=0.0))
        cfs.append(characteristic(a, floor, n_detrend, jump=False))
        names.append("acceleration")
    cf = cfs[0] if len(cfs) == 1 else 0.5 * (cfs[0] + cfs[1])
    n_sep = n_samples_of(params.min_separation_s, fs_hz, name="min_separation_s")
    trig = trigger_onsets(cf, params.on, params.off, n_sep)
    n_fit = max(n_samples_of(params.fit_window_s, fs_hz, name="fit_window_s"), params.poly_degree + 1)
    n_guard = n_samples_of(params.guard_s, fs_hz, name="guard_s")
    t_idx, onsets, v_in, v_out, strength = [], [], [], [], []
    for j, (start, peak, end) in enumerate(trig):
        j_lo, j_hi = start, end
        if v is not None:
            # The jump of v[k-1] -> v[k] is at cf index k, i.e. between samples k-1 and k.
            pk = start + int(np.argmax(cfs[0][start:end + 1]))
            t_k = _centroid(cfs[0], pk, -0.5)
            j_lo, j_hi = _half_region(cfs[0], pk)
        else:
            t_k = _centroid(cf, peak, 0.0)
        t_idx.append(t_k)
        onsets.append(start)
        strength.append(float(cf[peak]))
        if v is None:
            v_in.append(np.nan)
            v_out.append(np.nan)
            continue
        lo_lim = trig[j - 1][2] + 1 if j > 0 else 0
        hi_lim = trig[j + 1][0] - 1 if j + 1 < len(trig) else v.size - 1
        # the fits stop at the jump (half-height region of the velocity jump, plus the guard),
        # not at the trigger's off level, which the detrending side lobes widen
        pre_hi = j_lo - 1 - n_guard
        pre_lo = max(lo_lim, pre_hi - n_fit + 1)
        post_lo = j_hi + n_guard
        post_hi = min(hi_lim, post_lo + n_fit - 1)
        ti = np.arange(v.size, dtype=float)
        v_in.append(_fit_at(ti[pre_lo:pre_hi + 1], v[pre_lo:pre_hi + 1], t_k, params.poly_degree)
                    if pre_hi >= pre_lo else np.nan)
        v_out.append(_fit_at(ti[post_lo:post_hi + 1], v[post_lo:post_hi + 1], t_k, params.poly_degree)
                     if post_hi >= post_lo else np.nan)
    vin = np.asarray(v_in, dtype=float)
    vout = np.asarray(v_out, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.where(vin != 0, -vout / vin, np.nan)
    return ImpactLog(t_s=start_time_s + np.asarray(t_idx, dtype=float) / fs_hz,
                     onset_s=start_time_s + np.asarray(onsets, dtype=float) / fs_hz,
                     v_in_m_s=vin, v_out_m_s=vout, e=e, strength=np.asarray(strength, dtype=float),
                     channels=tuple(names), params=params, fs_hz=float(fs_hz))
