"""One reader per source format, behind :func:`rattle_lab.records.read`.

Every reader turns its file into a :class:`RawRecord`: the node tree of a
rattle record (the same tree a native HDF5 file gives) plus lazy sources for
its datasets.  The tree is then validated by the one JSON Schema and turned
into a :class:`~rattle_lab.records.Record` by the same code for all formats.

A reader module provides ``FORMAT`` (its name), ``sniff(head, path) -> bool``
(does this file look like mine?) and ``load(path, mapping) -> RawRecord``;
``rattle_lab.records._read.READERS`` lists them.  Foreign formats build their
tree from a mapping (:mod:`.mapping`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from .._model import ArraySource, Skipped


@dataclass
class RawRecord:
    """What a reader returns: the node tree, its dataset sources, and what it skipped."""

    tree: dict[str, Any]
    sources: Mapping[str, ArraySource]
    format: str
    skipped: tuple[Skipped, ...] = ()
    closer: Callable[[], None] | None = field(default=None, repr=False)

