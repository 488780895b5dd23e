"""Constants, result classes and content hashes of ingestion."""

from __future__ import annotations

import hashlib
import mmap
import os
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Literal

import xxhash

from rattle_lab.records import Finding, Skipped

Storage = Literal["link", "copy"]

HASH_ALGORITHM = "xxh3_128"
HASH_BLOCK_BYTES = 32 << 20  # a multiple of mmap.ALLOCATIONGRANULARITY

#: Catalogue columns (one row per channel) and their kinds.
CATALOGUE_COLUMNS: tuple[tuple[str, Literal["str", "float", "int"]], ...] = (
    ("input_key", "str"),
    ("file", "str"),
    ("file_hash", "str"),
    ("format", "str"),
    ("campaign_id", "str"),
    ("source", "str"),
    ("run_id", "str"),
    ("protocol", "str"),
    ("excitation_freq_hz", "float"),
    ("nominal_level", "float"),
    ("nominal_level_units", "str"),
    ("run_start_iso", "str"),
    ("channel", "str"),
    ("quantity", "str"),
    ("units", "str"),
    ("source_units", "str"),
    ("scale_to_si", "float"),
    ("timing", "str"),
    ("sample_rate_hz", "float"),
    ("start_time_s", "float"),
    ("n_samples", "int"),
    ("duration_s", "float"),
    ("min_si", "float"),
    ("max_si", "float"),
    ("flags", "str"),
    ("sensor_model", "str"),
    ("sensor_serial", "str"),
    ("calibration_date", "str"),
    ("store_path", "str"),
    ("storage", "str"),
    ("ingested_iso", "str"),
)


@dataclass(frozen=True)
class InputResult:
    """What happened to one input.

    Attributes
    ----------
    path : Path
        The input file.
    file_hash : str
        Content hash of its bytes (:func:`file_hash`).
    input_key : str
        Its group name under ``/records`` in the store.
    status : str
        ``"added"``, ``"unchanged"`` (already in the store, or repeated in the call), or
        ``"updated"`` (in the store, but linked to a file that has moved or changed, or
        linked while ``storage="copy"`` was asked for: ingested again in its place).
    format : str
        Detected format.
    skipped : tuple of Skipped
        Columns of a foreign file that were not ingested, with reasons.
    findings : tuple of Finding
        Data-quality findings (all flagged in the catalogue).
    """

    path: Path
    file_hash: str
    input_key: str
    status: Literal["added", "unchanged", "updated"]
    format: str
    skipped: tuple[Skipped, ...] = ()
    findings: tuple[Finding, ...] = ()


@dataclass(frozen=True)
class IngestReport:
    """Result of :func:`ingest`.

    Attributes
    ----------
    store : Path
        The store file.
    inputs : tuple of InputResult
        One per input, in the order given.
    catalogue : pandas.DataFrame
        Catalogue rows (one per channel) of this call's inputs, added or unchanged.
    changed : bool
        Whether the store file was (re)written.
    """

    store: Path
    inputs: tuple[InputResult, ...]
    catalogue: Any = field(repr=False)
    changed: bool = False

    @property
    def findings(self) -> tuple[Finding, ...]:
        """All findings of the inputs added by this call."""
        return tuple(f for r in self.inputs for f in r.findings)


def file_hash(path: str | os.PathLike[str]) -> str:
    """Content hash of a file's bytes: ``"xxh3_128:"`` + 32 hex digits, read in blocks.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     p = pathlib.Path(folder) / "x.bin"
    ...     _ = p.write_bytes(b"")
    ...     file_hash(p)            # XXH3-128 of no bytes, as xxhsum -H2 prints it
    'xxh3_128:99aa06d3014798d86001c324468d497f'
    """
    h = xxhash.xxh3_128()
    with open(path, "rb", buffering=0) as fh:
        size = os.fstat(fh.fileno()).st_size
        # Hashing mapped pages spares the copy into a buffer that read() makes (twice the
        # speed on a warm page cache).  The file is mapped one window at a time, so that the
        # resident memory stays bounded by the window, not the file.
        for start in range(0, size, HASH_BLOCK_BYTES):
            length = min(HASH_BLOCK_BYTES, size - start)
            with mmap.mmap(fh.fileno(), length, offset=start, access=mmap.ACCESS_READ) as window:
                if hasattr(window, "madvise"):  # read-ahead for a cold cache
                    window.madvise(mmap.MADV_SEQUENTIAL)
                view = memoryview(window)
                try:
                    h.update(view)
                finally:
                    view.release()
    return f"{HASH_ALGORITHM}:{h.hexdigest()}"


def input_key(content_hash: str, mapping_sha256: str | None) -> str:
    """Store group name of an input: ``in_`` + 16 hex digits of SHA-256(file hash [+ mapping hash])."""
    text = content_hash if mapping_sha256 is None else f"{content_hash}:{mapping_sha256}"
    return "in_" + hashlib.sha256(text.encode()).hexdigest()[:16]


def _now_iso() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")


