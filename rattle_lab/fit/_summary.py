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

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from rattle_lab.exceptions import SummaryFormatError, SummaryVersionError
from ._bands import negative_hysteresis, student_t_ci
from ._estimates import Fits, RatioRestitution, _In, _json, _Normalised

#: Layout version of :meth:`FitSummary.to_dict`; :meth:`FitSummary.from_dict` reads only this.
SUMMARY_SCHEMA_VERSION = 1


# --- per-run rows and tables ----------------------------------------------------------------

@dataclass(frozen=True)
class RunRow(_Normalised):
    """One analysed run in the summary (see :class:`~rattle_lab.detect.RunResult` for the fields).

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


# --- the table of fitted quantities -----------------------------------------------------------

@dataclass(frozen=True)
class TableRow:
    """One row of :meth:`FitSummary.table`: a fitted quantity as the CLI, the demo and the
    report print it.

    Attributes
    ----------
    quantity : str
        Its label (``""``: a row that is only a note).
    value, stderr : float or None
        Value and standard error, in ``unit`` (None: not available; ``stderr`` of the
        ``"all"`` and ``"truth"`` views' SPL slope: half its 95 % interval).
    unit : str
        Unit of ``value`` (``"mm"`` for the gap in the ``"recommended"`` view, else SI).
    ci_low, ci_high : float or None
        95 % interval (``"recommended"`` view only).
    truth : float or None
        The synthetic rig's value (``"truth"`` view only; NaN where the truth has none).
    fixed : bool
        A parameter held fixed, not fitted.
    note : str
        What the reader needs to know about the value (``"recommended"`` view only).
    section : str
        ``""``, or ``"eq34"`` for the eq. (3.4) rows that the recommended values supersede.
    """

    quantity: str
    value: float | None = None
    stderr: float | None = None
    unit: str = ""
    ci_low: float | None = None
    ci_high: float | None = None
    truth: float | None = None
    fixed: bool = False
    note: str = ""
    section: str = ""

    @property
    def ci(self) -> tuple[float | None, float | None]:
        """``(ci_low, ci_high)``."""
        return self.ci_low, self.ci_high


def _fmt(x: Any, digits: str = ".4g") -> str:
    """``x`` formatted with ``digits``; ``"-"`` for None or a non-finite number."""
    if x is None:
        return "-"
    xf = float(x)
    return format(xf, digits) if math.isfinite(xf) else "-"


def _half(lo: float | None, hi: float | None) -> float | None:
    return None if lo is None or hi is None else (hi - lo) / 2


def _t_stderr(ci: tuple[Any, Any], dof: int) -> float | None:
    """The standard error behind a Student t 95 % interval with ``dof`` degrees of freedom."""
    from scipy import stats

    lo, hi = ci
    if lo is None or hi is None or dof < 1:
        return None
    return (hi - lo) / (2.0 * float(stats.t.ppf(0.975, dof)))


def _all_rows(fits: Fits) -> list[TableRow]:
    rows: list[TableRow] = []
    if fits.grazing is not None:
        for name, p in fits.grazing.params.items():
            rows.append(TableRow(f"grazing.{name}" + ("" if p.vary else " (fixed)"), p.value,
                                 p.stderr, p.unit, p.ci_low, p.ci_high, fixed=not p.vary))
    if fits.grazing_ramp is not None:
        for name in fits.grazing_ramp.PARAMETERS:
            est = getattr(fits.grazing_ramp, name)
            rows.append(TableRow(f"grazing_ramp.{name}", est.value, est.stderr, est.unit,
                                 est.ci_low, est.ci_high))
    for label, est in (("damping_ramp.zeta (ramp replay)", fits.damping_ramp),
                       ("restitution_ratio.e", fits.restitution_ratio),
                       (f"restitution_down.e ({fits.restitution_down.method or '?'})"
                        if fits.restitution_down is not None else "", fits.restitution_down)):
        if est is not None:
            rows.append(TableRow(label, est.value, est.stderr, "1", est.ci_low, est.ci_high))
    for name in ("first", "max", "rms"):
        law = fits.spl_law(name)
        if law is not None:
            lin = law.linear
            rows.append(TableRow(f"spl_law_{name}.slope (95% half)", lin.slope,
                                 _half(lin.slope_ci_low, lin.slope_ci_high), "Pa/(m/s)",
                                 lin.slope_ci_low, lin.slope_ci_high))
            rows.append(TableRow(f"spl_law_{name}.r2", lin.r2, None, "1"))
            rows.append(TableRow(f"spl_law_{name}.db_offset", law.db.c_db, None,
                                 "dB re 20 uPa @1 m/s", law.db.c_ci_low, law.db.c_ci_high))
    return rows


def _truth_rows(fits: Fits, truth: Mapping[str, Any]) -> list[TableRow]:
    def t(key: str) -> Any:
        return truth.get(key, float("nan"))

    rows: list[TableRow] = []
    graz = fits.grazing
    for key, name, unit in (("gap_m", "gap", "m"), ("f_s_hz", "f_s", "Hz"), ("zeta", "zeta", "1")):
        p = graz.params[key] if graz is not None else None
        rows.append(TableRow(name, None if p is None else p.value,
                             None if p is None else p.stderr, unit, truth=t(key)))
    if fits.grazing_ramp is not None:  # eq. (3.4) less each ramp's replayed lag
        for key, name, unit in (("gap_m", "gap (ramp-corrected)", "m"),
                                ("zeta", "zeta (ramp-corrected)", "1")):
            est = getattr(fits.grazing_ramp, key)
            rows.append(TableRow(name, est.value, est.stderr, unit, truth=t(key)))
    if fits.damping_ramp is not None:  # zeta from replaying the ramps, if fitted
        z = fits.damping_ramp
        rows.append(TableRow("zeta (ramp model)", z.value, z.stderr, "1", truth=t("zeta")))
    for e, name in ((fits.restitution_ratio, "e (velocity ratios)"),
                    (fits.restitution_down, "e (down thresholds)")):
        rows.append(TableRow(name, None if e is None else e.value,
                             None if e is None else e.stderr, "1", truth=t("e")))
    law = fits.spl_law_first.linear if fits.spl_law_first is not None else None
    lo, hi = (law.slope_ci_low, law.slope_ci_high) if law is not None else (None, None)
    rows.append(TableRow("SPL slope, 1st peak (95%)", None if law is None else law.slope,
                         _half(lo, hi),
                         "Pa/(m/s)", lo, hi, truth=t("spl_slope_first")))
    return rows


#: grazing parameter -> (label, scale, unit) in the recommended view
_GRAZING_NAMES = {"gap_m": ("gap h", 1e3, "mm"), "f_s_hz": ("f_s (modal frequency)", 1.0, "Hz"),
                  "zeta": ("zeta (damping ratio)", 1.0, "1"),
                  "participation": ("participation Q1/Q2", 1.0, "1")}


def _scaled(quantity: str, value: Any, stderr: Any, ci: tuple[Any, Any] | None, unit: str,
            note: str = "", scale: float = 1.0, *, fixed: bool = False,
            section: str = "") -> TableRow:
    def sc(x: Any) -> Any:
        return None if x is None else float(x) * scale

    lo, hi = (None, None) if fixed or ci is None or None in ci else (sc(ci[0]), sc(ci[1]))
    return TableRow(quantity, sc(value), None if fixed else sc(stderr), unit, lo, hi,
                    fixed=fixed, note=note, section=section)


class _Recommended:
    """The rows of the ``"recommended"`` view (:meth:`FitSummary.table`)."""

    def __init__(self, summary: FitSummary):
        self.summary, self.fits = summary, summary.fits

    def not_fitted(self, key: str) -> str:
        return " ".join(self.summary.not_fitted.get(key, "not fitted").split())

    def grazing(self) -> list[TableRow]:
        """Gap, zeta, f_s as recommended: ramp-corrected where that fit exists, else eq. (3.4)."""
        g, rg, damp = self.fits.grazing, self.fits.grazing_ramp, self.fits.damping_ramp
        assert g is not None
        rows: list[TableRow] = []
        for key in ("gap_m", "zeta", "f_s_hz", "participation"):
            label, scale, unit = _GRAZING_NAMES[key]
            p = g.params[key]
            if key == "participation":
                rows.append(_scaled(label, p.value, p.stderr, (p.ci_low, p.ci_high), unit,
                                    scale=scale, fixed=not p.vary))
                continue
            if rg is not None and getattr(rg, key).value is not None:
                est = getattr(rg, key)
                ci = (est.ci_low, est.ci_high)
                if None in ci:
                    ci = student_t_ci(est.value, est.stderr, max(len(rg.lag_rel) - 3, 0))
                rows.append(_scaled(f"{label.split(' (')[0]} (ramp-corrected)"
                                    if key != "f_s_hz" else "f_s, ramp-corrected",
                                    est.value, est.stderr, ci, unit, "; ".join(est.notes),
                                    scale=scale))
            elif key == "zeta" and damp is not None and damp.value is not None:
                ci = (damp.ci_low, damp.ci_high)
                if None in ci:
                    ci = student_t_ci(damp.value, damp.stderr, damp.n - 1)
                rows.append(_scaled("zeta (ramp replay)", damp.value, damp.stderr, ci, unit,
                                    "; ".join(damp.notes), scale=scale))
            else:
                rows.append(_scaled(f"{label}, eq. (3.4)", p.value, p.stderr,
                                    (p.ci_low, p.ci_high), unit,
                                    p.bias_note if p.vary else "", scale=scale,
                                    fixed=not p.vary))
        return rows

    def others(self) -> list[TableRow]:
        """Restitution (and the ramp-replay zeta where not above), then the SPL laws."""
        fits, rows = self.fits, []
        for key, label, what in (("damping_ramp", "zeta (ramp replay)", "upward ramps"),
                                 ("restitution_ratio", "e (velocity ratios)", "impacts"),
                                 ("restitution_down", "e (disappearance thresholds)",
                                  "thresholds")):
            est = getattr(fits, key)
            if key == "damping_ramp" and (fits.grazing_ramp is None and est is not None):
                continue  # already the recommended zeta above
            if est is None:
                if key != "damping_ramp" or key in self.summary.not_fitted:  # only if tried
                    rows.append(TableRow(label, note="not fitted: " + self.not_fitted(key)))
                continue
            n = int(getattr(est, "n", 0))
            method = getattr(est, "method", "")
            note = f"from {n} {what}" + (f" ({method})" if method else "")
            if isinstance(est, RatioRestitution) and est.median is not None:
                note += f"; median {_fmt(est.median)}, scatter (std) {_fmt(est.std)}"
            err = est.stderr
            if err is not None and est.value is not None and err > abs(est.value):
                note += "; NOT IDENTIFIED: the standard error exceeds the value"
            for extra in est.notes:
                note += f"; {extra}"
            ci: tuple[float | None, float | None] = (est.ci_low, est.ci_high)
            if None in ci:
                ci = student_t_ci(est.value, err, n - 1)
            rows.append(_scaled(label, est.value, err, ci, "1", note))
        for name, label in (("first", "first peak"), ("max", "maximum peak"),
                            ("rms", "RMS per impact")):
            law = fits.spl_law(name)
            if law is None:
                rows.append(TableRow(f"SPL law, {label}",
                                     note="not fitted: " + self.not_fitted(f"spl_law_{name}")))
                continue
            lin, db = law.linear, law.db
            slope_ci = (lin.slope_ci_low, lin.slope_ci_high)
            icpt_ci = (lin.intercept_ci_low, lin.intercept_ci_high)
            c_ci = (db.c_ci_low, db.c_ci_high)
            rows.append(_scaled(
                f"SPL {label}: slope", lin.slope, _t_stderr(slope_ci, lin.n - 2), slope_ci,
                "Pa/(m/s)", f"p = slope * |v_in| + intercept, r2 = {_fmt(lin.r2, '.3f')}, "
                f"{lin.n} impacts (OLS; std. error from the t interval)"))
            rows.append(_scaled(f"SPL {label}: intercept", lin.intercept,
                                _t_stderr(icpt_ci, lin.n - 2), icpt_ci, "Pa"))
            rows.append(_scaled(
                f"SPL {label}: C", db.c_db, _t_stderr(c_ci, db.n - 1), c_ci,
                "dB re 20 uPa at 1 m/s",
                f"L = 20 log10(|v_in| / (1 m/s)) + C; free-slope check k = "
                f"{_fmt(db.k_db_per_decade, '.3g')} dB/decade (20 for a linear law)"))
        return rows

    def eq34(self, keys: tuple[str, ...]) -> list[TableRow]:
        """The eq. (3.4) fit's ``keys`` with their biases, then its notes (section "eq34")."""
        g = self.fits.grazing
        assert g is not None
        rows: list[TableRow] = []
        for key in keys:
            label, scale, unit = _GRAZING_NAMES[key]
            p = g.params[key]
            rows.append(_scaled(f"{label.split(' (')[0]}, eq. (3.4)", p.value, p.stderr,
                                (p.ci_low, p.ci_high), unit,
                                ("BIASED: " + p.bias_note) if p.bias_note and p.vary else "",
                                scale=scale, fixed=not p.vary, section="eq34"))
        notes = list(g.unidentifiable)
        if g.outliers_hz:
            notes.append("thresholds left out as outliers at " + ", ".join(
                f"{_fmt(f)} Hz" for f in g.outliers_hz))
        rows += [TableRow("", note="note: " + note, section="eq34") for note in notes]
        return rows

    def rows(self) -> list[TableRow]:
        fits, g = self.fits, self.fits.grazing
        rows = self.grazing() if g is not None else [
            TableRow("gap h, f_s, zeta", note="not fitted: " + self.not_fitted("grazing"))]
        rows += self.others()
        # the eq. (3.4) values that a ramp-corrected one supersedes above, with their biases;
        # without any ramp-corrected fit the eq. (3.4) values are the recommended ones
        superseded: tuple[str, ...] = (
            ("gap_m", "zeta", "f_s_hz") if fits.grazing_ramp is not None
            else ("zeta",) if fits.damping_ramp is not None and fits.damping_ramp.value is not None
            else ())
        if g is not None and (superseded or g.unidentifiable or g.outliers_hz):
            rows += self.eq34(superseded)
        return rows


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

    def table(self, view: Literal["all", "truth", "recommended"] = "all", *,
              truth: Mapping[str, Any] | None = None) -> list[TableRow]:
        """The fitted quantities as rows of quantity, value, standard error and unit: the one
        source of ``rattle-lab fit``'s table, the demo's table against the truth and the
        report's parameter table, which only lay the rows out.

        Parameters
        ----------
        view : {"all", "truth", "recommended"}
            ``"all"``: every fitted quantity under its stored name (``grazing.gap_m``, ...),
            in SI units, the SPL laws' slope with half its 95 % interval as ``stderr``, r2 and
            dB offset (``rattle-lab fit``).  ``"truth"``: the quantities a synthetic rig
            knows -- gap, f_s, zeta (eq. 3.4, then ramp-corrected and ramp-replayed where
            fitted), e both ways, the first-peak SPL slope -- each with ``truth``; a
            quantity not fitted has a row of None.  ``"recommended"``: the recommended value
            of each quantity first (gap and zeta ramp-corrected where fitted; gap in mm)
            with its 95 % interval (as the fit gives it, else Student t from the standard
            error) and notes, a ``"not fitted: why"`` row for each fit not made, then
            (section ``"eq34"``) the eq. (3.4) values superseded above, with their biases,
            and the grazing fit's notes.
        truth : mapping of str to float
            ``"truth"`` view only: the rig's ``"gap_m"`` (m), ``"f_s_hz"`` (Hz), ``"zeta"``,
            ``"e"`` and ``"spl_slope_first"`` (Pa/(m/s)); a key not given is NaN.

        Examples
        --------
        >>> from rattle_lab.fit import RatioRestitution
        >>> s = FitSummary(2, 2, fits=Fits(restitution_ratio=RatioRestitution(0.6, 0.01, "1")))
        >>> [(r.quantity, r.value, r.stderr, r.unit) for r in s.table()]
        [('restitution_ratio.e', 0.6, 0.01, '1')]
        >>> [(r.quantity, r.value, r.truth) for r in s.table("truth", truth={"e": 0.61})][3]
        ('e (velocity ratios)', 0.6, 0.61)
        """
        if view == "all":
            return _all_rows(self.fits)
        if view == "truth":
            if truth is None:
                raise TypeError("FitSummary.table('truth') needs the truth")
            return _truth_rows(self.fits, truth)
        if view == "recommended":
            return _Recommended(self).rows()
        raise ValueError(f"FitSummary.table: unknown view {view!r} "
                         "(one of 'all', 'truth', 'recommended')")

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
           "TableRow", "ThresholdTable", "TransientRun"]
