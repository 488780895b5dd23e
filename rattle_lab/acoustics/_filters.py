"""Frequency weightings (IEC 61672-1) and third-octave band filters (IEC 61260-1), applied exactly.

Both are the *analog* responses the standards define, evaluated on the FFT bins
of the signal (magnitude and phase), so that nothing is warped near Nyquist:

* A and C weighting: IEC 61672-1:2013 Annex E, poles ``f1 = 20.598997 Hz``,
  ``f2 = 107.65265 Hz``, ``f3 = 737.86223 Hz``, ``f4 = 12194.217 Hz``;
  ``H_C(s) = k_C s^2 w4^2 / ((s + w1)^2 (s + w4)^2)``,
  ``H_A(s) = k_A s^4 w4^2 / ((s + w1)^2 (s + w2) (s + w3) (s + w4)^2)``, ``k`` normalising
  to 0 dB at 1 kHz (these are causal, minimum-phase responses: a C-weighted peak
  is the standard's).
* Third-octave bands: base-ten ratio ``G = 10^(3/10)``, exact mid-band frequencies
  ``f_m = 1000 G^(x/3)`` Hz (``x = -17 .. 13``: 20 Hz .. 20 kHz), edges
  ``f_m G^(+-1/6)``; each band a third-order analog Butterworth band-pass
  (:func:`scipy.signal.butter` with ``analog=True``), which meets the class-1
  attenuation mask (checked in the tests).

Why not digital IIR filters: the bilinear transform (the usual digital
A-weighting, and :func:`scipy.signal.butter` with ``fs``) compresses the response
towards Nyquist; at ``fs = 48 kHz`` the third-octave bands from 10 kHz up miss the
class-1 stop-band limits and the A-weighting misses class 1 at 16-20 kHz
(``benchmarks/bench_acoustic_filters.py`` prints both).
"""

from __future__ import annotations

from typing import Literal

import numba
import numpy as np

from rattle_lab.exceptions import ParameterError

Weighting = Literal["A", "C", "Z"]

_F1_HZ, _F2_HZ, _F3_HZ, _F4_HZ = 20.598997, 107.65265, 737.86223, 12194.217
#: Base-ten octave ratio of IEC 61260-1.
G10 = 10.0 ** 0.3
#: Band numbers ``x`` of the third-octave bands 20 Hz .. 20 kHz (``f_m = 1000 G^(x/3)``).
BAND_NUMBERS = tuple(range(-17, 14))
#: Nominal mid-band frequencies (IEC 61260-1 Annex E), Hz, as labels.
NOMINAL_THIRD_OCTAVE_HZ = ("20", "25", "31.5", "40", "50", "63", "80", "100", "125", "160", "200",
                           "250", "315", "400", "500", "630", "800", "1000", "1250", "1600", "2000",
                           "2500", "3150", "4000", "5000", "6300", "8000", "10000", "12500",
                           "16000", "20000")


def _unnormalised(weighting: Weighting, freq_hz: np.ndarray) -> np.ndarray:
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    w1, w2, w3, w4 = (2 * np.pi * f for f in (_F1_HZ, _F2_HZ, _F3_HZ, _F4_HZ))
    if weighting == "C":
        return s**2 * w4**2 / ((s + w1) ** 2 * (s + w4) ** 2)
    if weighting == "A":
        return s**4 * w4**2 / ((s + w1) ** 2 * (s + w2) * (s + w3) * (s + w4) ** 2)
    if weighting == "Z":
        return np.ones_like(s)
    raise ParameterError(f"`weighting` must be 'A', 'C' or 'Z', was {weighting!r}")


def weighting_response(weighting: Weighting, freq_hz: object) -> np.ndarray:
    """Complex analog response of the A, C (or Z = flat) weighting, 1 at 1 kHz.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(abs(weighting_response("A", 1000.0)), 1.0))
    True
    >>> bool(np.isclose(20 * np.log10(abs(weighting_response("C", 31.6228))), -3.0, atol=0.05))
    True
    """
    h = _unnormalised(weighting, np.asarray(freq_hz, dtype=float))
    return h / abs(complex(_unnormalised(weighting, np.array(1000.0))))


def weighting_db(weighting: Weighting, freq_hz: object) -> np.ndarray:
    """Weighting in dB (``-inf`` at 0 Hz for A and C)."""
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(np.abs(weighting_response(weighting, freq_hz)))


def apply_weighting(pressure_pa: np.ndarray, fs_hz: float, weighting: Weighting) -> np.ndarray:
    """The frequency-weighted signal: the analog response applied on the FFT bins.

    The signal is zero-padded by 0.5 s (at least) before the transform so that the
    weighting's decay (time constant ``1 / (2 pi 20.6 Hz) = 7.7 ms``) does not wrap
    around to the start; the result is the causal filter's output over the record.
    """
    return apply_weightings(pressure_pa, fs_hz, (weighting,))[0]


def apply_weightings(pressure_pa: np.ndarray, fs_hz: float,
                     weightings: tuple[Weighting, ...]) -> list[np.ndarray]:
    """:func:`apply_weighting` for several weightings from one transform of the signal."""
    p = np.asarray(pressure_pa, dtype=float)
    if p.size == 0:
        return [p.copy() for _ in weightings]
    n_fft = fast_length(p.size + max(round(0.5 * fs_hz), 1))
    spec = None
    out = []
    for weighting in weightings:
        if weighting == "Z":
            out.append(p.copy())
            continue
        if spec is None:
            spec = np.fft.rfft(p, n=n_fft)
        out.append(np.fft.irfft(spec * _response_on_bins(weighting, n_fft, float(fs_hz)),
                                n=n_fft)[: p.size])
    return out


def fast_length(n: int) -> int:
    """The smallest ``2^a 3^b 5^c >= n``: a transform length the FFT does fast.

    A power of two can be nearly twice the record (and its transform three to four times
    slower: 10 s at 51.2 kHz with its 0.5 s of padding, 537600 samples, goes to 540000,
    not 1048576).

    Examples
    --------
    >>> fast_length(537600), fast_length(1025), fast_length(1)
    (540000, 1080, 1)
    """
    best = 1 << max(int(n - 1).bit_length(), 0)   # the power of two: an upper bound
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            m = p35
            while m < n:
                m *= 2
            best = min(best, m)
            p35 *= 3
        p5 *= 5
    return best


_WEIGHTING_CODE = {"A": 0, "C": 1}


def _response_on_bins(weighting: Weighting, n_fft: int, fs_hz: float) -> np.ndarray:
    """:func:`weighting_response` on the bins ``k fs / n_fft`` of an ``n_fft`` transform
    (compiled: evaluating it in numpy costs as much as the transform)."""
    if weighting not in _WEIGHTING_CODE:
        raise ParameterError(f"`weighting` must be 'A', 'C' or 'Z', was {weighting!r}")
    norm = abs(complex(_unnormalised(weighting, np.array(1000.0))))
    return _weighting_bins(_WEIGHTING_CODE[weighting], n_fft // 2 + 1, fs_hz / n_fft,
                           _F1_HZ, _F2_HZ, _F3_HZ, _F4_HZ, 1.0 / norm)


@numba.njit(cache=True)
def _weighting_bins(code: int, n_bins: int, df_hz: float, f1: float, f2: float, f3: float,
                    f4: float, scale: float) -> np.ndarray:  # pragma: no cover - compiled
    """:func:`_unnormalised` (A: ``code`` 0, C: 1) times ``scale`` at ``k df_hz``."""
    out = np.empty(n_bins, dtype=np.complex128)
    tp = 2.0 * np.pi
    w1, w2, w3, w4 = tp * f1, tp * f2, tp * f3, tp * f4
    for k in range(n_bins):
        s = 1j * (tp * (k * df_hz))
        s2 = s * s
        d14 = (s + w1) * (s + w1) * (s + w4) * (s + w4)
        if code == 0:
            out[k] = scale * (s2 * s2 * w4 * w4 / (d14 * (s + w2) * (s + w3)))
        else:
            out[k] = scale * (s2 * w4 * w4 / d14)
    return out


def band_edges_hz(band_number: int) -> tuple[float, float, float]:
    """``(lower, exact mid-band, upper)`` frequency of third-octave band ``x``, Hz."""
    fm = 1000.0 * G10 ** (band_number / 3.0)
    return fm * G10 ** (-1.0 / 6.0), fm, fm * G10 ** (1.0 / 6.0)


#: Order of the Butterworth low-pass prototype of each third-octave band-pass.
BAND_ORDER = 3


def band_gain(band_number: int, freq_hz: object) -> np.ndarray:
    """``|H|`` of the class-1 third-order Butterworth band-pass of band ``x`` (analog).

    The band-pass is the Butterworth low-pass ``|H|^2 = 1 / (1 + W^(2N))`` under the
    low-pass to band-pass transform ``W = (w^2 - w_l w_h) / (w (w_h - w_l))``, in closed
    form (what :func:`scipy.signal.butter` with ``analog=True`` designs; the tests compare
    the two).  Zero at 0 Hz.
    """
    lo, _, hi = band_edges_hz(band_number)
    f = np.abs(np.atleast_1d(np.asarray(freq_hz, float)))
    with np.errstate(divide="ignore", over="ignore"):
        w2 = ((f * f - lo * hi) / (f * (hi - lo))) ** 2
        return 1.0 / np.sqrt(1.0 + w2 * w2 * w2)   # W^(2N), N = BAND_ORDER = 3


def band_mean_squares(x: np.ndarray, fs_hz: float) -> dict[str, float]:
    """Mean square of ``x`` in each third-octave band 20 Hz .. 20 kHz that fits the record.

    Parseval on the FFT of the whole segment with the band's ``|H|^2``: the mean
    square of the band filter's steady-state output.  A band is left out when its
    upper edge is not below ``fs_hz / 2`` or when the segment is shorter than one
    over the band's width (too few spectral lines to resolve the band).

    Returns
    -------
    dict
        Nominal mid-band frequency (``"1000"``) -> mean square (units of ``x`` squared).
    """
    x = np.asarray(x, dtype=float)
    n = x.size
    out: dict[str, float] = {}
    if n == 0:
        return out
    spec = np.fft.rfft(x)    # any length: the segment's own periodic spectrum
    spec2 = spec.real**2 + spec.imag**2
    fold = np.full(spec2.size, 2.0)
    fold[0] = 1.0
    if n % 2 == 0:
        fold[-1] = 1.0
    power = fold * spec2 / n**2  # sums to mean(x**2)
    duration_s = n / fs_hz
    kept = []
    for x_band, label in zip(BAND_NUMBERS, NOMINAL_THIRD_OCTAVE_HZ):
        lo, _, hi = band_edges_hz(x_band)
        if hi >= fs_hz / 2 or duration_s * (hi - lo) < 1.0:
            continue
        kept.append((label, lo, hi))
    if kept:
        sums = _band_power_sums(power, fs_hz / n, np.array([k[1] for k in kept]),
                                np.array([k[2] for k in kept]))
        out.update({label: float(v) for (label, _, _), v in zip(kept, sums)})
    return out


@numba.njit(cache=True)
def _band_power_sums(power: np.ndarray, df_hz: float, lo_hz: np.ndarray,
                     hi_hz: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """``sum_k power[k] |H_b(k df)|^2`` for each band ``b`` (:func:`band_gain`'s response, in
    one pass over the bins: no array per band).  Bin 0 (0 Hz) has no gain."""
    nb = lo_hz.size
    out = np.zeros(nb)
    prod = lo_hz * hi_hz
    inv_bw = 1.0 / (hi_hz - lo_hz)
    for k in range(1, power.size):
        f = k * df_hz
        f2 = f * f
        inv_f = 1.0 / f
        pk = power[k]
        for b in range(nb):
            w = (f2 - prod[b]) * inv_f * inv_bw[b]
            w2 = w * w
            out[b] += pk / (1.0 + w2 * w2 * w2)
    return out


__all__ = ["BAND_NUMBERS", "G10", "NOMINAL_THIRD_OCTAVE_HZ", "Weighting", "apply_weighting",
           "apply_weightings", "band_edges_hz", "band_gain", "band_mean_squares", "weighting_db",
           "weighting_response"]
