"""``/results`` of a store: what ``rattle-lab fit`` writes, and reading it back.

Layout added to an ingest store (written through :func:`rattle_lab.store.edit_store`: under
the writers' lock, on a copy renamed over the store; an error leaves the previous store intact)::

    /results                    attrs: results_version (1), created_iso, rattle_lab_version,
                                       provenance (JSON: function, parameters, inputs
                                       {input_key: ingest_input_hash}), summary (JSON of
                                       ``FitSummary.to_dict()``, as printed by
                                       ``rattle-lab fit --json``; it carries its own
                                       ``schema_version``, absent in summaries written
                                       before the fit results were typed)
    /results/runs/{input_key}/{run_id}
                                attrs: status ("ok" | "skipped"), reason, protocol, freq_hz,
                                       channels_used (JSON), n_impacts, pattern, pattern_n,
                                       acoustic_delay_s, expected_delay_s, spl_rms_db,
                                       spl_rms_a_db, threshold_direction, threshold_accel_ms2,
                                       threshold_t_s, threshold_censored (0/1), the measured
                                       ramp threshold_ramp_start_ms2, threshold_ramp_end_ms2,
                                       threshold_ramp_duration_s, threshold_ramp_rms_ms2,
                                       threshold_impact_gap_cycles
                                       (NaN / "" where not applicable)
        datasets (status "ok"): t_s, onset_s, v_in_m_s, v_out_m_s, e, strength (impacts);
                                t_first_s, p_first_pa, t_max_s, p_max_pa, p_rms_pa,
                                delay_first_s, delay_max_s, spl_first_db, spl_max_db (sound
                                peaks and their levels in dB re 20 uPa, with a microphone);
                                cycle_counts (impacts per forcing cycle)
    /results/thresholds         datasets freq_hz, up_ms2, down_ms2, hysteresis_ms2
                                [, up_se_ms2, down_se_ms2: standard uncertainties]

:func:`read_results` returns all of it as a :class:`StoredResults`.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab._version import __version__
from ._errors import StoreError

from ._layout import check_store, edit_store, open_store

RESULTS_VERSION = 1

_IMPACT_FIELDS = ("t_s", "onset_s", "v_in_m_s", "v_out_m_s", "e", "strength")
_PEAK_FIELDS = ("t_first_s", "p_first_pa", "t_max_s", "p_max_pa", "p_rms_pa", "delay_first_s",
                "delay_max_s", "spl_first_db", "spl_max_db")


@dataclass(frozen=True)
class StoredResults:
    """What :func:`read_results` returns.

    Attributes
    ----------
    summary : dict
        The fit summary as stored (:meth:`rattle_lab.fit.FitSummary.to_dict`'s JSON form;
        :meth:`rattle_lab.fit.FitSummary.from_stored` types it, older layouts included).
    provenance : dict
        As written.
    runs : dict
        Per-run attributes and arrays, keyed by ``(input_key, run_id)`` (keys as in the
        layout above).
    thresholds : dict of str to ndarray
        ``freq_hz, up_ms2, down_ms2, hysteresis_ms2`` [, ``up_se_ms2, down_se_ms2``].
    created_iso, rattle_lab_version : str
    """

    summary: dict[str, Any]
    provenance: dict[str, Any]
    runs: dict[tuple[str, str], dict[str, Any]]
    thresholds: dict[str, np.ndarray]
    created_iso: str
    rattle_lab_version: str


def _now_iso() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")


def _attr(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    return value


def _write(fh: h5py.File, fit: Any) -> None:
    # the summary is typed by the fit package (a layer below would not know it): it writes
    # itself as JSON values (FitSummary.to_dict, strict JSON with its schema_version)
    summary = fit.summary.to_dict() if hasattr(fit.summary, "to_dict") else fit.summary
    if "results" in fh:
        del fh["results"]
    root = fh.create_group("results")
    root.attrs.update({"results_version": RESULTS_VERSION, "created_iso": _now_iso(),
                       "rattle_lab_version": __version__,
                       "provenance": json.dumps(fit.provenance, allow_nan=True),
                       "summary": json.dumps(summary, allow_nan=True)})
    runs = root.create_group("runs")
    for r in fit.runs:
        g = runs.require_group(r.input_key).create_group(r.run_id)
        thr = r.threshold
        g.attrs.update({k: _attr(v) for k, v in {
            "status": r.status, "reason": r.reason, "protocol": r.protocol, "freq_hz": r.freq_hz,
            "channels_used": json.dumps(list(r.channels_used)),
            "n_impacts": r.impacts.n_impacts if r.impacts is not None else 0,
            "pattern": r.pattern, "pattern_n": r.pattern_n, "acoustic_delay_s": r.acoustic_delay_s,
            "expected_delay_s": r.expected_delay_s, "spl_rms_db": r.spl_rms_db,
            "spl_rms_a_db": r.spl_rms_a_db,
            "threshold_direction": thr.direction if thr else "",
            "threshold_accel_ms2": thr.accel_ms2 if thr else np.nan,
            "threshold_t_s": thr.t_s if thr else np.nan,
            "threshold_censored": int(thr.censored) if thr else 0,
            "threshold_ramp_start_ms2": thr.ramp_start_ms2 if thr else np.nan,
            "threshold_ramp_end_ms2": thr.ramp_end_ms2 if thr else np.nan,
            "threshold_ramp_duration_s": thr.ramp_duration_s if thr else np.nan,
            "threshold_ramp_rms_ms2": thr.ramp_rms_ms2 if thr else np.nan,
            "threshold_impact_gap_cycles": thr.impact_gap_cycles if thr else np.nan}.items()})
        if r.impacts is not None:
            for name in _IMPACT_FIELDS:
                g.create_dataset(name, data=np.asarray(getattr(r.impacts, name), dtype=np.float64))
            g.create_dataset("cycle_counts", data=np.asarray(r.cycle_counts, dtype=np.int64))
        if r.peaks is not None:
            for name in _PEAK_FIELDS:
                g.create_dataset(name, data=np.asarray(getattr(r.peaks, name), dtype=np.float64))
    th = root.create_group("thresholds")
    for name in ("freq_hz", "up_ms2", "down_ms2", "hysteresis_ms2", "up_se_ms2", "down_se_ms2"):
        col = getattr(fit.thresholds, name, None)
        if col is not None and (len(col) or name in ("freq_hz", "up_ms2", "down_ms2",
                                                     "hysteresis_ms2")):
            th.create_dataset(name, data=np.asarray(col, dtype=np.float64))


def write_results(store: str | os.PathLike[str], fit: Any) -> None:
    """Replace ``/results`` of ``store`` with ``fit`` (a :class:`rattle_lab.fit._results.StoreFit`,
    whose ``summary`` is a :class:`rattle_lab.fit.FitSummary`).

    Raises
    ------
    StoreError
        If ``store`` does not exist.
    OutputError
        If it cannot be written (the previous store is left intact).
    """
    with edit_store(store, what="write results") as fh:
        _write(fh, fit)


def _decode(value: Any) -> Any:
    if isinstance(value, bytes):
        return value.decode()
    if isinstance(value, np.generic):
        return value.item()
    return value


def read_results(store: str | os.PathLike[str]) -> StoredResults:
    """The results written by :func:`write_results` (``rattle-lab fit``).

    Raises
    ------
    StoreError
        If the store does not exist or holds no results.
    """
    store = Path(store)
    with open_store(store, check=False) as fh:
        if "results" not in fh:
            raise StoreError(f"{store}: /results: no results (run `rattle-lab fit` first)")
        check_store(fh, store)
        root = fh["results"]
        runs: dict[tuple[str, str], dict[str, Any]] = {}
        for key, grp in root["runs"].items():
            for run_id, g in grp.items():
                d = {k: _decode(v) for k, v in g.attrs.items()}
                d["channels_used"] = tuple(json.loads(d["channels_used"]))
                d.update({k: g[k][()] for k in g})
                runs[(key, run_id)] = d
        thresholds = {k: root["thresholds"][k][()] for k in root["thresholds"]}
        return StoredResults(json.loads(_decode(root.attrs["summary"])),
                             json.loads(_decode(root.attrs["provenance"])), runs, thresholds,
                             str(_decode(root.attrs["created_iso"])),
                             str(_decode(root.attrs["rattle_lab_version"])))
