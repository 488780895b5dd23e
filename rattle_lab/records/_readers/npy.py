"""NumPy ``.npy`` arrays, read through a mapping (memory-mapped, read-only).

A 1-D array is one channel; a 2-D array holds one channel per row
(``axis = 0``, the default) or per column (``axis = 1``), chosen with
``index``.  An array carries no metadata, so the mapping states every
quantity, unit and sample rate, or names a row as the time base
(``[runs.timestamps.t] index = 0``).  Pickled (object) arrays are refused.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rattle_lab.exceptions import FileFormatError
from .._errors import MappingError
from .._model import ArraySource
from . import RawRecord
from .mapping import MappingSpec, build_raw

FORMAT = "npy"


def sniff(head: bytes, path: Path) -> bool:
    """``.npy`` files start with ``\\x93NUMPY``."""
    return head.startswith(b"\x93NUMPY")


class NpySource:
    """One row or column of a memory-mapped array."""

    def __init__(self, array: np.ndarray, index: int | None, axis: int) -> None:
        self.array = array
        self.index = index
        self.axis = axis
        self.dtype = array.dtype
        self.n_samples = int(array.shape[0] if index is None else array.shape[1 - axis])

    def read(self, start: int, stop: int) -> np.ndarray:
        if self.index is None:
            return np.array(self.array[start:stop])
        if self.axis == 0:
            return np.array(self.array[self.index, start:stop])
        return np.array(self.array[start:stop, self.index])


def _check_declared_size(path: Path) -> None:
    """Refuse a .npy file whose header declares more bytes than the file holds."""
    fmt = np.lib.format
    try:
        with open(path, "rb") as fh:
            major, _minor = fmt.read_magic(fh)
            read_header = {1: fmt.read_array_header_1_0, 2: fmt.read_array_header_2_0}.get(major)
            if read_header is None:
                return  # np.load reports versions it does not know
            shape, _fortran, dtype = read_header(fh)
            data_bytes = path.stat().st_size - fh.tell()
    except (ValueError, OSError, EOFError, OverflowError, TypeError):
        return  # np.load gives the error, below
    n = 1
    for d in shape:
        n *= int(d)
    declared = n * dtype.itemsize
    if declared > data_bytes:
        raise FileFormatError(f"{path}: not a readable .npy array: the header declares shape "
                              f"{tuple(shape)} of {dtype} ({declared} bytes) but the file holds "
                              f"{data_bytes} bytes of data (truncated?)")


class NpyBackend:
    """Rows (or columns) of a ``.npy`` array, selected by ``index``."""

    format = FORMAT

    def __init__(self, path: Path) -> None:
        _check_declared_size(path)
        try:
            self.array = np.load(path, mmap_mode="r", allow_pickle=False)
        except (ValueError, OSError, EOFError, OverflowError) as exc:
            raise FileFormatError(f"{path}: not a readable .npy array (truncated, or pickled "
                                  f"objects?): {' '.join(str(exc).split())}") from exc
        if self.array.ndim not in (1, 2) or self.array.dtype.kind not in "fiu":
            raise FileFormatError(f"{path}: a .npy record must be a 1-D or 2-D numeric array, got "
                                  f"shape {self.array.shape} dtype {self.array.dtype}")
        self.path = path
        self.axis: int | None = None

    def _label(self, index: int | None, axis: int) -> str:
        if index is None:
            return "array"
        return f"row {index}" if axis == 0 else f"column {index}"

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        if "source" in spec or "segment" in spec:
            raise MappingError(f"{where}: a .npy array is selected with 'index' (and 'axis'), "
                               "not 'source' or 'segment'")
        index = spec.get("index")
        axis = spec.get("axis", 0)
        if self.array.ndim == 1:
            if index is not None:
                raise MappingError(f"{where}: key 'index': the array is 1-D (one channel)")
            return NpySource(self.array, None, 0), {}, ("array",)
        if index is None:
            raise MappingError(f"{where}: missing key 'index' (the array has shape "
                               f"{self.array.shape})")
        if axis not in (0, 1) or not isinstance(index, int) or not 0 <= index < self.array.shape[axis]:
            raise MappingError(f"{where}: key 'index': {index!r} along axis {axis!r} is outside "
                               f"shape {self.array.shape}")
        if self.axis is not None and axis != self.axis:
            raise MappingError(f"{where}: key 'axis': channels must all run along one axis")
        self.axis = axis
        return NpySource(self.array, index, axis), {}, (self._label(index, axis),)

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        src, _, used = self.channel(spec, where)
        if src.dtype != np.float64:
            raise MappingError(f"{where}: timestamps must be float64 seconds, got {src.dtype}")
        return src, used

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        return {}

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        raise MappingError(f"{where}: references into the file ({{ source = ... }}) work for HDF5 "
                           "only; give the value")

    def inventory(self) -> list[tuple[str, str]]:
        if self.array.ndim == 1:
            return [("array", f"{self.array.shape[0]} samples")]
        axis = self.axis or 0
        n = self.array.shape[1 - axis]
        return [(self._label(i, axis), f"{n} samples") for i in range(self.array.shape[axis])]

    def close(self) -> None:
        mm = getattr(self.array, "_mmap", None)
        if mm is not None:
            mm.close()


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read a ``.npy`` array through ``mapping`` (an array says nothing about its rows)."""
    if mapping is None:
        raise FileFormatError(f"{path}: a .npy array carries no metadata (quantities, units, "
                              "sample rate): pass a mapping (--mapping FILE.toml)")
    return build_raw(path, mapping, NpyBackend(path))
