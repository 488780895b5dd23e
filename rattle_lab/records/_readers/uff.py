"""Universal File Format (UFF) files: the time functions of dataset 58 (via pyuff).

Each dataset 58 of function type 1 (time response) with an even abscissa is one
channel: sample rate ``1 / abscissa_inc``, start time ``abscissa_min``, units SI by
the ordinate's specific data type (15 pressure -> ``sound_pressure`` in Pa, 12
acceleration -> ``plate_acceleration`` in m/s^2, 11 velocity -> ``plate_velocity``
in m/s, 13 excitation force -> ``excitation_force`` in N).  Other datasets (spectra,
FRFs, uneven functions, other dataset types) are reported as skipped.

Without a mapping, the ID lines that ``rattle-lab export`` writes
(:mod:`rattle_lab.exchange`) give back the campaign (line 1 ``rattle_lab NAME``),
the run, channel name and quantity (line 2 ``run=R ch=C q=QUANTITY``), the
protocol, frequency and level (line 3 ``p= f= f1= l= l1= u=``) and the start time
(line 4 ``t0=``).  A file from another tool becomes one run ``uff`` (protocol
``unspecified``) with channels named after the response entity, node and direction.
A mapping selects datasets with ``index`` (their position in the file, from 0).
A file that declares non-SI units (dataset 164 other than SI) is refused.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from rattle_lab.exceptions import FileFormatError
from .._errors import MappingError
from .._model import ArraySource
from . import RawRecord
from .mapping import MappingSpec, build_raw, load_mapping

FORMAT = "uff"
_QUANTITY_OF_TYPE = {15: "sound_pressure", 12: "plate_acceleration", 11: "plate_velocity",
                     13: "excitation_force"}
_SI_UNITS = {"sound_pressure": "Pa", "base_acceleration": "m/s^2", "plate_acceleration": "m/s^2",
             "plate_velocity": "m/s", "excitation_force": "N", "drive_signal": "V"}
_HEAD = re.compile(rb"^(?:[ \t]*-1[ \t]*\r?\n)+[ \t]*\d+")
_PROTOCOLS = ("sine_dwell", "amplitude_ramp_up", "amplitude_ramp_down", "stepped_frequency",
              "swept_frequency", "transient", "unspecified")


def sniff(head: bytes, path: Path) -> bool:
    """A UFF file starts with a ``-1`` delimiter line and a dataset number."""
    return _HEAD.match(head) is not None


def _fields(line: str) -> dict[str, str]:
    return {m.group(1): m.group(2) for m in re.finditer(r"(\w+)=(\S+)", line or "")}


class ArraySourceInMemory:
    """A channel already in memory (pyuff reads whole datasets)."""

    def __init__(self, data: np.ndarray) -> None:
        self.data = np.ascontiguousarray(data, dtype=np.float64)
        self.dtype = self.data.dtype
        self.n_samples = int(self.data.size)

    def read(self, start: int, stop: int) -> np.ndarray:
        return self.data[start:stop].copy()


class UffBackend:
    """Dataset-58 time functions of a UFF file, selected by ``index``."""

    format = FORMAT

    def __init__(self, path: Path) -> None:
        import pyuff

        try:
            uff = pyuff.UFF(str(path))
            types = [int(t) for t in uff.get_set_types()]
            sets = uff.read_sets(list(range(len(types)))) if types else []
        except Exception as exc:  # pyuff raises bare Exceptions for malformed files
            raise FileFormatError(f"{path}: not a readable UFF file: "
                                  f"{' '.join(str(exc).split())}") from exc
        if isinstance(sets, dict):
            sets = [sets]
        self.path = path
        self.sets: list[dict[str, Any]] = list(sets)
        for i, s in enumerate(self.sets):
            if int(s.get("type", 0)) == 164 and int(s.get("units_code", 1)) != 1:
                raise FileFormatError(f"{path}: dataset {i} (164): units code "
                                      f"{s.get('units_code')} is not SI; convert the file to SI")

    def is_time(self, i: int) -> bool:
        s = self.sets[i]
        return (int(s.get("type", 0)) == 58 and int(s.get("func_type", -1)) == 1
                and int(s.get("abscissa_spacing", 0)) == 1 and float(s.get("abscissa_inc", 0)) > 0
                and not np.iscomplexobj(s.get("data", 0.0)))

    def label(self, i: int) -> str:
        return f"dataset {i}"

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        if set(spec) & {"source", "segment", "axis"}:
            raise MappingError(f"{where}: a UFF dataset is selected with 'index' only")
        index = spec.get("index")
        if not isinstance(index, int) or not 0 <= index < len(self.sets):
            raise MappingError(f"{where}: key 'index': {index!r}; the file has {len(self.sets)} "
                               "datasets")
        if not self.is_time(index):
            raise MappingError(f"{where}: key 'index': dataset {index} is not an evenly sampled "
                               "time function (dataset 58, function type 1)")
        s = self.sets[index]
        declared: dict[str, Any] = {"sample_rate_hz": 1.0 / float(s["abscissa_inc"]),
                                    "start_time_s": float(s.get("abscissa_min", 0.0))}
        return ArraySourceInMemory(np.asarray(s["data"], dtype=float)), declared, \
            (self.label(index),)

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        raise MappingError(f"{where}: UFF time functions are evenly sampled; no timestamps")

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        return {}

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        raise MappingError(f"{where}: references into the file ({{ source = ... }}) work for HDF5 "
                           "only; give the value")

    def inventory(self) -> list[tuple[str, str]]:
        out = []
        for i, s in enumerate(self.sets):
            kind = (f"dataset 58, function type {s.get('func_type')}, {s.get('num_pts')} values, "
                    f"'{str(s.get('id2', '')).strip()}'") if int(s.get("type", 0)) == 58 \
                else f"dataset {s.get('type')}"
            out.append((self.label(i), kind))
        return out

    def close(self) -> None:
        self.sets = []


def default_mapping(path: Path, backend: UffBackend) -> dict[str, Any]:
    """The mapping used when none is given (from ``rattle-lab export``'s ID lines if present)."""
    campaign = "{stem}"
    runs: dict[str, dict[str, Any]] = {}
    skips = []
    for i, s in enumerate(backend.sets):
        if not backend.is_time(i):
            skips.append({"source": backend.label(i),
                          "reason": "not an evenly sampled time function (dataset 58 type 1)"})
            continue
        id1 = str(s.get("id1", "")).strip()
        if id1.startswith("rattle_lab "):
            campaign = id1.split(None, 1)[1]
        f2 = _fields(str(s.get("id2", "")))
        quantity = f2.get("q")
        full_scale = bool(quantity and quantity.endswith("(full-scale)"))
        if full_scale and quantity:
            quantity = quantity.removesuffix("(full-scale)")
        quantity = quantity or _QUANTITY_OF_TYPE.get(int(s.get("ordinate_spec_data_type", 0)))
        if quantity not in _SI_UNITS:
            skips.append({"source": backend.label(i), "reason": "ordinate type "
                          f"{s.get('ordinate_spec_data_type')} is not a record quantity"})
            continue
        run_id = f2.get("run", "uff")
        name = f2.get("ch") or re.sub(r"\W+", "_", f"{str(s.get('rsp_ent_name', 'ch')).strip()}_"
                                                  f"{s.get('rsp_node')}_{s.get('rsp_dir')}")
        run = runs.setdefault(run_id, {"run_id": run_id, "protocol": "unspecified",
                                       "channels": [], **_run_attrs(s)})
        run["channels"].append({"name": name, "index": i, "quantity": quantity,
                                "units": "1" if full_scale else _SI_UNITS[quantity]})
    if not runs:
        raise FileFormatError(f"{path}: no evenly sampled time function (dataset 58, function "
                              "type 1) of a known quantity")
    return {"mapping": {"version": 1, "format": "uff"},
            "campaign": {"campaign_id": campaign, "source": "measured"},
            "rig": {"apparatus": "other", "description": f"UFF file {path.name}: no rig "
                                                         "description"},
            "runs": list(runs.values()), **({"skip": skips} if skips else {})}


def _run_attrs(s: Mapping[str, Any]) -> dict[str, Any]:
    f3, f4 = _fields(str(s.get("id3", ""))), _fields(str(s.get("id4", "")))

    def num(key: str) -> float | None:
        try:
            return float(f3[key]) if key in f3 and f3[key] != "-" else None
        except ValueError:
            return None

    out: dict[str, Any] = {}
    for key, name in (("f", "excitation_freq_hz"), ("f1", "freq_end_hz"), ("l", "nominal_level"),
                      ("l1", "level_end")):
        if num(key) is not None:
            out[name] = num(key)
    if f3.get("u", "-") != "-":
        out["nominal_level_units"] = f3["u"]
    if f4.get("t0", "-") != "-":
        out["start_time_iso"] = f4["t0"]
    protocol = f3.get("p", "unspecified")
    if protocol in _PROTOCOLS:
        out["protocol"] = protocol
    return out


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read a UFF file, through ``mapping`` or the default one."""
    backend = UffBackend(path)
    if mapping is None:
        mapping = load_mapping(default_mapping(path, backend),
                               label=f"{path} (its ID lines as the mapping)")
    return build_raw(path, mapping, backend)
