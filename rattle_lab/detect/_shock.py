"""The shock of a transient record (drop table, impact hammer): one event, its onset and peak.

A record whose protocol is ``transient`` holds a single shock (schema); the structure then
rings for tens or hundreds of milliseconds, and the rattle detector's trigger, which
re-arms at every swing of that ringing, would report dozens of "impacts".  Here the shock
is the record's largest excursion from its baseline, if it stands above the noise floor
(``on`` noise units; the noise is that of the quietest stretch of the record, where no
ringing is), and its onset is where the signal's variance changes before that peak: the
Akaike-information-criterion picker of seismology (Maeda 1985) over the stretch before
the peak, which neither a local fit nor a trigger level biases on a slow rise.  A record that
rests at exactly zero (a commanded pulse, no noise at all) has nothing to leave: its onset is
where the rise before the peak passes :data:`ZERO_REST_ONSET` of the peak.

A shock is often given on top of a steady excitation (a shaker's sine with a shock pulse
added, the forced-shock record of ``../shared/realdata``): the sine is then the largest
thing in every block, the noise floor is the sine, and a shock of twice its amplitude does
not stand out.  Such a steady part is a line in the spectrum that is there, with the same
amplitude and phase, at the start and at the end of the record; it is fitted (the line's
frequency refined, with :data:`N_HARMONICS` harmonics) and taken off before the shock is
looked for (:func:`steady_periodic`).  The ringing that follows a shock is a line too, but
not at the start of the record, so it is left alone.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._common import as_signal, robust_sigma

#: Blocks the record is cut into to find its quietest stretch (the noise floor).
N_NOISE_BLOCKS = 20
#: Harmonics fitted with a steady line (the line itself included).
N_HARMONICS = 3
#: A line is steady when its amplitude in the first and the last third of the record is
#: within this factor of the whole record's, and its phase within ``STEADY_PHASE_RAD``.
STEADY_AMPLITUDE_RATIO = 1.25
STEADY_PHASE_RAD = 0.3
#: Onset of a record that rests at exactly zero (noise floor below 1e-12 of its peak, a
#: commanded pulse): the first sample of the rise to the peak at or above this fraction
#: of the peak (0.1 %, a 10-bit converter's step on the peak's range).
ZERO_REST_ONSET = 1e-3


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


def _line_fit(x: np.ndarray, t: np.ndarray, f_hz: float, n_harm: int
              ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares fit of a constant and ``n_harm`` harmonics of ``f_hz``: (fit, coefficients)."""
    cols = [np.ones_like(t)]
    for k in range(1, n_harm + 1):
        cols += [np.cos(2 * np.pi * k * f_hz * t), np.sin(2 * np.pi * k * f_hz * t)]
    design = np.column_stack(cols)
    coef = np.linalg.lstsq(design, x, rcond=None)[0]
    return design @ coef, coef


def steady_periodic(x: np.ndarray, fs_hz: float) -> np.ndarray | None:
    """The steady periodic part of ``x`` (a line and its harmonics), or None when there is none.

    The line is the largest peak of the spectrum (Hann window, zero-padded, its frequency
    refined by least squares within a bin); it is steady when a fit over the first and
    over the last third of the record each gives its amplitude within
    :data:`STEADY_AMPLITUDE_RATIO` and its phase within :data:`STEADY_PHASE_RAD` of the
    whole record's fit, and the line holds at least two periods in each third.

    Examples
    --------
    >>> import numpy as np
    >>> fs = 1000.0
    >>> t = np.arange(4000) / fs
    >>> sine = 0.5 * np.sin(2 * np.pi * 5.0 * t + 0.3)
    >>> bool(np.allclose(steady_periodic(sine, fs), sine, atol=1e-6))
    True
    >>> ring = (t >= 2.0) * np.exp(-(t - 2.0) / 0.1) * np.sin(2 * np.pi * 40.0 * (t - 2.0))
    >>> steady_periodic(ring, fs) is None
    True
    """
    from scipy.optimize import minimize_scalar

    n = x.size
    if n < 64:
        return None
    t = np.arange(n) / fs_hz
    xc = x - np.mean(x)
    n_fft = 8 * int(2 ** np.ceil(np.log2(n)))
    spec = np.abs(np.fft.rfft(xc * np.hanning(n), n_fft))
    k = int(np.argmax(spec[1:])) + 1
    df = fs_hz / n_fft
    bin_hz = fs_hz / n
    f0 = k * df
    if f0 * n / (3 * fs_hz) < 2.0:     # fewer than two periods in a third
        return None
    n_harm = max(1, min(N_HARMONICS, int((0.5 * fs_hz) // f0) - 1 or 1))
    f0 = float(minimize_scalar(lambda f: float(np.sum((xc - _line_fit(xc, t, f, 1)[0]) ** 2)),
                               bounds=(max(f0 - bin_hz, 0.5 * f0), f0 + bin_hz),
                               method="bounded", options={"xatol": 1e-6 * f0}).x)
    whole = _line_fit(x, t, f0, 1)[1][1:3]
    amp = float(np.hypot(*whole))
    if amp == 0.0:
        return None
    third = n // 3
    for sl in (slice(0, third), slice(n - third, n)):
        part = _line_fit(x[sl], t[sl], f0, 1)[1][1:3]
        ratio = float(np.hypot(*part)) / amp
        dphase = np.angle(complex(part[0], -part[1]) / complex(whole[0], -whole[1]))
        if not (1 / STEADY_AMPLITUDE_RATIO <= ratio <= STEADY_AMPLITUDE_RATIO
                and abs(dphase) <= STEADY_PHASE_RAD):
            return None
    fit, coef = _line_fit(x, t, f0, n_harm)
    return fit - coef[0]


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
    steady = steady_periodic(dev, fs_hz) if data.size >= 6 else None
    if steady is not None:          # a shock on top of a steady excitation: take it off
        dev = dev - steady
        dev = dev - np.median(dev)
    floor = noise_floor(dev)
    sigma = max(floor, 1e-12 * float(np.max(np.abs(dev), initial=0.0)))
    nan = float("nan")
    if sigma == 0.0 or data.size < 6:
        return Shock(False, nan, nan, nan, 0.0, float(sigma))
    pk = int(np.argmax(np.abs(dev)))
    strength = float(abs(dev[pk]) / sigma)
    if strength <= on:
        return Shock(False, nan, nan, float(dev[pk]), strength, float(sigma))
    if floor <= 1e-12 * abs(dev[pk]):
        # it rests at exactly zero (a commanded pulse): there is no noise to leave, and the
        # picker would take the first denormal of the pulse's tail; the onset is where the
        # rise before the peak passes ZERO_REST_ONSET of the peak
        below = np.flatnonzero(np.abs(dev[:pk + 1]) < ZERO_REST_ONSET * abs(dev[pk]))
        onset = int(below[-1]) + 1 if below.size else 0
    else:
        onset = aic_onset(dev[:pk + 1]) if pk >= 6 else 0
    return Shock(True, start_time_s + onset / fs_hz, start_time_s + pk / fs_hz, float(dev[pk]),
                 strength, float(sigma))


__all__ = ["N_HARMONICS", "N_NOISE_BLOCKS", "ZERO_REST_ONSET", "Shock", "aic_onset", "detect_shock", "noise_floor",
           "steady_periodic"]
