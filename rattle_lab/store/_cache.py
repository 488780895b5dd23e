"""``/pipeline_cache``: the pipeline's stage keys and cached products, in the store.

Layout::

    /pipeline_cache             attrs: one per stage key (``detect``, ``fit``, ...) and
                                       per output digest (``ingest:records``, ``fit:results``,
                                       ``report:hash``, ``simulate:<file>``, ...)
        detect/                 attrs: n_runs; one member per run (``000000``, ...)
        thresholds/             the threshold curve

Products are frozen dataclasses of arrays and scalars (the detection results),
written by :func:`put_dataclass`: a group per object with attribute
``__class__`` (``module:qualname``, only ``rattle_lab.*`` classes are rebuilt),
a dataset per array field, a JSON attribute per scalar field.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib
import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab.exceptions import DataError
from ._errors import StoreError

from ._layout import edit_store, open_store

CACHE_GROUP = "pipeline_cache"


def _digest(obj: Any) -> str:
    text = json.dumps(obj, sort_keys=True, default=str, allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def read_cache_keys(store: str | os.PathLike[str]) -> dict[str, str]:
    """The stage keys recorded in ``store`` (``{}`` without a store or a cache)."""
    store = Path(store)
    if not store.is_file():
        return {}
    try:
        with open_store(store) as fh:
            g = fh.get(CACHE_GROUP)
            if g is None:
                return {}
            return {k: (v.decode() if isinstance(v, bytes) else str(v)) for k, v in g.attrs.items()}
    except (OSError, StoreError):
        return {}


def record_cache_keys(store: str | os.PathLike[str], keys: Mapping[str, str]) -> None:
    """Add (or overwrite) stage keys in ``store``."""
    with edit_store(store, what=f"update {CACHE_GROUP}") as fh:
        fh.require_group(CACHE_GROUP).attrs.update(dict(keys))


def put_dataclass(group: h5py.Group, name: str, value: Any) -> None:
    """Write ``value`` (a dataclass, array or JSON scalar) as ``group[name]``."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        sub = group.create_group(name)
        cls = type(value)
        sub.attrs["__class__"] = f"{cls.__module__}:{cls.__qualname__}"
        for f in dataclasses.fields(value):
            put_dataclass(sub, f.name, getattr(value, f.name))
    elif isinstance(value, np.ndarray):
        group.create_dataset(name, data=value)
    else:
        group.attrs[name] = json.dumps(value.item() if isinstance(value, np.generic) else value,
                                       allow_nan=True)


def get_dataclass(group: h5py.Group) -> Any:
    """Rebuild what :func:`put_dataclass` wrote (rattle_lab classes only)."""
    path = group.attrs["__class__"]
    module, _, qualname = (path.decode() if isinstance(path, bytes) else str(path)).partition(":")
    if not module.startswith("rattle_lab."):  # only our own result classes are rebuilt
        raise DataError(f"{group.name}: attribute '__class__': {module}:{qualname} is not a "
                        "rattle_lab class")
    try:
        cls = getattr(importlib.import_module(module), qualname)
    except (ImportError, AttributeError):  # written by other rattle_lab code: a stale product
        raise DataError(f"{group.name}: attribute '__class__': {module}:{qualname} does not "
                        "exist in this rattle_lab (the product was cached by another "
                        "version; run the stage again)") from None
    kwargs: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        if f.name in group:
            item = group[f.name]
            kwargs[f.name] = get_dataclass(item) if isinstance(item, h5py.Group) else item[()]
        elif f.name in group.attrs:
            value = json.loads(group.attrs[f.name])
            kwargs[f.name] = tuple(value) if isinstance(value, list) else value
    return cls(**kwargs)


def write_cached(store: str | os.PathLike[str], name: str, value: Any) -> None:
    """Replace ``/pipeline_cache/{name}`` with ``value`` (a sequence of runs for ``detect``)."""
    with edit_store(store, what=f"update {CACHE_GROUP}") as fh:
        cache = fh.require_group(CACHE_GROUP)
        if name in cache:
            del cache[name]
        if name == "detect":
            g = cache.create_group("detect")
            g.attrs["n_runs"] = len(value)
            for i, r in enumerate(value):
                put_dataclass(g, f"{i:06d}", r)
        else:
            put_dataclass(cache, name, value)


def read_cached(store: str | os.PathLike[str], name: str) -> Any:
    """``/pipeline_cache/{name}`` (a tuple of runs for ``detect``).

    Raises
    ------
    DataError
        If the store holds no such product.
    """
    with open_store(store) as fh:
        g = fh.get(f"{CACHE_GROUP}/{name}")
        if g is None:
            raise DataError(f"{store}: /{CACHE_GROUP}/{name}: no cached {name}")
        if name == "detect":
            return tuple(get_dataclass(g[k]) for k in sorted(g))
        return get_dataclass(g)


def output_digest(store: str | os.PathLike[str], stage: str) -> str:
    """A digest of what ``stage`` left in the store ("" if absent).

    ``ingest``: the records and their input hashes; ``fit``: the ``/results``
    header (summary, provenance, time written), which any rewrite changes.
    """
    store = Path(store)
    if not store.is_file():
        return ""
    try:
        with open_store(store) as fh:
            if stage == "ingest":
                group = fh.get("records")
                if group is None:
                    return ""
                items = sorted((k, str(g.attrs.get("ingest_input_hash", "")))
                               for k, g in group.items())
            else:
                group = fh.get("results")
                if group is None:
                    return ""
                items = sorted((k, str(v)) for k, v in group.attrs.items())
    except (OSError, StoreError):
        return ""
    return _digest(items)


def input_hashes(store: str | os.PathLike[str],
                 keys: Sequence[str] | None = None) -> dict[str, str]:
    """``{input_key: ingest_input_hash}`` of the stored inputs (all, or ``keys``)."""
    with open_store(store) as fh:
        records = fh.get("records", {})
        wanted = list(records) if keys is None else list(keys)
        out = {}
        for key in wanted:
            group = records.get(key) if hasattr(records, "get") else None
            if group is None:
                raise StoreError(f"{store}: /records/{key}: no such ingested input")
            value = group.attrs.get("ingest_input_hash", "")
            out[key] = value.decode() if isinstance(value, bytes) else str(value)
        return out


def provenance_log(store: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The store's ``/provenance/log`` entries (unreadable entries skipped)."""
    out: list[dict[str, Any]] = []
    with open_store(store) as fh:
        log = fh.get("provenance/log")
        if log is None:
            return out
        items = log[()] if isinstance(log, h5py.Dataset) else [log[k][()] for k in sorted(log)]
        for item in np.atleast_1d(items):
            try:
                out.append(json.loads(item.decode() if isinstance(item, bytes) else str(item)))
            except (TypeError, ValueError):
                continue
    return out
