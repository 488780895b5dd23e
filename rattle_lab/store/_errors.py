"""The store's error."""

from __future__ import annotations

from rattle_lab.exceptions import DataError

__all__ = ["StoreError"]


class StoreError(DataError):
    """An ingest store is not a rattle_lab store, or is damaged."""
