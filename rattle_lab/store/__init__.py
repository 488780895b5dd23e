"""The store: one HDF5 file per campaign, owned by this package.

Everything that opens a store goes through here: its layout and layout
version (:mod:`._layout`, with migration of older stores), the writers' lock
and read-modify-write (:func:`edit_store`), ingestion (:func:`ingest`),
reading records and the catalogue, the fit's ``/results``, the pipeline's
cached products (``/pipeline_cache``) and content verification
(:func:`verify_store`).
"""

from __future__ import annotations

from ._errors import StoreError
from ._cache import (
                     CACHE_GROUP,
                     input_hashes,
                     output_digest,
                     provenance_log,
                     read_cache_keys,
                     read_cached,
                     record_cache_keys,
                     write_cached,
)
from ._catalogue import open_stored_record, read_catalogue
from ._index import REINGEST_ADVICE, reingest_advice
from ._ingest import MappingIgnoredWarning, ingest
from ._ingest_types import CATALOGUE_COLUMNS, IngestReport, InputResult, file_hash, input_key
from ._layout import (
                     READABLE_VERSIONS,
                     STORE_FORMAT,
                     STORE_VERSION,
                     edit_store,
                     has_path,
                     open_store,
                     record_attrs,
                     store_lock,
)
from ._results import RESULTS_VERSION, StoredResults, read_results, write_results
from ._verify import Mismatch, check_linked_inputs, record_attrs_count, verify_store

__all__ = ["ingest", "read_catalogue", "open_stored_record", "IngestReport", "InputResult",
           "CATALOGUE_COLUMNS", "file_hash", "input_key", "MappingIgnoredWarning",
           "STORE_FORMAT", "STORE_VERSION", "READABLE_VERSIONS", "open_store", "edit_store",
           "store_lock", "has_path", "read_results", "write_results", "StoredResults",
           "CACHE_GROUP", "read_cache_keys", "record_cache_keys", "read_cached", "write_cached",
           "output_digest", "input_hashes", "provenance_log", "verify_store",
           "check_linked_inputs", "Mismatch", "record_attrs_count", "REINGEST_ADVICE",
           "reingest_advice", "StoreError", "RESULTS_VERSION", "record_attrs"]
