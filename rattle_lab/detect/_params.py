"""The ``[detect]`` parameters of a pipeline, typed and checked in one place.

:class:`DetectParams` holds every key a pipeline TOML's ``[detect]`` table (and
``rattle-lab fit --pipeline``) accepts: the fields of :class:`ImpactParams` and the sound
keys of :data:`SOUND_KEYS` with ``channel``.  :meth:`DetectParams.from_mapping` builds it
from the table and refuses an unknown key or a bad value; :meth:`DetectParams.to_dict` gives
back the keys that were given, with their values as given, which is what the pipeline's
content keys hash and what ``/results`` records as its provenance ``parameters``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._impacts import ImpactParams

#: The defaults of the sound keys of ``[detect]`` (:func:`~rattle_lab.detect.sound_peaks`'s
#: window and first-peak fraction, the acoustic delay's largest lag, s) and of ``channel``
#: (the channel to detect on; None: chosen by what each channel measures).
SOUND_KEYS: dict[str, Any] = {"window_s": 5e-3, "first_fraction": 0.5, "max_lag_s": 0.01,
                              "channel": None}

#: The defaults of the keys that split a long run into segments analysed one at a time
#: (:mod:`rattle_lab.detect._segments`): a run whose detection channel holds more than
#: 1.5 ``segment_samples`` is cut into segments of about ``segment_samples`` (2**20: 41 s at
#: 25.6 kHz, 20 s at 51.2 kHz), each read with ``segment_margin_s`` of the record either side.
SEGMENT_KEYS: dict[str, Any] = {"segment_samples": 1 << 20, "segment_margin_s": 1.0}

#: The default of ``measurand_if_undetermined``: how an undeclared vibrometer is read in a
#: run whose own data cannot tell its measurand (:func:`~rattle_lab.detect.infer_measurand`).
#: ``""``: the relative reading, with the absolute one's difference in e's error;
#: ``"panel_relative_to_striker"`` or ``"panel_absolute"``: that reading (the campaign's
#: other runs established it, :func:`~rattle_lab.detect.campaign_measurand`, or the user
#: knows it).
MEASURAND_KEYS: dict[str, Any] = {"measurand_if_undetermined": ""}
#: Its values.
MEASURANDS = ("", "panel_relative_to_striker", "panel_absolute")

_IMPACT_FIELDS = tuple(f.name for f in dataclasses.fields(ImpactParams))


@dataclass(frozen=True)
class DetectParams:
    """Parameters of the per-run detection (``[detect]`` of a pipeline TOML).

    Attributes
    ----------
    on, off, min_separation_s, detrend_window_s, fit_window_s, guard_s, poly_degree, \
sigma_floor_rel, fit_basis, sine_window_s, sine_degree, sine_guard_s, min_reversal, \
velocity_model, ring_modes, ring_modes_runs, ring_fundamental, identify_decoder
        Those of :class:`ImpactParams` (same defaults, same checks).
    window_s : float
        Length of the window after each impact the sound peaks are read in, s.
    first_fraction : float
        The first sound peak is the first above this fraction of the window's largest.
    max_lag_s : float
        Largest lag of the impact-to-sound cross-correlation, s.
    channel : str or None
        The channel to detect on in every run (None: the run's ``detect_channel``, else
        chosen by what each channel measures).
    segment_samples : int
        A run whose detection channel holds more than 1.5 times this many samples is
        analysed in segments of about this many (bounded memory whatever the run's length;
        :mod:`rattle_lab.detect._segments`).
    segment_margin_s : float
        Record read on either side of a segment, s (the detector's context at its edges).
    measurand_if_undetermined : str
        How an undeclared vibrometer is read in a run whose own data cannot tell its
        measurand (:data:`MEASURAND_KEYS`): ``""`` (default) the relative reading, the
        absolute one's difference in e's error; ``"panel_relative_to_striker"`` or
        ``"panel_absolute"`` that reading, flagged ``measurand_inferred``.  ``rattle-lab
        fit`` sets it where the campaign's other runs establish the measurand
        (:func:`~rattle_lab.detect.campaign_measurand`).
    given : tuple of str
        The keys the mapping gave, in its order (:meth:`to_dict`).

    The values are kept as given (a TOML integer stays an integer), so that :meth:`to_dict`
    is the mapping the parameters were built from.
    """

    on: float = ImpactParams.on
    off: float = ImpactParams.off
    min_separation_s: float = ImpactParams.min_separation_s
    detrend_window_s: float = ImpactParams.detrend_window_s
    fit_window_s: float = ImpactParams.fit_window_s
    guard_s: float = ImpactParams.guard_s
    poly_degree: int = ImpactParams.poly_degree
    sigma_floor_rel: float = ImpactParams.sigma_floor_rel
    fit_basis: str = ImpactParams.fit_basis
    sine_window_s: float = ImpactParams.sine_window_s
    sine_degree: int = ImpactParams.sine_degree
    sine_guard_s: float = ImpactParams.sine_guard_s
    min_reversal: float = ImpactParams.min_reversal
    velocity_model: str = ImpactParams.velocity_model
    ring_modes: Sequence[Sequence[float]] = ImpactParams.ring_modes
    ring_modes_runs: int = ImpactParams.ring_modes_runs
    ring_fundamental: Sequence[float] = ImpactParams.ring_fundamental
    identify_decoder: bool = ImpactParams.identify_decoder
    window_s: float = SOUND_KEYS["window_s"]
    first_fraction: float = SOUND_KEYS["first_fraction"]
    max_lag_s: float = SOUND_KEYS["max_lag_s"]
    channel: str | None = SOUND_KEYS["channel"]
    segment_samples: int = SEGMENT_KEYS["segment_samples"]
    segment_margin_s: float = SEGMENT_KEYS["segment_margin_s"]
    measurand_if_undetermined: str = MEASURAND_KEYS["measurand_if_undetermined"]
    given: tuple[str, ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        self.impact_params()   # the checks of ImpactParams
        for name in ("window_s", "max_lag_s", "first_fraction"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.number)) \
                    or not (np.isfinite(value) and value > 0):
                raise ParameterError(f"`{name}` must be a number > 0, was {value!r}")
        if self.first_fraction > 1:
            raise ParameterError(f"`first_fraction` must be in (0, 1], was {self.first_fraction}")
        n = self.segment_samples
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1 << 14:
            raise ParameterError(f"`segment_samples` must be an integer >= 16384, was {n!r}")
        m = self.segment_margin_s
        if isinstance(m, bool) or not isinstance(m, (int, float, np.number)) \
                or not (np.isfinite(m) and m > 0):
            raise ParameterError(f"`segment_margin_s` must be a number > 0, was {m!r}")
        if self.measurand_if_undetermined not in MEASURANDS:
            raise ParameterError("`measurand_if_undetermined` must be one of "
                                 f"{', '.join(repr(m) for m in MEASURANDS)}, was "
                                 f"{self.measurand_if_undetermined!r}")
        if self.channel is not None and not isinstance(self.channel, str):
            raise ParameterError(f"`channel` must be a channel name, was {self.channel!r}")
        unknown = sorted(set(self.given) - set(keys()))
        if unknown:
            raise ParameterError(f"unknown key {unknown[0]!r}")

    @classmethod
    def from_mapping(cls, values: Mapping[str, Any] | DetectParams | None,
                     where: str = "") -> DetectParams:
        """The parameters of a ``[detect]`` mapping (its keys recorded in ``given``).

        Raises
        ------
        ParameterError
            For an unknown key (named, prefixed with ``where``) or a value out of range.
        """
        if isinstance(values, DetectParams):
            return values
        values = dict(values or {})
        unknown = sorted(set(values) - set(keys()))
        if unknown:
            raise ParameterError(f"{where}unknown key {unknown[0]!r} "
                                 f"(known: {', '.join(sorted(keys()))})")
        try:
            return cls(**values, given=tuple(values))
        except ParameterError as exc:
            raise ParameterError(f"{where}{exc}") from None

    def impact_params(self) -> ImpactParams:
        """The :class:`ImpactParams` of :func:`~rattle_lab.detect.detect_impacts`."""
        return ImpactParams(**{k: getattr(self, k) for k in _IMPACT_FIELDS})

    def to_dict(self) -> dict[str, Any]:
        """The keys that were given, with their values as given, and any value changed
        since (:func:`dataclasses.replace`) from its default.

        For parameters built by :meth:`from_mapping`, the mapping they were built from: what
        the pipeline's content key of the detect stage and ``/results``'s provenance hold.
        """
        out = {k: getattr(self, k) for k in self.given}
        for f in dataclasses.fields(self):
            if f.name != "given" and f.name not in out and _changed(getattr(self, f.name),
                                                                    f.default):
                out[f.name] = getattr(self, f.name)
        return out


def _changed(value: Any, default: Any) -> bool:
    if value is default:
        return False
    try:
        return bool(value != default)
    except (TypeError, ValueError):
        return True


def keys() -> tuple[str, ...]:
    """Every key of ``[detect]``."""
    return _IMPACT_FIELDS + tuple(SOUND_KEYS) + tuple(SEGMENT_KEYS) + tuple(MEASURAND_KEYS)


__all__ = ["DetectParams", "MEASURAND_KEYS", "SEGMENT_KEYS", "SOUND_KEYS"]
