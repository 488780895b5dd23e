"""Typed results of ``rattle-lab fit``: the store-level fit summary as frozen dataclasses.

:func:`~rattle_lab.fit.summarise_fits` returns a :class:`FitSummary`; the CLI's ``--json``
prints :meth:`FitSummary.to_dict`, the store keeps that dict (JSON) under ``/results`` and the
report reads it back with :meth:`FitSummary.from_stored`.

The stored form (``to_dict``)
-----------------------------
A dict of plain JSON values (``dict`` with ``str`` keys, ``list``, ``str``, ``int``,
``float``, ``bool``, ``None``) that :func:`json.dumps` writes as strict JSON
(``allow_nan=False``); ``"schema_version"`` (:data:`SUMMARY_SCHEMA_VERSION`) says its layout.
The layout is the one ``rattle-lab fit --json`` printed before these classes existed, plus
``schema_version``::

    {"schema_version": 1,
     "participation": {"value", "source"[, "note"]},  "data_quality": [str],
     "n_runs": int, "n_ok": int,
     "skipped": [{"input_key", "run_id", "reason"}],
     "runs": [{"input_key", "run_id", "protocol", "freq_hz", "n_impacts", "pattern",
               "acoustic_delay_s", "expected_delay_s", "spl_rms_db", "spl_rms_a_db",
               "threshold_accel_ms2", ["acoustics": {...}, "calibration": {...}]}],
     "thresholds": {"freq_hz", "up_ms2", "down_ms2", "hysteresis_ms2",
                    ["up_se_ms2", "down_se_ms2"]: [float | null]},
     "fits": {"grazing": {"gap_m" | "f_s_hz" | "zeta" | "participation":
                              {"value", "stderr", "unit", "ci": [lo, hi], "vary",
                               ["bias_rel", "bias_note"]},
                          "unidentifiable", "outliers_hz", "residuals_ms2",
                          "correlation": {"names", "matrix"}, "redchi"},
              "restitution_ratio": {"value", "stderr", "unit", "std", "median", "n", "n_runs",
                                    "notes", "ringing_share", "ringing_share_stderr",
                                    "ringing_runs"},
              "damping_ramp": {"value", "stderr", "unit", "ci", "method", "n",
                               "residuals_ms2", "notes"},
              "restitution_down": {... as damping_ramp, "run_ids", "zeta_used",
                                   "stderr_from_zeta"},
              "spl_law_first" | "spl_law_max" | "spl_law_rms":
                  {"linear": {"slope", "slope_ci", "intercept", "intercept_ci", "r2", "n",
                              "slope_unit", "intercept_unit"},
                   "db": {"c_db", "c_ci", "k_db_per_decade", "n", "unit"}}},
     "not_fitted": {fit name: reason},
     ["transients": [{"input_key", "run_id", "channels": [{...}]}]]}

A fit that was not made is absent from ``"fits"`` (and named in ``"not_fitted"``); keys in
``[...]`` are written only when they hold something.

Numbers: a value that is not a finite number (NaN, +-inf: "not available") is ``None``, in
the objects as in the dict -- the classes normalise it when built, so an object, its dict and
its JSON text round-trip exactly (``FitSummary.from_dict(s.to_dict()) == s``).  NumPy scalars
become Python numbers; arrays and lists become tuples in the objects and lists in the dict.
The open mappings (a run's ``acoustics`` and ``calibration``, a transient's ``channels``) are
kept as JSON values under the same rules.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rattle_lab.exceptions import SummaryFormatError, SummaryVersionError
from ._bands import negative_hysteresis
from ._estimates import Fits, _In, _json, _Normalised

#: Layout version of :meth:`FitSummary.to_dict`; :meth:`FitSummary.from_dict` reads only this.
SUMMARY_SCHEMA_VERSION = 1


# --- per-run rows and tables ----------------------------------------------------------------

@dataclass(frozen=True)
class RunRow(_Normalised):
    """One analysed run in the summary (see :class:`~rattle_lab.fit.RunResult` for the fields).

    ``acoustics`` and ``calibration`` (runs with a microphone) are
    :meth:`rattle_lab.acoustics.RunAcoustics.summary`'s mappings, as JSON values.
    """

    input_key: str
    run_id: str
    protocol: str
    freq_hz: float | None = None
    n_impacts: int = 0
    pattern: str = ""
    acoustic_delay_s: float | None = None
    expected_delay_s: float | None = None
    spl_rms_db: float | None = None
    spl_rms_a_db: float | None = None
    threshold_accel_ms2: float | None = None
    acoustics: dict[str, Any] | None = None
    calibration: dict[str, Any] | None = None

    _SCALARS = ("input_key", "run_id", "protocol", "freq_hz", "n_impacts", "pattern",
                "acoustic_delay_s", "expected_delay_s", "spl_rms_db", "spl_rms_a_db",
                "threshold_accel_ms2")

    def to_dict(self) -> dict[str, Any]:
        d = {n: getattr(self, n) for n in self._SCALARS}
        for n in ("acoustics", "calibration"):
            if getattr(self, n) is not None:
                d[n] = _json(getattr(self, n))
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "runs[]") -> RunRow:
        r = _In(d, path)
        return r.build(cls, **{n: r[n] for n in cls._SCALARS},  # type: ignore[no-any-return]
                       acoustics=r.get("acoustics"), calibration=r.get("calibration"))


@dataclass(frozen=True)
class SkippedRun(_Normalised):
    """A run that lacked the channels its analysis needs."""

    input_key: str
    run_id: str
    reason: str

    def to_dict(self) -> dict[str, Any]:
        return {"input_key": self.input_key, "run_id": self.run_id, "reason": self.reason}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "skipped[]") -> SkippedRun:
        r = _In(d, path)
        return r.build(cls, input_key=r["input_key"], run_id=r["run_id"],  # type: ignore[no-any-return]
                       reason=r["reason"])


@dataclass(frozen=True)
class ThresholdTable(_Normalised):
    """Onset (up) and disappearance (down) thresholds against frequency, m/s^2 and Hz
    (:class:`~rattle_lab.detect.thresholds.ThresholdCurve`; None where not measured), with
    their standard uncertainties (``up_se_ms2``, ``down_se_ms2``: empty in summaries written
    before they were kept)."""

    freq_hz: tuple[float | None, ...] = ()
    up_ms2: tuple[float | None, ...] = ()
    down_ms2: tuple[float | None, ...] = ()
    hysteresis_ms2: tuple[float | None, ...] = ()
    up_se_ms2: tuple[float | None, ...] = ()
    down_se_ms2: tuple[float | None, ...] = ()

    _COLUMNS = ("freq_hz", "up_ms2", "down_ms2", "hysteresis_ms2")
    _OPTIONAL = ("up_se_ms2", "down_se_ms2")

    def __post_init__(self) -> None:
        super().__post_init__()
        sizes = {n: len(getattr(self, n)) for n in self._COLUMNS}
        sizes.update({n: len(getattr(self, n)) for n in self._OPTIONAL if getattr(self, n)})
        if len(set(sizes.values())) > 1:
            raise SummaryFormatError(f"ThresholdTable: columns of unequal length {sizes}")

    def array(self, name: str) -> np.ndarray:
        """Column ``name`` as a float array (NaN where None; an absent optional column is
        all NaN)."""
        col = getattr(self, name)
        if not col and name in self._OPTIONAL:
            return np.full(len(self.freq_hz), np.nan)
        return np.array([np.nan if v is None else v for v in col], dtype=float)

    def negative_hysteresis(self) -> list[tuple[float, float]]:
        """``(freq_hz, onset - disappearance)`` where the hysteresis is significantly negative
        (:func:`rattle_lab.fit.negative_hysteresis`)."""
        return negative_hysteresis(*(self.array(n) for n in ("freq_hz", "up_ms2", "down_ms2",
                                                               "up_se_ms2", "down_se_ms2")))

    def to_dict(self) -> dict[str, Any]:
        d = {n: list(getattr(self, n)) for n in self._COLUMNS}
        d.update({n: list(getattr(self, n)) for n in self._OPTIONAL if getattr(self, n)})
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "thresholds") -> ThresholdTable:
        r = _In(d, path)
        return r.build(cls, **{n: r[n] for n in cls._COLUMNS},  # type: ignore[no-any-return]
                       **{n: r.get(n) or () for n in cls._OPTIONAL})


@dataclass(frozen=True)
class ParticipationInfo(_Normalised):
    """The modal participation ``Q1/Q2`` the fits used (nondimensional) and where it came
    from (``"pipeline"``, ``"command line"``, ``"rig modal_participation"``, ...)."""

    value: float | None
    source: str
    #: Why the rig's plate model was not used, with both frequencies (``plate_model_disagrees``).
    note: str | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"value": self.value, "source": self.source}
        if self.note is not None:
            out["note"] = self.note
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "participation") -> ParticipationInfo:
        r = _In(d, path)
        return r.build(cls, value=r["value"], source=r["source"],  # type: ignore[no-any-return]
                       note=r.get("note"))


@dataclass(frozen=True)
class TransientRun(_Normalised):
    """A transient (single-shock) run: one row per channel (role, channel, quantity, found,
    onset_s, peak_s, delay_s, ...; :func:`~rattle_lab.fit._store.transient_shocks`)."""

    input_key: str
    run_id: str
    channels: tuple[dict[str, Any], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {"input_key": self.input_key, "run_id": self.run_id,
                "channels": [_json(c) for c in self.channels]}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "transients[]") -> TransientRun:
        r = _In(d, path)
        return r.build(cls, input_key=r["input_key"], run_id=r["run_id"],  # type: ignore[no-any-return]
                       channels=r["channels"])


# --- the summary ----------------------------------------------------------------------------

def _items(r: _In, key: str, cls: Any, default: Any = None) -> tuple[Any, ...]:
    xs = r[key] if default is None else r.get(key, default)
    if not isinstance(xs, (list, tuple)):
        raise SummaryFormatError(f"summary: {key}: expected a list, got {xs!r}")
    return tuple(cls.from_dict(x, f"{key}[{i}]") for i, x in enumerate(xs))


@dataclass(frozen=True)
class FitSummary(_Normalised):
    """What ``rattle-lab fit`` derives from a store, as :func:`~rattle_lab.fit.summarise_fits`
    gives it (the module docstring shows the stored form).

    Attributes
    ----------
    n_runs, n_ok : int
        Runs in the store, and runs analysed (not skipped).
    runs : tuple of RunRow
        One row per analysed run.
    skipped : tuple of SkippedRun
        Runs skipped, with the reason.
    thresholds : ThresholdTable
        Ramp thresholds against frequency.
    fits : Fits
        The store-level fits that were made.
    not_fitted : dict of str to str
        Fit name -> why it was not made.
    participation : ParticipationInfo or None
        ``Q1/Q2`` the fits used and its source (None only in summaries of old releases).
    data_quality : tuple of str
        Data-quality flags (``participation_assumed``, ``"input_key/run_id: flag"``, ...).
    transients : tuple of TransientRun
        Transient runs, one shock per channel.
    """

    n_runs: int
    n_ok: int
    runs: tuple[RunRow, ...] = ()
    skipped: tuple[SkippedRun, ...] = ()
    thresholds: ThresholdTable = field(default_factory=ThresholdTable)
    fits: Fits = field(default_factory=Fits)
    not_fitted: dict[str, str] = field(default_factory=dict)
    participation: ParticipationInfo | None = None
    data_quality: tuple[str, ...] = ()
    transients: tuple[TransientRun, ...] = ()

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("runs", "skipped", "transients"):
            object.__setattr__(self, name, tuple(getattr(self, name)))

    @property
    def shocks_only(self) -> bool:
        """True when every analysed run is a transient (single shock): no rattle fits apply."""
        return bool(self.runs) and all(r.protocol == "transient" for r in self.runs)

    def to_dict(self) -> dict[str, Any]:
        """The stored form (module docstring): JSON values, with ``schema_version``."""
        d: dict[str, Any] = {"schema_version": SUMMARY_SCHEMA_VERSION}
        if self.participation is not None:
            d["participation"] = self.participation.to_dict()
        d.update({
            "data_quality": list(self.data_quality), "n_runs": self.n_runs, "n_ok": self.n_ok,
            "skipped": [s.to_dict() for s in self.skipped],
            "runs": [r.to_dict() for r in self.runs],
            "thresholds": self.thresholds.to_dict(), "fits": self.fits.to_dict(),
            "not_fitted": dict(self.not_fitted)})
        if self.transients:
            d["transients"] = [t.to_dict() for t in self.transients]
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> FitSummary:
        """Inverse of :meth:`to_dict`.

        Raises
        ------
        SummaryVersionError
            If ``d["schema_version"]`` is absent or not :data:`SUMMARY_SCHEMA_VERSION`.
        SummaryFormatError
            If a field is missing or of the wrong type (the message names its path).

        Examples
        --------
        >>> s = FitSummary(n_runs=2, n_ok=1, not_fitted={"grazing": "too few thresholds"},
        ...                thresholds=ThresholdTable((50.0,), (float("nan"),), (1.5,), (None,)))
        >>> s.thresholds.up_ms2
        (None,)
        >>> FitSummary.from_dict(s.to_dict()) == s
        True
        >>> FitSummary.from_dict({"schema_version": 99})
        Traceback (most recent call last):
        ...
        rattle_lab.exceptions.SummaryVersionError: summary: schema_version 99 is not supported ...
        """
        r = _In(d, "top level")
        version = r.get("schema_version")
        if version is None:
            raise SummaryVersionError(
                "summary: no schema_version: an unversioned summary written before rattle_lab "
                f"had typed results (read it with FitSummary.from_stored); this release "
                f"reads schema_version {SUMMARY_SCHEMA_VERSION}")
        if isinstance(version, bool) or version != SUMMARY_SCHEMA_VERSION:
            raise SummaryVersionError(
                f"summary: schema_version {version!r} is not supported (this release of "
                f"rattle_lab reads {SUMMARY_SCHEMA_VERSION}; a newer release wrote it?)")
        part = r.get("participation")
        return r.build(  # type: ignore[no-any-return]
            cls, n_runs=r["n_runs"], n_ok=r["n_ok"], runs=_items(r, "runs", RunRow),
            skipped=_items(r, "skipped", SkippedRun),
            thresholds=ThresholdTable.from_dict(r["thresholds"]),
            fits=Fits.from_dict(r["fits"]), not_fitted=r["not_fitted"],
            participation=None if part is None else ParticipationInfo.from_dict(part),
            data_quality=r.get("data_quality", ()),
            transients=_items(r, "transients", TransientRun, default=()))

    @classmethod
    def from_stored(cls, d: Mapping[str, Any]) -> FitSummary:
        """A summary as a store holds it, from this or an older release.

        A summary with ``schema_version`` is read by :meth:`from_dict`.  One without it was
        written before the summary was versioned (``/results`` ``results_version`` 1): its
        layout is schema 1's, with the keys later added (``participation``,
        ``data_quality``, ``transients``) possibly absent, so it is read as schema 1.
        """
        if isinstance(d, Mapping) and "schema_version" not in d:
            d = {**d, "schema_version": 1}
        return cls.from_dict(d)


__all__ = ["FitSummary", "ParticipationInfo", "RunRow", "SUMMARY_SCHEMA_VERSION", "SkippedRun",
           "ThresholdTable", "TransientRun"]
