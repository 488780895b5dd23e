"""ECMA-418-2:2025 (Sottek Hearing Model) loudness, tonality and roughness, via
``sottek-hearing-model``.

Why this implementation.  On the standard's own reference signals (checked in
``tests/acoustics/test_psychoacoustics_ecma.py``; the standard sets its calibration factors so
that each gives exactly 1):

============================================  ============  ============================
reference signal                              sottek-hm     MoSQITo 1.2.1
============================================  ============  ============================
1 kHz tone, 40 dB SPL: loudness (sone_HMS)    0.99999964    0.970 (``loudness_ecma``,
                                                            2022 ed., stationary only)
1 kHz tone, 40 dB SPL: tonality (tu_HMS)      1.0000004     not implemented (MoSQITo's
                                                            tonality is ECMA-418-1's TNR/PR)
1 kHz, 100 % AM at 70 Hz, 60 dB: roughness    0.9999955     0.995 (``roughness_ecma``)
============================================  ============  ============================

(5 s signals at 48 kHz, free frontal field; ``docs/explanation/psychoacoustics.md``.)  Only
sottek-hearing-model gives all three metrics and reproduces all three anchors; it is
used here.  It is an *optional* dependency (``pip install rattle-lab[ecma418]``): it
is licensed AGPL-3.0 (rattle_lab is MIT) and pulls in PyQt6.  Without it the metrics
are absent and flagged ``ecma418_unavailable``.

Cost: it is pure NumPy and slow -- about 6 s of CPU per second of sound for tonality
(which also gives the loudness's tonal and noise components) and 1.2 s for roughness
(measured in ``benchmarks/psychoacoustics.py``), far from 50x real time.  The fit
therefore computes it only when asked (``[fit] ecma418 = true``), on rattle episodes
only, up to a budget of seconds of sound per run.

Reported values (ECMA-418-2:2025 single values): loudness -- the power average
``N`` over time (``loudness_powavg``), sone_HMS; tonality -- the time average
``T`` (``tonality_avg``), tu_HMS; roughness -- the 90th percentile of ``R(t)``
(``roughness90pc``), asper_HMS.
"""

from __future__ import annotations

import contextlib
import io
import warnings
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from rattle_lab.exceptions import ParameterError

#: Shortest sound the ECMA-418-2 metrics are computed for, s: the standard's time
#: averages leave out the first 0.3 s (the filter bank's and averagers' start-up).
MIN_ECMA_S = 0.5
FLAG_UNAVAILABLE = "ecma418_unavailable"

_FIELDS = {"free": "free_frontal", "diffuse": "diffuse"}


@dataclass(frozen=True)
class Ecma418:
    """ECMA-418-2 single values of a stretch of sound.

    Attributes
    ----------
    loudness_sone : float
        Power-averaged loudness, sone_HMS.
    tonality_tu : float
        Time-averaged tonality, tu_HMS.
    roughness_asper : float
        90th-percentile roughness, asper_HMS.
    duration_s : float
        Length of the stretch, s.
    """

    loudness_sone: float
    tonality_tu: float
    roughness_asper: float
    duration_s: float

    def to_dict(self) -> dict[str, Any]:
        """The ``fit --json`` keys."""
        return {"loudness_ecma_sone": self.loudness_sone, "tonality_tu": self.tonality_tu,
                "roughness_asper": self.roughness_asper}


def ecma418_available() -> bool:
    """Whether ``sottek-hearing-model`` can be imported (imported here, its side effects
    on Matplotlib undone: see :func:`_import_package`)."""
    try:
        _import_package()
    except Exception:   # ImportError, or a broken install (its plotting backend)
        return False
    return True


def _import_package() -> None:
    """Import sottek-hearing-model and undo what its import does to Matplotlib: it sets
    the global font sizes (16-20 pt) and family, which would break the layout of every
    figure drawn afterwards in the process (the report's pages), and may switch the
    backend."""
    import sys

    if "sottek_hearing_model" in sys.modules:
        return
    import matplotlib

    backend = matplotlib.get_backend()
    try:
        with matplotlib.rc_context():
            import sottek_hearing_model  # noqa: F401
    finally:
        if matplotlib.get_backend() != backend:
            matplotlib.use(backend)


def ecma418(pressure_pa: object, fs_hz: float, *,
            field_type: Literal["free", "diffuse"] = "free") -> Ecma418:
    """ECMA-418-2:2025 loudness, tonality and roughness of a calibrated pressure signal.

    Parameters
    ----------
    pressure_pa : array_like
        Sound pressure, Pa (at least :data:`MIN_ECMA_S`).
    fs_hz : float
        Sampling rate, Hz (resampled to the standard's 48 kHz by the package).
    field_type : {"free", "diffuse"}
        Sound field of the outer-ear filter (free = frontal incidence).

    Raises
    ------
    ParameterError
        For a short or non-finite signal, an unknown field, or when
        ``sottek-hearing-model`` is not installed.
    """
    p = np.asarray(pressure_pa, dtype=float)
    if field_type not in _FIELDS:
        raise ParameterError(f"`field_type` must be 'free' or 'diffuse', was {field_type!r}")
    if p.ndim != 1 or p.size < MIN_ECMA_S * fs_hz or not np.all(np.isfinite(p)):
        raise ParameterError(f"`pressure_pa` must be a finite 1-D signal of at least "
                             f"{MIN_ECMA_S} s for ECMA-418-2")
    if not ecma418_available():
        raise ParameterError("ECMA-418-2 needs the optional package sottek-hearing-model "
                             "(pip install 'rattle-lab[ecma418]')")
    import matplotlib

    from sottek_hearing_model import (shm_loudness_ecma_from_comp, shm_roughness_ecma,
                                      shm_tonality_ecma)

    field = _FIELDS[field_type]
    backend = matplotlib.get_backend()
    # the package prints progress and may touch the plotting backend: keep both quiet
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        ton = shm_tonality_ecma(p, int(round(fs_hz)) if float(fs_hz).is_integer() else fs_hz,
                                soundfield=field, wait_bar=False, out_plot=False,
                                parallel_cores=1)
        loud = shm_loudness_ecma_from_comp(ton["spec_tonal_loudness"], ton["spec_noise_loudness"],
                                           out_plot=False)
        rough = shm_roughness_ecma(p, fs_hz, soundfield=field, wait_bar=False, out_plot=False,
                                   parallel_cores=1)
    if matplotlib.get_backend() != backend:
        matplotlib.use(backend)
    return Ecma418(float(np.ravel(loud["loudness_powavg"])[0]),
                   float(np.ravel(ton["tonality_avg"])[0]),
                   float(np.ravel(rough["roughness90pc"])[0]), p.size / fs_hz)


__all__ = ["Ecma418", "FLAG_UNAVAILABLE", "MIN_ECMA_S", "ecma418", "ecma418_available"]
