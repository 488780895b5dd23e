"""WAV microphone files (via soundfile), read chunk by chunk.

Samples are read as full-scale values (-1 <= x < 1) in units ``"1"``: a WAV
file is not calibrated to pascals, so its channels are flagged
``uncalibrated``.  For integer PCM the clipping limits are the full-scale
codes (``-1`` and ``1 - 2**(1 - bits)``).  Without a mapping each channel
becomes a ``sound_pressure`` channel (``mic``, or ``mic0``, ``mic1``, ...)
of one run ``wav`` with protocol ``unspecified``; a mapping may name the
run, the protocol and the rig, but may not relabel full-scale values as Pa.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import soundfile as sf

from rattle_lab.exceptions import FileFormatError
from .._errors import MappingError
from .._model import ArraySource
from . import RawRecord
from .mapping import MappingSpec, build_raw, load_mapping

FORMAT = "wav"
PCM_BITS = {"PCM_U8": 8, "PCM_S8": 8, "PCM_16": 16, "PCM_24": 24, "PCM_32": 32}


def sniff(head: bytes, path: Path) -> bool:
    """RIFF/WAVE (and RF64) files."""
    return head[:4] in (b"RIFF", b"RF64") and head[8:12] == b"WAVE"


class WavSource:
    """One channel of a WAV file, as full-scale floats."""

    def __init__(self, handle: sf.SoundFile, channel: int, dtype: np.dtype) -> None:
        self.handle = handle
        self.channel = channel
        self.dtype = dtype
        self.n_samples = int(handle.frames)

    def read(self, start: int, stop: int) -> np.ndarray:
        try:
            self.handle.seek(start)
            data = self.handle.read(stop - start, dtype=self.dtype.name, always_2d=True)
        except (sf.LibsndfileError, RuntimeError) as exc:
            raise FileFormatError(f"{self.handle.name}: channel {self.channel}: samples "
                                  f"{start}:{stop}: cannot be read: {exc}") from exc
        if data.shape[0] != stop - start:
            raise FileFormatError(f"{self.handle.name}: channel {self.channel}: samples "
                                  f"{start}:{stop}: file ends after {start + data.shape[0]} "
                                  "(truncated?)")
        return np.ascontiguousarray(data[:, self.channel])


#: A RIFF size field left at this value means "unknown" (a recorder that streamed the file).
_STREAMING_SIZES = (0, 0xFFFFFFFF)


def _data_chunk_problem(path: Path) -> str | None:
    """Why the RIFF ``data`` chunk's declared size does not fit the file, or None.

    libsndfile reads what the file holds; a size field that promises more (and is
    not the streaming marker 0 or 0xFFFFFFFF) means a truncated or forged file.
    """
    try:
        size = path.stat().st_size
        with open(path, "rb") as fh:
            head = fh.read(12)
            if len(head) < 12 or head[:4] != b"RIFF" or head[8:12] != b"WAVE":
                return None  # RF64, W64 ...: libsndfile's own checks apply
            pos = 12
            while pos + 8 <= size:
                fh.seek(pos)
                chunk = fh.read(8)
                cid, n = chunk[:4], int.from_bytes(chunk[4:8], "little")
                if cid == b"data":
                    if n not in _STREAMING_SIZES and pos + 8 + n > size:
                        return (f"chunk 'data' declares {n} bytes but the file holds "
                                f"{size - pos - 8} (truncated?)")
                    return None
                pos += 8 + n + (n & 1)
    except OSError:
        return None
    return None


class WavBackend:
    """Channels of a WAV file, selected by ``index`` (default 0)."""

    format = FORMAT

    def __init__(self, path: Path) -> None:
        try:
            self.handle = sf.SoundFile(path, "r")
        except (sf.LibsndfileError, RuntimeError) as exc:
            raise FileFormatError(f"{path}: not a readable WAV file: {exc}") from exc
        self.path = path
        problem = _data_chunk_problem(path)
        if problem is not None:
            self.handle.close()
            raise FileFormatError(f"{path}: not a readable WAV file: {problem}")
        bits = PCM_BITS.get(self.handle.subtype)
        self.dtype = np.dtype("f8") if bits is None or bits > 24 else np.dtype("f4")
        if self.handle.subtype == "DOUBLE":
            self.dtype = np.dtype("f8")
        self.range = (-1.0, 1.0 - 2.0 ** (1 - bits)) if bits else None

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        if "source" in spec or "segment" in spec or "axis" in spec:
            raise MappingError(f"{where}: a WAV channel is selected with 'index' only")
        index = spec.get("index", 0)
        if not isinstance(index, int) or not 0 <= index < self.handle.channels:
            raise MappingError(f"{where}: key 'index': {index!r}; the file has "
                               f"{self.handle.channels} channel(s)")
        declared: dict[str, Any] = {"units": "1", "sample_rate_hz": float(self.handle.samplerate),
                                    "start_time_s": 0.0}
        if self.range is not None:
            declared["range_min"], declared["range_max"] = self.range
        return WavSource(self.handle, index, self.dtype), declared, (f"channel {index}",)

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        raise MappingError(f"{where}: a WAV file is regularly sampled; it has no timestamps")

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        return {}

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        raise MappingError(f"{where}: references into the file ({{ source = ... }}) work for HDF5 "
                           "only; give the value")

    def inventory(self) -> list[tuple[str, str]]:
        return [(f"channel {i}", f"{self.handle.frames} samples at {self.handle.samplerate} Hz, "
                 f"{self.handle.subtype}") for i in range(self.handle.channels)]

    def close(self) -> None:
        self.handle.close()


def default_mapping(path: Path, n_channels: int) -> dict[str, Any]:
    """The mapping used when none is given: one run of sound-pressure channels."""
    names = ["mic"] if n_channels == 1 else [f"mic{i}" for i in range(n_channels)]
    return {
        "mapping": {"version": 1, "format": "wav"},
        "campaign": {"campaign_id": "{stem}", "source": "measured"},
        "rig": {"apparatus": "other",
                "description": f"WAV file {path.name}, ingested without a mapping: no rig description"},
        "runs": [{"run_id": "wav", "protocol": "unspecified",
                  "channels": [{"name": n, "index": i, "quantity": "sound_pressure"}
                               for i, n in enumerate(names)]}],
    }


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read a WAV file, through ``mapping`` or the default one."""
    backend = WavBackend(path)
    if mapping is None:
        mapping = load_mapping(default_mapping(path, backend.handle.channels),
                               label=f"{path} (read without a mapping)")
    return build_raw(path, mapping, backend)
