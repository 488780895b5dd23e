"""One input into the store: channel plans, virtual datasets, SI names and catalogue rows."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab._progress import progress_bar
from rattle_lab.records import (ArraySource, Channel, ChannelChecker, Finding, QualityLimits,
                                Record, TimestampChecker, record_to_tree, write_tree)

from ._ingest_types import Storage

# --- one input --------------------------------------------------------------------------------


@dataclass
class _ChannelPlan:
    channel: Channel
    run_id: str
    path: str
    scale: float
    si_units: str
    checker: ChannelChecker


def _store_tree(record: Record, plans: Mapping[str, _ChannelPlan]) -> tuple[dict[str, Any],
                                                                           dict[str, ArraySource]]:
    """The record's node tree for the store: the input's own attributes plus the SI conversion."""
    tree, sources = record_to_tree(record, store=True)   # edges in EDGE_ORDER
    for run_id, run_node in tree["members"]["runs"]["members"].items():
        for name, node in run_node["members"]["channels"]["members"].items():
            plan = plans[f"/runs/{run_id}/channels/{name}"]
            node["attrs"]["ingest_si_units"] = plan.si_units
            node["attrs"]["ingest_scale_to_si"] = plan.scale
    return tree, sources


def _virtual_dataset(group: h5py.Group, name: str, node: Mapping[str, Any], path: str,
                     source: ArraySource | None) -> h5py.Dataset | None:
    """A virtual dataset of ``group`` mapping onto the source's whole 1-D HDF5 dataset, or None.

    A missing source file would read as the fill value: NaN for floats (and
    :func:`open_stored_record` refuses a record whose linked input has gone).
    """
    location = getattr(source, "location", None)
    shape = tuple(node["shape"])
    if location is None or len(shape) != 1 or shape[0] == 0:
        return None
    file, dataset_path = location
    dtype = np.dtype(node["dtype"])
    layout = h5py.VirtualLayout(shape=shape, dtype=dtype)
    layout[:] = h5py.VirtualSource(str(Path(file).resolve()), dataset_path, shape=shape, dtype=dtype)
    return group.create_virtual_dataset(name, layout, fillvalue=np.nan if dtype.kind == "f" else 0)


def _ingest_record(out: h5py.Group, record: Record, label: str, *, storage: Storage,
                   limits: QualityLimits, n_chunk_samples: int,
                   quiet: bool) -> tuple[list[Finding], dict[str, Any], bool]:
    """Write ``record`` into ``out`` (linked or copied, checked on the way).

    Returns the findings, per-channel statistics, and whether any dataset is linked.
    """
    plans: dict[str, _ChannelPlan] = {}
    ts_users: dict[str, list[str]] = {}
    for run in record.runs:
        for ch in run.channels:
            path = f"/runs/{run.run_id}/channels/{ch.name}"
            plans[path] = _ChannelPlan(
                channel=ch, run_id=run.run_id, path=path, scale=ch.scale_to_si,
                si_units=ch.si_units,
                checker=ChannelChecker(ch.data.dtype, range_min=ch.range_min, range_max=ch.range_max,
                                       n_dropout=limits.n_dropout(ch.sample_rate_hz), limits=limits))
            if ch.timestamps is not None:
                ts_users.setdefault(f"/runs/{run.run_id}/timestamps/{ch.timestamps}", []).append(path)
    ts_checkers = {path: TimestampChecker(limits) for path in ts_users}
    total = sum(p.channel.n_samples for p in plans.values())
    bar = progress_bar(total, desc=Path(label).name, unit="samples", unit_scale=True, quiet=quiet)
    linked: list[str] = []

    def make_dataset(group: h5py.Group, name: str, node: Mapping[str, Any], path: str,
                     source: ArraySource | None) -> h5py.Dataset | None:
        ds = _virtual_dataset(group, name, node, path, source) if storage == "link" else None
        if ds is not None:
            linked.append(path)
        return ds

    def write_data(ds: h5py.Dataset, path: str, source: ArraySource) -> None:
        # The checks run here, in line with the reads: the content hash already runs on a
        # second thread, and a third (checks overlapped with reads) was slower on two cores.
        checker = plans[path].checker if path in plans else ts_checkers.get(path)
        copy = not ds.is_virtual
        if not copy and checker is None:
            return  # linked, and nothing to check
        n = source.n_samples
        for start in range(0, n, n_chunk_samples):
            stop = min(n, start + n_chunk_samples)
            raw = source.read(start, stop)
            if checker is not None:
                checker.update(raw)
            if copy:
                ds[start:stop] = raw
            if path in plans:
                bar.update(stop - start)

    tree, sources = _store_tree(record, plans)
    try:
        write_tree(out, tree, sources, write_data=write_data, make_dataset=make_dataset)
    finally:
        bar.close()

    findings: list[Finding] = []
    per_channel: dict[str, list[str]] = {path: [] for path in plans}
    for ts_path, checker in ts_checkers.items():
        for flag, index, count, detail in checker.finish():
            findings.append(Finding(flag, label, ts_path, "timestamps", detail, index, count))
            for user in ts_users[ts_path]:
                per_channel[user].append(flag)
    for path, plan in plans.items():
        for flag, index, count, detail in plan.checker.finish():
            findings.append(Finding(flag, label, path, "data", detail, index, count))
            per_channel[path].append(flag)
        ch = plan.channel
        if ch.units == "1":
            findings.append(Finding("uncalibrated", label, path, "units",
                                    f"amplitude in full-scale units '1', not calibrated to "
                                    f"{_si_name(ch)}"))
            per_channel[path].append("uncalibrated")
        if ch.units_assumed:
            findings.append(Finding("units_assumed", label, path, "units",
                                    f"units {ch.units!r} were assumed by the mapping, not stated "
                                    "by the source"))
            per_channel[path].append("units_assumed")
    rates = _effective_rates(plans, ts_checkers)
    for run in record.runs:
        paths = [f"/runs/{run.run_id}/channels/{ch.name}" for ch in run.channels]
        ref_path = paths[0]
        for path in paths[1:]:
            a, b = rates[ref_path], rates[path]
            if np.isfinite(a) and np.isfinite(b) and not np.isclose(a, b, rtol=limits.rate_rtol, atol=0):
                findings.append(Finding(
                    "rate_mismatch", label, path, "sample_rate_hz",
                    f"{b:.9g} Hz differs from {a:.9g} Hz of channel "
                    f"{plans[ref_path].channel.name!r} in run {run.run_id!r}"))
                per_channel[path].append("rate_mismatch")
    stats = {}
    for path, plan in plans.items():
        flags = ",".join(dict.fromkeys(per_channel[path]))
        out[path.lstrip("/")].attrs["ingest_flags"] = flags
        c = plan.checker
        stats[path] = {"flags": flags, "rate_hz": rates[path],
                       "min_si": c.vmin * plan.scale if np.isfinite(c.vmin) else np.nan,
                       "max_si": c.vmax * plan.scale if np.isfinite(c.vmax) else np.nan}
    return findings, stats, bool(linked)


def _si_name(ch: Channel) -> str:
    from rattle_lab.records import SI_UNITS

    return SI_UNITS[ch.quantity]


def _effective_rates(plans: Mapping[str, _ChannelPlan],
                     ts_checkers: Mapping[str, TimestampChecker]) -> dict[str, float]:
    rates = {}
    for path, plan in plans.items():
        ch = plan.channel
        if ch.sample_rate_hz is not None:
            rates[path] = float(ch.sample_rate_hz)
        else:
            ts_path = f"/runs/{plan.run_id}/timestamps/{ch.timestamps}"
            rates[path] = ts_checkers[ts_path].mean_rate_hz
    return rates


def _catalogue_rows(record: Record, key: str, label: str, content_hash: str, fmt: str,
                    stats: Mapping[str, Mapping[str, Any]], when: str,
                    storage: Storage) -> list[dict[str, Any]]:
    rows = []
    for run in record.runs:
        for ch in run.channels:
            path = f"/runs/{run.run_id}/channels/{ch.name}"
            st = stats[path]
            rate = st["rate_hz"]
            rows.append({
                "input_key": key, "file": label, "file_hash": content_hash, "format": fmt,
                "campaign_id": record.campaign_id, "source": record.source, "run_id": run.run_id,
                "protocol": run.protocol,
                "excitation_freq_hz": _num(run.excitation_freq_hz),
                "nominal_level": _num(run.nominal_level),
                "nominal_level_units": run.nominal_level_units or "",
                "run_start_iso": run.start_time_iso or "",
                "channel": ch.name, "quantity": ch.quantity, "units": ch.si_units,
                "source_units": ch.units, "scale_to_si": ch.scale_to_si,
                "timing": "rate" if ch.sample_rate_hz is not None else "timestamps",
                "sample_rate_hz": rate,
                "start_time_s": _num(ch.start_time_s),
                "n_samples": ch.n_samples,
                "duration_s": ch.n_samples / rate if rate and np.isfinite(rate) else np.nan,
                "min_si": st["min_si"], "max_si": st["max_si"], "flags": st["flags"],
                "sensor_model": ch.sensor_model or "", "sensor_serial": ch.sensor_serial or "",
                "calibration_date": ch.calibration_date or "",
                "store_path": f"/records/{key}{path}", "storage": storage, "ingested_iso": when,
            })
    return rows


def _num(value: float | None) -> float:
    return np.nan if value is None else float(value)


