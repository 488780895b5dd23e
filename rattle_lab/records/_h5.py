"""Raw HDF5 access: read-only opening, attribute decoding, the node tree, lazy datasets.

This is the bottom layer.  It knows HDF5, not the rattle schema: it turns a
group into the JSON-like tree that :mod:`._schema` validates, and it gives
lazy, chunk-wise access to datasets.  Files are only ever opened with mode
``"r"``.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from ..exceptions import FileFormatError, SchemaError

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"

#: Largest attribute (bytes of storage) read; a bigger one is refused before it is read.
MAX_ATTRIBUTE_BYTES = 1 << 20

#: Deepest group nesting followed when building the tree.
MAX_DEPTH = 12


def hdf5_signature_offset(path: str | os.PathLike[str]) -> int | None:
    """Offset of the HDF5 superblock (0, 512, 1024, 2048, ...), or None if not HDF5.

    HDF5 looks for its signature at 0 and at 512 * 2**k (files with a user
    block, such as MATLAB v7.3 ``.mat`` files, start at 512).
    """
    size = os.path.getsize(path)
    with open(path, "rb") as fh:
        offset = 0
        while offset + len(HDF5_SIGNATURE) <= size:
            fh.seek(offset)
            if fh.read(len(HDF5_SIGNATURE)) == HDF5_SIGNATURE:
                return offset
            offset = 512 if offset == 0 else offset * 2
    return None


def open_readonly(path: str | os.PathLike[str]) -> h5py.File:
    """Open an HDF5 file read-only (mode ``"r"``), turning failures into FileFormatError."""
    try:
        return h5py.File(path, "r")
    except OSError as exc:
        reason = " ".join(str(exc).split())
        raise FileFormatError(f"{path}: not a readable HDF5 file (truncated or damaged?): {reason}") from exc


def decode_attr_value(value: Any, *, where: str, name: str) -> Any:
    """Turn an h5py attribute value into plain Python (str, int, float, bool, list).

    Raises
    ------
    SchemaError
        For values that are not UTF-8 text, empty, or of an unsupported type.
    """
    if isinstance(value, h5py.Empty):
        raise SchemaError(f"{where}: attribute '{name}': has no value (HDF5 empty dataspace)")
    if isinstance(value, (bytes, np.bytes_)):
        try:
            return bytes(value).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise SchemaError(f"{where}: attribute '{name}': text is not valid UTF-8 "
                              f"(byte {exc.start})") from exc
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value)
    if isinstance(value, np.ndarray):
        if value.dtype.kind in "SUO" or value.dtype.kind in "biuf":
            if value.ndim == 0:
                return decode_attr_value(value[()], where=where, name=name)
            return [decode_attr_value(v, where=where, name=name) for v in value.ravel().tolist()]
    raise SchemaError(f"{where}: attribute '{name}': unsupported attribute type "
                      f"{type(value).__name__} ({getattr(value, 'dtype', '')})")


def _storage_bytes(obj: h5py.HLObject, name: str) -> int:
    try:
        return int(obj.attrs.get_id(name).get_storage_size())
    except RuntimeError:  # HDF5 reports an empty dataspace's zero size as an error
        return 0


def read_attrs(obj: h5py.HLObject, where: str) -> dict[str, Any]:
    """All attributes of ``obj``, decoded; refuses attributes over :data:`MAX_ATTRIBUTE_BYTES`."""
    out: dict[str, Any] = {}
    for name in obj.attrs:
        try:
            storage = _storage_bytes(obj, name)
            raw = obj.attrs[name] if storage <= MAX_ATTRIBUTE_BYTES else None
        except (KeyError, OSError, TypeError, ValueError) as exc:
            # A damaged file, or a datatype h5py cannot read.
            raise FileFormatError(f"{where}: attribute '{name}': cannot be read: "
                                  f"{' '.join(str(exc).split())}") from exc
        if raw is None:
            raise SchemaError(f"{where}: attribute '{name}': is {storage} bytes, over the limit "
                              f"of {MAX_ATTRIBUTE_BYTES} bytes")
        value = decode_attr_value(raw, where=where, name=name)
        if isinstance(value, str) and len(value) > MAX_ATTRIBUTE_BYTES:
            raise SchemaError(f"{where}: attribute '{name}': is {len(value)} characters, over the "
                              f"limit of {MAX_ATTRIBUTE_BYTES}")
        out[name] = value
    return out


def node_tree(obj: h5py.Group | h5py.Dataset, file_label: str, path: str = "/",
              depth: int = 0) -> dict[str, Any]:
    """The JSON-like node tree of an HDF5 group (see the schema's description).

    A group becomes ``{"kind": "group", "attrs": {...}, "members": {...}}``, a
    dataset ``{"kind": "dataset", "attrs": {...}, "dtype": str, "shape": list}``.
    ``path`` is the HDF5 path named in errors.
    """
    where = f"{file_label}: {path}"
    if depth > MAX_DEPTH:
        raise SchemaError(f"{where}: groups nested deeper than {MAX_DEPTH} levels")
    attrs = read_attrs(obj, where)
    if isinstance(obj, h5py.Dataset):
        return {"kind": "dataset", "attrs": attrs, "dtype": obj.dtype.str, "shape": list(obj.shape)}
    members: dict[str, Any] = {}
    for name in obj:
        child_path = path.rstrip("/") + "/" + name
        try:
            child = obj.get(name)  # None for a dangling soft or external link
        except (KeyError, OSError):
            child = None
        if child is None:
            raise FileFormatError(f"{file_label}: {child_path}: cannot be read (dangling soft or "
                                  "external link, or damaged file)")
        if isinstance(child, h5py.Datatype):
            raise SchemaError(f"{file_label}: {child_path}: named datatypes are not part of the layout")
        members[name] = node_tree(child, file_label, child_path, depth + 1)
    return {"kind": "group", "attrs": attrs, "members": members}


class H5Handle:
    """A file opened read-only on first use and kept open until :meth:`close`.

    Sources share one handle, so reading a record opens its file once.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self._file: h5py.File | None = None

    def get(self) -> h5py.File:
        """The open file (opened with mode ``"r"`` if needed)."""
        if self._file is None or not self._file.id.valid:
            self._file = open_readonly(self.path)
        return self._file

    def close(self) -> None:
        """Close the file; a later :meth:`get` opens it again."""
        if self._file is not None and self._file.id.valid:
            self._file.close()
        self._file = None


class H5Source:
    """Lazy 1-D view of an HDF5 dataset: ``read(start, stop)`` reads only that slice.

    Parameters
    ----------
    handle : H5Handle
        The open-on-demand file.
    dataset_path : str
        Absolute HDF5 path of the dataset.
    index : int, optional
        For a 2-D dataset: which row (``axis=0``) or column (``axis=1``) holds the
        samples of this channel.  ``None`` for a 1-D dataset or a 2-D dataset with
        one singleton axis (MATLAB vectors are stored as ``(n, 1)`` or ``(1, n)``).
    axis : int
        The axis ``index`` runs along.
    """

    def __init__(self, handle: H5Handle, dataset_path: str, *, index: int | None = None,
                 axis: int = 0) -> None:
        self.handle = handle
        self.dataset_path = dataset_path
        self.index = index
        self.axis = axis
        ds = self._dataset()
        shape = ds.shape
        self.dtype = ds.dtype
        self._squeeze_axis: int | None = None
        if index is None:
            if len(shape) == 1:
                self.n_samples = int(shape[0])
            elif len(shape) == 2 and 1 in shape:
                self._squeeze_axis = 0 if shape[0] == 1 else 1
                self.n_samples = int(shape[1 - self._squeeze_axis])
            else:
                raise SchemaError(f"{handle.path}: {dataset_path}: dataset 'shape': a channel must be "
                                  f"1-D (or a MATLAB vector), got shape {shape}")
        else:
            if len(shape) != 2 or axis not in (0, 1) or not 0 <= index < shape[axis]:
                raise SchemaError(f"{handle.path}: {dataset_path}: dataset 'shape': cannot take index "
                                  f"{index} along axis {axis} of shape {shape}")
            self.n_samples = int(shape[1 - axis])

    def _dataset(self) -> h5py.Dataset:
        # The dataset object is kept while its file stays open (a lookup per chunk costs ~1 ms).
        cached = getattr(self, "_ds", None)
        if cached is not None and cached.id.valid:
            return cached
        obj = self.handle.get().get(self.dataset_path)
        if not isinstance(obj, h5py.Dataset):
            raise SchemaError(f"{self.handle.path}: {self.dataset_path}: not a dataset")
        self._ds: h5py.Dataset | None = obj
        return obj

    @property
    def location(self) -> tuple[Path, str] | None:
        """``(file, dataset path)`` when the samples are a whole 1-D dataset (they can be linked)."""
        if self.index is None and self._squeeze_axis is None:
            return self.handle.path, self.dataset_path
        return None

    def read(self, start: int, stop: int) -> np.ndarray:
        """Samples ``start:stop`` as a 1-D array of the stored dtype."""
        ds = self._dataset()
        try:
            if self.index is not None:
                sel = np.s_[self.index, start:stop] if self.axis == 0 else np.s_[start:stop, self.index]
                return np.asarray(ds[sel])
            if self._squeeze_axis is None:
                return np.asarray(ds[start:stop])
            sel = np.s_[0, start:stop] if self._squeeze_axis == 0 else np.s_[start:stop, 0]
            return np.asarray(ds[sel])
        except OSError as exc:
            raise FileFormatError(f"{self.handle.path}: {self.dataset_path}: data 'samples "
                                  f"{start}:{stop}': cannot be read (truncated file?): "
                                  f"{' '.join(str(exc).split())}") from exc
