"""Time-varying loudness (ISO 532-1:2017, Zwicker) and sharpness (DIN 45692), compiled.

:mod:`rattle_lab.acoustics._iso532` implements ISO 532-1 method 1 for time-varying sounds
(third-octave levels every 0.5 ms, core loudness, nonlinear decay, slopes, temporal
weighting; output every 2 ms) as one compiled pass over the samples.  MoSQITo
(``mosqito.sq_metrics.loudness_zwtv``) is one test reference: ``tests/acoustics/test_acoustics.py``
checks ``N(t)`` against it to ISO 532-1 annex B's tolerances on synthetic annex-B-like
signals, and the standard's anchors (1 kHz tone at 40 dB -> 1 sone, 60 dB -> 4 sone) and
the DIN 45692 reference sound (1 acum).  ``tests/acoustics/test_iso532_annex_b.py`` checks
it against the standard's own published results for its annex B.2-B.4 test signals.

* ``N5``: the loudness exceeded 5 % of the time (the 95th percentile of ``N(t)``),
  ``Nmax`` its maximum, sone.
* Sharpness: DIN 45692 (``g(z)`` = 1 up to 15.8 Bark, then ``0.15 e^(0.42 (z - 15.8)) +
  0.85``) applied to the time-averaged specific loudness ``N'(z)`` (one value for the
  stretch), acum.

The record is resampled to 48 kHz (the rate of the standard's filter coefficients) with
a polyphase filter when it is at another rate.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Any, Literal

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._iso532 import time_varying_loudness

FieldType = Literal["free", "diffuse"]
_FS_LOUDNESS_HZ = 48000


@dataclass(frozen=True)
class Loudness:
    """Loudness and sharpness of a stretch of a pressure record.

    Attributes
    ----------
    n5_sone : float
        Percentile loudness ``N5`` (exceeded 5 % of the time), sone (ISO 532-1).
    nmax_sone : float
        Largest time-varying loudness, sone.
    sharpness_acum : float
        DIN 45692 sharpness of the time-averaged specific loudness, acum.
    field_type : {"free", "diffuse"}
        Sound field assumed (free = frontal incidence).
    curve : (ndarray, ndarray) or None
        ``N(t)`` (sone, every 2 ms) and the time-averaged ``N'(z)`` (sone/Bark), where asked
        (:func:`loudness`'s ``keep_curve``); not compared.
    """

    n5_sone: float
    nmax_sone: float
    sharpness_acum: float
    field_type: FieldType = "free"
    curve: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False,
                                                        repr=False)

    def to_dict(self) -> dict[str, Any]:
        """Plain dict."""
        return {"loudness_n5_sone": self.n5_sone, "loudness_max_sone": self.nmax_sone,
                "sharpness_acum": self.sharpness_acum, "field_type": self.field_type}


def _at_48k(p: np.ndarray, fs_hz: float) -> np.ndarray:
    if fs_hz == _FS_LOUDNESS_HZ:
        return p
    ratio = Fraction(_FS_LOUDNESS_HZ / fs_hz).limit_denominator(1000)
    if abs(float(ratio) * fs_hz - _FS_LOUDNESS_HZ) > 1e-6 * _FS_LOUDNESS_HZ:
        raise ParameterError(f"cannot resample {fs_hz} Hz to 48 kHz by a ratio of small integers")
    from scipy import signal   # here: scipy.signal costs about 1 s to import

    return signal.resample_poly(p, ratio.numerator, ratio.denominator)


def _din45692_sharpness(spec_mean: np.ndarray) -> float:
    """DIN 45692 sharpness, acum, of a specific loudness on the 0.1 Bark grid."""
    z = np.arange(1, spec_mean.size + 1) * 0.1
    g = np.where(z > 15.8, 0.15 * np.exp(0.42 * (z - 15.8)) + 0.85, 1.0)
    n_total = float(np.sum(spec_mean) * 0.1)
    if n_total <= 0:
        return float("nan")
    return float(0.11 * np.sum(spec_mean * g * z * 0.1) / n_total)


def loudness(pressure_pa: object, fs_hz: float, *, field_type: FieldType = "free",
             keep_curve: bool = False) -> Loudness:
    """ISO 532-1 time-varying loudness (N5, Nmax) and DIN 45692 sharpness of a pressure signal.

    Parameters
    ----------
    pressure_pa : array_like
        Calibrated sound pressure, Pa (at least 0.1 s).
    fs_hz : float
        Sampling rate, Hz.
    field_type : {"free", "diffuse"}
        Free field (frontal incidence, the default) or diffuse field.
    keep_curve : bool
        Keep ``N(t)`` and the time-averaged ``N'(z)`` on the result (``curve``), for
        stretches joined later (:func:`joined_loudness`).

    Raises
    ------
    ParameterError
        For an unknown ``field_type``, a record shorter than 0.1 s or non-finite.
    """
    if field_type not in ("free", "diffuse"):
        raise ParameterError(f"`field_type` must be 'free' or 'diffuse', was {field_type!r}")
    p = np.asarray(pressure_pa, dtype=float)
    if p.ndim != 1 or p.size < 0.1 * fs_hz or not np.all(np.isfinite(p)):
        raise ParameterError("`pressure_pa` must be a finite 1-D signal of at least 0.1 s")
    n_t, spec_mean = time_varying_loudness(_at_48k(p, fs_hz), diffuse=field_type == "diffuse")
    out = loudness_of_curve(n_t, spec_mean, field_type)
    return out if keep_curve else replace(out, curve=None)


def loudness_of_curve(n_t: np.ndarray, spec_mean: np.ndarray,
                      field_type: FieldType = "free") -> Loudness:
    """:class:`Loudness` of a time-varying loudness ``N(t)`` (sone) and its time-averaged
    specific loudness (sone/Bark, 0.1 Bark grid), the curves kept (``curve``)."""
    return Loudness(float(np.percentile(n_t, 95.0)), float(np.max(n_t)),
                    _din45692_sharpness(spec_mean), field_type,
                    curve=(np.asarray(n_t, float), np.asarray(spec_mean, float)))


def joined_loudness(parts: list[Loudness]) -> Loudness:
    """The loudness of consecutive stretches joined: N5 and Nmax of their ``N(t)`` curves
    end to end, sharpness of their specific loudness averaged over time (each weighted by
    its length).  Every part must carry its curves (:func:`loudness_of_curve`)."""
    curves = [ld.curve for ld in parts if ld.curve is not None]
    if len(curves) != len(parts) or not curves:
        raise ParameterError("joined_loudness needs each part's curves")
    n_t = np.concatenate([c[0] for c in curves])
    w = [float(c[0].size) for c in curves]
    spec = np.sum([wi * c[1] for wi, c in zip(w, curves)], axis=0) / sum(w)
    out = loudness_of_curve(n_t, spec, parts[0].field_type)
    return replace(out, curve=None)


__all__ = ["FieldType", "Loudness", "joined_loudness", "loudness", "loudness_of_curve"]
