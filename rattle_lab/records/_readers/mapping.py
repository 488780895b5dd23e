"""Foreign layouts: a TOML mapping says how a file maps onto the rattle record schema.

The same mapping format serves every foreign source: any HDF5 layout
(including MATLAB v7.3 ``.mat`` files, which are HDF5 with a 512-byte user
block), LabVIEW ``.lvm`` text, NumPy ``.npy`` arrays, TDMS and WAV.  The
mapping supplies what the file does not say (quantities, rig, protocol) and
selects each channel's samples; what the file does say (LVM ``Delta_X`` and
``Y_Unit_Label``, WAV sample rate, TDMS ``wf_increment``) is taken from the
file, and a mapping that contradicts it is an error, never silently obeyed.
Columns the mapping does not use are reported as skipped, with a reason.

Example (``droptable.toml``)::

    [mapping]
    version = 1
    format = "lvm"                    # hdf5 | lvm | npy | tdms | wav (optional)

    [campaign]
    campaign_id = "droptable-{stem}"  # {stem}: the input file name without suffix
    source = "measured"

    [rig]
    apparatus = "other"
    description = "drop table with a circuit board"

    [[runs]]
    run_id = "shock"
    protocol = "transient"

    [[runs.channels]]
    name = "table"
    source = "Acceleration_0"         # LVM column; HDF5 dataset path; TDMS "group/channel"
    quantity = "base_acceleration"    # units and sample rate come from the LVM header

    [[skip]]
    source = "Untitled"
    reason = "impedance value, 5 samples: not a time series"

``[rig] edge_conditions`` are in the plate model's order
(:data:`rattle_lab.model.plate.EDGE_ORDER`: y=0, x=length, y=width, x=0) whatever
schema version the built record says.

Channel selectors: ``source`` (name or path), ``index`` and ``axis`` (a row or
column of a 2-D array; NumPy rows, WAV channels), ``segment`` (LVM segment).
Explicit time bases go in ``[runs.timestamps.NAME]`` with the same selectors
and are referenced by a channel's ``timestamps = "NAME"``.  In HDF5 mappings
any attribute value may be read from the file: ``sample_rate_hz = { source =
"/fs" }`` (a scalar or 1x1 dataset) or ``{ source = "/meta", attr = "fs" }``.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import h5py
import numpy as np

from rattle_lab._resources import resolve_resource
from rattle_lab.exceptions import FileFormatError
from .._convert import (CHANNEL_FIELDS, RIG_FIELDS, ROOT_FIELDS, RUN_FIELDS, SCHEMA_NAME,
                        SCHEMA_VERSION, SCHEMA_VERSION_CHAIN, edges_to_v1)
from .._errors import DuplicateRunError, MappingError
from .._h5 import H5Handle, H5Source, decode_attr_value, hdf5_signature_offset
from .._model import ArraySource, Skipped
from .._units import UNIT_TO_SI
from . import RawRecord

FORMAT = "hdf5"
MAPPING_VERSION = 1
FORMATS = ("hdf5", "lvm", "npy", "tdms", "uff", "wav")
SELECTOR_KEYS = ("source", "index", "axis", "segment")

_TOP_KEYS = {"mapping", "campaign", "rig", "runs", "skip"}
_CAMPAIGN_KEYS = set(ROOT_FIELDS)
_RIG_KEYS = set(RIG_FIELDS) | {"sensors"}
_SENSOR_KEYS = {"sensor_id", "position_m", "mounted_on", "description"}
_RUN_KEYS = set(RUN_FIELDS) | {"run_id", "channels", "timestamps"}
_CHANNEL_KEYS = set(CHANNEL_FIELDS) | set(SELECTOR_KEYS) | {"name"}
_TEMPLATE_KEYS = {"campaign_id", "run_id", "description", "notes"}


@dataclass(frozen=True)
class MappingSpec:
    """A parsed and checked mapping.

    Attributes
    ----------
    data : dict
        The TOML content.
    label : str
        What errors call it (the mapping file's path).
    sha256 : str
        Hash of the mapping file's bytes (provenance; part of the ingest key).
    """

    data: Mapping[str, Any]
    label: str
    sha256: str

    @property
    def format(self) -> str | None:
        """The declared source format, or None to detect it."""
        return self.data.get("mapping", {}).get("format")


def load_mapping(source: str | os.PathLike[str] | Mapping[str, Any], *,
                 label: str | None = None) -> MappingSpec:
    """Read and check a TOML mapping (a path) or take a mapping given as a dict.

    ``label`` names a dict mapping in messages (default ``"<mapping>"``; a reader's own
    default mapping names the file it was made from).

    Raises
    ------
    MappingError
        Naming the mapping file and the key, e.g. ``map.toml: runs[0].channels[1]: unknown key 'unit'``.
    """
    if isinstance(source, Mapping):
        data = dict(source)
        label = label or "<mapping>"
        digest = hashlib.sha256(repr(sorted(data.items())).encode()).hexdigest()
    else:
        # a file, or a mapping shipped with rattle_lab, by name
        path = resolve_resource("mappings", Path(source), MappingError, "cannot read the mapping file")
        label = str(path)
        try:
            raw = path.read_bytes()
        except OSError as exc:
            raise MappingError(f"{label}: cannot read the mapping file: {exc.strerror}") from exc
        digest = hashlib.sha256(raw).hexdigest()
        try:
            data = tomllib.loads(raw.decode("utf-8"))
        except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
            raise MappingError(f"{label}: not a valid TOML mapping: {exc}") from exc
    _check_mapping(data, label)
    return MappingSpec(data=data, label=label, sha256=digest)


def _unknown(table: Mapping[str, Any], allowed: set[str], label: str, where: str) -> None:
    for key in table:
        if key not in allowed and not key.startswith("x_"):
            raise MappingError(f"{label}: {where}: unknown key {key!r} "
                               f"(known: {', '.join(sorted(allowed))}; extras start with 'x_')")


def _table(value: Any, label: str, where: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise MappingError(f"{label}: {where}: must be a table")
    return value


def _check_mapping(data: Mapping[str, Any], label: str) -> None:
    _unknown(data, _TOP_KEYS, label, "top level")
    head = _table(data.get("mapping", {}), label, "[mapping]")
    _unknown(head, {"version", "format"}, label, "[mapping]")
    if head.get("version", MAPPING_VERSION) != MAPPING_VERSION:
        raise MappingError(f"{label}: [mapping]: version {head.get('version')!r} is not supported "
                           f"(this reader knows version {MAPPING_VERSION})")
    if "format" in head and head["format"] not in FORMATS:
        raise MappingError(f"{label}: [mapping]: format {head['format']!r} is not one of "
                           f"{', '.join(FORMATS)}")
    campaign = _table(data.get("campaign"), label, "[campaign]") if "campaign" in data else None
    if campaign is None or "campaign_id" not in campaign:
        raise MappingError(f"{label}: [campaign]: missing key 'campaign_id'")
    _unknown(campaign, _CAMPAIGN_KEYS, label, "[campaign]")
    rig = _table(data.get("rig", {}), label, "[rig]")
    if "rig" not in data:
        raise MappingError(f"{label}: [rig]: missing table (give at least apparatus and description)")
    _unknown(rig, _RIG_KEYS, label, "[rig]")
    for i, sensor in enumerate(rig.get("sensors", [])):
        _unknown(_table(sensor, label, f"rig.sensors[{i}]"), _SENSOR_KEYS, label, f"rig.sensors[{i}]")
    runs = data.get("runs")
    if not isinstance(runs, list) or not runs:
        raise MappingError(f"{label}: [[runs]]: a mapping needs at least one run")
    seen: dict[str, int] = {}
    for i, run in enumerate(runs):
        where = f"runs[{i}]"
        _unknown(_table(run, label, where), _RUN_KEYS, label, where)
        if "run_id" not in run:
            raise MappingError(f"{label}: {where}: missing key 'run_id'")
        if run["run_id"] in seen:
            raise DuplicateRunError(f"{label}: {where}: duplicated run_id {run['run_id']!r} "
                                    f"(also runs[{seen[run['run_id']]}])")
        seen[run["run_id"]] = i
        channels = run.get("channels")
        if not isinstance(channels, list) or not channels:
            raise MappingError(f"{label}: {where}: missing [[runs.channels]] (at least one channel)")
        names: set[str] = set()
        for j, ch in enumerate(channels):
            cwhere = f"{where}.channels[{j}]"
            _unknown(_table(ch, label, cwhere), _CHANNEL_KEYS, label, cwhere)
            for key in ("name", "quantity"):
                if key not in ch:
                    raise MappingError(f"{label}: {cwhere}: missing key {key!r}")
            if ch["name"] in names:
                raise MappingError(f"{label}: {cwhere}: duplicated channel name {ch['name']!r}")
            names.add(ch["name"])
        for name, spec in _table(run.get("timestamps", {}), label, f"{where}.timestamps").items():
            _unknown(_table(spec, label, f"{where}.timestamps.{name}"), set(SELECTOR_KEYS), label,
                     f"{where}.timestamps.{name}")
    for i, skip in enumerate(data.get("skip", [])):
        _unknown(_table(skip, label, f"skip[{i}]"), {"source", "reason"}, label, f"skip[{i}]")
        if "source" not in skip or "reason" not in skip:
            raise MappingError(f"{label}: skip[{i}]: needs 'source' and 'reason'")


class Backend(Protocol):
    """What a foreign format offers to :func:`build_raw`."""

    format: str

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        """(source, attributes the file declares, inventory labels of what was used)."""

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        """(source, inventory labels of what was used) of an explicit time base, s."""

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        """Run attributes the file declares (e.g. its start time), given the inventory labels
        of the run's channels."""

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        """Value of a ``{source = ..., attr = ...}`` reference into the file."""

    def inventory(self) -> list[tuple[str, str]]:
        """(label, description) of everything the file holds that could be a channel."""

    def close(self) -> None:
        """Release the file."""


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=0.0)
    return bool(a == b)


def _id_from(text: str) -> str:
    cleaned = re.sub(r"[^A-Za-z0-9_.-]+", "_", text).strip("_.-")
    return (cleaned or "record")[:64]


def _fill(value: Any, stem: str, key: str) -> Any:
    if isinstance(value, str) and key in _TEMPLATE_KEYS:
        stem_text = _id_from(stem) if key in ("campaign_id", "run_id") else stem
        return value.replace("{stem}", stem_text)
    return value


def build_raw(path: Path, spec: MappingSpec, backend: Backend) -> RawRecord:
    """Build the node tree of ``path`` from a mapping and a format backend."""
    label = spec.label
    stem = path.stem
    data = spec.data
    try:
        def value(v: Any, key: str, where: str) -> Any:
            if isinstance(v, Mapping):
                return backend.resolve(v, f"{label}: {where}.{key}")
            return _fill(v, stem, key)

        root_attrs = {"schema": SCHEMA_NAME, "schema_version": SCHEMA_VERSION}
        root_attrs.update({k: value(v, k, "[campaign]") for k, v in data["campaign"].items()})
        root_attrs.setdefault("source", "measured")
        rig_data = dict(data["rig"])
        sensors = {}
        for i, s in enumerate(rig_data.pop("sensors", [])):
            s = dict(s)
            sensor_id = s.pop("sensor_id", None)
            if sensor_id is None:
                raise MappingError(f"{label}: rig.sensors[{i}]: missing key 'sensor_id'")
            sensors[sensor_id] = {"kind": "group", "members": {},
                                  "attrs": {k: value(v, k, f"rig.sensors[{i}]") for k, v in s.items()}}
        rig_attrs = {k: value(v, k, "[rig]") for k, v in rig_data.items()}
        rig = {"kind": "group", "attrs": rig_attrs,
               "members": {"sensors": {"kind": "group", "attrs": {}, "members": sensors}}
               if sensors else {}}

        sources: dict[str, ArraySource] = {}
        used: set[str] = set()
        runs: dict[str, Any] = {}
        for i, run in enumerate(data["runs"]):
            where = f"runs[{i}]"
            run_id = _fill(run["run_id"], stem, "run_id")
            run_used: list[str] = []
            ts_nodes = {}
            for name, ts_spec in run.get("timestamps", {}).items():
                src, used_label = backend.timestamps(ts_spec, f"{label}: {where}.timestamps.{name}")
                used.update(used_label)
                sources[f"/runs/{run_id}/timestamps/{name}"] = src
                ts_nodes[name] = {"kind": "dataset", "attrs": {"units": "s"},
                                  "dtype": np.dtype(src.dtype).str, "shape": [src.n_samples]}
            channels = {}
            for j, ch in enumerate(run["channels"]):
                cwhere = f"{where}.channels[{j}]"
                src, declared, used_label = backend.channel(ch, f"{label}: {cwhere}")
                used.update(used_label)
                run_used.extend(used_label)
                ch_attrs = _merge(declared, {k: value(v, k, cwhere) for k, v in ch.items()
                                             if k not in SELECTOR_KEYS and k != "name"},
                                  label, cwhere, " + ".join(used_label))
                if "timestamps" in ch_attrs:
                    declared_fs = ch_attrs.pop("sample_rate_hz", None)
                    ch_attrs.pop("start_time_s", None)
                    ts_src = sources.get(f"/runs/{run_id}/timestamps/{ch_attrs['timestamps']}")
                    _check_rate_against_time(declared_fs, ts_src, f"{label}: {cwhere}")
                sources[f"/runs/{run_id}/channels/{ch['name']}"] = src
                channels[ch["name"]] = {"kind": "dataset", "attrs": ch_attrs,
                                        "dtype": np.dtype(src.dtype).str, "shape": [src.n_samples]}
            attrs = dict(backend.run_defaults(tuple(run_used)))
            for k, v in run.items():
                if k not in ("run_id", "channels", "timestamps"):
                    attrs[k] = value(v, k, where)
            members: dict[str, Any] = {"channels": {"kind": "group", "attrs": {}, "members": channels}}
            if ts_nodes:
                members["timestamps"] = {"kind": "group", "attrs": {}, "members": ts_nodes}
            if run_id in runs:
                raise DuplicateRunError(f"{label}: {where}: duplicated run_id {run_id!r}")
            runs[run_id] = {"kind": "group", "attrs": attrs, "members": members}

        inventory = dict(backend.inventory())
        reasons = {}
        for i, skip in enumerate(data.get("skip", [])):
            if skip["source"] not in inventory:
                raise MappingError(f"{label}: skip[{i}]: {skip['source']!r} is not in "
                                   f"{path.name} (has: {', '.join(inventory)})")
            reasons[skip["source"]] = skip["reason"]
        skipped = tuple(Skipped(name, reasons.get(name, f"not in the mapping ({desc})"))
                        for name, desc in inventory.items() if name not in used)
    except BaseException:
        backend.close()
        raise
    tree = {"kind": "group", "attrs": root_attrs,
            "members": {"rig": rig, "runs": {"kind": "group", "attrs": {}, "members": runs}}}
    if _uses_chain_attrs(rig, runs):
        root_attrs["schema_version"] = SCHEMA_VERSION_CHAIN
    elif "edge_conditions" in rig_attrs:
        # a mapping gives the edges in EDGE_ORDER; a version-1 tree lists them in v1's order
        rig_attrs["edge_conditions"] = edges_to_v1(rig_attrs["edge_conditions"])
    return RawRecord(tree=tree, sources=sources, format=backend.format, skipped=skipped,
                     closer=backend.close)


def _merge(declared: Mapping[str, Any], given: Mapping[str, Any], label: str, where: str,
           used_label: str) -> dict[str, Any]:
    """The file's declared attributes, completed by the mapping; contradictions raise."""
    out = dict(declared)
    for key, val in given.items():
        if key in declared and not _same(declared[key], val):
            raise MappingError(f"{label}: {where}: key {key!r}: the mapping says {val!r} but "
                               f"{used_label} says {declared[key]!r}")
        out[key] = val
    return out


def known_unit(label: str) -> str | None:
    """A unit label from a foreign file if it is one of ours (else None)."""
    text = label.strip()
    return text if text in UNIT_TO_SI else None


# --- HDF5 (any layout, including MATLAB v7.3 .mat) ------------------------------------------


def sniff(head: bytes, path: Path) -> bool:
    """Foreign HDF5 is never detected alone: it needs a mapping."""
    return False


def is_matlab(path: Path) -> bool:
    """True for a MATLAB v7.3 ``.mat`` file (HDF5 after a 512-byte user block)."""
    with open(path, "rb") as fh:
        head = fh.read(128)
    return head.startswith(b"MATLAB 7.3 MAT-file") or (
        b"MATLAB" in head and hdf5_signature_offset(path) == 512)


#: MATLAB classes whose arrays are samples (a v7.3 file's ``MATLAB_class`` attribute).
MATLAB_NUMERIC = ("double", "single", "int8", "int16", "int32", "int64", "uint8", "uint16",
                  "uint32", "uint64")


class HDF5Backend:
    """Channels are datasets of any HDF5 layout, selected by path."""

    format = FORMAT

    def __init__(self, path: Path) -> None:
        self.path = path
        self.handle = H5Handle(path)
        self.file = self.handle.get()
        self.matlab = is_matlab(path)
        self._referenced: set[str] = set()

    def _dataset(self, name: Any, where: str) -> h5py.Dataset:
        if not isinstance(name, str):
            raise MappingError(f"{where}: 'source' must be an HDF5 dataset path")
        obj = self.file.get(name)
        if not isinstance(obj, h5py.Dataset):
            raise MappingError(f"{where}: source {name!r}: no such dataset in {self.path}")
        return obj

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        if "source" not in spec:
            raise MappingError(f"{where}: missing key 'source' (the dataset path)")
        ds = self._dataset(spec["source"], where)
        if ds.dtype.kind not in "fiu":
            raise MappingError(f"{where}: source {spec['source']!r}: dataset of dtype {ds.dtype} "
                               "is not numeric")
        mclass = (decode_attr_value(ds.attrs["MATLAB_class"], where=f"{self.path}: {ds.name}",
                                    name="MATLAB_class")
                  if self.matlab and "MATLAB_class" in ds.attrs else "double")
        if mclass not in MATLAB_NUMERIC:
            # MATLAB stores text as uint16 and logicals as uint8: numbers that are not samples
            raise MappingError(f"{where}: source {spec['source']!r}: attribute 'MATLAB_class': "
                               f"{mclass!r} is not a numeric MATLAB array ("
                               f"{', '.join(MATLAB_NUMERIC)})")
        src = H5Source(self.handle, ds.name, index=spec.get("index"), axis=spec.get("axis", 0))
        return src, {}, (ds.name,)

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        src, _, used = self.channel(spec, where)
        return src, used

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        return {}

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        unknown = set(ref) - {"source", "attr"}
        if unknown or "source" not in ref:
            raise MappingError(f"{where}: a reference is {{ source = \"/path\" }} or "
                               f"{{ source = \"/path\", attr = \"name\" }}")
        obj = self.file.get(ref["source"])
        if obj is None:
            raise MappingError(f"{where}: source {ref['source']!r}: not in {self.path}")
        self._referenced.add(obj.name)
        if "attr" in ref:
            if ref["attr"] not in obj.attrs:
                raise MappingError(f"{where}: {ref['source']}: no attribute {ref['attr']!r}")
            return decode_attr_value(obj.attrs[ref["attr"]], where=f"{self.path}: {ref['source']}",
                                     name=ref["attr"])
        if not isinstance(obj, h5py.Dataset) or obj.size > 65536:
            raise MappingError(f"{where}: source {ref['source']!r}: must be a small dataset")
        arr = obj[()]
        cls = obj.attrs.get("MATLAB_class")
        if isinstance(cls, bytes):
            cls = cls.decode()
        if cls == "char":  # MATLAB text: UTF-16 code units
            return "".join(chr(c) for c in np.asarray(arr).ravel(order="F"))
        arr = np.asarray(arr)
        if arr.size != 1:
            raise MappingError(f"{where}: source {ref['source']!r}: expected one value, has shape "
                               f"{arr.shape}")
        return decode_attr_value(arr.reshape(()), where=f"{self.path}: {ref['source']}", name="value")

    def inventory(self) -> list[tuple[str, str]]:
        out: list[tuple[str, str]] = []

        def visit(name: str, obj: Any) -> None:
            # Datasets read as metadata ({ source = ... }) are used, not skipped.
            if (isinstance(obj, h5py.Dataset) and not name.startswith("#")
                    and "/" + name not in self._referenced):
                out.append(("/" + name, f"dataset {obj.shape} {obj.dtype}"))

        self.file.visititems(visit)
        return out

    def close(self) -> None:
        self.handle.close()


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read a foreign HDF5 layout (incl. MATLAB v7.3) through ``mapping``."""
    if mapping is None:
        what = "a MATLAB v7.3 .mat file" if is_matlab(path) else "an HDF5 file"
        raise FileFormatError(f"{path}: is {what} without the rattle record attributes "
                              "(root attribute schema='rattle_record'): pass a mapping "
                              "(--mapping FILE.toml) to read a foreign layout")
    return build_raw(path, mapping, HDF5Backend(path))



def _uses_chain_attrs(rig: Mapping[str, Any], runs: Mapping[str, Any]) -> bool:
    """True when a mapped record carries an attribute of schema version 2 (the chain)."""
    from .._schema import V2_CHANNEL_ATTRS, V2_RIG_ATTRS, V2_RUN_ATTRS

    if any(k in rig["attrs"] for k in V2_RIG_ATTRS):
        return True
    if any(k in run["attrs"] for run in runs.values() for k in V2_RUN_ATTRS):
        return True
    return any(k in ch["attrs"] for run in runs.values()
               for ch in run["members"]["channels"]["members"].values() for k in V2_CHANNEL_ATTRS)


#: Relative disagreement between a declared sample rate and a time vector that is refused.
RATE_TOLERANCE = 1e-3


def _check_rate_against_time(fs_hz: Any, ts: Any, where: str) -> None:
    """Refuse a declared sample rate that contradicts the channel's own time vector."""
    if fs_hz is None or ts is None or ts.n_samples < 3:
        return
    t = np.asarray(ts.read(0, min(ts.n_samples, 100_000)), dtype=np.float64)
    dt = float(np.median(np.diff(t)))
    if not dt > 0:
        return
    if abs(1.0 / dt - float(fs_hz)) > RATE_TOLERANCE * float(fs_hz):
        raise MappingError(f"{where}: sample_rate_hz {float(fs_hz):.6g} Hz contradicts the "
                           f"channel's time vector (median step {dt:.6g} s = {1.0 / dt:.6g} Hz); "
                           "give one of the two")
