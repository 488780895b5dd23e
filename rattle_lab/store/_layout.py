"""The store file: its layout version, opening, the writers' lock, and read-modify-write.

Every ``h5py.File`` on a store is opened here.  Readers open the store
read-only (:func:`open_store`); a writer calls :func:`edit_store`, which

1. takes the store's lock (an exclusive ``fcntl.flock`` on the store's folder,
   held by one writer at a time, across processes; nothing is left on disk),
2. copies the store to a temporary file beside it (:func:`rattle_lab._atomic.atomic_path`),
3. lets the caller change the copy, migrating an older layout first,
4. renames the copy over the store.

Writers never lose each other's updates (the read happens under the lock), and
readers always see a complete store: either the one before or the one after
a write, never a half-written file, whatever interrupts the writer.

Layout versions (root attribute ``store_version``):

* 2: ``/records``, ``/catalogue``, ``/provenance/log`` (and ``/results``,
  ``/pipeline_cache`` when the fit and the pipeline have run).
* 3: as 2; each ``/records/{key}`` adds ``ingest_link_targets`` (JSON object:
  file outside the input that the input links to -> its content hash; ``{}``
  for inputs without links).  A version-2 store reads as it is, and is
  migrated to version 3 by the next writer.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from rattle_lab._atomic import atomic_path
from rattle_lab.exceptions import OutputError
from ._errors import StoreError

STORE_FORMAT = "rattle_store"
STORE_VERSION = 3
#: Layout versions this code reads (older ones are migrated when written).
READABLE_VERSIONS = (2, 3)


def text(value: Any) -> str:
    """An HDF5 attribute value as text."""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


#: File suffixes of the records ``rattle-lab ingest`` reads (not stores).
RECORD_SUFFIXES = (".lvm", ".tdms", ".uff", ".unv", ".csv", ".txt")


def not_a_store(store: Path, why: str, *, writing: bool = False,
                record: bool = False) -> StoreError:
    """The error for a file that is not an ingest store: what is wrong and what to do.

    ``writing``: the command would write a new store there (ingest), and will not;
    ``record``: the file is a record (``ingest`` reads it), given where a store belongs.
    """
    if writing:
        what = ("a readable HDF5 ingest store" if why.startswith("not an HDF5")
                else "a rattle_lab ingest store")
        return StoreError(f"{store}: exists and is not {what} ({why}); "
                          "refusing to overwrite it: give another output name, or move that "
                          "file away")
    if record or store.suffix.lower() in RECORD_SUFFIXES:
        from rattle_lab._resources import resource_names

        suffix = store.suffix.lower().lstrip(".")
        maps = [m for m in resource_names("mappings") if suffix and m.endswith("_" + suffix)]
        mapping = (f" --mapping {maps[0] if len(maps) == 1 else 'NAME'}" if maps else "")
        shipped = (f"; shipped mappings for .{suffix}: {', '.join(maps)}" if len(maps) > 1
                   else "")
        return StoreError(f"{store}: is a record, not an ingest store: ingest it first "
                          f"(`rattle-lab ingest {store}{mapping} -o store.h5`{shipped}), then "
                          "give store.h5")
    return StoreError(f"{store}: is not a rattle_lab ingest store ({why}): it is damaged or "
                      "another kind of file; give the store that `rattle-lab ingest` wrote, "
                      "or ingest the records again into a new one")


def check_store(fh: h5py.File, store: Path, *, writing: bool = False) -> int:
    """The layout version of an open store; StoreError if it is not a store this code reads."""
    fmt = fh.attrs.get("store_format")
    if isinstance(fmt, bytes):
        fmt = fmt.decode("utf-8", "replace")
    if fmt != STORE_FORMAT:
        record = "schema" in fh.attrs and "runs" in fh
        raise not_a_store(store, f"root attribute 'store_format' is {fmt!r}", writing=writing,
                          record=record)
    version = fh.attrs.get("store_version")
    shown = version.item() if isinstance(version, np.generic) else version
    if not isinstance(shown, int) or shown not in READABLE_VERSIONS:
        raise StoreError(f"{store}: /: attribute 'store_version': {shown!r} is not supported "
                         f"(this code reads versions {', '.join(map(str, READABLE_VERSIONS))})")
    return shown


def open_store(store: str | os.PathLike[str], *, check: bool = True,
               writing: bool = False) -> h5py.File:
    """Open an existing store read-only (``check=False``: any HDF5 file, for callers that look
    for their own group first and check the store after; ``writing``: the caller would write
    a new store in its place, which the error then refuses).

    Raises
    ------
    StoreError
        If it does not exist, is not HDF5, or is not a store of a readable version.
    """
    store = Path(store)
    if store.is_dir():
        raise StoreError(f"{store}: is a directory, not a store; give the store's file name")
    if not store.is_file():
        raise StoreError(f"{store}: no such store")
    try:
        fh = h5py.File(store, "r")
    except OSError as exc:
        raise not_a_store(store, "not an HDF5 file: " + " ".join(str(exc).split()),
                          writing=writing) from exc
    try:
        if check:
            check_store(fh, store, writing=writing)
    except BaseException:
        fh.close()
        raise
    return fh


# --- the writers' lock ----------------------------------------------------------------------

# (folder, thread) -> depth: the lock is re-entrant within a thread; other threads of this
# process open their own descriptor, and flock makes them wait like other processes.
_held: dict[tuple[str, int], int] = {}
_held_guard = threading.RLock()


@contextlib.contextmanager
def store_lock(store: str | os.PathLike[str]) -> Iterator[None]:
    """Hold the writers' lock of ``store`` (blocks until other writers are done).

    The lock is an exclusive ``flock`` on the store's folder: it needs no file
    of its own (nothing to clean up after a crash; the kernel releases it when
    the holder dies), and it also covers the temporary files written beside the
    store.  Writers to other stores of the same folder wait for each other too.
    Re-entrant within a thread (a pipeline holding it may call ``ingest``).

    Raises
    ------
    OutputError
        If the folder does not exist or cannot be opened.
    """
    folder = Path(store).parent if str(Path(store).parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"{store}: output directory {folder} does not exist")
    path = str(folder.resolve())
    key = (path, threading.get_ident())
    with _held_guard:
        depth = _held.get(key, 0)
        _held[key] = depth + 1
        if depth:
            fd = -1
        else:
            try:
                fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
            except OSError as exc:
                _held[key] -= 1
                raise OutputError(f"{store}: output directory {folder} cannot be used: "
                                  f"{exc.strerror or exc}") from exc
    try:
        if fd >= 0:
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        with _held_guard:
            _held[key] -= 1
            if not _held[key]:
                del _held[key]
        if fd >= 0:
            os.close(fd)  # releases the flock


def migrate(fh: h5py.File) -> None:
    """Bring an open (writable) store of an older readable version to :data:`STORE_VERSION`."""
    version = fh.attrs.get("store_version")
    version = version.item() if isinstance(version, np.generic) else version
    if version == 2:
        for group in fh.get("records", {}).values():
            if "ingest_link_targets" not in group.attrs:
                group.attrs["ingest_link_targets"] = "{}"
    fh.attrs["store_version"] = STORE_VERSION


def new_store(fh: h5py.File, created_iso: str) -> None:
    """Write the root attributes of a new, empty store."""
    fh.attrs["store_format"] = STORE_FORMAT
    fh.attrs["store_version"] = STORE_VERSION
    fh.attrs["created_iso"] = created_iso


@contextlib.contextmanager
def edit_store(store: str | os.PathLike[str], *, create: str | None = None,
               what: str = "update") -> Iterator[h5py.File]:
    """Read-modify-write ``store`` under its lock, atomically.

    Yields the copy opened for writing (migrated to :data:`STORE_VERSION`).
    The copy replaces the store when the block ends without an error; any
    error, signal or crash leaves the store as it was.

    Parameters
    ----------
    store : path-like
    create : str, optional
        If given, a missing store is created (with this ``created_iso``);
        otherwise a missing store is a :class:`StoreError`.
    what : str
        Words for error messages ("could not {what}").

    Raises
    ------
    StoreError
        If the store is missing (and ``create`` is None) or is not a readable store.
    OutputError
        If the store cannot be written (the previous store is left intact).
    """
    store = Path(store)
    with store_lock(store):
        exists = store.exists()
        if exists:
            # a StoreError for anything but a readable store
            open_store(store, writing=create is not None).close()
        elif create is None:
            raise StoreError(f"{store}: no such store")
        try:
            with atomic_path(store) as tmp:
                if exists:
                    shutil.copyfile(store, tmp)
                    fh = h5py.File(tmp, "a")
                    migrate(fh)
                else:
                    fh = h5py.File(tmp, "w", track_order=True)
                    new_store(fh, create or "")
                with fh:
                    yield fh
        except OSError as exc:
            if isinstance(exc, OutputError) or exc.errno is None:
                raise
            raise OutputError(f"{store}: could not {what}: "
                              f"{' '.join(str(exc.strerror or exc).split())}") from exc


def has_path(store: str | os.PathLike[str], path: str) -> bool:
    """Whether the store exists and holds the HDF5 object ``path``."""
    store = Path(store)
    if not store.is_file():
        return False
    try:
        with open_store(store) as fh:
            return path in fh
    except StoreError:
        return False


def record_attrs(store: str | os.PathLike[str]) -> dict[str, dict[str, Any]]:
    """The attributes of each ``/records/{key}`` group, as plain values."""
    out: dict[str, dict[str, Any]] = {}
    with open_store(store) as fh:
        for key, group in fh.get("records", {}).items():
            out[key] = {name: (text(v) if isinstance(v, (bytes, str)) else
                               v.item() if isinstance(v, np.generic) else v)
                        for name, v in group.attrs.items()}
    return out
