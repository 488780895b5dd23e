"""Compatibility name: ingestion lives in :mod:`rattle_lab.store` (the module that owns the store).

``from rattle_lab.ingest import ingest`` keeps working; new code imports from
:mod:`rattle_lab.store`.
"""

from __future__ import annotations

from ..store._ingest import (CATALOGUE_COLUMNS, HASH_ALGORITHM, HASH_BLOCK_BYTES,  # noqa: F401
                             STORE_FORMAT, STORE_VERSION, IngestReport, InputResult,
                             MappingIgnoredWarning, file_hash, ingest, input_key,
                             open_stored_record, read_catalogue)

__all__ = ["ingest", "read_catalogue", "open_stored_record", "IngestReport", "InputResult",
           "CATALOGUE_COLUMNS", "file_hash", "input_key"]
