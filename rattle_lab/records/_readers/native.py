"""Reader of native rattle records (HDF5 files in the v1 layout)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab.exceptions import FileFormatError
from .._h5 import H5Handle, H5Source, hdf5_signature_offset, node_tree, open_readonly
from .._model import ArraySource
from . import RawRecord

FORMAT = "rattle_hdf5"


def is_native(path: Path) -> bool:
    """True for an HDF5 file whose root says ``schema = 'rattle_record'``."""
    if hdf5_signature_offset(path) is None:
        return False
    with open_readonly(path) as fh:  # a damaged HDF5 file is reported as such, not as foreign
        try:
            value = fh.attrs.get("schema")
        except (OSError, TypeError, ValueError) as exc:
            raise FileFormatError(f"{path}: /: attribute 'schema': cannot be read: "
                                  f"{' '.join(str(exc).split())}") from exc
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    return value == "rattle_record"


def sniff(head: bytes, path: Path) -> bool:
    """Native records are HDF5 files whose root attribute ``schema`` is ``rattle_record``."""
    return is_native(path)


def _collect_sources(tree: dict[str, Any], handle: H5Handle, base: str, prefix: str = "/",
                     out: dict[str, ArraySource] | None = None) -> dict[str, ArraySource]:
    out = {} if out is None else out
    for name, node in tree.get("members", {}).items():
        path = prefix.rstrip("/") + "/" + name
        if node["kind"] == "group":
            _collect_sources(node, handle, base, path, out)
        elif len(node["shape"]) in (1, 2):
            out[path] = _LazyH5Source(handle, base.rstrip("/") + path, node)
    return out


class _LazyH5Source:
    """An :class:`H5Source` made on first read (the tree already knows dtype and shape)."""

    def __init__(self, handle: H5Handle, dataset_path: str, node: dict[str, Any]) -> None:
        self._handle = handle
        self._path = dataset_path
        self.dtype = np.dtype(node["dtype"])
        self.n_samples = int(node["shape"][0]) if node["shape"] else 0
        self._source: H5Source | None = None
        #: ``(file, dataset path)`` of a 1-D dataset (see :attr:`H5Source.location`).
        self.location = (handle.path, dataset_path) if len(node["shape"]) == 1 else None

    def read(self, start: int, stop: int) -> Any:
        if self._source is None:
            self._source = H5Source(self._handle, self._path)
        return self._source.read(start, stop)


def load_group(path: Path, group: str = "/", tree: dict[str, Any] | None = None) -> RawRecord:
    """Read the record stored in ``group`` of ``path`` (``"/"`` for a record file).

    Error paths are given from the file's root, so a record inside an ingest
    store is named by its full HDF5 path.  ``tree`` is the group's node tree when
    the caller has read it from the same, unchanged file before (the datasets are
    then opened without reading every attribute again).
    """
    handle = H5Handle(path)
    try:
        fh = handle.get()
        obj = fh.get(group)
        if not isinstance(obj, h5py.Group):
            raise FileFormatError(f"{path}: {group}: no such group")
        if tree is None:
            tree = node_tree(obj, str(path), group)
    except BaseException:
        handle.close()
        raise
    sources = _collect_sources(tree, handle, group)
    return RawRecord(tree=tree, sources=sources, format=FORMAT, closer=handle.close)


def load(path: Path, mapping: Any = None) -> RawRecord:
    """Read a native record file (``read()`` passes no mapping for native files)."""
    return load_group(path, "/")
