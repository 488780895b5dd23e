"""Impact pattern per forcing cycle (thesis Fig. 6-4)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from rattle_lab.exceptions import ParameterError

Pattern = Literal["no impact", "1/1", "1/n", "several per cycle", "irregular"]


@dataclass(frozen=True)
class PatternResult:
    """Impacts per excitation cycle and the class of the run.

    Attributes
    ----------
    counts : ndarray of int
        Impacts in each whole forcing cycle ``[t0 + k/f, t0 + (k+1)/f)``.
    pattern : str
        ``"no impact"``, ``"1/1"``, ``"1/n"`` (one impact every ``n`` cycles),
        ``"several per cycle"`` or ``"irregular"``.
    n : int
        The ``n`` of a 1/n pattern (1 for 1/1, 0 otherwise).
    """

    counts: np.ndarray
    pattern: Pattern
    n: int


def impact_pattern(impact_t_s: object, freq_hz: float, t_start_s: float, t_stop_s: float, *,
                   settle_cycles: int = 0, tolerance: float = 0.9) -> PatternResult:
    """Classify a run by its impacts per forcing cycle.

    ``tolerance`` is the fraction of cycles (or of impact intervals) that must
    follow the pattern; the rest are allowed to deviate (noise, a missed impact).  It
    must exceed 1/2, so that a run cannot be "1/1" and "several per cycle" at once.
    ``settle_cycles`` whole cycles at the start are left out (transients).

    Raises
    ------
    ParameterError
        For ``freq_hz <= 0``, an empty time span, ``tolerance`` outside (0.5, 1] or a
        negative or fractional ``settle_cycles``.

    Examples
    --------
    >>> import numpy as np
    >>> t = 0.25 / 100 + np.arange(0, 50, 2) / 100.0   # one impact every 2 cycles at 100 Hz
    >>> r = impact_pattern(t, 100.0, 0.0, 0.5)
    >>> r.pattern, r.n
    ('1/n', 2)
    """
    if not (np.isfinite(freq_hz) and freq_hz > 0):
        raise ParameterError(f"`freq_hz` must be > 0, was {freq_hz}")
    if not t_stop_s > t_start_s:
        raise ParameterError(f"`t_stop_s` must be > `t_start_s` ({t_start_s}), was {t_stop_s}")
    if not 0.5 < tolerance <= 1.0:
        raise ParameterError(f"`tolerance` must be in (0.5, 1], was {tolerance}")
    if int(settle_cycles) != settle_cycles or settle_cycles < 0:
        raise ParameterError(f"`settle_cycles` must be an integer >= 0, was {settle_cycles}")
    settle_cycles = int(settle_cycles)
    t = np.sort(np.atleast_1d(np.asarray(impact_t_s, dtype=float)))
    period = 1.0 / freq_hz
    n_cycles = int(np.floor((t_stop_s - t_start_s) / period + 1e-9))
    edges = t_start_s + period * np.arange(n_cycles + 1)
    counts = np.histogram(t, bins=edges)[0] if n_cycles > 0 else np.zeros(0, dtype=int)
    counts = counts[settle_cycles:]
    if counts.size == 0 or counts.sum() == 0:
        return PatternResult(counts, "no impact", 0)
    if np.mean(counts == 1) >= tolerance:
        return PatternResult(counts, "1/1", 1)
    if np.mean(counts >= 2) >= tolerance:
        return PatternResult(counts, "several per cycle", 0)
    if np.all(counts <= 1):
        tt = t[(t >= edges[settle_cycles]) & (t < edges[-1])]
        gaps = np.round(np.diff(tt) / period).astype(int)
        if gaps.size:
            values, freq = np.unique(gaps, return_counts=True)
            n = int(values[np.argmax(freq)])
            if n >= 2 and np.max(freq) >= tolerance * gaps.size:
                return PatternResult(counts, "1/n", n)
    return PatternResult(counts, "irregular", 0)


def impacts_per_cycle(impact_t_s: object, freq_hz: float, t_start_s: float,
                      duration_s: float) -> np.ndarray:
    """Impacts in each whole forcing cycle ``[t0 + k/f, t0 + (k+1)/f)`` of a run.

    Unlike :func:`impact_pattern` this only counts (no classification, no checks
    beyond a positive frequency): the report draws one point per cycle.

    Parameters
    ----------
    impact_t_s : array_like
        Impact times, s.
    freq_hz : float
        Excitation frequency, Hz, > 0.
    t_start_s, duration_s : float
        Start and length of the run, s; ``floor(duration_s * freq_hz)`` whole cycles.

    Returns
    -------
    ndarray of int
        One count per cycle (impacts outside the whole cycles are left out).

    Raises
    ------
    ParameterError
        For ``freq_hz <= 0``.

    Examples
    --------
    >>> impacts_per_cycle([0.001, 0.011, 0.012, 0.035], 100.0, 0.0, 0.04).tolist()
    [1, 2, 0, 1]
    """
    if not (np.isfinite(freq_hz) and freq_hz > 0):
        raise ParameterError(f"`freq_hz` must be > 0, was {freq_hz}")
    n_cycles = int(np.floor(duration_s * freq_hz))
    k = np.floor((np.asarray(impact_t_s, dtype=float) - t_start_s) * freq_hz).astype(int)
    k = k[(k >= 0) & (k < n_cycles)]
    return np.bincount(k, minlength=n_cycles)
