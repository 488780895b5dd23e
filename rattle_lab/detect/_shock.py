"""The shock of a transient record (drop table, impact hammer): one event, its onset and peak.

A record whose protocol is ``transient`` holds a single shock (schema); the structure then
rings for tens or hundreds of milliseconds, and the rattle detector's trigger, which
re-arms at every swing of that ringing, would report dozens of "impacts".  Here the shock
is the record's largest excursion from its baseline, if it stands above the noise floor
(``on`` noise units; the noise is that of the quietest stretch of the record, where no
ringing is), and its onset is where the signal's variance changes before that peak: the
Akaike-information-criterion picker of seismology (Maeda 1985) over the stretch before
the peak, which neither a local fit nor a trigger level biases on a slow rise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._common import as_signal, robust_sigma

#: Blocks the record is cut into to find its quietest stretch (the noise floor).
N_NOISE_BLOCKS = 20


@dataclass(frozen=True)
class Shock:
    """The shock of a transient record.

    Attributes
    ----------
    found : bool
        False when nothing stands ``on`` noise units above the baseline.
    onset_s, peak_s : float
        Onset (AIC picker) and largest excursion, s (NaN when not found).
    peak_value : float
        Signed largest excursion from the baseline, in the channel's units.
    strength : float
        ``|peak_value|`` in noise units.
    noise : float
        Noise unit: 1.4826 MAD of the quietest of :data:`N_NOISE_BLOCKS` blocks.
    """

    found: bool
    onset_s: float
    peak_s: float
    peak_value: float
    strength: float
    noise: float


def noise_floor(dev: np.ndarray) -> float:
    """1.4826 MAD of the quietest of :data:`N_NOISE_BLOCKS` equal blocks of ``dev``."""
    n = max(1, dev.size // N_NOISE_BLOCKS)
    blocks = [dev[i:i + n] for i in range(0, dev.size - n + 1, n)] or [dev]
    return float(min(robust_sigma(b - np.median(b)) for b in blocks))


def aic_onset(x: np.ndarray) -> int:
    """Index where the variance of ``x`` changes (AIC picker, Maeda 1985); 0 when too short."""
    n = x.size
    if n < 6:
        return 0
    k = np.arange(2, n - 2)
    c1 = np.cumsum(x)
    c2 = np.cumsum(x * x)
    var1 = c2[k - 1] / k - (c1[k - 1] / k) ** 2
    tail1 = c1[-1] - c1[k - 1]
    tail2 = c2[-1] - c2[k - 1]
    m = n - k
    var2 = tail2 / m - (tail1 / m) ** 2
    tiny = np.finfo(float).tiny
    aic = k * np.log(np.maximum(var1, tiny)) + (m - 1) * np.log(np.maximum(var2, tiny))
    return int(k[np.argmin(aic)])


def detect_shock(x: object, fs_hz: float, *, start_time_s: float = 0.0,
                 on: float = 12.0) -> Shock:
    """The shock of a transient record: largest excursion above ``on`` noise units, its onset.

    Parameters
    ----------
    x : array
        The samples (any units).
    fs_hz : float
        Sample rate, Hz.
    start_time_s : float
        Time of the first sample, s.
    on : float
        Level, in noise units, the peak must exceed to count as a shock.

    Raises
    ------
    ParameterError
        For a bad level or rate, or non-finite samples.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> fs = 10000.0
    >>> t = np.arange(5000) / fs
    >>> ring = (t >= 0.2) * np.exp(-(t - 0.2) / 0.05) * np.sin(2 * np.pi * 800 * (t - 0.2))
    >>> s = detect_shock(0.01 * rng.standard_normal(t.size) + ring, fs)
    >>> s.found, bool(abs(s.onset_s - 0.2) <= 2e-4)
    (True, True)
    """
    if not (np.isfinite(on) and on > 0):
        raise ParameterError(f"`on` must be > 0, was {on}")
    if not (np.isfinite(fs_hz) and fs_hz > 0):
        raise ParameterError(f"`fs_hz` must be > 0, was {fs_hz}")
    data = np.asarray(as_signal(x, "x"), dtype=np.float64)
    dev = data - np.median(data)
    sigma = max(noise_floor(dev), 1e-12 * float(np.max(np.abs(dev), initial=0.0)))
    nan = float("nan")
    if sigma == 0.0 or data.size < 6:
        return Shock(False, nan, nan, nan, 0.0, float(sigma))
    pk = int(np.argmax(np.abs(dev)))
    strength = float(abs(dev[pk]) / sigma)
    if strength <= on:
        return Shock(False, nan, nan, float(dev[pk]), strength, float(sigma))
    onset = aic_onset(dev[:pk + 1]) if pk >= 6 else 0
    return Shock(True, start_time_s + onset / fs_hz, start_time_s + pk / fs_hz, float(dev[pk]),
                 strength, float(sigma))


__all__ = ["N_NOISE_BLOCKS", "Shock", "aic_onset", "detect_shock", "noise_floor"]
