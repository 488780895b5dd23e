"""The store's index: catalogue columns, provenance log and the state of linked inputs."""

from __future__ import annotations

import os

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from ._errors import StoreError

from ._ingest_types import CATALOGUE_COLUMNS, Storage
from ._layout import open_store, text

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


def _read_index(store: Path, *, writing: bool = False) -> _StoreIndex:
    index = _StoreIndex()
    if not store.exists():
        return index
    with open_store(store, writing=writing) as fh:
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


#: What a message about a changed or moved input advises (the general form; messages that
#: know the paths give :func:`reingest_advice`).
REINGEST_ADVICE = ("ingest it again to re-link it (`rattle-lab ingest --replace FILE -o STORE`; "
                   "or ingest with --copy for a store that stands alone)")


def reingest_advice(input_path: str | os.PathLike[str], store: str | os.PathLike[str],
                    missing: bool = False) -> str:
    """The re-ingest command for one input of one store, with their paths.

    >>> reingest_advice("run2.h5", "store.h5").split(": ", 1)[1]
    '`rattle-lab ingest --replace run2.h5 -o store.h5` (or with --copy, for a store that stands alone)'
    """
    where = " (at the file's new path, if it moved)" if missing else ""
    return (f"ingest it again to re-link it: `rattle-lab ingest --replace {input_path} -o "
            f"{store}`{where} (or with --copy, for a store that stands alone)")


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

def _read_columns_from(store: Path) -> dict[str, np.ndarray]:
    if not store.exists():
        return {}
    with _open_store(store) as fh:
        return _read_columns(fh, store)
