"""Writing rattle records: validate first, then write atomically.

:func:`write_record` is what the synthetic rig and the tests use to make
valid files without hand-written h5py code.  :func:`write_tree` writes a
validated node tree into any HDF5 group (the ingest store reuses it).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab._atomic import atomic_path
from ._convert import record_to_tree
from ._model import DEFAULT_CHUNK_SAMPLES, ArraySource, Record
from ._schema import validate_tree

#: ``write_data(dataset, hdf5_path, source)`` fills a created dataset from its source.
DataWriter = Callable[[h5py.Dataset, str, ArraySource], None]

#: ``make_dataset(group, name, node, hdf5_path, source)`` creates a dataset itself (a link
#: to the source, say) and returns it, or returns None to have an ordinary one created.
DatasetMaker = Callable[[h5py.Group, str, Mapping[str, Any], str, ArraySource | None],
                        h5py.Dataset | None]


def _attr_value(value: Any) -> Any:
    if isinstance(value, bool):
        return np.bool_(value)
    if isinstance(value, list):
        if all(isinstance(v, str) for v in value):
            return np.array(value, dtype=h5py.string_dtype("utf-8"))
        return np.asarray(value)
    return value


def copy_chunks(n_chunk_samples: int = DEFAULT_CHUNK_SAMPLES) -> DataWriter:
    """A :data:`DataWriter` copying the source chunk by chunk (bounded memory)."""

    def write(dataset: h5py.Dataset, path: str, source: ArraySource) -> None:
        for start in range(0, source.n_samples, n_chunk_samples):
            stop = min(source.n_samples, start + n_chunk_samples)
            dataset[start:stop] = source.read(start, stop)

    return write


def write_tree(group: h5py.Group, tree: Mapping[str, Any], sources: Mapping[str, ArraySource],
               *, write_data: DataWriter | None = None, make_dataset: DatasetMaker | None = None,
               path: str = "/") -> None:
    """Write a node tree into ``group``: attributes, subgroups and datasets.

    Groups keep their creation order (HDF5 ``track_order``), so runs and channels
    read back in the order they were written.  Datasets are made by
    ``make_dataset`` when it returns one, else created with the tree's ``dtype``
    and ``shape``; either way ``write_data`` (default: :func:`copy_chunks`) is
    then called with ``sources[path]`` (a ``write_data`` that only reads, to check
    the samples, suits a linked dataset).
    """
    write_data = write_data or copy_chunks()
    for key, value in tree.get("attrs", {}).items():
        group.attrs[key] = _attr_value(value)
    for name, node in tree.get("members", {}).items():
        child_path = path.rstrip("/") + "/" + name
        if node["kind"] == "group":
            write_tree(group.create_group(name, track_order=True), node, sources, write_data=write_data,
                       make_dataset=make_dataset, path=child_path)
        else:
            ds = (make_dataset(group, name, node, child_path, sources.get(child_path))
                  if make_dataset is not None else None)
            if ds is None:
                ds = group.create_dataset(name, shape=tuple(node["shape"]),
                                          dtype=np.dtype(node["dtype"]))
            for key, value in node.get("attrs", {}).items():
                ds.attrs[key] = _attr_value(value)
            if ds.size:
                write_data(ds, child_path, sources[child_path])


def write_record(path: str | os.PathLike[str], record: Record, *,
                 n_chunk_samples: int = DEFAULT_CHUNK_SAMPLES) -> Path:
    """Write ``record`` to an HDF5 file in the rattle record v1 layout, atomically.

    The record is validated against the schema before anything is written;
    the file appears only when complete (temporary file + rename).

    Parameters
    ----------
    path : path-like
        Output file (``.h5``).  Its directory must exist.
    record : Record
        The campaign to write.  Channel data may be arrays or lazy sources
        (:class:`~rattle_lab.records.GeneratedData` for long records).
    n_chunk_samples : int
        Samples copied at a time.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    SchemaError
        If the record does not conform to the schema (nothing is written).
    OutputError
        If the file cannot be written.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from rattle_lab.records import Channel, Record, Rig, Run, read, write_record
    >>> rig = Rig("other", description="doctest")
    >>> ch = Channel("mic", "sound_pressure", "Pa", np.zeros(4) + [0.0, 1.0, -1.0, 0.5],
    ...              sample_rate_hz=8000.0, start_time_s=0.0)
    >>> rec = Record("demo", "measured", rig, [Run("r1", "transient", [ch])])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     out = write_record(pathlib.Path(folder) / "demo.h5", rec)
    ...     with read(out) as back:
    ...         print(back == rec, back.run("r1").channel("mic").read().tolist())
    True [0.0, 1.0, -1.0, 0.5]
    """
    target = Path(path)
    tree, sources = record_to_tree(record)
    validate_tree(tree, str(target))
    with atomic_path(target) as tmp:
        with h5py.File(tmp, "w", track_order=True) as fh:
            write_tree(fh, tree, sources, write_data=copy_chunks(n_chunk_samples))
    return target
