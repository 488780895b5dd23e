"""Sound levels of a pressure record: LAeq, LAFmax, LCpeak and third-octave band levels.

Definitions (IEC 61672-1:2013, levels in dB re ``p0 = 20 uPa``):

* ``LAeq = 10 log10(mean(p_A^2) / p0^2)``, ``p_A`` the A-weighted pressure;
* ``LAFmax = max_t 10 log10(m_F(t) / p0^2)``, with the F ("fast") exponential time
  weighting ``m_F(t) = (1/tau) int p_A^2(xi) exp(-(t - xi)/tau) dxi``, ``tau = 0.125 s``
  (discretised as the exact step response of the first-order lag, starting at rest);
* ``LCpeak = 20 log10(max |p_C| / p0)``, ``p_C`` the C-weighted pressure;
* band level ``L_b = 10 log10(mean square in band b / p0^2)`` (IEC 61260-1 class-1
  third-octave bands, :func:`~rattle_lab.acoustics.band_mean_squares`).

The weightings are the standards' analog responses applied on FFT bins
(:mod:`rattle_lab.acoustics._filters`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._filters import apply_weightings, band_mean_squares

P_REF_PA = 20e-6
#: Time constant of the F (fast) time weighting, s (IEC 61672-1).
TAU_FAST_S = 0.125


def _db10(mean_square: float) -> float:
    return float(10.0 * np.log10(mean_square / P_REF_PA**2)) if mean_square > 0 else float("-inf")


@dataclass(frozen=True)
class SoundLevels:
    """Levels of one stretch of a pressure record (a run, a rattle episode, the background).

    Attributes
    ----------
    laeq_db : float
        A-weighted equivalent continuous level, ``10 log10(mean(p_A^2)/p0^2)``, dB.
    lafmax_db : float
        Largest A-weighted, F-time-weighted level (``tau = 0.125 s``), dB.
    lcpeak_db : float
        C-weighted peak level ``20 log10(max|p_C|/p0)``, dB.
    third_octave_db : dict of str to float
        Nominal mid-band frequency in Hz (``"31.5"``, ``"1000"``) -> unweighted band
        level, dB (bands that the record cannot resolve are absent).
    duration_s : float
        Length of the stretch, s.
    """

    laeq_db: float
    lafmax_db: float
    lcpeak_db: float
    third_octave_db: dict[str, float] = field(default_factory=dict)
    duration_s: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (JSON-ready apart from non-finite floats)."""
        return {"laeq_db": self.laeq_db, "lafmax_db": self.lafmax_db,
                "lcpeak_db": self.lcpeak_db, "third_octave_db": dict(self.third_octave_db),
                "duration_s": self.duration_s}

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> SoundLevels:
        """Inverse of :meth:`to_dict` (``None`` read as NaN)."""
        def num(v: Any) -> float:
            return float("nan") if v is None else float(v)
        return cls(num(d["laeq_db"]), num(d["lafmax_db"]), num(d["lcpeak_db"]),
                   {k: num(v) for k, v in d.get("third_octave_db", {}).items()},
                   num(d.get("duration_s", 0.0)))


def fast_time_weighted(mean_square_in: np.ndarray, fs_hz: float,
                       tau_s: float = TAU_FAST_S) -> np.ndarray:
    """Exponential time weighting of a squared signal: ``y[n] = a y[n-1] + (1 - a) x[n]``.

    ``a = exp(-1 / (fs tau))``: the sampled first-order lag of IEC 61672-1, from rest.
    """
    from scipy import signal   # here: scipy.signal costs about 1 s to import

    a = float(np.exp(-1.0 / (fs_hz * tau_s)))
    return signal.lfilter([1.0 - a], [1.0, -a], np.asarray(mean_square_in, dtype=float))


def sound_levels(pressure_pa: object, fs_hz: float, *, bands: bool = True) -> SoundLevels:
    """LAeq, LAFmax, LCpeak and third-octave band levels of a pressure signal.

    Parameters
    ----------
    pressure_pa : array_like
        Calibrated sound pressure, Pa.
    fs_hz : float
        Sampling rate, Hz.
    bands : bool
        Compute the third-octave band levels (20 Hz .. 20 kHz, those below Nyquist).

    Returns
    -------
    SoundLevels

    Raises
    ------
    ParameterError
        For a non-positive ``fs_hz``, an empty or non-finite signal.

    Examples
    --------
    >>> import numpy as np
    >>> fs = 48000.0
    >>> t = np.arange(int(fs)) / fs
    >>> p = np.sqrt(2) * 1.0 * np.sin(2 * np.pi * 1000 * t)  # 1 Pa rms: 93.98 dB
    >>> lv = sound_levels(p, fs)
    >>> round(lv.laeq_db, 2), round(lv.third_octave_db["1000"], 2)
    (93.98, 93.98)
    """
    return levels_and_bands(pressure_pa, fs_hz, bands=bands)[0]


def levels_and_bands(pressure_pa: object, fs_hz: float, *, bands: bool = True
                     ) -> tuple[SoundLevels, dict[str, float]]:
    """:func:`sound_levels` and the third-octave bands' mean squares it took its band levels
    from (:func:`~rattle_lab.acoustics.band_mean_squares`, Pa^2; empty without ``bands``):
    what pools the bands of several stretches, without their transforms again."""
    lv, ms, _ = levels_bands_fast(pressure_pa, fs_hz, bands=bands)
    return lv, ms


def levels_bands_fast(pressure_pa: object, fs_hz: float, *, bands: bool = True
                      ) -> tuple[SoundLevels, dict[str, float], np.ndarray]:
    """:func:`levels_and_bands` and the F-weighted A mean square ``m_F(t)`` (Pa^2, one value
    per sample) that LAFmax is the largest of: what ``L_AF`` of the impulsiveness rating
    is sampled from (:func:`~rattle_lab.acoustics.laf_db`), without the weighting again."""
    p = np.asarray(pressure_pa, dtype=float)
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ParameterError(f"`fs_hz` must be > 0, was {fs_hz}")
    if p.ndim != 1 or p.size == 0 or not np.all(np.isfinite(p)):
        raise ParameterError("`pressure_pa` must be a non-empty 1-D finite signal")
    p_a, p_c = apply_weightings(p, fs_hz, ("A", "C"))
    laeq = _db10(float(np.mean(p_a**2)))
    fast_a = fast_time_weighted(p_a**2, fs_hz)
    lafmax = _db10(float(np.max(fast_a)))
    peak = float(np.max(np.abs(p_c)))
    lcpeak = float(20.0 * np.log10(peak / P_REF_PA)) if peak > 0 else float("-inf")
    ms = band_mean_squares(p, fs_hz) if bands else {}
    third = {k: _db10(v) for k, v in ms.items()}
    return SoundLevels(laeq, lafmax, lcpeak, third, p.size / fs_hz), ms, fast_a


def rattle_episodes(impact_t_s: object, *, start_time_s: float, duration_s: float,
                    gap_s: float = 0.5, tail_s: float = 0.05) -> list[tuple[float, float]]:
    """Stretches of a run with rattle: impacts closer than ``gap_s`` form one episode.

    An episode runs from its first impact to its last impact plus ``tail_s`` (the
    ring-down of the last impact's sound), cut at the run's end.

    Returns
    -------
    list of (t_start_s, t_end_s)
    """
    t = np.sort(np.atleast_1d(np.asarray(impact_t_s, dtype=float)))
    t = t[np.isfinite(t)]
    end_run = start_time_s + duration_s
    out: list[tuple[float, float]] = []
    if t.size == 0:
        return out
    breaks = np.flatnonzero(np.diff(t) > gap_s)
    starts = np.concatenate([[0], breaks + 1])
    stops = np.concatenate([breaks, [t.size - 1]])
    for i, j in zip(starts, stops):
        lo, hi = max(float(t[i]), start_time_s), min(float(t[j]) + tail_s, end_run)
        if hi > lo:
            out.append((lo, hi))
    return out


__all__ = ["P_REF_PA", "SoundLevels", "TAU_FAST_S", "fast_time_weighted", "levels_and_bands",
           "levels_bands_fast", "rattle_episodes", "sound_levels"]


def energy_mean_db(levels_db: object) -> float:
    """Energy (power) mean of levels: ``10 log10(mean(10^(L/10)))``, dB on the levels' reference.

    Examples
    --------
    >>> round(energy_mean_db([60.0, 60.0]), 6), round(energy_mean_db([70.0, 0.0]), 3)
    (60.0, 66.99)
    """
    levels = np.asarray(levels_db, dtype=float)
    if levels.size == 0:
        raise ParameterError("`levels_db` must hold at least one level")
    return float(10 * np.log10(np.mean(10 ** (levels / 10))))
