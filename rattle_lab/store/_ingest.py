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
import json
import os
import platform
import warnings
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError, RattleLabWarning
from rattle_lab.records import (DEFAULT_CHUNK_SAMPLES, DuplicateRunError, Finding, LinkPolicy,
                                MappingSpec, QualityLimits, detect_format, link_policy,
                                load_mapping, read)

from ._catalogue import _frame
from ._channels import _catalogue_rows, _ingest_record
from ._index import _append_log, _read_index, _Stored, _StoreIndex, _write_catalogue
from ._ingest_types import (
    CATALOGUE_COLUMNS,
    IngestReport,
    InputResult,
    Storage,
    _now_iso,
    file_hash,
    input_key,
)
from ._layout import edit_store, store_lock

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
    index = _read_index(store, writing=True)

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



def _write_store(store: Path, index: _StoreIndex, new: list[_Input], spec: MappingSpec | None,
                 key_of: Callable[[_Input], str], *, storage: Storage, allow_flagged: bool,
                 limits: QualityLimits, n_chunk_samples: int, quiet: bool,
                 unchanged: list[_Input], replace: bool = False, allow_links: bool = False
                 ) -> tuple[dict[_Input, InputResult], dict[str, list[Any]]]:
    """Write the new inputs into (a copy of) the store; return their results and the catalogue."""
    from rattle_lab.acoustics.calibration import (
        apply_campaign_calibration,  # [issue 17 calibration hook]
    )

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


__all__ = ["ingest", "MappingIgnoredWarning"]
