"""Sound pressure level in dB re 20 uPa, and A-weighting per IEC 61672-1.

The A-weighting is applied in the frequency domain with the exact analog
response of IEC 61672-1:2013, eq. (E.6)-(E.7): ``A(f) = 20 log10(R_A(f)) - A_1000``,
``R_A(f) = f4^2 f^4 / ((f^2 + f1^2) sqrt((f^2 + f2^2)(f^2 + f3^2)) (f^2 + f4^2))`` with
``f1 = 20.598997 Hz, f2 = 107.65265 Hz, f3 = 737.86223 Hz, f4 = 12194.217 Hz``
and ``A_1000 = -2.000 dB`` (so that ``A(1 kHz) = 0``).  A frequency-domain
weighting has no bilinear-transform warping near Nyquist.
"""

from __future__ import annotations

import numpy as np

from ._common import as_signal

P_REF_PA = 20e-6
_F1_HZ, _F2_HZ, _F3_HZ, _F4_HZ = 20.598997, 107.65265, 737.86223, 12194.217


def _r_a(freq_hz: np.ndarray) -> np.ndarray:
    f2 = np.asarray(freq_hz, dtype=float) ** 2
    return (_F4_HZ**2 * f2**2) / ((f2 + _F1_HZ**2) * np.sqrt((f2 + _F2_HZ**2) * (f2 + _F3_HZ**2))
                                  * (f2 + _F4_HZ**2))


_A1000_DB = -20.0 * np.log10(float(_r_a(np.array(1000.0))))


def a_weighting_db(freq_hz: object) -> np.ndarray:
    """A-weighting ``A(f)`` in dB (IEC 61672-1 eq. E.6), 0 dB at 1 kHz; ``-inf`` at 0 Hz.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(a_weighting_db(1000.0), 0.0, atol=1e-12))
    True
    >>> bool(np.isclose(a_weighting_db(1000 * 10**-1.5), -39.4, atol=0.05))  # nominal 31.5 Hz
    True
    """
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(_r_a(np.asarray(freq_hz, dtype=float))) + _A1000_DB


def a_weight(pressure_pa: object, fs_hz: float) -> np.ndarray:
    """The A-weighted pressure signal (frequency-domain weighting of the whole record), Pa."""
    p = as_signal(pressure_pa, "pressure_pa")
    if p.size == 0:
        return p
    spec = np.fft.rfft(p)
    freq = np.fft.rfftfreq(p.size, 1.0 / fs_hz)
    gain = 10.0 ** (a_weighting_db(freq) / 20.0)
    return np.fft.irfft(spec * gain, n=p.size)


def spl_db(pressure_pa: object) -> np.ndarray:
    """Level ``20 log10(|p| / 20 uPa)`` of pressures (peaks or RMS values), dB re 20 uPa."""
    p = np.abs(np.asarray(pressure_pa, dtype=float))
    with np.errstate(divide="ignore"):
        return 20.0 * np.log10(p / P_REF_PA)


def rms_spl_db(pressure_pa: object, fs_hz: float | None = None, *, a_weighted: bool = False) -> float:
    """RMS sound pressure level of a record, dB re 20 uPa (``a_weighted`` needs ``fs_hz``)."""
    p = as_signal(pressure_pa, "pressure_pa")
    if a_weighted:
        if fs_hz is None:
            from rattle_lab.exceptions import ParameterError
            raise ParameterError("`fs_hz` is needed for an A-weighted level, was None")
        p = a_weight(p, fs_hz)
    if p.size == 0:
        return float("nan")
    return float(spl_db(np.sqrt(np.mean(p**2))))
