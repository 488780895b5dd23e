"""Issue 28, item 4: the LVM reader against NI's published LVM specification, not examples.

A generator (plain Python writing text as the "Specification for the LabVIEW Measurement
File (.lvm)" lays it out: file header, segments with their own headers or none, X columns
No/One/Multi, per-channel Samples/X0/Delta_X, Tab or Comma separators, decimal point or
comma, Time_Pref Absolute (seconds since 1904-01-01 UTC) or Relative) writes the same two
channels in every variant; every variant must read to the same numbers.  The values are
written with six decimals, and the expected numbers are those six-decimal texts read by
``float`` (so the comparison is exact: a reader that lost or shifted one value fails).
"""

from __future__ import annotations

import itertools
import re
from decimal import Decimal
from pathlib import Path

import numpy as np
import pytest

from rattle_lab.exceptions import FileFormatError
from rattle_lab.records import read
from rattle_lab.records._readers.lvm import LvmHeaderWarning, parse_lvm
from conftest import realdata

# two channels of unequal length and rate per segment (ragged columns), two writes
A_PER_SEG, B_PER_SEG = 6, 3
DX = {"a": Decimal("0.001"), "b": Decimal("0.002")}
#: Relative: X0 of each channel's first sample; Absolute adds T_ABS (seconds since 1904).
X0 = {"a": Decimal("0.5"), "b": Decimal("0.75")}
T_ABS = Decimal("3786912000")          # 2024-01-01T00:00:00 UTC in LabVIEW seconds
rng = np.random.default_rng(28)
VALUES = {"a": rng.normal(0.0, 3.0, 2 * A_PER_SEG), "b": rng.normal(0.0, 0.5, 2 * B_PER_SEG)}


def _text(v: float | Decimal, decimal: str, fmt: str = ".6f") -> str:
    return format(v, fmt).replace(".", decimal)


def _stamp(seconds: Decimal | int) -> str:
    return "00:00:00" + (f".{str(seconds).split('.')[1]}" if seconds else "")


def write_lvm(path: Path, *, sep: str = "\t", decimal: str = ".", x_columns: str = "One",
              x_heading: str | None = "X_Value", multi_headings: str = "Yes",
              blank_between: bool = True, time_pref: str = "Relative",
              crlf: bool = False) -> None:
    """Write the two channels (two segments) as an LVM file per the specification.

    ``x_heading`` (X_Columns No only): the heading of the empty first column LabVIEW
    writes ("X_Value" or ""), or None for no such column.  ``multi_headings="No"``: the
    second write has no header, after a blank line when ``blank_between``.
    """
    offset = T_ABS if time_pref == "Absolute" else Decimal(0)
    lines = ["LabVIEW Measurement" + sep, f"Writer_Version{sep}2", f"Reader_Version{sep}2",
             f"Separator{sep}{'Tab' if sep == chr(9) else 'Comma'}",
             f"Decimal_Separator{sep}{decimal}", f"Multi_Headings{sep}{multi_headings}",
             f"X_Columns{sep}{x_columns}", f"Time_Pref{sep}{time_pref}",
             f"Operator{sep}someone", f"Description{sep}generated per the LVM specification",
             f"Project{sep}issue 28", f"Date{sep}2024/01/01", f"Time{sep}00:00:00",
             f"***End_of_Header***{sep}", ""]
    names = ["a", "b"]
    for seg in range(2):
        n = {"a": A_PER_SEG, "b": B_PER_SEG}
        x0 = {c: offset + X0[c] + seg * n[c] * DX[c] for c in names}
        vals = {c: VALUES[c][seg * n[c]:(seg + 1) * n[c]] for c in names}
        if seg == 0 or multi_headings == "Yes":
            if seg:
                lines.append("")
            lines += [sep.join(["Channels", "2"] + [""] * 2),
                      sep.join(["Samples", str(n["a"]), str(n["b"]), ""]),
                      sep.join(["Date", "2024/01/01", "2024/01/01", ""]),
                      # Absolute: each channel's stamp is the time of its X0 (UTC here)
                      sep.join(["Time"] + [_stamp(x0[c] - offset if offset else 0) for c in names]
                               + [""]),
                      sep.join(["Y_Unit_Label", "m/s^2", "V", ""]),
                      sep.join(["X_Dimension", "Time", "Time", ""]),
                      sep.join(["X0"] + [_text(x0[c], decimal, ".16E") for c in names] + [""]),
                      sep.join(["Delta_X"] + [_text(DX[c], decimal, "f") for c in names] + [""]),
                      sep.join(["***End_of_Header***", "", "", ""])]
            if x_columns == "One":
                heading = ["X_Value", "a", "b"]
            elif x_columns == "Multi":
                heading = ["X_Value", "a", "X_Value", "b"]
            else:
                heading = ([] if x_heading is None else [x_heading]) + ["a", "b"]
            lines.append(sep.join(heading + ["Comment"]))
        elif blank_between:
            lines.append("")
        for r in range(max(n.values())):
            fields = []
            for j, c in enumerate(names):
                have = r < n[c]
                x = _text(x0[c] + r * DX[c], decimal) if have else ""
                y = _text(vals[c][r], decimal) if have else ""
                if x_columns == "Multi":
                    fields += [x, y]
                elif x_columns == "One":
                    fields += ([x] if j == 0 else []) + [y]
                else:
                    fields += ([""] if j == 0 and x_heading is not None else []) + [y]
            lines.append(sep.join(fields))
    eol = "\r\n" if crlf else "\n"
    path.write_bytes((eol.join(lines) + eol).encode("utf-8"))


MAPPING = """
[mapping]
version = 1
format = "lvm"
[campaign]
campaign_id = "gen"
[rig]
apparatus = "other"
description = "LVM generator"
[[runs]]
run_id = "r"
protocol = "transient"
[[runs.channels]]
name = "a"
source = "a"
quantity = "base_acceleration"
[[runs.channels]]
name = "b"
source = "b"
quantity = "drive_signal"
"""

X_LAYOUTS = [("No", "X_Value"), ("No", ""), ("No", None), ("One", "X_Value"), ("Multi", "X_Value")]
WRITES = [("Yes", True), ("No", True), ("No", False)]
FORMATS = [("\t", "."), ("\t", ","), (",", ".")]
VARIANTS = [pytest.param(*fmt, *xl, *wr, tp, id=f"{'tab' if fmt[0] == chr(9) else 'comma'}-"
                         f"dec{fmt[1]}-X{xl[0]}{'' if xl[0] != 'No' else repr(xl[1])}-"
                         f"MH{wr[0]}{'' if wr[0] == 'Yes' else ('-blank' if wr[1] else '-direct')}"
                         f"-{tp}")
            for fmt, xl, wr, tp in itertools.product(FORMATS, X_LAYOUTS, WRITES,
                                                     ("Relative", "Absolute"))]


def test_the_absolute_offset_is_2024_in_labview_seconds():
    from datetime import UTC, datetime
    since = datetime(2024, 1, 1, tzinfo=UTC) - datetime(1904, 1, 1, tzinfo=UTC)
    assert Decimal(int(since.total_seconds())) == T_ABS     # 43830 days


def _expected(c: str) -> np.ndarray:
    return np.array([float(f"{v:.6f}") for v in VALUES[c]])


@pytest.mark.parametrize(("sep", "decimal", "x_columns", "x_heading", "multi_headings",
                          "blank_between", "time_pref"), VARIANTS)
def test_every_lvm_variant_reads_to_the_same_numbers(tmp_path, sep, decimal, x_columns,
                                                     x_heading, multi_headings, blank_between,
                                                     time_pref):
    path = tmp_path / "gen.lvm"
    write_lvm(path, sep=sep, decimal=decimal, x_columns=x_columns, x_heading=x_heading,
              multi_headings=multi_headings, blank_between=blank_between, time_pref=time_pref,
              crlf=sep == ",")
    lvm = parse_lvm(path)
    assert lvm.n_segments == 2 and lvm.time_pref == time_pref
    assert [c.name for c in lvm.channels] == ["a", "b", "a", "b"]
    toml = tmp_path / "m.toml"
    toml.write_text(MAPPING)
    with read(path, mapping=toml) as rec:
        run = rec.run("r")
        a, b = run.channel("a"), run.channel("b")
        np.testing.assert_array_equal(a.read(), _expected("a"))
        np.testing.assert_array_equal(b.read(), _expected("b"))
        assert (a.sample_rate_hz, b.sample_rate_hz) == (1000.0, 500.0)
        assert (a.units, b.units) == ("m/s^2", "V")
        if time_pref == "Relative":      # seconds since the Date/Time stamps
            assert (a.start_time_s, b.start_time_s) == (0.5, 0.75)
            assert run.start_time_iso == "2024-01-01T00:00:00"
        else:    # time zero: the earliest X0, at its channel's Date/Time stamp
            assert (a.start_time_s, b.start_time_s) == (0.0, 0.25)
            assert run.start_time_iso == "2024-01-01T00:00:00.500"


def test_undefined_header_fields_are_warned_about_and_not_used(tmp_path):
    path = tmp_path / "gen.lvm"
    write_lvm(path)
    text = path.read_text().replace("Project\tissue 28", "Projekt\tissue 28")
    path.write_text(text)
    with pytest.warns(LvmHeaderWarning, match=r"file header: field 'Projekt' not defined by"):
        lvm = parse_lvm(path)
    np.testing.assert_array_equal(lvm.channels[0].values, _expected("a")[:A_PER_SEG])


# --- the exact failure of issue 28 ------------------------------------------------------------

def test_column_name_row_starting_with_an_empty_field_reads_like_x_value(tmp_path):
    """Issue 28: a file of the forced-shock dataset whose column-name row starts with an empty
    field instead of ``X_Value`` was refused (``column '' has 0 values, the header 'Samples'
    says 12376``).  The same file with either heading must read to the same channels.
    Source: High-Rate-SHM-Working-Group/Dataset-7-forced-vibration-and-shock (CC BY-SA 4.0),
    see shared/realdata/README.md; read in place, the variant is written to tmp_path."""
    original = realdata("forced_shock/vibration_0.2.lvm")
    raw = original.read_bytes()
    assert raw.count(b"\nX_Value,time,") == 1
    copy = tmp_path / "vibration_0.2.lvm"
    copy.write_bytes(raw.replace(b"\nX_Value,time,", b"\n,time,"))
    empty, named = parse_lvm(copy), parse_lvm(original)
    assert [c.name for c in empty.channels] == [c.name for c in named.channels] == [
        "time", "excitation_vibration", "excitation_shock", "excitation_composite",
        "accelerometer_base", "accelerometer_board"]
    assert [c.values.size for c in empty.channels] == [12376, 13216, 13216, 12375, 12375, 12375]
    for e, n in zip(empty.channels, named.channels):
        np.testing.assert_array_equal(e.values, n.values)
        assert (e.delta_x, e.x0) == (n.delta_x, n.x0)


# --- what is refused, in one line naming the file and the field ------------------------------

HEAD = "LabVIEW Measurement\t\nSeparator\tTab\n"


@pytest.mark.parametrize(("text", "match"), [
    ("LabVIEW Measurement,\nSeparator,Comma\nDecimal_Separator,,\n***End_of_Header***,\n",
     r"bad\.lvm: line 3: header 'Decimal_Separator': ',' with 'Separator' Comma"),
    (HEAD + "Multi_Headings\tMaybe\n***End_of_Header***\n",
     r"bad\.lvm: header 'Multi_Headings': 'Maybe' is not Yes or No"),
    (HEAD + "Time_Pref\tLocal\n***End_of_Header***\n",
     r"bad\.lvm: header 'Time_Pref': 'Local' is not Absolute or Relative"),
    (HEAD + "X_Columns\tBoth\n***End_of_Header***\n",
     r"bad\.lvm: header 'X_Columns': 'Both' is not No, One or Multi"),
    (HEAD + "X_Columns\tNo\n***End_of_Header***\nChannels\t1\t\nSamples\t3\t\n"
     "***End_of_Header***\t\t\n\ta\tComment\n\t1\n\t2\n",
     r"bad\.lvm: segment 0: column 'a' has 2 values, the header 'Samples' says 3"),
])
def test_lvm_refusals_name_the_file_and_the_field(tmp_path, text, match):
    path = tmp_path / "bad.lvm"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=match) as info:
        parse_lvm(path)
    assert "\n" not in str(info.value)


def test_multi_headings_no_without_x_columns_assumes_the_writes_follow_on(tmp_path):
    """A header-less write with no X column has no time of its own: it follows the previous
    write's last sample (what the specification's one-header layout implies)."""
    path = tmp_path / "gen.lvm"
    write_lvm(path, x_columns="No", x_heading=None, multi_headings="No", blank_between=False)
    lvm = parse_lvm(path)
    a0, b0, a1, b1 = lvm.channels
    assert a1.x0_exact == X0["a"] + A_PER_SEG * DX["a"]
    assert b1.x0_exact == X0["b"] + B_PER_SEG * DX["b"]
    # with X columns the write's own X values give its start (here the same)
    write_lvm(path, x_columns="Multi", multi_headings="No", blank_between=False)
    a1m, b1m = parse_lvm(path).channels[2:]
    assert (a1m.x0_exact, b1m.x0_exact) == (a1.x0_exact, b1.x0_exact)


def test_lvm_x_columns_multi_keeps_each_channels_x(tmp_path):
    path = tmp_path / "gen.lvm"
    write_lvm(path, x_columns="Multi")
    assert re.search(r"X_Value\ta\tX_Value\tb\tComment", path.read_text())
    lvm = parse_lvm(path)
    np.testing.assert_array_equal(lvm.channels[1].values, _expected("b")[:B_PER_SEG])
