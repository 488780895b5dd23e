"""Content verification: re-hash the inputs a store refers to and compare with ingest's hashes.

A record stored with ``storage="link"`` reads its samples from the input file,
so the input must still hold the bytes that were checked at ingest.  The
modification time and size are a quick first look (``open_stored_record``);
this module re-hashes the whole file (XXH3-128 at memory speed), which also
catches a change that kept the size and the modification time.  Files an
input links to (``--allow-links``) are re-hashed too.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from ._errors import StoreError

from ._index import reingest_advice
from ._ingest_types import file_hash
from ._layout import record_attrs


@dataclass(frozen=True)
class Mismatch:
    """One input whose bytes are not those ingested.

    Attributes
    ----------
    input_key : str
        The stored input (``/records/{input_key}``).
    path : str
        The file re-hashed (the input, or a file it links to).
    problem : {"missing", "changed"}
    expected, found : str
        Hash recorded at ingest, and hash now ("" when missing).
    linked : bool
        Whether the store reads samples from this file (``storage="link"``, or a
        link target); a copied input that changed does not affect the store.
    """

    input_key: str
    path: str
    problem: Literal["missing", "changed"]
    expected: str
    found: str
    linked: bool

    @property
    def message(self) -> str:
        """One line naming the file and what is wrong."""
        what = "is missing" if self.problem == "missing" else (
            f"has changed since it was ingested (hash {self.found}, was {self.expected})")
        return f"/records/{self.input_key}: {self.path} {what}"


def _hash_or_none(path: Path) -> str | None:
    try:
        return file_hash(path)
    except OSError:
        return None


def verify_store(store: str | os.PathLike[str], keys: Iterable[str] | None = None, *,
                 linked_only: bool = False) -> list[Mismatch]:
    """Re-hash every input (and link target) of ``store``; return each mismatch.

    Parameters
    ----------
    store : path-like
    keys : iterable of str, optional
        Only these stored inputs (default: all).
    linked_only : bool
        Only inputs the store reads samples from (what ``fit`` and ``report`` need).

    Raises
    ------
    StoreError
        If ``store`` is not a readable store.
    """
    attrs = record_attrs(store)
    wanted = list(attrs) if keys is None else list(keys)
    out: list[Mismatch] = []
    for key in wanted:
        a = attrs.get(key)
        if a is None:
            raise StoreError(f"{store}: /records/{key}: no such ingested input")
        linked = str(a.get("ingest_storage", "copy")) == "link"
        targets = json.loads(str(a.get("ingest_link_targets", "{}")) or "{}")
        checks = [(str(a.get("ingest_input_path", "")), str(a.get("ingest_input_hash", "")), linked)]
        checks += [(path, digest, True) for path, digest in targets.items()]
        for path, expected, is_linked in checks:
            if linked_only and not is_linked:
                continue
            found = _hash_or_none(Path(path))
            if found is None:
                out.append(Mismatch(key, path, "missing", expected, "", is_linked))
            elif found != expected:
                out.append(Mismatch(key, path, "changed", expected, found, is_linked))
    return out


def record_attrs_count(store: str | os.PathLike[str]) -> int:
    """How many inputs the store holds."""
    return len(record_attrs(store))


def check_linked_inputs(store: str | os.PathLike[str], keys: Iterable[str] | None = None) -> None:
    """Raise if an input the store reads samples from is not the one ingested.

    Raises
    ------
    StoreError
        Naming the store, the input and the file, and advising ``ingest --replace``.
    """
    bad = verify_store(store, keys, linked_only=True)
    if bad:
        more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
        first = bad[0]
        source = str(record_attrs(store)[first.input_key].get("ingest_input_path", first.path))
        advice = reingest_advice(source, store, first.problem == "missing" and first.path == source)
        raise StoreError(f"{store}: {bad[0].message}{more}; {advice}")
