"""LabVIEW Measurement (``.lvm``) text files, read through a mapping.

Built to NI's published "Specification for the LabVIEW Measurement File (.lvm)" (LVM 1.0
and 2.0), not to examples.  What is honoured:

* file header (``LabVIEW Measurement`` ... ``***End_of_Header***``): ``Separator`` (Tab or
  Comma; Semicolon also read), ``Decimal_Separator`` (``.`` or ``,``; a comma with the Comma
  separator is refused, the fields could not be told apart), ``X_Columns`` (No, One or
  Multi), ``Multi_Headings`` (Yes or No), ``Time_Pref`` (Absolute: X0 and X values are
  seconds since 1904-01-01 00:00 UTC, time zero is the earliest X0 and the run starts at
  its channel's Date/Time stamp; Relative: seconds since the Date/Time stamps),
  ``Date``/``Time``; every other field the specification defines is kept and not used;
* one or more segments, each with its own header (``Channels``, ``Samples``,
  ``Y_Unit_Label``, ``X_Dimension``, ``X0``, ``Delta_X``, ``Date``, ``Time``; one value per
  channel), a column-name line and data rows.  Segments without a header (``Multi_Headings
  No``, or data resuming after a blank line) take the previous header; their start is the
  first value of their X column, or (without X columns) the sample after the previous
  segment's last.  With ``Multi_Headings No`` the rows after the header's ``Samples`` are
  such segments.  The trailing ``Comment`` column is ignored;
* the X columns: ``One`` (one X column first), ``Multi`` (an X column before every channel),
  ``No`` (none; LabVIEW still writes an empty first field on every row, under an
  ``X_Value`` heading or an empty one: that column is dropped, or kept as the X values when
  it holds numbers);
* each channel's timing comes from its own ``X0`` and ``Delta_X`` (the X column is printed
  with fewer digits), its unit from ``Y_Unit_Label``;
* ragged columns: a channel shorter than the others has empty fields at the end of its
  column; its value count must equal the header's ``Samples`` (per channel);
* header fields the specification does not define are reported with an
  :class:`LvmHeaderWarning` (kept in the parsed header, never used).

What is refused, in one line naming the file and the field (:class:`FileFormatError`): no
``LabVIEW Measurement`` line, no ``***End_of_Header***``, a separator other than Tab,
Comma or Semicolon, an unknown ``Decimal_Separator``, ``X_Columns``, ``Multi_Headings`` or
``Time_Pref``, data before any segment header, a field that is not a number, an empty field
followed by values, a value count other than ``Samples``, ``Channels`` above the number of
columns, and a ``Delta_X`` or ``X0`` that is not a number.

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
    #: ``X0`` as written (exact; with ``Time_Pref`` Absolute, seconds since 1904).
    x0_exact: Decimal | None = None


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
    multi_headings: str = "Yes"
    time_pref: str = "Relative"


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
        key = fields[0].strip()
        if key == "Decimal_Separator" and sep == "," and len(fields) > 2 and \
                not fields[1].strip() and not fields[2].strip():
            raise FileFormatError(f"{path}: line {i + 1}: header 'Decimal_Separator': ',' with "
                                  "'Separator' Comma: a number's comma and the field separator "
                                  "cannot be told apart")
        if key:
            header[key] = fields[1].strip() if len(fields) > 1 else ""
        i += 1
    if i >= len(lines):
        raise FileFormatError(f"{path}: file header has no '{END}' line")
    _warn_unknown(path, "file header", header, FILE_HEADER_FIELDS)
    i += 1
    decimal = header.get("Decimal_Separator", ".") or "."
    if decimal not in (".", ","):
        raise FileFormatError(f"{path}: header 'Decimal_Separator': {decimal!r} is not '.' or ','")
    x_columns = _choice(path, header, "X_Columns", ("No", "One", "Multi"), "One")
    multi_headings = _choice(path, header, "Multi_Headings", ("Yes", "No"), "Yes")
    time_pref = _choice(path, header, "Time_Pref", ("Absolute", "Relative"), "Relative")

    channels: list[LvmChannel] = []
    x_values: dict[int, np.ndarray] = {}
    seg_header: dict[str, list[str]] | None = None
    names: list[str] | None = None
    previous: list[LvmChannel] = []
    segment = -1
    n = len(lines)
    while i < n:
        fields = lines[i].split(sep)
        if not any(f.strip() for f in fields):
            i += 1
            continue
        headerless = _is_data(fields, decimal)
        if headerless:
            if seg_header is None or names is None:
                raise FileFormatError(f"{path}: line {i + 1}: data before any segment header")
            # Data resuming without a new header: a new segment with the previous header.
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
        start = i
        rows = []
        while i < n:
            f = lines[i].split(sep)
            if not _is_data(f, decimal):
                break
            rows.append(f)
            i += 1
        assert seg_header is not None and names is not None
        chunks = [(start, rows)]
        if multi_headings == "No" and not headerless:
            # one header for all writes: the rows after its Samples are the later writes
            n_first = _max_samples(seg_header)
            if n_first is not None and 0 < n_first < len(rows):
                chunks = [(start, rows[:n_first]), (start + n_first, rows[n_first:])]
        for k, (first_line, chunk) in enumerate(chunks):
            segment += 1
            previous = _segment(path, segment, seg_header, names, chunk, first_line, x_columns,
                                decimal, header, channels, x_values,
                                previous if (headerless or k > 0) else None)
    if not channels:
        raise FileFormatError(f"{path}: no data segment found")
    return LvmFile(path=path, header=header, separator=sep, decimal=decimal, x_columns=x_columns,
                   channels=tuple(channels), x_values=x_values, n_segments=segment + 1,
                   multi_headings=multi_headings, time_pref=time_pref)


def _choice(path: Path, header: Mapping[str, str], key: str, allowed: tuple[str, ...],
            default: str) -> str:
    value = header.get(key, default) or default
    if value not in allowed:
        raise FileFormatError(f"{path}: header {key!r}: {value!r} is not "
                              f"{', '.join(allowed[:-1])} or {allowed[-1]}")
    return value


def _max_samples(seg_header: Mapping[str, list[str]]) -> int | None:
    counts = []
    for v in seg_header.get("Samples", []):
        try:
            counts.append(int(v))
        except ValueError:
            continue
    return max(counts) if counts else None


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
             x_values: dict[int, np.ndarray],
             previous: list[LvmChannel] | None) -> list[LvmChannel]:
    """Add one segment's channels; ``previous``: the channels of the segment whose header a
    header-less segment continues (None for a segment with its own header)."""
    # X_Columns No: LabVIEW still writes an empty first field per row, under an X_Value or
    # an empty heading (the first field of the column-name line).
    x_heading = x_columns == "No" and len(names) > 1 and names[0] in ("X_Value", "")
    if x_columns == "One":
        ch_names = names[1:]
    elif x_columns == "Multi":
        ch_names = names[1::2]
    else:
        ch_names = names[1:] if x_heading else names
    declared = seg_header.get("Channels", [""])[0] if seg_header.get("Channels") else ""
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

    def first_x(col: int) -> Decimal | None:
        if col >= len(transposed):
            return None
        text = transposed[col][0].strip() if transposed[col] else ""
        return Decimal(_number(text, decimal)) if text else None

    if x_columns == "One":
        x_values[segment] = column(0, "column 'X_Value'")
    elif x_heading:
        x_col = column(0, "column 'X_Value'")
        if x_col.size:       # numbers under the heading after all: the X values
            x_values[segment] = x_col
    added: list[LvmChannel] = []
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
            if previous is None and n_declared != values.size:
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
            x0 = Decimal(_number(x0_text, decimal)) if x0_text is not None else None
            if x0 is not None and not x0.is_finite():
                raise InvalidOperation
        except InvalidOperation:
            raise FileFormatError(f"{path}: segment {segment} header 'X0': {x0_text!r} of column "
                                  f"{name!r} is not a number") from None
        if previous is not None:
            # a segment without a header starts where its X column says, or (no X column)
            # after the previous segment's last sample
            x_index = (2 * j if x_columns == "Multi"
                       else 0 if x_columns == "One" and j == 0 else None)   # One: channel 0's
            try:
                x0 = first_x(x_index) if x_index is not None else None
            except InvalidOperation:
                x0 = None    # reported by column() on the X column
            if x0 is None:
                prev = next((c for c in previous if c.column == j), None)
                x0 = (prev.x0_exact + prev.values.size * prev.delta_x
                      if prev is not None and prev.x0_exact is not None
                      and prev.delta_x is not None else None)
        ch = LvmChannel(
            name=name, segment=segment, column=j, values=values,
            unit_label=per_channel("Y_Unit_Label", j) or "",
            delta_x=delta_x, x0=float(x0) if x0 is not None else None,
            x_dimension=per_channel("X_Dimension", j) or "",
            date=per_channel("Date", j) or header.get("Date"),
            time=per_channel("Time", j) or header.get("Time"), x0_exact=x0)
        channels.append(ch)
        added.append(ch)
    return added


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
            declared["start_time_s"] = self._start_s(first)
        unit = known_unit(first.unit_label)
        if unit is not None:
            declared["units"] = unit
        elif first.unit_label:
            declared["x_source_units"] = first.unit_label
        return ArrayData(values), declared, tuple(self._labels[id(c)] for c in chans)

    def _t_ref(self) -> Decimal | None:
        """Time_Pref Absolute: the earliest X0 of the file (seconds since 1904), time zero."""
        starts = [c.x0_exact for c in self.lvm.channels if c.x0_exact is not None]
        return min(starts) if starts else None

    def _start_s(self, ch: LvmChannel) -> float:
        """The channel's ``start_time_s``: X0 (Relative: seconds since the Date/Time stamps),
        or X0 less the file's earliest X0 (Absolute: seconds since 1904; the run's
        ``start_time_iso`` is then the Date/Time stamp of the channel with that X0)."""
        if ch.x0_exact is None:
            return 0.0
        if self.lvm.time_pref == "Absolute":
            ref = self._t_ref()
            assert ref is not None
            return float(ch.x0_exact - ref)
        return float(ch.x0_exact)

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
        ref = self._t_ref()
        if self.lvm.time_pref == "Absolute" and ref is not None:
            # time zero is the file's earliest X0: its channel's Date/Time stamp
            first = next(c for c in self.lvm.channels if c.x0_exact == ref)
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
    if ch.x0_exact is None or ch.delta_x is None:
        return None
    return float(ch.x0_exact + ch.values.size * ch.delta_x)


def _contiguous(a: LvmChannel, b: LvmChannel) -> bool:
    if a.delta_x != b.delta_x or a.unit_label != b.unit_label:
        return False
    if a.x0_exact is None or a.delta_x is None or b.x0_exact is None:
        return a.x0_exact is None and b.x0_exact is None
    expected = a.x0_exact + a.values.size * a.delta_x
    return abs(b.x0_exact - expected) <= a.delta_x / 2


def load(path: Path, mapping: MappingSpec | None) -> RawRecord:
    """Read an LVM file through ``mapping`` (LVM files do not say what their columns measure)."""
    if mapping is None:
        lvm = parse_lvm(path)  # report format errors first
        raise FileFormatError(f"{path}: a LabVIEW .lvm file does not say which quantity each of its "
                              f"columns ({', '.join(c.name for c in lvm.channels)}) measures: pass "
                              "a mapping (--mapping FILE.toml)")
    return build_raw(path, mapping, LvmBackend(path))
