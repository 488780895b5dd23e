"""Gather what a report shows from an ingest store, defensively.

Each stage's data may be absent (no ``/results``, a fit that did not
converge, a run without a microphone): :func:`gather` never fails for that;
it records why in :attr:`ReportData.missing` and the section is left out.
Only a missing file or a file that is not an ingest store raises.  The rig facts are the
report's own types (``RecordInfo``): the rig page
draws them as gathered.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from rattle_lab.exceptions import RattleLabError
from rattle_lab.fit import FitSummary
from rattle_lab.store import StoreError
from rattle_lab.report import ChannelInfo, RecordInfo


@dataclass(frozen=True)
class ReportData:
    """Everything a report is computed from; ``results`` is None when ``/results`` is unusable.

    Attributes
    ----------
    store : Path
    catalogue : pandas.DataFrame
        One row per channel.
    records : tuple of RecordInfo
    provenance_log : list of dict
        The store's ``/provenance/log`` documents.
    results : rattle_lab.store.StoredResults or None
        What ``rattle-lab fit`` wrote (per-run arrays, thresholds, provenance).
    summary : rattle_lab.fit.FitSummary or None
        Its summary, typed (:meth:`~rattle_lab.fit.FitSummary.from_stored`); None exactly
        when ``results`` is.
    missing : dict of str to str
        Section name -> why it is left out, as gathering found (not modified later: the
        report's content adds the sections' reasons to a copy).
    """

    store: Path
    catalogue: Any
    records: tuple[RecordInfo, ...]
    provenance_log: list[dict[str, Any]]
    results: Any
    missing: dict[str, str] = field(default_factory=dict)
    summary: FitSummary | None = None


def _s(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, float):
        return "" if not np.isfinite(value) else f"{value:.6g}"
    return str(value)


def _record_info(store: Path, key: str) -> RecordInfo:
    from rattle_lab.store import open_stored_record

    with open_stored_record(store, key) as record:
        rig = record.rig
        positions = {s.sensor_id: s.position_m for s in rig.sensors}
        rig_facts = {
            "apparatus": rig.apparatus, "plate_length_m": rig.plate_length_m,
            "plate_width_m": rig.plate_width_m, "plate_thickness_m": rig.plate_thickness_m,
            "plate_material": rig.plate_material, "edge_conditions": rig.edge_conditions,
            "striker_x_m": rig.striker_x_m, "striker_y_m": rig.striker_y_m,
            "gap_m": rig.gap_m, "mic_distance_m": rig.mic_distance_m}
        seen: dict[str, ChannelInfo] = {}
        runs: dict[str, dict[str, Any]] = {}
        for run in record.runs:
            runs[run.run_id] = {"protocol": run.protocol, "freq_hz": run.excitation_freq_hz,
                                "level": run.nominal_level, "level_end": run.level_end,
                                "level_units": run.nominal_level_units or ""}
            for ch in run.channels:
                if ch.name in seen:
                    continue
                # the store keeps the input's units and sensitivity; ranges shown in SI
                sens, sens_units = ch.sensitivity, ch.sensitivity_units or ""
                scale = ch.scale_to_si
                rng = (f"{_s(ch.range_min * scale)} .. {_s(ch.range_max * scale)}"
                       if ch.range_min is not None and ch.range_max is not None else "")
                pos = positions.get(ch.sensor_id or "")
                seen[ch.name] = ChannelInfo(
                    key, ch.name, ch.quantity, ch.si_units, ch.units, scale,
                    f"{_s(sens)} {_s(sens_units)}".strip() if sens is not None else "",
                    float(ch.sample_rate_hz) if ch.sample_rate_hz else float("nan"),
                    _s(ch.sensor_model), _s(ch.sensor_serial), _s(ch.calibration_date), rng,
                    "(" + ", ".join(f"{x:.3g}" for x in pos) + ")" if pos else "")
        return RecordInfo(key, record.campaign_id, record.source, rig_facts,
                          tuple(seen.values()), runs)


def _provenance_log(store: Path) -> list[dict[str, Any]]:
    from rattle_lab.store import provenance_log

    return provenance_log(store)


def gather(store: str | os.PathLike[str]) -> ReportData:
    """Read everything a report needs from ``store``.

    Raises
    ------
    StoreError
        If ``store`` does not exist or is not an ingest store, or an input it
        reads samples from has changed or gone since it was ingested.
    """
    from rattle_lab.store import check_linked_inputs, read_catalogue

    store = Path(store)
    if not store.is_file():
        raise StoreError(f"{store}: no such store")
    catalogue = read_catalogue(store)  # raises StoreError for a non-store
    missing: dict[str, str] = {}
    keys = list(dict.fromkeys(catalogue["input_key"]))
    check_linked_inputs(store, keys)  # a changed input is an error, not a missing section
    records = []
    for key in keys:
        try:
            records.append(_record_info(store, key))
        except RattleLabError as exc:
            missing[f"rig ({key})"] = " ".join(str(exc).split())
    try:
        log = _provenance_log(store)
    except (OSError, ValueError) as exc:
        log, missing["provenance log"] = [], str(exc)
    results, summary = None, None
    try:
        from rattle_lab.store import read_results

        results = read_results(store)
        summary = FitSummary.from_stored(results.summary)
    except ImportError as exc:
        missing["results"] = f"the fit stage is not available ({exc})"
    except (RattleLabError, KeyError, ValueError, OSError) as exc:
        results = None  # a summary this release cannot read: no results section
        missing["results"] = " ".join(str(exc).split()) or type(exc).__name__
    return ReportData(store, catalogue, tuple(records), log, results, missing, summary)
