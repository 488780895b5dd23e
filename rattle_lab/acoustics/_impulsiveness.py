"""Prominence of impulsive sound and the adjustment to LAeq (ISO/PAS 1996-3:2022, NT ACOU 112).

The method reads the A-weighted, F-time-weighted level ``L_AF(t)`` (IEC 61672-1,
``tau = 0.125 s``) and finds its *onsets*: contiguous rising parts of ``L_AF`` whose
gradient exceeds 10 dB/s.  An onset starts where the gradient first exceeds 10 dB/s and
ends at the first point after it where the gradient falls below 10 dB/s; dips below
10 dB/s shorter than 50 ms do not end it.  For each onset

* level difference ``LD = L_AF(end) - L_AF(start)``, dB;
* onset rate ``OR = LD / (t_end - t_start)``, dB/s;
* predicted prominence ``P = 3 lg(OR / 1 dB/s) + 2 lg(LD / 1 dB)``;
* adjustment ``K_I = 1.8 (P - 5) dB`` for ``P > 5``, else 0.

A stretch of sound is rated by its most prominent onset (NT ACOU 112 rates the
prominent impulses; its ``K_I`` is the one added to LAeq).  ``LD`` and ``OR`` are
differences of levels, so ``P`` and ``K_I`` do not depend on the microphone's
sensitivity: an uncalibrated microphone still gives them.

The level is sampled every ``step_s`` (10 ms by default) after the exact sampled
first-order F weighting of the A-weighted square pressure; everything is a single pass
over the samples (FFT weighting, :func:`scipy.signal.lfilter`), then work on the
100 level samples per second only.

Reading of the 50 ms rule used here: a dip of the gradient shorter than 50 ms joins two
rising parts into one onset only when the level then rises past the onset's top so far.
A train of impacts (a rattle at 20 impacts/s or faster) then gives one onset while its
F-weighted level builds up from the background, and once the level plateaus each impact's
rise is an onset of its own; joining every short dip would stretch one onset over the
whole train and report a rate far below the rise that is heard.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._filters import apply_weighting
from ._levels import P_REF_PA, fast_time_weighted

#: Gradient above which ``L_AF`` is in an onset, dB/s.
ONSET_GRADIENT_DB_S = 10.0
#: Dips of the gradient shorter than this do not end an onset, s.
ONSET_GAP_S = 0.05
#: Sampling step of ``L_AF`` for the onsets, s.
ONSET_STEP_S = 0.01


def adjustment_db(prominence: float) -> float:
    """``K_I = 1.8 (P - 5)`` dB for ``P > 5``, else 0 (NaN for NaN).

    Examples
    --------
    >>> adjustment_db(4.0), round(adjustment_db(7.5), 6)
    (0.0, 4.5)
    """
    if not np.isfinite(prominence):
        return float("nan")
    return float(1.8 * (prominence - 5.0)) if prominence > 5.0 else 0.0


def prominence(onset_rate_db_s: float, level_difference_db: float) -> float:
    """``P = 3 lg(OR) + 2 lg(LD)`` (OR in dB/s, LD in dB); NaN unless both are > 0.

    Examples
    --------
    >>> round(prominence(100.0, 10.0), 6)   # 3 * 2 + 2 * 1
    8.0
    """
    if not (onset_rate_db_s > 0 and level_difference_db > 0):
        return float("nan")
    return float(3.0 * np.log10(onset_rate_db_s) + 2.0 * np.log10(level_difference_db))


@dataclass(frozen=True)
class Onsets:
    """The onsets of a stretch of ``L_AF``: arrays of equal length, one entry per onset.

    Attributes
    ----------
    t_start_s, t_end_s : ndarray
        Start and end of each onset, s (on the record's time axis).
    level_difference_db : ndarray
        ``LD``, dB.
    onset_rate_db_s : ndarray
        ``OR``, dB/s.
    prominence : ndarray
        ``P`` of each onset.
    """

    t_start_s: np.ndarray
    t_end_s: np.ndarray
    level_difference_db: np.ndarray
    onset_rate_db_s: np.ndarray
    prominence: np.ndarray

    def within(self, t0_s: float, t1_s: float) -> Onsets:
        """The onsets that start in ``[t0_s, t1_s)``."""
        sel = (self.t_start_s >= t0_s) & (self.t_start_s < t1_s)
        return Onsets(self.t_start_s[sel], self.t_end_s[sel], self.level_difference_db[sel],
                      self.onset_rate_db_s[sel], self.prominence[sel])

    def rating(self) -> dict[str, Any]:
        """``impulse_prominence`` (largest ``P``), ``impulse_penalty_db`` (its ``K_I``),
        ``impulse_onsets`` (number of onsets) and the ``LD``/``OR`` of the most prominent."""
        p = self.prominence
        ok = np.isfinite(p)
        if not ok.any():
            return {"impulse_prominence": float("nan"), "impulse_penalty_db": float("nan"),
                    "impulse_onsets": int(p.size), "impulse_level_difference_db": float("nan"),
                    "impulse_onset_rate_db_s": float("nan")}
        i = int(np.flatnonzero(ok)[np.argmax(p[ok])])
        return {"impulse_prominence": float(p[i]), "impulse_penalty_db": adjustment_db(p[i]),
                "impulse_onsets": int(p.size),
                "impulse_level_difference_db": float(self.level_difference_db[i]),
                "impulse_onset_rate_db_s": float(self.onset_rate_db_s[i])}


def laf_db(pressure_pa: object, fs_hz: float, step_s: float = ONSET_STEP_S, *,
           fast_a_ms: np.ndarray | None = None) -> np.ndarray:
    """``L_AF`` sampled every ``step_s`` (sample ``k`` at ``(k + 1) step_s - 1/fs``), dB re 20 uPa.

    The F weighting starts at rest; the first 0.5 s are its start-up (callers
    that rate onsets skip them: see :func:`find_onsets`).  ``fast_a_ms``: the record's
    F-weighted A mean square per sample, when already computed
    (:func:`~rattle_lab.acoustics._levels.levels_bands_fast`).
    """
    p = np.asarray(pressure_pa, dtype=float)
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ParameterError(f"`fs_hz` must be > 0, was {fs_hz}")
    if p.ndim != 1 or p.size == 0 or not np.all(np.isfinite(p)):
        raise ParameterError("`pressure_pa` must be a non-empty 1-D finite signal")
    hop = max(1, round(step_s * fs_hz))
    if fast_a_ms is None:
        fast_a_ms = fast_time_weighted(apply_weighting(p, fs_hz, "A") ** 2, fs_hz)
    elif fast_a_ms.shape != p.shape:
        raise ParameterError(f"`fast_a_ms` has {fast_a_ms.size} samples, the record {p.size}")
    m = fast_a_ms[hop - 1::hop]
    floor = (P_REF_PA * 1e-6) ** 2   # -120 dB: a digital silence has a level
    return np.asarray(10.0 * np.log10(np.maximum(m, floor) / P_REF_PA**2))


def find_onsets(pressure_pa: object, fs_hz: float, *, start_time_s: float = 0.0,
                step_s: float = ONSET_STEP_S, settle_s: float = 0.5,
                fast_a_ms: np.ndarray | None = None) -> Onsets:
    """The onsets of ``L_AF`` (see the module) of a pressure record.

    Parameters
    ----------
    pressure_pa : array_like
        Sound pressure, Pa (or any unit: ``P`` does not depend on the scale).
    fs_hz : float
        Sampling rate, Hz.
    start_time_s : float
        Time of the first sample, s.
    step_s : float
        Sampling step of ``L_AF``, s.
    settle_s : float
        Onsets starting in the first ``settle_s`` (the F weighting rising from rest,
        4 time constants) are left out, s.

    Examples
    --------
    A step of a 1 kHz tone (A weighting 0 dB) from 40 to 70 dB at 1 s: one onset of
    about 29 dB (its end is where the F-weighted rise slows below 10 dB/s).

    >>> import numpy as np
    >>> fs = 48000.0
    >>> t = np.arange(int(2 * fs)) / fs
    >>> amp = np.where(t < 1.0, 10 ** (40 / 20), 10 ** (70 / 20)) * 20e-6 * np.sqrt(2)
    >>> on = find_onsets(amp * np.sin(2 * np.pi * 1000 * t), fs)
    >>> on.t_start_s.size, round(float(on.level_difference_db[0]))
    (1, 29)
    """
    level = laf_db(pressure_pa, fs_hz, step_s, fast_a_ms=fast_a_ms)
    hop = max(1, round(step_s * fs_hz))
    dt = hop / fs_hz
    t = start_time_s + (np.arange(level.size) + 1) * hop / fs_hz - 1.0 / fs_hz
    grad = np.diff(level) / dt          # gradient over [t_k, t_k+1]
    rising = grad > ONSET_GRADIENT_DB_S
    empty = Onsets(*(np.zeros(0) for _ in range(5)))
    if not rising.any():
        return empty
    edges = np.flatnonzero(np.diff(np.concatenate([[0], rising.astype(np.int8), [0]])))
    starts, stops = edges[0::2], edges[1::2]     # rising over intervals [starts, stops)
    # a dip shorter than ONSET_GAP_S is an irregularity of the onset when the level then
    # rises on past the onset's top (a train of impacts faster than 20/s builds up its
    # F-weighted level as one onset; once it plateaus, each impact is its own onset)
    s_list: list[int] = [int(starts[0])]
    e_list: list[int] = [int(stops[0])]
    gap_steps = ONSET_GAP_S / dt - 1e-9
    for a, b in zip(starts[1:], stops[1:]):
        if a - e_list[-1] < gap_steps and level[b] > level[e_list[-1]]:
            e_list[-1] = int(b)
        else:
            s_list.append(int(a))
            e_list.append(int(b))
    s, e = np.array(s_list), np.array(e_list)
    ld = level[e] - level[s]
    dur = (e - s) * dt
    rate = ld / dur
    prom = np.array([prominence(r, d) for r, d in zip(rate, ld)])
    sel = t[s] >= start_time_s + settle_s
    return Onsets(t[s][sel], t[e][sel], ld[sel], rate[sel], prom[sel])


__all__ = ["ONSET_GAP_S", "ONSET_GRADIENT_DB_S", "ONSET_STEP_S", "Onsets", "adjustment_db",
           "find_onsets", "laf_db", "prominence"]
