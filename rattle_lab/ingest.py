"""Ingestion: record files in, one HDF5 store with SI data, a catalogue and provenance out.

:func:`ingest` reads each input with :func:`rattle_lab.records.read` (format
detected, schema validated, files opened read-only), streams every channel in
chunks through the data-quality checks and the conversion to SI, and writes
the store atomically (a temporary file renamed into place: an error leaves
the previous store, or no store, behind).

Store layout (``store_format = "rattle_store"``, ``store_version = 1``)::

    /                       attrs: store_format, store_version, created_iso, updated_iso,
                                   rattle_lab_version (of the last writer)
    /records/{input_key}    one ingested input, itself a valid rattle record (v1 layout)
                            with channel data in SI units; root attrs add ingest_input_path,
                            ingest_input_sha256, ingest_input_size_bytes, ingest_format,
                            ingest_mapping, ingest_mapping_sha256, ingest_time_iso,
                            ingest_rattle_lab_version, ingest_skipped (JSON)
        .../channels/{name} attrs add ingest_source_units, ingest_scale_to_si,
                            ingest_sensitivity, ingest_sensitivity_units, ingest_flags
    /catalogue              one 1-D dataset per column, one row per channel;
                            attrs: columns (JSON list), n_rows
    /provenance/log         one JSON document per ingest call that changed the store

``input_key`` is ``"in_"`` + the first 16 hex digits of SHA-256 over the input's
SHA-256 (and, for foreign formats, the mapping's): re-ingesting the same
content is a no-op, and the store file is then not touched at all.
"""

from __future__ import annotations

import concurrent.futures
import hashlib
import json
import os
import platform
import shutil
import sys
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import h5py
import numpy as np

from ._atomic import atomic_path
from ._version import __version__
from .exceptions import ParameterError
from .records import read
from .records._convert import record_to_tree
from .records._errors import DuplicateRunError, StoreError
from .records._model import DEFAULT_CHUNK_SAMPLES, ArraySource, Channel, Record, Skipped, si_dtype, to_si
from .records._quality import ChannelChecker, Finding, QualityLimits, TimestampChecker
from .records._read import detect_format
from .records._readers.mapping import MappingSpec, load_mapping
from .records._readers.native import load_group
from .records._schema import validate_tree
from .records._write import umask_mode, write_tree

if TYPE_CHECKING:  # pandas is imported when a catalogue is built, not at import time
    import pandas as pd

STORE_FORMAT = "rattle_store"
STORE_VERSION = 1
HASH_BLOCK_BYTES = 4 << 20

#: Catalogue columns (one row per channel) and their kinds.
CATALOGUE_COLUMNS: tuple[tuple[str, Literal["str", "float", "int"]], ...] = (
    ("input_key", "str"),
    ("file", "str"),
    ("file_sha256", "str"),
    ("format", "str"),
    ("campaign_id", "str"),
    ("source", "str"),
    ("run_id", "str"),
    ("protocol", "str"),
    ("excitation_freq_hz", "float"),
    ("nominal_level", "float"),
    ("nominal_level_units", "str"),
    ("run_start_iso", "str"),
    ("channel", "str"),
    ("quantity", "str"),
    ("units", "str"),
    ("source_units", "str"),
    ("scale_to_si", "float"),
    ("timing", "str"),
    ("sample_rate_hz", "float"),
    ("start_time_s", "float"),
    ("n_samples", "int"),
    ("duration_s", "float"),
    ("min_si", "float"),
    ("max_si", "float"),
    ("flags", "str"),
    ("sensor_model", "str"),
    ("sensor_serial", "str"),
    ("calibration_date", "str"),
    ("store_path", "str"),
    ("ingested_iso", "str"),
)


@dataclass(frozen=True)
class InputResult:
    """What happened to one input.

    Attributes
    ----------
    path : Path
        The input file.
    sha256 : str
        SHA-256 of its bytes.
    input_key : str
        Its group name under ``/records`` in the store.
    status : str
        ``"added"`` or ``"unchanged"`` (already in the store, or repeated in the call).
    format : str
        Detected format.
    skipped : tuple of Skipped
        Columns of a foreign file that were not ingested, with reasons.
    findings : tuple of Finding
        Data-quality findings (all flagged in the catalogue).
    """

    path: Path
    sha256: str
    input_key: str
    status: Literal["added", "unchanged"]
    format: str
    skipped: tuple[Skipped, ...] = ()
    findings: tuple[Finding, ...] = ()


@dataclass(frozen=True)
class IngestReport:
    """Result of :func:`ingest`.

    Attributes
    ----------
    store : Path
        The store file.
    inputs : tuple of InputResult
        One per input, in the order given.
    catalogue : pandas.DataFrame
        Catalogue rows (one per channel) of this call's inputs, added or unchanged.
    changed : bool
        Whether the store file was (re)written.
    """

    store: Path
    inputs: tuple[InputResult, ...]
    catalogue: Any = field(repr=False)
    changed: bool = False

    @property
    def findings(self) -> tuple[Finding, ...]:
        """All findings of the inputs added by this call."""
        return tuple(f for r in self.inputs for f in r.findings)


def sha256_file(path: str | os.PathLike[str]) -> str:
    """SHA-256 (hex) of a file's bytes, read in blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        if hasattr(os, "posix_fadvise"):  # read-ahead for a cold cache
            os.posix_fadvise(fh.fileno(), 0, 0, os.POSIX_FADV_SEQUENTIAL)
        while block := fh.read(HASH_BLOCK_BYTES):
            h.update(block)
    return h.hexdigest()


def input_key(file_sha256: str, mapping_sha256: str | None) -> str:
    """Store group name of an input: ``in_`` + 16 hex digits of SHA-256(file hash [+ mapping hash])."""
    text = file_sha256 if mapping_sha256 is None else f"{file_sha256}:{mapping_sha256}"
    return "in_" + hashlib.sha256(text.encode()).hexdigest()[:16]


def _now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds").replace("+00:00", "Z")


# --- the store ------------------------------------------------------------------------------


@dataclass
class _StoreIndex:
    """What an existing store holds: input keys with their sizes, and the catalogue columns."""

    keys: dict[str, int] = field(default_factory=dict)  # input_key -> input size in bytes
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    runs: dict[tuple[str, str], str] = field(default_factory=dict)  # (campaign, run) -> file


def _check_store(fh: h5py.File, store: Path) -> None:
    fmt = fh.attrs.get("store_format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode("utf-8", "replace")
    if fmt != STORE_FORMAT:
        raise StoreError(f"{store}: exists and is not a rattle_lab ingest store (root attribute "
                         f"'store_format' is {fmt!r}); refusing to overwrite it")
    version = fh.attrs.get("store_version")
    if version != STORE_VERSION:
        shown = version.item() if isinstance(version, np.generic) else version
        raise StoreError(f"{store}: /: attribute 'store_version': {shown!r} is not supported "
                         f"(this is version {STORE_VERSION})")


def _open_store(store: Path) -> h5py.File:
    try:
        fh = h5py.File(store, "r")
    except OSError as exc:
        raise StoreError(f"{store}: exists and is not a readable HDF5 ingest store; refusing to "
                         f"overwrite it ({' '.join(str(exc).split())})") from exc
    try:
        _check_store(fh, store)
    except BaseException:
        fh.close()
        raise
    return fh


def _read_columns(fh: h5py.File, store: Path) -> dict[str, np.ndarray]:
    group = fh.get("catalogue")
    if not isinstance(group, h5py.Group):
        raise StoreError(f"{store}: /catalogue: missing group")
    names = json.loads(group.attrs["columns"])
    out = {}
    for name in names:
        ds = group.get(name)
        if not isinstance(ds, h5py.Dataset):
            raise StoreError(f"{store}: /catalogue/{name}: missing dataset")
        out[name] = ds.asstr()[()] if h5py.check_string_dtype(ds.dtype) else ds[()]
    return out


def _read_index(store: Path) -> _StoreIndex:
    index = _StoreIndex()
    if not store.exists():
        return index
    with _open_store(store) as fh:
        records = fh.get("records", {})
        for key in records:
            attrs = records[key].attrs
            index.keys[key] = int(attrs["ingest_input_size_bytes"])
        index.columns = _read_columns(fh, store)
    cols = index.columns
    for campaign, run, file in zip(cols.get("campaign_id", []), cols.get("run_id", []),
                                   cols.get("file", [])):
        index.runs[(str(campaign), str(run))] = str(file)
    return index


def _write_catalogue(fh: h5py.File, columns: Mapping[str, Sequence[Any]]) -> None:
    if "catalogue" in fh:
        del fh["catalogue"]
    group = fh.create_group("catalogue")
    names = [name for name, _ in CATALOGUE_COLUMNS]
    n_rows = len(columns[names[0]]) if names else 0
    for name, kind in CATALOGUE_COLUMNS:
        values = columns[name]
        if kind == "str":
            group.create_dataset(name, data=np.array([str(v) for v in values], dtype=object),
                                 dtype=h5py.string_dtype("utf-8"), shape=(n_rows,))
        elif kind == "int":
            group.create_dataset(name, data=np.asarray(values, dtype=np.int64), shape=(n_rows,))
        else:
            group.create_dataset(name, data=np.asarray(values, dtype=np.float64), shape=(n_rows,))
    group.attrs["columns"] = json.dumps(names)
    group.attrs["n_rows"] = n_rows


def _append_log(fh: h5py.File, entry: Mapping[str, Any]) -> None:
    group = fh.require_group("provenance")
    text = json.dumps(entry, sort_keys=True)
    if "log" not in group:
        group.create_dataset("log", shape=(0,), maxshape=(None,), dtype=h5py.string_dtype("utf-8"),
                             chunks=(64,))
    log = group["log"]
    log.resize((log.shape[0] + 1,))
    log[-1] = text


# --- one input --------------------------------------------------------------------------------


@dataclass
class _ChannelPlan:
    channel: Channel
    run_id: str
    path: str
    scale: float
    si_units: str
    checker: ChannelChecker


class _Bar:
    """Progress over samples, drawn on a terminal only (see :mod:`rattle_lab._progress`)."""

    def __init__(self, total: int, desc: str, quiet: bool) -> None:
        from ._progress import progress_enabled

        self._bar = None
        if progress_enabled(quiet):
            from tqdm.auto import tqdm

            self._bar = tqdm(total=total, desc=desc, unit="samples", unit_scale=True,
                             file=sys.stderr, leave=False)

    def update(self, n: int) -> None:
        if self._bar is not None:
            self._bar.update(n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()


def _store_tree(record: Record, plans: Mapping[str, _ChannelPlan]) -> tuple[dict[str, Any],
                                                                           dict[str, ArraySource]]:
    """The record's node tree rewritten for the store: SI units and dtypes, ingest attributes."""
    tree, sources = record_to_tree(record)
    for run_id, run_node in tree["members"]["runs"]["members"].items():
        for name, node in run_node["members"]["channels"]["members"].items():
            plan = plans[f"/runs/{run_id}/channels/{name}"]
            ch = plan.channel
            attrs = node["attrs"]
            for key in ("sensitivity", "sensitivity_units"):
                attrs.pop(key, None)
            attrs["units"] = plan.si_units
            if ch.range_min is not None and ch.range_max is not None:
                attrs["range_min"] = ch.range_min * plan.scale
                attrs["range_max"] = ch.range_max * plan.scale
            attrs["ingest_source_units"] = ch.units
            attrs["ingest_scale_to_si"] = plan.scale
            if ch.sensitivity is not None:
                attrs["ingest_sensitivity"] = ch.sensitivity
                attrs["ingest_sensitivity_units"] = ch.sensitivity_units
            node["dtype"] = si_dtype(np.dtype(node["dtype"])).str
    return tree, sources


def _ingest_record(out: h5py.Group, record: Record, label: str, *, limits: QualityLimits,
                   n_chunk_samples: int, quiet: bool) -> tuple[list[Finding], dict[str, Any]]:
    """Write ``record`` into ``out`` (SI data, checks on the way); return findings and per-channel stats."""
    plans: dict[str, _ChannelPlan] = {}
    ts_users: dict[str, list[str]] = {}
    for run in record.runs:
        for ch in run.channels:
            path = f"/runs/{run.run_id}/channels/{ch.name}"
            scale = ch.scale_to_si
            plans[path] = _ChannelPlan(
                channel=ch, run_id=run.run_id, path=path, scale=scale, si_units=ch.si_units,
                checker=ChannelChecker(ch.data.dtype, range_min=ch.range_min, range_max=ch.range_max,
                                       n_dropout=limits.n_dropout(ch.sample_rate_hz), limits=limits))
            if ch.timestamps is not None:
                ts_users.setdefault(f"/runs/{run.run_id}/timestamps/{ch.timestamps}", []).append(path)
    ts_checkers = {path: TimestampChecker(limits) for path in ts_users}
    total = sum(p.channel.n_samples for p in plans.values())
    bar = _Bar(total, Path(label).name, quiet)

    def write_data(ds: h5py.Dataset, path: str, source: ArraySource) -> None:
        plan = plans.get(path)
        ts_checker = ts_checkers.get(path)
        n = source.n_samples
        for start in range(0, n, n_chunk_samples):
            stop = min(n, start + n_chunk_samples)
            raw = source.read(start, stop)
            if plan is not None:
                plan.checker.update(raw)
                ds[start:stop] = to_si(raw, plan.scale)
                bar.update(stop - start)
            else:
                if ts_checker is not None:
                    ts_checker.update(raw)
                ds[start:stop] = raw

    tree, sources = _store_tree(record, plans)
    try:
        write_tree(out, tree, sources, write_data=write_data)
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
    return findings, stats


def _si_name(ch: Channel) -> str:
    from .records._units import SI_UNITS

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


def _catalogue_rows(record: Record, key: str, label: str, sha: str, fmt: str,
                    stats: Mapping[str, Mapping[str, Any]], when: str) -> list[dict[str, Any]]:
    rows = []
    for run in record.runs:
        for ch in run.channels:
            path = f"/runs/{run.run_id}/channels/{ch.name}"
            st = stats[path]
            rate = st["rate_hz"]
            rows.append({
                "input_key": key, "file": label, "file_sha256": sha, "format": fmt,
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
                "store_path": f"/records/{key}{path}", "ingested_iso": when,
            })
    return rows


def _num(value: float | None) -> float:
    return np.nan if value is None else float(value)


# --- the library function -------------------------------------------------------------------


@dataclass(eq=False)
class _Input:
    path: Path
    label: str
    size: int
    format: str
    foreign: bool
    sha: str | None = None
    future: concurrent.futures.Future[str] | None = None

    def digest(self) -> str:
        if self.sha is None:
            if self.future is not None:
                self.sha = self.future.result()
            else:
                self.sha = sha256_file(self.path)
        return self.sha


def ingest(inputs: Iterable[str | os.PathLike[str]], store: str | os.PathLike[str], *,
           mapping: str | os.PathLike[str] | Mapping[str, Any] | MappingSpec | None = None,
           allow_flagged: bool = False, quiet: bool = True,
           limits: QualityLimits = QualityLimits(),
           n_chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
           on_warning: Callable[[Finding], None] | None = None) -> IngestReport:
    """Ingest record files into an HDF5 store (created, or appended to).

    Parameters
    ----------
    inputs : iterable of path-like
        Record files, of any format :func:`rattle_lab.records.read` knows.
        They are opened read-only and never modified.
    store : path-like
        The store (``.h5``).  Created if absent; inputs not yet in it are
        appended; inputs already in it (same content hash) are left alone.
    mapping : path-like, dict or MappingSpec, optional
        TOML mapping applied to the foreign-format inputs.
    allow_flagged : bool
        Ingest data with fatal findings (NaN, Inf, clipping, dropouts, rate
        mismatch, non-monotonic timestamps, empty channels), flagging them in
        the catalogue and warning, instead of raising.
    quiet : bool
        No progress bar (it is drawn only on a terminal anyway).
    limits : QualityLimits
        Thresholds of the data-quality checks.
    n_chunk_samples : int
        Samples read at a time (memory stays bounded by a few chunks).
    on_warning : callable, optional
        Called with each finding to report instead of :func:`warnings.warn`.

    Returns
    -------
    IngestReport
        Per-input results and this call's catalogue rows.

    Raises
    ------
    FileFormatError, SchemaError, MappingError
        An input cannot be read or does not conform (file, HDF5 path, field named).
    DataQualityError
        A fatal finding while ``allow_flagged`` is False (e.g. :class:`NaNGapError`,
        naming file, path, field and first sample index).
    DuplicateRunError
        A ``(campaign_id, run_id)`` already in the store from another file, or twice in the call.
    StoreError
        ``store`` exists and is not an ingest store.
    OutputError
        The store cannot be written.  In every error case the store is left as it was.

    Warns
    -----
    DataQualityWarning
        One per finding that is flagged rather than raised (e.g. ``ClippingWarning``,
        ``UncalibratedWarning``).
    """
    paths = [Path(p) for p in inputs]
    if not paths:
        raise ParameterError("`inputs` must name at least one file")
    if n_chunk_samples < 1:
        raise ParameterError(f"`n_chunk_samples` must be >= 1, was {n_chunk_samples}")
    store = Path(store)
    spec = mapping if isinstance(mapping, MappingSpec) or mapping is None else load_mapping(mapping)
    store_resolved = store.resolve()
    items = []
    for p in paths:
        fmt = detect_format(p)
        if p.resolve() == store_resolved:
            raise ParameterError(f"the store {store} is also given as an input")
        items.append(_Input(path=p, label=str(p), size=p.stat().st_size, format=fmt,
                            foreign=fmt != "rattle_hdf5"))
    index = _read_index(store)

    def key_of(item: _Input) -> str:
        return input_key(item.digest(), spec.sha256 if (item.foreign and spec) else None)

    results: dict[int, InputResult] = {}
    new: list[_Input] = []
    sizes = set(index.keys.values())
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        batch_keys: set[str] = set()
        for i, item in enumerate(items):
            # Content can only repeat at an equal size: hash those first; hash the others
            # in the background while their data are checked and converted.
            if item.size in sizes:
                for other in new:
                    if other.size == item.size:
                        batch_keys.add(key_of(other))
                key = key_of(item)
                if key in index.keys or key in batch_keys:
                    results[i] = InputResult(item.path, item.digest(), key, "unchanged", item.format)
                    continue
                batch_keys.add(key)
            else:
                item.future = pool.submit(sha256_file, item.path)
            sizes.add(item.size)
            new.append(item)
        changed = False
        if new:
            added = _write_store(store, index, new, spec, key_of, allow_flagged=allow_flagged,
                                 limits=limits, n_chunk_samples=n_chunk_samples, quiet=quiet,
                                 unchanged=[items[i] for i in results])
            changed = True
            for item, result in added.items():
                results[items.index(item)] = result
    ordered = tuple(results[i] for i in range(len(items)))
    for result in ordered:
        for finding in result.findings:
            if on_warning is not None:
                on_warning(finding)
            else:
                warnings.warn(finding.message, finding.warning_class, stacklevel=2)
    catalogue = _frame(_read_columns_from(store) if changed else index.columns)
    keys = {r.input_key for r in ordered}
    if len(catalogue):
        catalogue = catalogue[catalogue["input_key"].isin(keys)].reset_index(drop=True)
    return IngestReport(store=store, inputs=ordered, catalogue=catalogue, changed=changed)


def _read_columns_from(store: Path) -> dict[str, np.ndarray]:
    if not store.exists():
        return {}
    with _open_store(store) as fh:
        return _read_columns(fh, store)


def _write_store(store: Path, index: _StoreIndex, new: list[_Input], spec: MappingSpec | None,
                 key_of: Callable[[_Input], str], *, allow_flagged: bool, limits: QualityLimits,
                 n_chunk_samples: int, quiet: bool,
                 unchanged: list[_Input]) -> dict[_Input, InputResult]:
    when = _now_iso()
    added: dict[_Input, InputResult] = {}
    rows: list[dict[str, Any]] = []
    runs = dict(index.runs)
    with atomic_path(store) as tmp:
        if store.exists():
            shutil.copyfile(store, tmp)
            shutil.copymode(store, tmp)
            fh = h5py.File(tmp, "a")
        else:
            umask_mode(tmp)
            fh = h5py.File(tmp, "w", track_order=True)
            fh.attrs["store_format"] = STORE_FORMAT
            fh.attrs["store_version"] = STORE_VERSION
            fh.attrs["created_iso"] = when
        with fh:
            records = fh.require_group("records")
            for item in new:
                with read(item.path, mapping=spec if item.foreign else None) as record:
                    for run in record.runs:
                        other = runs.get((record.campaign_id, run.run_id))
                        if other is not None:
                            raise DuplicateRunError(
                                f"{item.label}: /runs/{run.run_id}: run id {run.run_id!r} of "
                                f"campaign {record.campaign_id!r} is already ingested from {other}")
                        runs[(record.campaign_id, run.run_id)] = item.label
                    pending = records.create_group("_pending", track_order=True)
                    findings, stats = _ingest_record(pending, record, item.label, limits=limits,
                                                     n_chunk_samples=n_chunk_samples, quiet=quiet)
                    fatal = [f for f in findings if f.fatal]
                    if fatal and not allow_flagged:
                        more = (f" (and {len(fatal) - 1} more fatal findings)" if len(fatal) > 1
                                else "")
                        err = fatal[0].error()
                        err.args = (err.args[0] + more + "; use --allow-flagged (allow_flagged=True) "
                                    "to ingest with flags",)
                        raise err
                    sha = item.digest()
                    key = key_of(item)
                    records.move("_pending", key)
                    group = records[key]
                    skipped = record.origin.skipped if record.origin else ()
                    group.attrs.update({
                        "ingest_input_path": str(item.path.resolve()),
                        "ingest_input_sha256": sha,
                        "ingest_input_size_bytes": item.size,
                        "ingest_format": item.format,
                        "ingest_mapping": spec.label if (spec and item.foreign) else "",
                        "ingest_mapping_sha256": spec.sha256 if (spec and item.foreign) else "",
                        "ingest_time_iso": when,
                        "ingest_rattle_lab_version": __version__,
                        "ingest_skipped": json.dumps([[s.source, s.reason] for s in skipped]),
                    })
                    rows.extend(_catalogue_rows(record, key, str(item.path.resolve()), sha,
                                                item.format, stats, when))
                    added[item] = InputResult(item.path, sha, key, "added", item.format,
                                              tuple(skipped), tuple(findings))
            columns = {name: list(index.columns.get(name, [])) for name, _ in CATALOGUE_COLUMNS}
            for row in rows:
                for name, _ in CATALOGUE_COLUMNS:
                    columns[name].append(row[name])
            _write_catalogue(fh, columns)
            fh.attrs["updated_iso"] = when
            fh.attrs["rattle_lab_version"] = __version__
            _append_log(fh, {
                "command": "ingest", "time_iso": when, "rattle_lab_version": __version__,
                "python": platform.python_version(), "numpy": np.__version__,
                "h5py": h5py.__version__, "hdf5": h5py.version.hdf5_version,
                "allow_flagged": allow_flagged,
                "mapping": {"path": spec.label, "sha256": spec.sha256} if spec else None,
                "inputs": [{"path": str(i.path.resolve()), "sha256": r.sha256, "input_key": r.input_key,
                            "format": i.format, "status": "added"} for i, r in added.items()]
                + [{"path": str(i.path.resolve()), "sha256": i.digest(), "input_key": key_of(i),
                    "format": i.format, "status": "unchanged"} for i in unchanged],
            })
    return added


# --- reading the store ------------------------------------------------------------------------


def _frame(columns: Mapping[str, np.ndarray]) -> pd.DataFrame:
    import pandas as pd

    data = {}
    for name, kind in CATALOGUE_COLUMNS:
        values = columns.get(name, [])
        if kind == "str":
            data[name] = pd.Series([str(v) for v in values], dtype=object)
        elif kind == "int":
            data[name] = pd.Series(np.asarray(values, dtype=np.int64))
        else:
            data[name] = pd.Series(np.asarray(values, dtype=np.float64))
    return pd.DataFrame(data)


def read_catalogue(store: str | os.PathLike[str],
                   level: Literal["channels", "runs"] = "channels") -> pd.DataFrame:
    """The store's catalogue as a DataFrame.

    Parameters
    ----------
    store : path-like
        An ingest store.
    level : {"channels", "runs"}
        One row per channel (all columns, see :data:`CATALOGUE_COLUMNS`), or one
        row per run (``input_key, file, campaign_id, run_id, protocol,
        excitation_freq_hz, nominal_level, nominal_level_units, run_start_iso,
        n_channels, channels, duration_s, flags``).

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store.
    ParameterError
        For another ``level``.
    """
    if level not in ("channels", "runs"):
        raise ParameterError(f"`level` must be 'channels' or 'runs', was {level!r}")
    store = Path(store)
    if not store.exists():
        raise StoreError(f"{store}: no such store")
    frame = _frame(_read_columns_from(store))
    if level == "channels":
        return frame
    keys = ["input_key", "file", "campaign_id", "run_id", "protocol", "excitation_freq_hz",
            "nominal_level", "nominal_level_units", "run_start_iso"]
    rows = []
    for values, group in frame.groupby(keys[:4], sort=False, dropna=False):
        first = group.iloc[0]
        flags = dict.fromkeys(f for text in group["flags"] for f in text.split(",") if f)
        rows.append({**{k: first[k] for k in keys}, "n_channels": len(group),
                     "channels": ",".join(group["channel"]),
                     "duration_s": float(group["duration_s"].max()), "flags": ",".join(flags)})
    import pandas as pd

    return pd.DataFrame(rows, columns=keys + ["n_channels", "channels", "duration_s", "flags"])


def open_stored_record(store: str | os.PathLike[str], input_key: str) -> Record:
    """An ingested input as a :class:`~rattle_lab.records.Record` (SI data, read lazily).

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store or has no such input.
    """
    from .records._convert import record_from_tree
    from .records._model import Origin

    store = Path(store)
    with _open_store(store) as fh:
        if f"records/{input_key}" not in fh:
            raise StoreError(f"{store}: /records/{input_key}: no such ingested input")
    raw = load_group(store, f"/records/{input_key}")
    label = f"{store}: /records/{input_key}"
    try:
        validate_tree(raw.tree, label)
        return record_from_tree(raw.tree, raw.sources,
                                Origin(path=store, format="rattle_store", closer=raw.closer))
    except BaseException:
        if raw.closer is not None:
            raw.closer()
        raise


__all__ = ["ingest", "read_catalogue", "open_stored_record", "IngestReport", "InputResult",
           "CATALOGUE_COLUMNS", "sha256_file", "input_key"]
