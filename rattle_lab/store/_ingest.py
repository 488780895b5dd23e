"""Ingestion: record files in, one HDF5 store with a catalogue and provenance out.

:func:`ingest` reads each input with :func:`rattle_lab.records.read` (format
detected, schema validated, files opened read-only), streams every channel in
chunks through the data-quality checks, works out the conversion to SI, and
writes the store atomically under the store's writers' lock
(:func:`rattle_lab.store.edit_store`: a temporary file renamed into place; an
error, a signal or a crash leaves the previous store, or no store, behind, and
concurrent ingests never lose each other's runs).  References out of an HDF5
input (external links, virtual datasets, external storage) are refused unless
``allow_links`` (then only inside the input's folder, hashed); a dataset that
declares more samples than its file stores is refused before any read.

Samples are kept as the input stores them (raw volts, ADC counts, or SI), with
the exact factor to SI beside them, as NWB's ``conversion`` attribute does;
:meth:`~rattle_lab.records.Channel.read` applies it, so every reader of the
store gets SI values.  How the samples get into the store (``storage``):

``"link"`` (default)
    A channel that is a whole 1-D dataset of an HDF5 input (every native
    record) becomes an HDF5 *virtual dataset* of the store that maps onto the
    input's dataset: nothing is copied, a week of shaker data is not stored
    twice, and h5py, MATLAB or HDFView read the store as if it held the data.
    The input's path, size and modification time are recorded; opening a
    record whose input has moved or changed raises :class:`StoreError`
    (re-ingesting the input re-links it).  Other sources (LabVIEW, WAV, TDMS,
    NumPy, MATLAB matrices) are copied.
``"copy"``
    Every sample is copied: the store stands alone.

Store layout (``store_format = "rattle_store"``, ``store_version = 3``, see
:mod:`rattle_lab.store._layout` for the versions and the writers' lock)::

    /                       attrs: store_format, store_version, created_iso, updated_iso,
                                   rattle_lab_version (of the last writer)
    /records/{input_key}    one ingested input, itself a valid rattle record (v1 layout);
                            root attrs add ingest_input_path, ingest_input_hash,
                            ingest_input_size_bytes, ingest_input_mtime_ns, ingest_storage
                            ("link": some datasets are virtual, or "copy"), ingest_format,
                            ingest_mapping, ingest_mapping_sha256, ingest_time_iso,
                            ingest_rattle_lab_version, ingest_skipped (JSON),
                            ingest_link_targets (JSON: file linked from the input -> hash)
        .../channels/{name} the input's samples and attributes (virtual or copied); attrs
                            add ingest_si_units, ingest_scale_to_si, ingest_flags
    /catalogue              one 1-D dataset per column, one row per channel;
                            attrs: columns (JSON list), n_rows
    /provenance/log         one JSON document per ingest call that changed the store

Content hashes are XXH3-128 (``"xxh3_128:"`` + 32 hex digits, the digits
``xxhsum -H2`` prints): a non-cryptographic hash that runs at memory speed, so
hashing a long record costs a fraction of reading it (SHA-256 costs several
times the read).  ``input_key`` is ``"in_"`` + 16 hex digits of SHA-256 over
the input's hash (and, for foreign formats, the mapping's): re-ingesting the
same content is a no-op, and the store file is then not touched at all.
"""

from __future__ import annotations

import concurrent.futures
import hashlib
import json
import mmap
import os
import platform
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from datetime import datetime, UTC
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import h5py
import numpy as np
import xxhash

from rattle_lab._progress import progress_bar
from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError, RattleLabWarning
from rattle_lab.records import read
from rattle_lab.records._convert import record_to_tree
from rattle_lab.records._errors import DuplicateRunError, StoreError
from rattle_lab.records._h5 import LinkPolicy, link_policy
from rattle_lab.records._model import DEFAULT_CHUNK_SAMPLES, ArraySource, Channel, Record, Skipped
from rattle_lab.records._quality import ChannelChecker, Finding, QualityLimits, TimestampChecker
from rattle_lab.records._read import detect_format
from rattle_lab.records._readers.mapping import MappingSpec, load_mapping
from rattle_lab.records._readers.native import load_group
from rattle_lab.records._schema import validate_tree
from rattle_lab.records._write import write_tree
from ._layout import (STORE_FORMAT, STORE_VERSION, edit_store, open_store,  # noqa: F401
                      store_lock, text)

Storage = Literal["link", "copy"]

if TYPE_CHECKING:  # pandas is imported when a catalogue is built, not at import time
    import pandas as pd

HASH_ALGORITHM = "xxh3_128"
HASH_BLOCK_BYTES = 32 << 20  # a multiple of mmap.ALLOCATIONGRANULARITY

#: Catalogue columns (one row per channel) and their kinds.
CATALOGUE_COLUMNS: tuple[tuple[str, Literal["str", "float", "int"]], ...] = (
    ("input_key", "str"),
    ("file", "str"),
    ("file_hash", "str"),
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
    ("storage", "str"),
    ("ingested_iso", "str"),
)


@dataclass(frozen=True)
class InputResult:
    """What happened to one input.

    Attributes
    ----------
    path : Path
        The input file.
    file_hash : str
        Content hash of its bytes (:func:`file_hash`).
    input_key : str
        Its group name under ``/records`` in the store.
    status : str
        ``"added"``, ``"unchanged"`` (already in the store, or repeated in the call), or
        ``"updated"`` (in the store, but linked to a file that has moved or changed, or
        linked while ``storage="copy"`` was asked for: ingested again in its place).
    format : str
        Detected format.
    skipped : tuple of Skipped
        Columns of a foreign file that were not ingested, with reasons.
    findings : tuple of Finding
        Data-quality findings (all flagged in the catalogue).
    """

    path: Path
    file_hash: str
    input_key: str
    status: Literal["added", "unchanged", "updated"]
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


def file_hash(path: str | os.PathLike[str]) -> str:
    """Content hash of a file's bytes: ``"xxh3_128:"`` + 32 hex digits, read in blocks.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     p = pathlib.Path(folder) / "x.bin"
    ...     _ = p.write_bytes(b"")
    ...     file_hash(p)            # XXH3-128 of no bytes, as xxhsum -H2 prints it
    'xxh3_128:99aa06d3014798d86001c324468d497f'
    """
    h = xxhash.xxh3_128()
    with open(path, "rb", buffering=0) as fh:
        size = os.fstat(fh.fileno()).st_size
        # Hashing mapped pages spares the copy into a buffer that read() makes (twice the
        # speed on a warm page cache).  The file is mapped one window at a time, so that the
        # resident memory stays bounded by the window, not the file.
        for start in range(0, size, HASH_BLOCK_BYTES):
            length = min(HASH_BLOCK_BYTES, size - start)
            with mmap.mmap(fh.fileno(), length, offset=start, access=mmap.ACCESS_READ) as window:
                if hasattr(window, "madvise"):  # read-ahead for a cold cache
                    window.madvise(mmap.MADV_SEQUENTIAL)
                view = memoryview(window)
                try:
                    h.update(view)
                finally:
                    view.release()
    return f"{HASH_ALGORITHM}:{h.hexdigest()}"


def input_key(content_hash: str, mapping_sha256: str | None) -> str:
    """Store group name of an input: ``in_`` + 16 hex digits of SHA-256(file hash [+ mapping hash])."""
    text = content_hash if mapping_sha256 is None else f"{content_hash}:{mapping_sha256}"
    return "in_" + hashlib.sha256(text.encode()).hexdigest()[:16]


def _now_iso() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")


# --- the store ------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Stored:
    """An input already in the store."""

    size: int  # bytes of the input
    storage: Storage
    link_ok: bool  # for "link": the linked file is where it was, unchanged


@dataclass
class _StoreIndex:
    """What an existing store holds: its inputs, and the catalogue columns."""

    keys: dict[str, _Stored] = field(default_factory=dict)
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    # (campaign, run) -> (file, input_key)
    runs: dict[tuple[str, str], tuple[str, str]] = field(default_factory=dict)


def _open_store(store: Path) -> h5py.File:
    return open_store(store)


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
            storage = _text(attrs.get("ingest_storage", "copy"))
            index.keys[key] = _Stored(int(attrs["ingest_input_size_bytes"]),
                                      "link" if storage == "link" else "copy",
                                      storage != "link" or _link_problem(attrs) is None)
        index.columns = _read_columns(fh, store)
    cols = index.columns
    for campaign, run, file, key in zip(cols.get("campaign_id", []), cols.get("run_id", []),
                                        cols.get("file", []), cols.get("input_key", [])):
        index.runs[(str(campaign), str(run))] = (str(file), str(key))
    return index


_text = text


#: What a message about a changed or moved input advises.
REINGEST_ADVICE = ("ingest it again to re-link it (`rattle-lab ingest --replace FILE -o STORE`; "
                   "or ingest with --copy for a store that stands alone)")


def _link_problem(attrs: Any) -> str | None:
    """Why a linked record's input cannot serve its samples any more, or None if it can."""
    path = Path(_text(attrs["ingest_input_path"]))
    try:
        st = path.stat()
    except OSError:
        return f"the linked input {path} is missing"
    if st.st_size != int(attrs["ingest_input_size_bytes"]):
        return (f"the linked input {path} has changed since it was ingested (size {st.st_size} "
                f"bytes, was {int(attrs['ingest_input_size_bytes'])})")
    if st.st_mtime_ns != int(attrs["ingest_input_mtime_ns"]):
        return f"the linked input {path} has changed since it was ingested (modification time)"
    return None


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


def _store_tree(record: Record, plans: Mapping[str, _ChannelPlan]) -> tuple[dict[str, Any],
                                                                           dict[str, ArraySource]]:
    """The record's node tree for the store: the input's own attributes plus the SI conversion."""
    tree, sources = record_to_tree(record)
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
    from rattle_lab.records._units import SI_UNITS

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


# --- the library function -------------------------------------------------------------------


@dataclass(eq=False)
class _Input:
    path: Path
    label: str
    size: int
    mtime_ns: int
    format: str
    foreign: bool
    content_hash: str | None = None
    future: concurrent.futures.Future[str] | None = None
    replaces: bool = False  # its key is in the store and is ingested again in its place

    def digest(self) -> str:
        if self.content_hash is None:
            if self.future is not None:
                self.content_hash = self.future.result()
            else:
                self.content_hash = file_hash(self.path)
        return self.content_hash


def ingest(inputs: Iterable[str | os.PathLike[str]], store: str | os.PathLike[str], *,
           mapping: str | os.PathLike[str] | Mapping[str, Any] | MappingSpec | None = None,
           storage: Storage = "link", allow_flagged: bool = False, quiet: bool = True,
           limits: QualityLimits = QualityLimits(),  # noqa: B008 (frozen, immutable)
           n_chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
           on_warning: Callable[[Finding], None] | None = None, replace: bool = False,
           allow_links: bool = False) -> IngestReport:
    """Ingest record files into an HDF5 store (created, or appended to).

    The whole call runs under the store's writers' lock
    (:func:`rattle_lab.store.store_lock`): concurrent ingests into one store
    wait for each other, and each sees the runs the others added.

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
    storage : {"link", "copy"}
        ``"link"``: channels that are whole 1-D HDF5 datasets of the input become
        virtual datasets of the store that read the input (nothing copied; the
        input must stay where it is, unchanged); other channels are copied.
        ``"copy"``: every sample is copied (a self-contained store).  See the
        module docstring.
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
    replace : bool
        A run already in the store from another input (e.g. the same file, changed
        since it was ingested) is replaced: the stored input that holds it is
        removed, with all its runs.  Without it, that is a DuplicateRunError.
    allow_links : bool
        Resolve HDF5 external links, virtual datasets and external storage of
        the inputs, but only to files inside the input's own folder; those files
        are hashed with the input (and their samples copied).  Default: refuse
        any reference out of an input (:class:`~rattle_lab.records._h5.LinkError`).

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
    LinkError
        An HDF5 input refers to another file (and ``allow_links`` is False, or the
        file is outside the input's folder).
    DataError
        A dataset declares more samples than its file stores.
    OutputError
        The store cannot be written.  In every error case the store is left as it was.
    ParameterError
        For no inputs, ``n_chunk_samples < 1``, another ``storage``, or the store among the inputs.

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
    if storage not in ("link", "copy"):
        raise ParameterError(f"`storage` must be 'link' or 'copy', was {storage!r}")
    store = Path(store)
    spec = mapping if isinstance(mapping, MappingSpec) or mapping is None else load_mapping(mapping)
    store_resolved = store.resolve()
    items = []
    for p in paths:
        if p.resolve() == store_resolved:
            raise ParameterError(f"the store {store} is also given as an input")
        fmt = detect_format(p)
        st = p.stat()
        items.append(_Input(path=p, label=str(p), size=st.st_size, mtime_ns=st.st_mtime_ns,
                            format=fmt, foreign=fmt != "rattle_hdf5"))
        if spec is not None and fmt == "rattle_hdf5":
            warnings.warn(f"{p}: is a native rattle record; the mapping {spec.label} does not "
                          "apply to it and is ignored", MappingIgnoredWarning, stacklevel=2)
    with store_lock(store):
        return _ingest_locked(store, items, spec, storage=storage, allow_flagged=allow_flagged,
                              quiet=quiet, limits=limits, n_chunk_samples=n_chunk_samples,
                              on_warning=on_warning, replace=replace, allow_links=allow_links)


class MappingIgnoredWarning(RattleLabWarning):
    """An option was given that does not apply to an input (e.g. a mapping with a native record)."""


def _ingest_locked(store: Path, items: list[_Input], spec: MappingSpec | None, *,
                   storage: Storage, allow_flagged: bool, quiet: bool, limits: QualityLimits,
                   n_chunk_samples: int, on_warning: Callable[[Finding], None] | None,
                   replace: bool, allow_links: bool) -> IngestReport:
    """:func:`ingest` once the store's lock is held: read the store, add, write."""
    index = _read_index(store)

    def key_of(item: _Input) -> str:
        return input_key(item.digest(), spec.sha256 if (item.foreign and spec) else None)

    def current(stored: _Stored) -> bool:  # can the stored copy of an input stand as it is?
        return stored.storage == "copy" or (storage == "link" and stored.link_ok)

    results: dict[int, InputResult] = {}
    new: list[_Input] = []
    sizes = {stored.size for stored in index.keys.values()}
    with concurrent.futures.ThreadPoolExecutor(max_workers=1) as pool:
        batch_keys: set[str] = set()
        for i, item in enumerate(items):
            # Content can only repeat at an equal size: hash those first; hash the others
            # in the background while their data are checked.
            if item.size in sizes:
                for other in new:
                    if other.size == item.size:
                        batch_keys.add(key_of(other))
                key = key_of(item)
                if key in batch_keys or (key in index.keys and current(index.keys[key])):
                    results[i] = InputResult(item.path, item.digest(), key, "unchanged", item.format)
                    continue
                item.replaces = key in index.keys
                batch_keys.add(key)
            else:
                item.future = pool.submit(file_hash, item.path)
            sizes.add(item.size)
            new.append(item)
        changed = False
        columns: Mapping[str, Any] = index.columns
        if new:
            added, columns = _write_store(store, index, new, spec, key_of, storage=storage,
                                          allow_flagged=allow_flagged, limits=limits,
                                          n_chunk_samples=n_chunk_samples, quiet=quiet,
                                          unchanged=[items[i] for i in results],
                                          replace=replace, allow_links=allow_links)
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
    catalogue = _frame(columns)
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
                 key_of: Callable[[_Input], str], *, storage: Storage, allow_flagged: bool,
                 limits: QualityLimits, n_chunk_samples: int, quiet: bool,
                 unchanged: list[_Input], replace: bool = False, allow_links: bool = False
                 ) -> tuple[dict[_Input, InputResult], dict[str, list[Any]]]:
    """Write the new inputs into (a copy of) the store; return their results and the catalogue."""
    from rattle_lab.acoustics.calibration import apply_campaign_calibration  # [issue 17 calibration hook]

    when = _now_iso()
    added: dict[_Input, InputResult] = {}
    rows: list[dict[str, Any]] = []
    replaced = {key_of(item) for item in new if item.replaces}
    runs = {run: where for run, where in index.runs.items() if where[1] not in replaced}
    with edit_store(store, create=when, what="write the store") as fh:
        records = fh.require_group("records")
        for item in new:
            policy = LinkPolicy(allow=allow_links)
            with link_policy(policy), read(item.path,
                                           mapping=spec if item.foreign else None) as record:
                # [issue 17 calibration hook] sensitivities from the campaign's calibrator
                # records, with provenance (rattle_lab.acoustics.calibration)
                record = apply_campaign_calibration(record)
                for run in record.runs:
                    other = runs.get((record.campaign_id, run.run_id))
                    if other is not None and replace and other[1] and other[1] in records:
                        # --replace: the stored input holding this run goes (all its runs)
                        replaced.add(other[1])
                        del records[other[1]]
                        runs = {r: w for r, w in runs.items() if w[1] != other[1]}
                        other = None
                    if other is not None:
                        raise DuplicateRunError(
                            f"{item.label}: /runs/{run.run_id}: run id {run.run_id!r} of "
                            f"campaign {record.campaign_id!r} is already ingested from "
                            f"{other[0]}; use `ingest --replace` (replace=True) to replace "
                            "the stored input that holds it")
                    runs[(record.campaign_id, run.run_id)] = (item.label, "")
                pending = records.create_group("_pending", track_order=True)
                # samples reached through references are copied (the store links inputs
                # only, and only by their own datasets)
                findings, stats, linked = _ingest_record(
                    pending, record, item.label,
                    storage="copy" if policy.targets else storage, limits=limits,
                    n_chunk_samples=n_chunk_samples, quiet=quiet)
                fatal = [f for f in findings if f.fatal]
                if fatal and not allow_flagged:
                    more = (f" (and {len(fatal) - 1} more fatal findings)" if len(fatal) > 1
                            else "")
                    err = fatal[0].error()
                    err.args = (err.args[0] + more + "; use --allow-flagged (allow_flagged=True) "
                                "to ingest with flags",)
                    raise err
                content_hash = item.digest()
                key = key_of(item)
                if key in records:  # an outdated link, ingested again in its place
                    del records[key]
                records.move("_pending", key)
                group = records[key]
                skipped = record.origin.skipped if record.origin else ()
                kept: Storage = "link" if linked else "copy"
                group.attrs.update({
                    "ingest_input_path": str(item.path.resolve()),
                    "ingest_input_hash": content_hash,
                    "ingest_input_size_bytes": item.size,
                    "ingest_input_mtime_ns": item.mtime_ns,
                    "ingest_storage": kept,
                    "ingest_format": item.format,
                    "ingest_mapping": spec.label if (spec and item.foreign) else "",
                    "ingest_mapping_sha256": spec.sha256 if (spec and item.foreign) else "",
                    "ingest_time_iso": when,
                    "ingest_rattle_lab_version": __version__,
                    "ingest_skipped": json.dumps([[s.source, s.reason] for s in skipped]),
                    "ingest_link_targets": json.dumps(
                        {str(t): file_hash(t) for t in sorted(policy.targets)}),
                })
                rows.extend(_catalogue_rows(record, key, str(item.path.resolve()), content_hash,
                                            item.format, stats, when, kept))
                added[item] = InputResult(item.path, content_hash, key,
                                          "updated" if item.replaces else "added", item.format,
                                          tuple(skipped), tuple(findings))
        keep = [i for i, key in enumerate(index.columns.get("input_key", []))
                if str(key) not in replaced]
        columns = {name: [index.columns[name][i] for i in keep] if name in index.columns else []
                   for name, _ in CATALOGUE_COLUMNS}
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
            "allow_flagged": allow_flagged, "storage": storage,
            "mapping": {"path": spec.label, "sha256": spec.sha256} if spec else None,
            "inputs": [{"path": str(i.path.resolve()), "hash": r.file_hash,
                        "input_key": r.input_key, "format": i.format, "status": r.status}
                       for i, r in added.items()]
            + [{"path": str(i.path.resolve()), "hash": i.digest(), "input_key": key_of(i),
                "format": i.format, "status": "unchanged"} for i in unchanged],
        })
    return added, columns


# --- reading the store ------------------------------------------------------------------------


def _frame(columns: Mapping[str, Sequence[Any] | np.ndarray]) -> pd.DataFrame:
    import pandas as pd

    data = {}
    for name, kind in CATALOGUE_COLUMNS:
        values: Sequence[Any] | np.ndarray = columns.get(name, [])
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
    for _values, group in frame.groupby(keys[:4], sort=False, dropna=False):
        first = group.iloc[0]
        flags = dict.fromkeys(f for text in group["flags"] for f in text.split(",") if f)
        rows.append({**{k: first[k] for k in keys}, "n_channels": len(group),
                     "channels": ",".join(group["channel"]),
                     "duration_s": float(group["duration_s"].max()), "flags": ",".join(flags)})
    import pandas as pd

    return pd.DataFrame(rows, columns=keys + ["n_channels", "channels", "duration_s", "flags"])


def open_stored_record(store: str | os.PathLike[str], input_key: str) -> Record:
    """An ingested input as a :class:`~rattle_lab.records.Record` (read lazily).

    :meth:`Channel.read <rattle_lab.records.Channel.read>` gives SI values.

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store or has no such input, or if the
        input is linked (``storage="link"``) and its file has moved or changed
        since it was ingested.
    """
    from rattle_lab.records._convert import record_from_tree
    from rattle_lab.records._model import Origin

    store = Path(store)
    with _open_store(store) as fh:
        group = fh.get(f"records/{input_key}")
        if not isinstance(group, h5py.Group):
            raise StoreError(f"{store}: /records/{input_key}: no such ingested input")
        if _text(group.attrs.get("ingest_storage", "copy")) == "link":
            problem = _link_problem(group.attrs)
            if problem is not None:
                raise StoreError(f"{store}: /records/{input_key}: attribute 'ingest_input_path': "
                                 f"{problem}; {REINGEST_ADVICE}")
    with link_policy(LinkPolicy(trusted=True)):  # the store's own links, to ingested inputs
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
           "CATALOGUE_COLUMNS", "file_hash", "input_key"]
