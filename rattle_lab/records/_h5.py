"""Raw HDF5 access: read-only opening, attribute decoding, the node tree, lazy datasets.

This is the bottom layer.  It knows HDF5, not the rattle schema: it turns a
group into the JSON-like tree that :mod:`._schema` validates, and it gives
lazy, chunk-wise access to datasets.  Files are only ever opened with mode
``"r"``.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab.exceptions import DataError, FileFormatError, SchemaError

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"

#: Largest attribute (bytes of storage) read; a bigger one is refused before it is read.
MAX_ATTRIBUTE_BYTES = 1 << 20

#: Deepest group nesting followed when building the tree.
MAX_DEPTH = 12


@dataclass
class LinkPolicy:
    """What may be followed out of an HDF5 input: external links, virtual datasets, external storage.

    Attributes
    ----------
    allow : bool
        False (default): any reference to another file is refused
        (:class:`LinkError`).  True: references are resolved, but only to
        existing files inside the input's own folder; the files reached are
        collected in ``targets`` (so that ingest can hash them).
    trusted : bool
        The file is a store this package wrote: its virtual datasets (links
        to ingested inputs, verified by hash elsewhere) are followed.
    targets : set of Path
        Files outside the input reached through references (resolved paths).
    """

    allow: bool = False
    trusted: bool = False
    targets: set[Path] = field(default_factory=set)


class LinkError(FileFormatError):
    """An HDF5 input refers to data in another file, and that is not allowed."""


# No shared default instance: a LinkPolicy holds a mutable set of targets.
_POLICY: ContextVar[LinkPolicy | None] = ContextVar("rattle_lab_link_policy", default=None)


@contextlib.contextmanager
def link_policy(policy: LinkPolicy) -> Iterator[LinkPolicy]:
    """Apply ``policy`` to the HDF5 files opened (and their lazy sources made) in the block."""
    token = _POLICY.set(policy)
    try:
        yield policy
    finally:
        _POLICY.reset(token)


def current_link_policy() -> LinkPolicy:
    """The policy in force (refuse every link unless a caller said otherwise)."""
    policy = _POLICY.get()
    return LinkPolicy() if policy is None else policy


def _approve(policy: LinkPolicy, home: Path, target: Path, where: str, what: str) -> None:
    """Refuse, or (``policy.allow``) accept a reference from ``home`` to ``target``."""
    if target == home:
        return
    hint = ("; pass --allow-links (allow_links=True) to resolve references inside the "
            "input's folder")
    if not policy.allow:
        raise LinkError(f"{where}: {what} refers to another file ({target}); references out of "
                        f"an input are refused{hint}")
    if home.parent not in target.parents:
        raise LinkError(f"{where}: {what} refers to {target}, outside the input's folder "
                        f"{home.parent}; refused even with --allow-links")
    if not target.is_file():
        raise LinkError(f"{where}: {what} refers to {target}, which does not exist")
    policy.targets.add(target)


def check_references(ds: h5py.Dataset, home: Path, where: str,
                     policy: LinkPolicy | None = None) -> None:
    """Check a dataset's virtual sources and external storage against the link policy."""
    policy = policy if policy is not None else current_link_policy()
    if policy.trusted:
        return
    reached = Path(ds.file.filename).resolve()
    _approve(policy, home, reached, where, "the path (through an external link)")
    if ds.is_virtual:
        for vs in ds.virtual_sources():
            name = vs.file_name
            target = reached if name == "." else (reached.parent / name).resolve()
            _approve(policy, home, target, where, f"virtual dataset source {vs.dset_name!r}")
    external = ds.external
    if external:
        for name, _offset, _size in external:
            # HDF5 reads external raw storage relative to the working folder
            raw = name.decode() if isinstance(name, bytes) else str(name)
            _approve(policy, home, Path(raw).resolve(), where, "external raw data storage")


def available_memory_bytes() -> int:
    """Memory available to a new allocation (Linux ``MemAvailable``; else the free pages)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return 1 << 62


def check_extent(ds: h5py.Dataset, where: str) -> None:
    """Refuse a dataset that declares more samples than its file stores.

    A contiguous dataset must have storage for every byte it declares, and a
    chunked one every chunk (missing chunks would read as fill values: a file of
    a few kB can declare 1e12 samples).  The storage must also fit in the file.
    Costs a look at the chunk index, not a read.

    Raises
    ------
    DataError
        Naming the dataset, the declared and the stored extent.
    """
    if ds.is_virtual or ds.external or ds.size == 0:
        return
    nbytes = int(ds.size) * ds.dtype.itemsize
    if ds.chunks is None:
        stored = int(ds.id.get_storage_size())
        if stored < nbytes:
            raise DataError(f"{where}: dataset 'shape': declares {ds.shape} ({nbytes} bytes) but "
                            f"stores only {stored} bytes (truncated or hostile file)")
        offset = ds.id.get_offset()
        try:
            file_size = os.path.getsize(ds.file.filename)
        except OSError:
            file_size = None
        if offset is not None and file_size is not None and offset + nbytes > file_size:
            raise DataError(f"{where}: dataset 'shape': declares {nbytes} bytes at offset {offset}, "
                            f"beyond the end of the file ({file_size} bytes): truncated file")
        return
    expected = 1
    for n, c in zip(ds.shape, ds.chunks):
        expected *= -(-int(n) // int(c))
    stored_chunks = int(ds.id.get_num_chunks())
    if stored_chunks < expected:
        raise DataError(f"{where}: dataset 'shape': declares {ds.shape} in {expected} chunks but "
                        f"the file stores {stored_chunks}; refusing a dataset whose samples are "
                        "mostly not there (truncated or hostile file)")


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
              depth: int = 0, home: Path | None = None) -> dict[str, Any]:
    """The JSON-like node tree of an HDF5 group (see the schema's description).

    A group becomes ``{"kind": "group", "attrs": {...}, "members": {...}}``, a
    dataset ``{"kind": "dataset", "attrs": {...}, "dtype": str, "shape": list}``.
    ``path`` is the HDF5 path named in errors.
    """
    where = f"{file_label}: {path}"
    if home is None:
        home = Path(obj.file.filename).resolve()
    if depth > MAX_DEPTH:
        raise SchemaError(f"{where}: groups nested deeper than {MAX_DEPTH} levels")
    attrs = read_attrs(obj, where)
    if isinstance(obj, h5py.Dataset):
        check_references(obj, home, where)
        check_extent(obj, where)
        return {"kind": "dataset", "attrs": attrs, "dtype": obj.dtype.str, "shape": list(obj.shape)}
    members: dict[str, Any] = {}
    for name in obj:
        child_path = path.rstrip("/") + "/" + name
        try:
            link = obj.get(name, getlink=True)
        except (KeyError, OSError):
            link = None
        if isinstance(link, h5py.ExternalLink):
            policy = current_link_policy()
            if not policy.trusted:
                target = (home.parent / link.filename).resolve()
                _approve(policy, home, target, f"{file_label}: {child_path}",
                         f"external link to {link.filename}:{link.path}")
        try:
            child = obj.get(name)  # None for a dangling soft or external link
        except (KeyError, OSError):
            child = None
        if child is None:
            raise FileFormatError(f"{file_label}: {child_path}: cannot be read (dangling soft or "
                                  "external link, or damaged file)")
        if isinstance(child, h5py.Datatype):
            raise SchemaError(f"{file_label}: {child_path}: named datatypes are not part of the layout")
        if not current_link_policy().trusted:
            _approve(current_link_policy(), home, Path(child.file.filename).resolve(),
                     f"{file_label}: {child_path}", "the path (through an external link)")
        members[name] = node_tree(child, file_label, child_path, depth + 1, home)
    return {"kind": "group", "attrs": attrs, "members": members}


class H5Handle:
    """A file opened read-only on first use and kept open until :meth:`close`.

    Sources share one handle, so reading a record opens its file once.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self._file: h5py.File | None = None
        #: The link policy in force when the handle was made (lazy reads come later).
        self.policy = current_link_policy()

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
        where = f"{self.handle.path}: {self.dataset_path}"
        check_references(obj, self.handle.path.resolve(), where, self.handle.policy)
        check_extent(obj, where)
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
        need = max(0, min(stop, self.n_samples) - start) * ds.dtype.itemsize
        if need > (64 << 20) and need > available_memory_bytes():
            raise DataError(f"{self.handle.path}: {self.dataset_path}: data 'samples {start}:{stop}'"
                            f": {need} bytes do not fit in the memory available "
                            f"({available_memory_bytes()} bytes)")
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
