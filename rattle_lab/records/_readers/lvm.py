"""LabVIEW Measurement (``.lvm``) text files, read through a mapping.

The parser honours the header rather than guessing:

* file header (``LabVIEW Measurement`` ... ``***End_of_Header***``):
  ``Separator`` (Tab, Comma or Semicolon), ``Decimal_Separator`` (``.`` or
  ``,``), ``X_Columns`` (No, One or Multi), ``Date``/``Time``;
* one or more segments, each with its own header (``Channels``, ``Samples``,
  ``Y_Unit_Label``, ``X_Dimension``, ``X0``, ``Delta_X``, ``Date``, ``Time``;
  one value per channel), a column-name line and data rows.  Data that resume
  after a blank line without a new header form a segment with the previous
  header.  The trailing ``Comment`` column is ignored;
* each channel's timing comes from its own ``X0`` and ``Delta_X`` (the X
  column is printed with fewer digits, and LabVIEW guarantees it for the first
  channel only), its unit from ``Y_Unit_Label``;
* a channel shorter than the others has empty fields at the end of its column;
  its value count must equal the header's ``Samples``;
* ``X_Columns No``: LabVIEW still writes the ``X_Value`` heading and an empty first
  field on every row; that column is dropped (not taken for the first channel), or
  kept as the X values when it holds numbers;
* header fields the LabVIEW format does not define are reported with an
  :class:`LvmHeaderWarning` (they are kept in the parsed header, never used).

The whole text is parsed at once: LVM files are text and small by nature
(a 1 s, 51.2 kHz record is 1.6 MB); use HDF5 or TDMS for long records.
"""

from __future__ import annotations

import itertools
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from pathlib import Path
from typing import Any

import numpy as np

from rattle_lab.exceptions import FileFormatError, RattleLabWarning
from .._errors import MappingError
from .._model import ArrayData, ArraySource
from . import RawRecord
from .mapping import MappingSpec, build_raw, known_unit

FORMAT = "lvm"
END = "***End_of_Header***"
SEPARATORS = {"tab": "\t", "comma": ",", "semicolon": ";"}

#: File-header fields of the LabVIEW Measurement format (LabVIEW's LVM file specification).
FILE_HEADER_FIELDS = frozenset({
    "Writer_Version", "Reader_Version", "Separator", "Decimal_Separator", "Multi_Headings",
    "X_Columns", "Time_Pref", "Operator", "Description", "Date", "Time", "Project",
    "Test_Name", "Test_Numbers", "Test Series", "UUT_Name", "UUT_Model", "UUT_Serial_Number",
    "Hardware", "Software", "Notes"})
#: Segment-header fields of the format.
SEGMENT_HEADER_FIELDS = frozenset({
    "Channels", "Samples", "Date", "Time", "Y_Unit_Label", "X_Dimension", "X0", "Delta_X",
    "Notes", "Test_Name", "Test_Numbers", "Test Series", "UUT_Name", "UUT_Model",
    "UUT_Serial_Number", "Operator", "Description"})


class LvmHeaderWarning(RattleLabWarning):
    """An LVM header carries a field the LabVIEW Measurement format does not define."""


@dataclass(frozen=True)
class LvmChannel:
    """One channel of one segment of an LVM file."""

    name: str
    segment: int
    column: int
    values: np.ndarray
    unit_label: str
    delta_x: Decimal | None
    x0: float | None
    x_dimension: str
    date: str | None
    time: str | None


@dataclass(frozen=True)
class LvmFile:
    """A parsed LVM file: header fields and channels of all segments."""

    path: Path
    header: Mapping[str, str]
    separator: str
    decimal: str
    x_columns: str
    channels: tuple[LvmChannel, ...]
    x_values: Mapping[int, np.ndarray]
    n_segments: int


def sniff(head: bytes, path: Path) -> bool:
    """LVM files with a header start with ``LabVIEW Measurement``."""
    return head.lstrip(b"\xef\xbb\xbf").startswith(b"LabVIEW Measurement")


def _decode(raw: bytes) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")  # LabVIEW writes the system code page


def parse_lvm(path: str | Path) -> LvmFile:
    """Parse an LVM file (see the module docstring for what is honoured).

    Raises
    ------
    FileFormatError
        Naming the file, the line and the field.
    """
    path = Path(path)
    lines = _decode(path.read_bytes()).splitlines()
    if not lines or not sniff(lines[0].encode(), path):
        raise FileFormatError(f"{path}: line 1: not a LabVIEW .lvm file with a header "
                              "(expected 'LabVIEW Measurement')")
    sep = None
    for line in lines[1:200]:
        m = re.match(r"^Separator[\t,;]\s*(\w+)", line)
        if m:
            key = m.group(1).lower()
            if key not in SEPARATORS:
                raise FileFormatError(f"{path}: header 'Separator': {m.group(1)!r} is not Tab, "
                                      "Comma or Semicolon")
            sep = SEPARATORS[key]
            break
        if line.startswith(END):
            break
    if sep is None:
        tail = lines[0][len("LabVIEW Measurement"):len("LabVIEW Measurement") + 1]
        sep = tail if tail in ("\t", ",", ";") else "\t"
    header: dict[str, str] = {}
    i = 1
    while i < len(lines) and not lines[i].split(sep)[0].strip() == END:
        fields = lines[i].split(sep)
        if fields[0].strip():
            header[fields[0].strip()] = fields[1].strip() if len(fields) > 1 else ""
        i += 1
    if i >= len(lines):
        raise FileFormatError(f"{path}: file header has no '{END}' line")
    _warn_unknown(path, "file header", header, FILE_HEADER_FIELDS)
    i += 1
    decimal = header.get("Decimal_Separator", ".") or "."
    # (A comma separator cannot also be the decimal one: the header value would be empty.)
    if decimal not in (".", ","):
        raise FileFormatError(f"{path}: header 'Decimal_Separator': {decimal!r} is not '.' or ','")
    x_columns = header.get("X_Columns", "One") or "One"
    if x_columns not in ("No", "One", "Multi"):
        raise FileFormatError(f"{path}: header 'X_Columns': {x_columns!r} is not No, One or Multi")

    channels: list[LvmChannel] = []
    x_values: dict[int, np.ndarray] = {}
    seg_header: dict[str, list[str]] | None = None
    names: list[str] | None = None
    segment = -1
    n = len(lines)
    while i < n:
        fields = lines[i].split(sep)
        if not any(f.strip() for f in fields):
            i += 1
            continue
        if _is_data(fields, decimal):
            if seg_header is None or names is None:
                raise FileFormatError(f"{path}: line {i + 1}: data before any segment header")
            # Data resuming after a blank line: a new segment with the previous header.
        else:
            seg_header = {}
            while i < n and lines[i].split(sep)[0].strip() != END:
                f = lines[i].split(sep)
                if f[0].strip():
                    seg_header[f[0].strip()] = [v.strip() for v in f[1:]]
                i += 1
            if i >= n:
                raise FileFormatError(f"{path}: segment header without '{END}'")
            _warn_unknown(path, f"segment {segment + 1} header", seg_header, SEGMENT_HEADER_FIELDS)
            i += 1
            if i >= n:
                raise FileFormatError(f"{path}: line {i}: segment header without a column-name line")
            names = [v.strip() for v in lines[i].split(sep)]
            i += 1
        segment += 1
        start = i
        rows = []
        while i < n:
            f = lines[i].split(sep)
            if not _is_data(f, decimal):
                break
            rows.append(f)
            i += 1
        assert seg_header is not None and names is not None
        _segment(path, segment, seg_header, names, rows, start, x_columns, decimal, header,
                 channels, x_values)
    if not channels:
        raise FileFormatError(f"{path}: no data segment found")
    return LvmFile(path=path, header=header, separator=sep, decimal=decimal, x_columns=x_columns,
                   channels=tuple(channels), x_values=x_values, n_segments=segment + 1)


def _warn_unknown(path: Path, where: str, header: Mapping[str, Any], known: frozenset[str]) -> None:
    unknown = sorted(k for k in header if k not in known)
    if unknown:
        warnings.warn(f"{path}: {where}: field{'s' if len(unknown) > 1 else ''} "
                      f"{', '.join(repr(k) for k in unknown)} not defined by the LabVIEW "
                      "Measurement format (kept in the header, not used)", LvmHeaderWarning,
                      stacklevel=3)


def _number(text: str, decimal: str) -> str:
    return text.strip().replace(decimal, ".") if decimal == "," else text.strip()


def _is_data(fields: list[str], decimal: str) -> bool:
    for f in fields:
        if f.strip():
            try:
                float(_number(f, decimal))
            except ValueError:
                return False
            return True
    return False


def _segment(path: Path, segment: int, seg_header: Mapping[str, list[str]], names: list[str],
             rows: list[list[str]], first_line: int, x_columns: str, decimal: str,
             header: Mapping[str, str], channels: list[LvmChannel],
             x_values: dict[int, np.ndarray]) -> None:
    # X_Columns No: LabVIEW still writes the X_Value heading and an empty first field per row.
    x_heading = x_columns == "No" and bool(names) and names[0] == "X_Value"
    if x_columns == "One":
        ch_names = names[1:]
    elif x_columns == "Multi":
        ch_names = names[1::2]
    else:
        ch_names = names[1:] if x_heading else names
    declared = seg_header.get("Channels", [""])[0]
    if declared:
        try:
            n_ch = int(declared)
        except ValueError:
            raise FileFormatError(f"{path}: segment {segment} header 'Channels': {declared!r} "
                                  "is not an integer") from None
        if n_ch > len(ch_names):
            raise FileFormatError(f"{path}: segment {segment}: header says {n_ch} channels, the "
                                  f"column-name line has {len(ch_names)}")
    else:
        n_ch = len([c for c in ch_names if c and c != "Comment"])
    ch_names = ch_names[:n_ch]

    def per_channel(key: str, j: int) -> str | None:
        values = seg_header.get(key)
        if values is None or j >= len(values) or values[j] == "":
            return None
        return values[j]

    transposed = list(itertools.zip_longest(*rows, fillvalue=""))

    def column(col: int, what: str) -> np.ndarray:
        texts = [t.strip() for t in transposed[col]] if col < len(transposed) else []
        last = len(texts)
        while last and texts[last - 1] == "":
            last -= 1
        for k in range(last):
            if texts[k] == "":
                raise FileFormatError(f"{path}: line {first_line + k + 1}: {what}: empty field "
                                      "followed by values")
        if decimal == ",":
            texts = [t.replace(",", ".") for t in texts]
        try:
            return np.array(texts[:last], dtype=np.float64)
        except ValueError:
            for k, t in enumerate(texts[:last]):
                try:
                    float(_number(t, decimal))
                except ValueError:
                    raise FileFormatError(f"{path}: line {first_line + k + 1}: {what}: {t!r} is "
                                          "not a number") from None
            raise

    if x_columns == "One":
        x_values[segment] = column(0, "column 'X_Value'")
    elif x_heading:
        x_col = column(0, "column 'X_Value'")
        if x_col.size:       # numbers under the heading after all: the X values
            x_values[segment] = x_col
    for j, name in enumerate(ch_names):
        col = (j + 1 if x_columns == "One" or x_heading
               else (2 * j + 1 if x_columns == "Multi" else j))
        values = column(col, f"column {name!r}")
        samples = per_channel("Samples", j)
        if samples is not None:
            try:
                n_declared = int(samples)
            except ValueError:
                raise FileFormatError(f"{path}: segment {segment} header 'Samples': {samples!r} "
                                      f"of column {name!r} is not an integer") from None
            if n_declared != values.size:
                raise FileFormatError(f"{path}: segment {segment}: column {name!r} has "
                                      f"{values.size} values, the header 'Samples' says {n_declared}")
        dx_text = per_channel("Delta_X", j)
        try:
            delta_x = Decimal(_number(dx_text, decimal)) if dx_text is not None else None
        except InvalidOperation:
            raise FileFormatError(f"{path}: segment {segment} header 'Delta_X': {dx_text!r} of "
                                  f"column {name!r} is not a number") from None
        x0_text = per_channel("X0", j)
        try:
            x0 = float(_number(x0_text, decimal)) if x0_text is not None else None
        except ValueError:
            raise FileFormatError(f"{path}: segment {segment} header 'X0': {x0_text!r} of column "
                                  f"{name!r} is not a number") from None
        channels.append(LvmChannel(
            name=name, segment=segment, column=j, values=values,
            unit_label=per_channel("Y_Unit_Label", j) or "",
            delta_x=delta_x, x0=x0, x_dimension=per_channel("X_Dimension", j) or "",
            date=per_channel("Date", j) or header.get("Date"),
            time=per_channel("Time", j) or header.get("Time")))


def iso_from_lvm(date: str | None, time: str | None) -> str | None:
    """``2023/05/05`` + ``13:39:50.88701993...`` -> ``2023-05-05T13:39:50.887019931`` (local time)."""
    if not date or not time:
        return None
    m = re.fullmatch(r"(\d{4})[/-](\d{2})[/-](\d{2})", date.strip())
    t = re.fullmatch(r"(\d{2}):(\d{2}):(\d{2})(?:[.,](\d+))?", time.strip())
    if not m or not t:
        return None
    frac = f".{t.group(4)[:9]}" if t.group(4) else ""
    return f"{m.group(1)}-{m.group(2)}-{m.group(3)}T{t.group(1)}:{t.group(2)}:{t.group(3)}{frac}"


class LvmBackend:
    """Columns of an LVM file, selected by name (``source``) or channel ``index``."""

    format = FORMAT

    def __init__(self, path: Path) -> None:
        self.lvm = parse_lvm(path)
        counts: dict[str, int] = {}
        for ch in self.lvm.channels:
            counts[ch.name] = counts.get(ch.name, 0) + 1
        self._labels = {id(ch): (ch.name if counts[ch.name] == 1 and ch.name
                                 else f"{ch.name or 'column'} (segment {ch.segment}, column {ch.column})")
                        for ch in self.lvm.channels}

    def _select(self, spec: Mapping[str, Any], where: str) -> list[LvmChannel]:
        chans = list(self.lvm.channels)
        if "segment" in spec:
            chans = [c for c in chans if c.segment == spec["segment"]]
            if not chans:
                raise MappingError(f"{where}: segment {spec['segment']!r}: the file has segments "
                                   f"0..{self.lvm.n_segments - 1}")
        if "source" in spec:
            chans = [c for c in chans if c.name == spec["source"]]
        elif "index" in spec:
            chans = [c for c in chans if c.column == spec["index"]]
        else:
            raise MappingError(f"{where}: missing key 'source' (the LVM column name) or 'index'")
        if not chans:
            names = sorted({c.name for c in self.lvm.channels})
            raise MappingError(f"{where}: no column {spec.get('source', spec.get('index'))!r} in "
                               f"{self.lvm.path.name} (has: {', '.join(names)})")
        if len({c.segment for c in chans}) != len(chans):
            raise MappingError(f"{where}: column name {chans[0].name!r} is not unique in a segment; "
                               "select it with 'index'")
        return chans

    def channel(self, spec: Mapping[str, Any],
                where: str) -> tuple[ArraySource, dict[str, Any], tuple[str, ...]]:
        chans = self._select(spec, where)
        first = chans[0]
        for prev, nxt in zip(chans, chans[1:]):
            if not _contiguous(prev, nxt):
                raise MappingError(
                    f"{where}: column {first.name!r} is in segments "
                    f"{', '.join(str(c.segment) for c in chans)}, which are not contiguous "
                    f"(segment {nxt.segment} starts at X0={nxt.x0}, expected "
                    f"{_expected_x0(prev)}): choose one with segment = k")
        values = np.concatenate([c.values for c in chans]) if len(chans) > 1 else first.values
        declared: dict[str, Any] = {}
        if first.delta_x is not None:
            if first.delta_x <= 0:
                raise FileFormatError(f"{self.lvm.path}: header 'Delta_X' of column "
                                      f"{first.name!r}: must be > 0, was {first.delta_x}")
            declared["sample_rate_hz"] = float(Decimal(1) / first.delta_x)
            declared["start_time_s"] = first.x0 if first.x0 is not None else 0.0
        unit = known_unit(first.unit_label)
        if unit is not None:
            declared["units"] = unit
        elif first.unit_label:
            declared["x_source_units"] = first.unit_label
        return ArrayData(values), declared, tuple(self._labels[id(c)] for c in chans)

    def timestamps(self, spec: Mapping[str, Any], where: str) -> tuple[ArraySource, tuple[str, ...]]:
        if spec.get("source") == "X_Value":
            seg = spec.get("segment", 0)
            if seg not in self.lvm.x_values:
                raise MappingError(f"{where}: no X_Value column in segment {seg!r} "
                                   f"(X_Columns is {self.lvm.x_columns})")
            return ArrayData(self.lvm.x_values[seg]), ()
        src, _, used = self.channel(spec, where)
        return src, used

    def run_defaults(self, used: tuple[str, ...]) -> dict[str, Any]:
        by_label = {self._labels[id(c)]: c for c in self.lvm.channels}
        first = next((by_label[u] for u in used if u in by_label), None)
        if first is None:
            return {}
        iso = iso_from_lvm(first.date, first.time)
        return {"start_time_iso": iso} if iso else {}

    def resolve(self, ref: Mapping[str, Any], where: str) -> Any:
        raise MappingError(f"{where}: references into the file ({{ source = ... }}) work for HDF5 "
                           "only; give the value")

    def inventory(self) -> list[tuple[str, str]]:
        out = []
        for c in self.lvm.channels:
            parts = [f"{c.values.size} samples"]
            if c.delta_x is not None:
                parts.append(f"Delta_X {c.delta_x}" + (f" ({c.x_dimension})" if c.x_dimension else ""))
            if c.unit_label:
                parts.append(f"unit {c.unit_label!r}")
            out.append((self._labels[id(c)], ", ".join(parts)))
        return out

    def close(self) -> None:
        return None


def _expected_x0(ch: LvmChannel) -> float | None:
    if ch.x0 is None or ch.delta_x is None:
        return None
    return ch.x0 + ch.values.size * float(ch.delta_x)


def _contiguous(a: LvmChannel, b: LvmChannel) -> bool:
    if a.delta_x != b.delta_x or a.unit_label != b.unit_label:
        return False
    expected = _expected_x0(a)
    if expected is None or b.x0 is None or a.delta_x is None:
        return expected is None and b.x0 is None
    return abs(b.x0 - expected) <= 0.5 * float(a.delta_x)


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read an LVM file through ``mapping`` (LVM files do not say what their columns measure)."""
    if mapping is None:
        lvm = parse_lvm(path)  # report format errors first
        raise FileFormatError(f"{path}: a LabVIEW .lvm file does not say which quantity each of its "
                              f"columns ({', '.join(c.name for c in lvm.channels)}) measures: pass "
                              "a mapping (--mapping FILE.toml)")
    return build_raw(path, mapping, LvmBackend(path))
