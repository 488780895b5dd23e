"""Reading the store: the catalogue as a table, and one stored record."""

from __future__ import annotations

import copy
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import h5py
import numpy as np

from rattle_lab.exceptions import ParameterError
from ._errors import StoreError
from rattle_lab.records import LinkPolicy, Record, link_policy, load_group, validate_tree

from ._index import _link_problem, _open_store, _read_columns_from, _text, reingest_advice
from ._ingest_types import CATALOGUE_COLUMNS

if TYPE_CHECKING:  # pandas is imported when a catalogue is built, not at import time
    import pandas as pd

# --- reading the store ------------------------------------------------------------------------


def _frame(columns: Mapping[str, Sequence[Any] | np.ndarray]) -> pd.DataFrame:
    import pandas as pd

    data = {}
    for name, kind in CATALOGUE_COLUMNS:
        values: Sequence[Any] | np.ndarray = columns.get(name, [])
        if kind == "str":
            data[name] = pd.Series([str(v) for v in values], dtype=object)
        elif kind == "int":
            data[name] = pd.Series(np.asarray(values, dtype=np.int64))
        else:
            data[name] = pd.Series(np.asarray(values, dtype=np.float64))
    return pd.DataFrame(data)


def read_catalogue(store: str | os.PathLike[str],
                   level: Literal["channels", "runs"] = "channels") -> pd.DataFrame:
    """The store's catalogue as a DataFrame.

    Parameters
    ----------
    store : path-like
        An ingest store.
    level : {"channels", "runs"}
        One row per channel (all columns, see :data:`CATALOGUE_COLUMNS`), or one
        row per run (``input_key, file, campaign_id, run_id, protocol,
        excitation_freq_hz, nominal_level, nominal_level_units, run_start_iso,
        n_channels, channels, duration_s, flags``).

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store.
    ParameterError
        For another ``level``.
    """
    if level not in ("channels", "runs"):
        raise ParameterError(f"`level` must be 'channels' or 'runs', was {level!r}")
    store = Path(store)
    if not store.exists():
        raise StoreError(f"{store}: no such store")
    frame = _frame(_read_columns_from(store))
    if level == "channels":
        return frame
    keys = ["input_key", "file", "campaign_id", "run_id", "protocol", "excitation_freq_hz",
            "nominal_level", "nominal_level_units", "run_start_iso"]
    rows = []
    for _values, group in frame.groupby(keys[:4], sort=False, dropna=False):
        first = group.iloc[0]
        flags = dict.fromkeys(f for text in group["flags"] for f in text.split(",") if f)
        rows.append({**{k: first[k] for k in keys}, "n_channels": len(group),
                     "channels": ",".join(group["channel"]),
                     "duration_s": float(group["duration_s"].max()), "flags": ",".join(flags)})
    import pandas as pd

    return pd.DataFrame(rows, columns=keys + ["n_channels", "channels", "duration_s", "flags"])


#: Node trees of stored records this process has read and validated, by the store file's
#: identity (device, inode, size, modification time in ns) and the input key.  A store's
#: record is content-addressed and never rewritten in place, so a fit that opens each of
#: a file's runs reads and validates its attributes once instead of once per run; any
#: change to the store file (a write, a replacement) changes the identity.
_VALIDATED_TREES: dict[tuple[Any, ...], dict[str, Any]] = {}
_MAX_REMEMBERED = 16


def _file_identity(store: Path, input_key: str) -> tuple[Any, ...] | None:
    try:
        st = store.stat()
    except OSError:
        return None
    return (str(store.resolve()), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns, input_key)


def _remember(identity: tuple[Any, ...], tree: dict[str, Any]) -> None:
    while len(_VALIDATED_TREES) >= _MAX_REMEMBERED:
        _VALIDATED_TREES.pop(next(iter(_VALIDATED_TREES)))
    _VALIDATED_TREES[identity] = tree


def open_stored_record(store: str | os.PathLike[str], input_key: str) -> Record:
    """An ingested input as a :class:`~rattle_lab.records.Record` (read lazily).

    :meth:`Channel.read <rattle_lab.records.Channel.read>` gives SI values.

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store or has no such input, or if the
        input is linked (``storage="link"``) and its file has moved or changed
        since it was ingested.
    """
    from rattle_lab.records import record_from_tree
    from rattle_lab.records import Origin

    store = Path(store)
    with _open_store(store) as fh:
        group = fh.get(f"records/{input_key}")
        if not isinstance(group, h5py.Group):
            raise StoreError(f"{store}: /records/{input_key}: no such ingested input")
        if _text(group.attrs.get("ingest_storage", "copy")) == "link":
            problem = _link_problem(group.attrs)
            if problem is not None:
                raise StoreError(f"{store}: /records/{input_key}: attribute 'ingest_input_path': "
                                 f"{problem}; " + reingest_advice(
                                     _text(group.attrs["ingest_input_path"]), store,
                                     "missing" in problem))
    identity = _file_identity(store, input_key)
    known = _VALIDATED_TREES.get(identity) if identity is not None else None
    with link_policy(LinkPolicy(trusted=True)):  # the store's own links, to ingested inputs
        raw = load_group(store, f"/records/{input_key}",
                         tree=copy.deepcopy(known) if known is not None else None)
    label = f"{store}: /records/{input_key}"
    try:
        if known is None:
            validate_tree(raw.tree, label)
            if identity is not None:
                _remember(identity, copy.deepcopy(raw.tree))
        return record_from_tree(raw.tree, raw.sources,
                                Origin(path=store, format="rattle_store", closer=raw.closer),
                                store=True)
    except BaseException:
        if raw.closer is not None:
            raw.closer()
        raise


