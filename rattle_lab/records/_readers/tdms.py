"""NI TDMS files (via npTDMS), read chunk by chunk.

Channels are named ``"group/channel"``.  The file's own waveform properties
are honoured: ``wf_increment`` (s) gives the sample rate, ``wf_start_offset``
(s) the start time, ``unit_string`` the units, ``wf_start_time`` the run's
start.  Without a mapping, a file whose every channel has a ``quantity``
property is read as one run per group (run id = group name, protocol from a
group property ``protocol`` or ``unspecified``).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from nptdms import TdmsFile

from rattle_lab.exceptions import FileFormatError
from .._errors import MappingError
from .._model import ArraySource
from . import RawRecord
from .mapping import MappingSpec, build_raw, known_unit, load_mapping

FORMAT = "tdms"


def sniff(head: bytes, path: Path) -> bool:
    """TDMS segments start with ``TDSm``."""
    return head.startswith(b"TDSm")


class _NptdmsLog(logging.Handler):
    """Collects npTDMS's log warnings (instead of letting it print them) while active."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.messages: list[str] = []
        self._saved: list[tuple[logging.Logger, list[logging.Handler], bool]] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(" ".join(record.getMessage().split()))

    def __enter__(self) -> _NptdmsLog:
        names = [n for n in logging.Logger.manager.loggerDict if n == "nptdms" or n.startswith("nptdms.")]
        for name in names:
            logger = logging.getLogger(name)
            self._saved.append((logger, list(logger.handlers), logger.propagate))
            logger.handlers = [self]
            logger.propagate = False
        return self

    def __exit__(self, *exc: object) -> None:
        for logger, handlers, propagate in self._saved:
            logger.handlers = handlers
            logger.propagate = propagate


class TdmsSource:
    """One TDMS channel, read with ``read_data(offset, length)``."""

    def __init__(self, channel: Any, label: str) -> None:
        self.channel = channel
        self.label = label
        self.dtype = np.dtype(channel.dtype)
        self.n_samples = int(len(channel))

    def read(self, start: int, stop: int) -> np.ndarray:
        with _NptdmsLog() as log:
            try:
                data = np.asarray(self.channel.read_data(offset=start, length=stop - start))
            except Exception as exc:  # npTDMS raises assorted errors on damaged files
                raise FileFormatError(f"{self.label}: samples {start}:{stop}: cannot be read: "
                                      f"{' '.join(str(exc).split())}") from exc
        if log.messages or data.shape != (stop - start,):
            raise FileFormatError(f"{self.label}: samples {start}:{stop}: cannot be read "
                                  f"(got {data.shape[0]}): " + "; ".join(log.messages))
        return data


class TdmsBackend:
    """Channels of a TDMS file, selected by ``source = "group/channel"``."""

    format = FORMAT

    def __init__(self, path: Path) -> None:
        with _NptdmsLog() as log:
            try:
                self.file = TdmsFile.open(path)
            except Exception as exc:  # npTDMS raises ValueError, KeyError, struct.error, ...
                raise FileFormatError(f"{path}: not a readable TDMS file (truncated or damaged?): "
                                      f"{type(exc).__name__}: {' '.join(str(exc).split())}") from exc
        if log.messages:
            # npTDMS reads what it can of a damaged file and only logs: that would be silent.
            self.file.close()
            raise FileFormatError(f"{path}: damaged TDMS file (truncated?): npTDMS says: "
                                  + "; ".join(log.messages))
        self.path = path
        self.channels = {f"{g.name}/{c.name}": c for g in self.file.groups() for c in g.channels()}

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        name = spec.get("source")
        if name is None or "index" in spec or "segment" in spec:
            raise MappingError(f"{where}: a TDMS channel is selected with source = \"group/channel\"")
        ch = self.channels.get(name)
        if ch is None:
            raise MappingError(f"{where}: no channel {name!r} in {self.path.name} "
                               f"(has: {', '.join(self.channels)})")
        if np.dtype(ch.dtype).kind not in "fiu":
            raise MappingError(f"{where}: channel {name!r} has non-numeric data ({ch.dtype})")
        props = ch.properties
        declared: dict[str, Any] = {}
        if "wf_increment" in props:
            inc = float(props["wf_increment"])
            if not inc > 0:
                raise FileFormatError(f"{self.path}: {name}: property 'wf_increment': must be > 0, "
                                      f"was {inc}")
            declared["sample_rate_hz"] = 1.0 / inc
            declared["start_time_s"] = float(props.get("wf_start_offset", 0.0))
        unit = str(props.get("unit_string", "")).strip()
        if known_unit(unit):
            declared["units"] = unit
        elif unit:
            declared["x_source_units"] = unit
        return TdmsSource(ch, f"{self.path}: {name}"), declared, (name,)

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        src, _, used = self.channel(spec, where)
        if src.dtype != np.float64:
            raise MappingError(f"{where}: timestamps must be float64 seconds, got {src.dtype}")
        return src, used

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        for name in used:
            props = self.channels[name].properties
            if "wf_start_time" in props:
                start = np.datetime64(props["wf_start_time"], "ns")
                return {"start_time_iso": str(start) + "Z"}  # TDMS timestamps are UTC
        return {}

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        raise MappingError(f"{where}: references into the file ({{ source = ... }}) work for HDF5 "
                           "only; give the value")

    def inventory(self) -> list[tuple[str, str]]:
        return [(name, f"{len(ch)} samples {ch.dtype}") for name, ch in self.channels.items()]

    def close(self) -> None:
        self.file.close()


def default_mapping(path: Path, backend: TdmsBackend) -> dict[str, Any]:
    """A mapping from the channels' own ``quantity`` properties, or an error saying what is missing."""
    runs = []
    for group in backend.file.groups():
        channels = []
        for ch in group.channels():
            quantity = ch.properties.get("quantity")
            if quantity is None:
                raise FileFormatError(f"{path}: channel {group.name}/{ch.name} has no 'quantity' "
                                      "property: pass a mapping (--mapping FILE.toml)")
            channels.append({"name": ch.name, "source": f"{group.name}/{ch.name}",
                             "quantity": str(quantity)})
        if channels:
            runs.append({"run_id": group.name,
                         "protocol": str(group.properties.get("protocol", "unspecified")),
                         "channels": channels})
    if not runs:
        raise FileFormatError(f"{path}: TDMS file without channels")
    return {"mapping": {"version": 1, "format": "tdms"},
            "campaign": {"campaign_id": "{stem}", "source": "measured"},
            "rig": {"apparatus": "other",
                    "description": f"TDMS file {path.name}, ingested without a mapping"},
            "runs": runs}


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read a TDMS file through ``mapping`` or its channels' own properties."""
    backend = TdmsBackend(path)
    try:
        if mapping is None:
            mapping = load_mapping(default_mapping(path, backend),
                                   label=f"{path} (its channels' properties as the mapping)")
    except BaseException:
        backend.close()
        raise
    return build_raw(path, mapping, backend)
