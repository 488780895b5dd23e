"""``read()``: detect a file's format, read it with its reader, validate, build the Record."""

from __future__ import annotations

import importlib
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

from rattle_lab.exceptions import FileFormatError
from ._convert import record_from_tree
from ._h5 import hdf5_signature_offset
from ._model import Origin, Record
from ._readers import RawRecord
from ._readers.mapping import MappingSpec, load_mapping
from ._schema import validate_tree

Format = Literal["rattle_hdf5", "hdf5", "lvm", "npy", "tdms", "uff", "wav"]

#: Format name -> reader module.  "hdf5" is a foreign HDF5 layout read through a mapping.
READERS: dict[str, str] = {
    "rattle_hdf5": "rattle_lab.records._readers.native",
    "hdf5": "rattle_lab.records._readers.mapping",
    "tdms": "rattle_lab.records._readers.tdms",
    "wav": "rattle_lab.records._readers.wav",
    "lvm": "rattle_lab.records._readers.lvm",
    "npy": "rattle_lab.records._readers.npy",
    "uff": "rattle_lab.records._readers.uff",  # [issue 17] UFF dataset 58
}

#: Formats recognised from their first bytes, in this order (HDF5 is checked before them).
SNIFFED: tuple[str, ...] = ("tdms", "wav", "lvm", "npy", "uff")


def _head(path: Path) -> bytes:
    with open(path, "rb") as fh:
        return fh.read(64)


def _known_but_refused(head: bytes) -> str | None:
    """Why a file of a format we recognise but do not read is refused (one line), or None."""
    if head.startswith(b"MATLAB 5.0 MAT-file"):
        return ("header: a MATLAB v5/v7 MAT-file (not HDF5); only v7.3 MAT-files are read: "
                "save it with save(name, '-v7.3')")
    if head.startswith(b"PK\x03\x04") and b".npy" in head:
        return ("header: a NumPy .npz archive (zip of arrays); save each array with numpy.save "
                "and give the .npy file with a mapping")
    return None


def detect_format(path: str | os.PathLike[str]) -> str:
    """The format of ``path``: ``rattle_hdf5``, ``hdf5`` (foreign layout), ``tdms``, ``wav``, ``lvm``, ``npy``.

    Raises
    ------
    FileFormatError
        For a missing, empty or unrecognised file.
    """
    path = Path(path)
    if not path.exists():
        raise FileFormatError(f"{path}: no such file")
    if not path.is_file():
        raise FileFormatError(f"{path}: not a regular file")
    if path.stat().st_size == 0:
        raise FileFormatError(f"{path}: file is empty (0 bytes)")
    if hdf5_signature_offset(path) is not None:
        native = importlib.import_module(READERS["rattle_hdf5"])
        return "rattle_hdf5" if native.is_native(path) else "hdf5"
    head = _head(path)
    for name in SNIFFED:
        if importlib.import_module(READERS[name]).sniff(head, path):
            return name
    refused = _known_but_refused(head)
    if refused is not None:
        raise FileFormatError(f"{path}: {refused}")
    raise FileFormatError(f"{path}: not a recognised record format (a rattle HDF5 record, or HDF5 / "
                          "MATLAB v7.3, TDMS, WAV, UFF 58, LabVIEW .lvm or NumPy .npy with a mapping)")


def read_raw(path: str | os.PathLike[str], *,
             mapping: str | os.PathLike[str] | Mapping[str, Any] | MappingSpec | None = None
             ) -> RawRecord:
    """The reader's raw output for ``path`` (node tree + sources), before validation."""
    path = Path(path)
    spec = mapping if isinstance(mapping, MappingSpec) or mapping is None else load_mapping(mapping)
    fmt = detect_format(path)
    if fmt == "rattle_hdf5":
        spec = None  # a native record needs no mapping; one given for other inputs is not applied
    elif spec is not None and spec.format is not None and spec.format != fmt:
        raise FileFormatError(f"{path}: the mapping {spec.label} is for format {spec.format!r}, "
                              f"but the file is {fmt!r}")
    module = importlib.import_module(READERS[fmt])
    return module.load(path, spec)


def read(path: str | os.PathLike[str], *,
         mapping: str | os.PathLike[str] | Mapping[str, Any] | MappingSpec | None = None) -> Record:
    """Read a record file of any supported format; validate it against the schema.

    The format is detected from the file's content: a native rattle record
    (HDF5 with ``schema = 'rattle_record'``), or a foreign file read through a
    TOML ``mapping`` (HDF5 of any layout including MATLAB v7.3 ``.mat``,
    TDMS, LabVIEW ``.lvm``, NumPy ``.npy``; WAV and TDMS with channel
    ``quantity`` properties also read without one).  Files are opened
    read-only and channels are read lazily.

    Parameters
    ----------
    path : path-like
        The file.
    mapping : path-like, dict or MappingSpec, optional
        Mapping for foreign layouts (ignored for native records).

    Returns
    -------
    Record
        Use it as a context manager to release the file.

    Raises
    ------
    FileFormatError
        Missing, empty, truncated or unrecognised file.
    SchemaError
        The record does not conform to the schema (file, HDF5 path, field named).
    MappingError
        The mapping is invalid or does not fit the file.
    """
    path = Path(path)
    raw = read_raw(path, mapping=mapping)
    try:
        validate_tree(raw.tree, str(path))
        return record_from_tree(raw.tree, raw.sources,
                                Origin(path=path, format=raw.format, skipped=raw.skipped,
                                       closer=raw.closer))
    except BaseException:
        if raw.closer is not None:
            raw.closer()
        raise
