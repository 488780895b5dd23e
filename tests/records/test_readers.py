"""Readers behind ``read()``: MATLAB v7.3 / foreign HDF5, LVM, TDMS, WAV and NPY, through mappings."""

from __future__ import annotations

import os
from pathlib import Path

import h5py
import numpy as np
import pytest
import soundfile
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter
from record_factory import write

from rattle_lab.exceptions import FileFormatError, SchemaError
from rattle_lab.store import ingest, read_catalogue
from rattle_lab.records import (DuplicateRunError, MappingError, NaNGapError, detect_format,
                                load_mapping, read)
from rattle_lab.records._readers.lvm import iso_from_lvm, parse_lvm

# --- MATLAB v7.3 and other HDF5 layouts ----------------------------------------------------------

N_MAT = 2000
MAT_HEADER = (b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Fri Mar  1 14:05:00 2024 "
              b"HDF5 schema 1.00 .")


def _matlab_class(ds: h5py.HLObject, cls: str) -> None:
    ds.attrs["MATLAB_class"] = np.bytes_(cls.encode())


def make_mat(path: Path) -> dict[str, np.ndarray]:
    """A file laid out as MATLAB v7.3 writes one: 512-byte user block, MATLAB_class attributes,
    column-major arrays (an N x 1 vector is stored with h5py shape (1, N), an N x 3 matrix as (3, N)),
    a struct as a group, text as uint16 'char' arrays."""
    rng = np.random.default_rng(7)
    signals = {k: rng.standard_normal(N_MAT) for k in ("acc", "mic", "d0", "d1", "d2")}
    with h5py.File(path, "w", userblock_size=512) as fh:
        _matlab_class(fh.create_dataset("acc", data=signals["acc"][None, :]), "double")   # N x 1
        _matlab_class(fh.create_dataset("mic", data=signals["mic"][:, None]), "double")   # 1 x N
        _matlab_class(fh.create_dataset("data", data=np.vstack([signals["d0"], signals["d1"],
                                                                  signals["d2"]])), "double")
        meta = fh.create_group("meta")
        _matlab_class(meta, "struct")
        _matlab_class(meta.create_dataset("fs", data=np.array([[25600.0]])), "double")
        op = meta.create_dataset("operator", data=np.array([[ord(c)] for c in "Ana"], dtype=np.uint16))
        _matlab_class(op, "char")
        op.attrs["MATLAB_int_decode"] = np.int32(2)
    with open(path, "r+b") as fh:
        fh.write(MAT_HEADER.ljust(116) + b"\x00" * 8 + b"\x00\x02IM")
    return signals


MAT_MAPPING = """
[mapping]
version = 1
format = "hdf5"

[campaign]
campaign_id = "mat-{stem}"
operator = { source = "/meta/operator" }

[rig]
apparatus = "plate_striker"
plate_length_m = 0.254
plate_width_m = 0.2286
plate_thickness_m = 0.00096
plate_material = "aluminium"
edge_conditions = "CFCF"
striker_x_m = 0.127
striker_y_m = 0.1143
mic_distance_m = 0.3
sensors = [{ sensor_id = "mic", position_m = [0.127, 0.1143, 0.3], mounted_on = "stand" }]

[[runs]]
run_id = "dwell_094"
protocol = "sine_dwell"
excitation_freq_hz = 94.0
nominal_level = 2.0
nominal_level_units = "m/s^2"
start_time_iso = "2024-03-01T14:05:00"

[[runs.channels]]
name = "base"
source = "/acc"
quantity = "base_acceleration"
units = "g"
sample_rate_hz = { source = "/meta/fs" }
start_time_s = 0.0

[[runs.channels]]
name = "mic"
source = "/mic"
quantity = "sound_pressure"
units = "V"
sensitivity = 50.0
sensitivity_units = "mV/Pa"
sensor_id = "mic"
sample_rate_hz = { source = "/meta/fs" }
start_time_s = 0.0

[[runs.channels]]
name = "drive"
source = "/data"
index = 1
quantity = "drive_signal"
units = "V"
sample_rate_hz = { source = "/meta/fs" }
start_time_s = 0.0
"""


def test_matlab_v73_file_through_a_mapping(tmp_path):
    mat = tmp_path / "lab_042.mat"
    signals = make_mat(mat)
    mapping = tmp_path / "mat.toml"
    mapping.write_text(MAT_MAPPING)
    assert detect_format(mat) == "hdf5"
    with read(mat, mapping=mapping) as rec:
        assert rec.campaign_id == "mat-lab_042" and rec.operator == "Ana"
        # a mapping's edge_conditions are in the plate model's EDGE_ORDER (issue 28)
        assert rec.rig.edge_conditions == "CFCF"
        run = rec.run("dwell_094")
        base, mic, drive = run.channels
        assert base.sample_rate_hz == 25600.0 and base.n_samples == N_MAT
        np.testing.assert_array_equal(base.read(si=False), signals["acc"])
        np.testing.assert_allclose(base.read(), signals["acc"] * 9.80665, rtol=1e-15)
        np.testing.assert_allclose(mic.read(), signals["mic"] / 0.05, rtol=1e-15)
        np.testing.assert_array_equal(drive.read(100, 200), signals["d1"][100:200])
        assert rec.origin is not None and rec.origin.format == "hdf5"
        assert rec.origin.skipped == ()  # /data is used (row 1); /meta/* were read as metadata


def test_matlab_file_ingests_read_only_and_unchanged(tmp_path):
    mat = tmp_path / "lab_042.mat"
    make_mat(mat)
    os.chmod(mat, 0o444)
    mapping = tmp_path / "mat.toml"
    mapping.write_text(MAT_MAPPING)
    before = (mat.stat().st_mtime_ns, mat.read_bytes())
    report = ingest([mat], tmp_path / "store.h5", mapping=mapping)
    assert (mat.stat().st_mtime_ns, mat.read_bytes()) == before
    assert report.inputs[0].format == "hdf5"
    cat = read_catalogue(tmp_path / "store.h5")
    assert list(cat["units"]) == ["m/s^2", "Pa", "V"] and set(cat["format"]) == {"hdf5"}


def test_unused_hdf5_datasets_are_reported_as_skipped(tmp_path):
    mat = tmp_path / "lab.mat"
    make_mat(mat)
    mapping = tmp_path / "m.toml"
    mapping.write_text(MAT_MAPPING.replace('operator = { source = "/meta/operator" }\n', ""))
    with read(mat, mapping=mapping) as rec:
        assert [(s.source, s.reason) for s in rec.origin.skipped] == [
            ("/meta/operator", "not in the mapping (dataset (3, 1) uint16)")]


@pytest.mark.parametrize(("edit", "cls", "match"), [
    (lambda m: m.replace('source = "/acc"', 'source = "/nope"'), MappingError,
     r"m\.toml: runs\[0\]\.channels\[0\]: source '/nope': no such dataset in"),
    (lambda m: m.replace('index = 1', 'index = 3'), SchemaError,
     r"/data: dataset 'shape': cannot take index 3 along axis 0 of shape \(3, 2000\)"),
    (lambda m: m.replace('{ source = "/meta/operator" }', '{ source = "/meta/fs", atr = "x" }'),
     MappingError, r"\[campaign\]\.operator: a reference is"),
    (lambda m: m.replace('format = "hdf5"', 'format = "lvm"'), FileFormatError,
     r"the mapping .*m\.toml is for format 'lvm', but the file is 'hdf5'"),
    (lambda m: m.replace('version = 1', 'version = 2'), MappingError,
     r"m\.toml: \[mapping\]: version 2 is not supported"),
    (lambda m: m.replace('run_id = "dwell_094"', 'run_id = "dwell_094"\nrun_idd = 1'), MappingError,
     r"m\.toml: runs\[0\]: unknown key 'run_idd'"),
    (lambda m: m + '\n[[runs]]\nrun_id = "dwell_094"\nprotocol = "transient"\n', DuplicateRunError,
     r"m\.toml: runs\[1\]: duplicated run_id 'dwell_094' \(also runs\[0\]\)"),
    (lambda m: m.replace("[campaign]", "[campaign\n"), MappingError, r"m\.toml: not a valid TOML mapping"),
])
def test_mapping_errors_name_the_mapping_and_the_key(tmp_path, edit, cls, match):
    mat = tmp_path / "lab.mat"
    make_mat(mat)
    mapping = tmp_path / "m.toml"
    mapping.write_text(edit(MAT_MAPPING))
    with pytest.raises(cls, match=match):
        read(mat, mapping=mapping)


def test_a_native_record_ignores_a_mapping_given_for_other_inputs(tmp_path):
    native = write(tmp_path)
    mapping = tmp_path / "m.toml"
    mapping.write_text(MAT_MAPPING)
    with read(native, mapping=mapping) as rec:
        assert rec.campaign_id == "plate96" and rec.origin.format == "rattle_hdf5"


# --- LabVIEW .lvm ----------------------------------------------------------------------------------

LVM_TWO_SEGMENTS = "\n".join([
    "LabVIEW Measurement\t",
    "Writer_Version\t2",
    "Separator\tTab",
    "Decimal_Separator\t,",
    "Multi_Headings\tYes",
    "X_Columns\tNo",
    "Date\t2024/03/01",
    "Time\t14:05:00,25",
    "***End_of_Header***\t",
    "",
    "Channels\t2\t\t",
    "Samples\t4\t2\t",
    "Date\t2024/03/01\t2024/03/01\t",
    "Time\t14:05:00,25\t14:05:00,25\t",
    "Y_Unit_Label\tm/s^2\tVolts\t",
    "X_Dimension\tTime\tTime\t",
    "X0\t0,0000000000000000E+0\t0,0000000000000000E+0\t",
    "Delta_X\t0,001\t0,002\t",
    "***End_of_Header***\t\t\t",
    "acc\tdrive\tComment",
    "1,5\t0,25",
    "-2,5\t0,5",
    "3,0\t",
    "4,0\t",
    "",
    "Channels\t2\t\t",
    "Samples\t2\t1\t",
    "Y_Unit_Label\tm/s^2\tVolts\t",
    "X_Dimension\tTime\tTime\t",
    "X0\t4,0000000000000000E-3\t{x0}\t",
    "Delta_X\t0,001\t0,002\t",
    "***End_of_Header***\t\t\t",
    "acc\tdrive\tComment",
    "5,0\t0,75",
    "6,0\t",
    "",
])

LVM_MAPPING = """
[mapping]
version = 1
format = "lvm"
[campaign]
campaign_id = "lvm-{stem}"
[rig]
apparatus = "other"
description = "LVM test"
[[runs]]
run_id = "shock"
protocol = "transient"
[[runs.channels]]
name = "acc"
source = "acc"
quantity = "base_acceleration"
[[runs.channels]]
name = "drive"
source = "drive"
quantity = "drive_signal"
units = "V"
"""


def _lvm(tmp_path: Path, x0: str = "4,0000000000000000E-3", mapping: str = LVM_MAPPING):
    path = tmp_path / "seg.lvm"
    path.write_text(LVM_TWO_SEGMENTS.format(x0=x0), encoding="utf-8")
    toml = tmp_path / "lvm.toml"
    toml.write_text(mapping)
    return path, toml


def test_lvm_parser_honours_separator_decimal_comma_and_per_channel_delta_x(tmp_path):
    path, _ = _lvm(tmp_path)
    lvm = parse_lvm(path)
    assert (lvm.separator, lvm.decimal, lvm.x_columns, lvm.n_segments) == ("\t", ",", "No", 2)
    acc0, drive0, acc1, drive1 = lvm.channels
    np.testing.assert_array_equal(acc0.values, [1.5, -2.5, 3.0, 4.0])
    np.testing.assert_array_equal(drive0.values, [0.25, 0.5])
    assert (str(acc0.delta_x), str(drive0.delta_x)) == ("0.001", "0.002")
    assert acc1.x0 == 0.004 and drive1.values.tolist() == [0.75]
    assert drive0.unit_label == "Volts"


def test_lvm_contiguous_segments_are_concatenated(tmp_path):
    path, toml = _lvm(tmp_path)
    with read(path, mapping=toml) as rec:
        run = rec.run("shock")
        acc, drive = run.channels
        np.testing.assert_array_equal(acc.read(), [1.5, -2.5, 3.0, 4.0, 5.0, 6.0])
        assert acc.sample_rate_hz == 1000.0 and drive.sample_rate_hz == 500.0
        assert acc.units == "m/s^2" and drive.extra == {"x_source_units": "Volts"}
        np.testing.assert_array_equal(drive.read(), [0.25, 0.5, 0.75])
        assert run.start_time_iso == "2024-03-01T14:05:00.25"


def test_lvm_non_contiguous_segments_need_a_choice(tmp_path):
    path, toml = _lvm(tmp_path, x0="1,0")
    with pytest.raises(MappingError, match=r"lvm\.toml: runs\[0\]\.channels\[1\]: column 'drive' is in "
                                           r"segments 0, 1, which are not contiguous \(segment 1 "
                                           r"starts at X0=1\.0, expected 0\.004\): choose one"):
        read(path, mapping=toml)
    chosen = LVM_MAPPING.replace('source = "drive"', 'source = "drive"\nsegment = 0')
    path, toml = _lvm(tmp_path, x0="1,0", mapping=chosen)
    with read(path, mapping=toml) as rec:
        np.testing.assert_array_equal(rec.run("shock").channel("drive").read(), [0.25, 0.5])


def test_lvm_mapping_must_give_units_the_file_does_not_state(tmp_path):
    path, toml = _lvm(tmp_path, mapping=LVM_MAPPING.replace('units = "V"\n', ""))
    with pytest.raises(SchemaError, match=r"seg\.lvm: /runs/shock/channels/drive: missing attribute 'units'"):
        read(path, mapping=toml)


@pytest.mark.parametrize(("text", "match"), [
    ("LabVIEW Measurement\nSeparator\tPipe\n***End_of_Header***\n",
     r"header 'Separator': 'Pipe' is not Tab, Comma or Semicolon"),
    ("LabVIEW Measurement\nSeparator\tTab\n", r"file header has no '\*\*\*End_of_Header\*\*\*' line"),
    ("LabVIEW Measurement\nSeparator\tTab\nX_Columns\tOne\n***End_of_Header***\n\nChannels\t1\n"
     "Samples\t3\n***End_of_Header***\nX_Value\ta\n0\t1\n1\t\n2\t3\n",
     r"line 11: column 'a': empty field followed by values"),
    ("LabVIEW Measurement\nSeparator\tTab\nX_Columns\tOne\n***End_of_Header***\n\nChannels\t1\n"
     "***End_of_Header***\nX_Value\ta\n0\t1\n1\tx1\n",
     r"line 10: column 'a': 'x1' is not a number"),
    ("time,acc\n0,1\n", r"line 1: not a LabVIEW \.lvm file with a header"),
])
def test_lvm_format_errors(tmp_path, text, match):
    path = tmp_path / "bad.lvm"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=match):
        parse_lvm(path)


def test_lvm_iso_time():
    assert iso_from_lvm("2023/05/05", "13:39:50.8870199312495426037") == "2023-05-05T13:39:50.887019931"
    assert iso_from_lvm("05.05.2023", "13:39") is None


# --- TDMS ------------------------------------------------------------------------------------------


def make_tdms(path: Path, with_quantity: bool = True) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    base, mic = rng.standard_normal(3000), rng.standard_normal(3000).astype(np.float32)
    q = (lambda name: {"quantity": name}) if with_quantity else (lambda name: {})
    with TdmsWriter(path) as writer:
        writer.write_segment([
            RootObject({"title": "tdms test"}),
            GroupObject("run1", properties={"protocol": "transient"}),
            ChannelObject("run1", "base", base[:1000], properties={
                "wf_increment": 1 / 51200, "wf_start_offset": 0.0, "unit_string": "m/s^2",
                "wf_start_time": np.datetime64("2024-03-01T14:05:00"), **q("base_acceleration")}),
            ChannelObject("run1", "mic", mic[:1000], properties={
                "wf_increment": 1 / 51200, "wf_start_offset": 0.0, "unit_string": "Pa",
                **q("sound_pressure")}),
        ])
        writer.write_segment([ChannelObject("run1", "base", base[1000:]),
                              ChannelObject("run1", "mic", mic[1000:])])
    return base, mic


def test_tdms_with_quantity_properties_reads_without_a_mapping(tmp_path):
    path = tmp_path / "rig.tdms"
    base, mic = make_tdms(path)
    assert detect_format(path) == "tdms"
    with read(path) as rec:
        run = rec.run("run1")
        assert run.protocol == "transient" and run.start_time_iso == "2024-03-01T14:05:00.000000000Z"
        ch_base, ch_mic = run.channels
        assert ch_base.sample_rate_hz == pytest.approx(51200.0, rel=1e-12)
        assert (ch_base.units, ch_mic.units, ch_mic.n_samples) == ("m/s^2", "Pa", 3000)
        # Chunks that cross the segment boundary at 1000.
        np.testing.assert_array_equal(np.concatenate([c for _, c in ch_base.iter_chunks(700)]), base)
        np.testing.assert_array_equal(ch_mic.read(900, 1100), mic[900:1100])


def test_tdms_without_quantities_needs_a_mapping(tmp_path):
    path = tmp_path / "rig.tdms"
    make_tdms(path, with_quantity=False)
    with pytest.raises(FileFormatError, match=r"rig\.tdms: channel run1/base has no 'quantity' property"):
        read(path)
    mapping = {
        "mapping": {"version": 1, "format": "tdms"}, "campaign": {"campaign_id": "t"},
        "rig": {"apparatus": "other", "description": "x"},
        "runs": [{"run_id": "r", "protocol": "transient", "channels": [
            {"name": "mic", "source": "run1/mic", "quantity": "sound_pressure", "units": "V",
             "sensitivity": 50.0, "sensitivity_units": "mV/Pa"}]}],
    }
    with pytest.raises(MappingError, match=r"<mapping>: runs\[0\]\.channels\[0\]: key 'units': the "
                                           r"mapping says 'V' but run1/mic says 'Pa'"):
        read(path, mapping=mapping)
    mapping["runs"][0]["channels"][0].update(units="Pa")
    del mapping["runs"][0]["channels"][0]["sensitivity"], mapping["runs"][0]["channels"][0]["sensitivity_units"]
    with read(path, mapping=mapping) as rec:
        assert [s.source for s in rec.origin.skipped] == ["run1/base"]


# --- WAV and NPY -----------------------------------------------------------------------------------


def test_stereo_wav_reads_as_uncalibrated_full_scale(tmp_path):
    path = tmp_path / "room.wav"
    codes = (np.random.default_rng(1).uniform(-0.5, 0.5, (4410, 2)) * 32768).astype(np.int16)
    soundfile.write(path, codes, 44100, subtype="PCM_16")
    assert detect_format(path) == "wav"
    with read(path) as rec:
        mic0, mic1 = rec.run("wav").channels
        assert (mic0.units, mic0.sample_rate_hz, mic0.range_max) == ("1", 44100.0, 32767 / 32768)
        assert mic0.uncalibrated and mic0.si_units == "1"
        np.testing.assert_array_equal(mic1.read(), codes[:, 1] / 32768.0)
        assert rec.campaign_id == "room" and rec.run("wav").protocol == "unspecified"
    mapping = {"mapping": {"version": 1}, "campaign": {"campaign_id": "w"},
               "rig": {"apparatus": "other", "description": "x"},
               "runs": [{"run_id": "r", "protocol": "transient",
                         "channels": [{"name": "mic", "index": 0, "quantity": "sound_pressure",
                                       "units": "Pa"}]}]}
    with pytest.raises(MappingError, match=r"key 'units': the mapping says 'Pa' but channel 0 says '1'"):
        read(path, mapping=mapping)


NPY_MAPPING = {
    "mapping": {"version": 1, "format": "npy"}, "campaign": {"campaign_id": "npy"},
    "rig": {"apparatus": "other", "description": "array"},
    "runs": [{"run_id": "r", "protocol": "transient", "timestamps": {"t": {"index": 0, "axis": 1}},
              "channels": [{"name": "force", "index": 1, "axis": 1, "quantity": "excitation_force",
                            "units": "N", "units_assumed": True, "timestamps": "t"}]}],
}


def test_npy_columns_with_a_time_column(tmp_path):
    path = tmp_path / "cols.npy"
    t = np.arange(500) / 1000.0
    arr = np.column_stack([t, np.sin(t), np.cos(t)])
    np.save(path, arr)
    assert detect_format(path) == "npy"
    with read(path, mapping=NPY_MAPPING) as rec:
        force = rec.run("r").channel("force")
        np.testing.assert_array_equal(force.read(), np.sin(t))
        assert force.uncalibrated and force.timestamps == "t"
        np.testing.assert_array_equal(rec.run("r").timestamps["t"].read(0, 500), t)
        assert [s.source for s in rec.origin.skipped] == ["column 2"]
    with pytest.raises(FileFormatError, match=r"cols\.npy: a \.npy array carries no metadata"):
        read(path)


def test_npy_nan_is_caught_at_ingest(tmp_path):
    path = tmp_path / "cols.npy"
    t = np.arange(500) / 1000.0
    arr = np.column_stack([t, np.sin(t), np.cos(t)])
    arr[250, 1] = np.nan
    np.save(path, arr)
    with pytest.raises(NaNGapError, match=r"cols\.npy: /runs/r/channels/force: data: nan: 1 NaN "
                                          r"sample\(s\) in 1 run\(s\), first at sample 250"):
        ingest([path], tmp_path / "store.h5", mapping=load_mapping(NPY_MAPPING))


# --- error paths of every reader ------------------------------------------------------------------

HEAD = "LabVIEW Measurement\nSeparator\tTab\n"


@pytest.mark.parametrize(("text", "match"), [
    (HEAD + "Decimal_Separator\tx\n***End_of_Header***\n", r"header 'Decimal_Separator': 'x' is not"),
    (HEAD + "X_Columns\tTwo\n***End_of_Header***\n", r"header 'X_Columns': 'Two' is not No, One or Multi"),
    (HEAD + "***End_of_Header***\n1\t2\n", r"line 4: data before any segment header"),
    (HEAD + "***End_of_Header***\nChannels\t1\n", r"segment header without '\*\*\*End_of_Header\*\*\*'"),
    (HEAD + "***End_of_Header***\nChannels\t1\n***End_of_Header***\n",
     r"segment header without a column-name line"),
    (HEAD + "***End_of_Header***\n\n", r"no data segment found"),
    (HEAD + "***End_of_Header***\nChannels\tx\n***End_of_Header***\nX_Value\ta\n0\t1\n",
     r"segment 0 header 'Channels': 'x' is not an integer"),
    (HEAD + "***End_of_Header***\nChannels\t3\n***End_of_Header***\nX_Value\ta\n0\t1\n",
     r"segment 0: header says 3 channels, the column-name line has 1"),
    (HEAD + "***End_of_Header***\nSamples\tx\n***End_of_Header***\nX_Value\ta\n0\t1\n",
     r"segment 0 header 'Samples': 'x' of column 'a' is not an integer"),
    (HEAD + "***End_of_Header***\nDelta_X\tabc\n***End_of_Header***\nX_Value\ta\n0\t1\n",
     r"segment 0 header 'Delta_X': 'abc' of column 'a' is not a number"),
    (HEAD + "***End_of_Header***\nX0\tabc\n***End_of_Header***\nX_Value\ta\n0\t1\n",
     r"segment 0 header 'X0': 'abc' of column 'a' is not a number"),
])
def test_lvm_header_errors(tmp_path, text, match):
    path = tmp_path / "bad.lvm"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=match):
        parse_lvm(path)


def _lvm_mapping(**channel) -> dict:
    return {"mapping": {"version": 1}, "campaign": {"campaign_id": "c"},
            "rig": {"apparatus": "other", "description": "x"},
            "runs": [{"run_id": "r", "protocol": "transient",
                      "channels": [{"name": "a", "quantity": "base_acceleration", **channel}]}]}


@pytest.mark.parametrize(("channel", "cls", "match"), [
    ({"source": "acc", "segment": 5}, MappingError, r"segment 5: the file has segments 0\.\.1"),
    ({}, MappingError, r"missing key 'source' \(the LVM column name\) or 'index'"),
    ({"source": "zz"}, MappingError, r"no column 'zz' in seg\.lvm \(has: acc, drive\)"),
    ({"source": "acc", "units": {"source": "/x"}}, MappingError,
     r"runs\[0\]\.channels\[0\]\.units: references into the file .* work for HDF5 only"),
])
def test_lvm_mapping_errors(tmp_path, channel, cls, match):
    path, _ = _lvm(tmp_path)
    with pytest.raises(cls, match=match):
        read(path, mapping=_lvm_mapping(**channel))


def test_lvm_needs_a_mapping_and_rejects_bad_timing(tmp_path):
    path, _ = _lvm(tmp_path)
    with pytest.raises(FileFormatError, match=r"a LabVIEW \.lvm file does not say which quantity each "
                                              r"of its columns \(acc, drive, acc, drive\) measures"):
        read(path)
    mapping = _lvm_mapping(source="acc")
    mapping["runs"][0]["timestamps"] = {"t": {"source": "X_Value"}}
    with pytest.raises(MappingError, match=r"timestamps\.t: no X_Value column in segment 0 "
                                           r"\(X_Columns is No\)"):
        read(path, mapping=mapping)
    dup = tmp_path / "dup.lvm"
    dup.write_text(HEAD + "***End_of_Header***\nDelta_X\t0\t0\n***End_of_Header***\nX_Value\ta\ta\n"
                   "0\t1\t2\n1\t2\t3\n")
    with pytest.raises(MappingError, match=r"column name 'a' is not unique in a segment; select it "
                                           r"with 'index'"):
        read(dup, mapping=_lvm_mapping(source="a"))
    with pytest.raises(FileFormatError, match=r"dup\.lvm: header 'Delta_X' of column 'a': must be > 0, "
                                              r"was 0"):
        read(dup, mapping=_lvm_mapping(index=0))


def _base_mapping(fmt: str, channels: list[dict], **run) -> dict:
    return {"mapping": {"version": 1, "format": fmt}, "campaign": {"campaign_id": "c"},
            "rig": {"apparatus": "other", "description": "x"},
            "runs": [{"run_id": "r", "protocol": "transient", "channels": channels, **run}]}


@pytest.mark.parametrize(("edit", "match"), [
    (lambda m: m.update(campaign=1), r"<mapping>: \[campaign\]: must be a table"),
    (lambda m: m["mapping"].update(format="xls"), r"\[mapping\]: format 'xls' is not one of hdf5, lvm"),
    (lambda m: m["campaign"].pop("campaign_id"), r"\[campaign\]: missing key 'campaign_id'"),
    (lambda m: m.pop("rig"), r"\[rig\]: missing table"),
    (lambda m: m.update(runs=[]), r"\[\[runs\]\]: a mapping needs at least one run"),
    (lambda m: m["runs"][0].pop("run_id"), r"runs\[0\]: missing key 'run_id'"),
    (lambda m: m["runs"][0].update(channels=[]), r"runs\[0\]: missing \[\[runs\.channels\]\]"),
    (lambda m: m["runs"][0]["channels"][0].pop("quantity"), r"runs\[0\]\.channels\[0\]: missing key "
                                                            r"'quantity'"),
    (lambda m: m["runs"][0]["channels"].append(dict(m["runs"][0]["channels"][0])),
     r"runs\[0\]\.channels\[1\]: duplicated channel name 'a'"),
    (lambda m: m.update(skip=[{"source": "x"}]), r"skip\[0\]: needs 'source' and 'reason'"),
])
def test_mapping_structure_errors(edit, match):
    mapping = _base_mapping("npy", [{"name": "a", "index": 0, "quantity": "drive_signal"}])
    edit(mapping)
    with pytest.raises(MappingError, match=match):
        load_mapping(mapping)


def test_mapping_file_errors(tmp_path):
    with pytest.raises(MappingError, match=r"nope\.toml: cannot read the mapping file: No such file"):
        load_mapping(tmp_path / "nope.toml")
    npy = tmp_path / "lab.npy"
    np.save(npy, np.zeros((2, 100)))
    channels = [{"name": "a", "index": 0, "quantity": "drive_signal", "units": "V",
                 "sample_rate_hz": 1.0, "start_time_s": 0.0}]
    mapping = _base_mapping("npy", channels)
    mapping["runs"].append({"run_id": "{stem}", "protocol": "transient", "channels": channels})
    mapping["runs"][0]["run_id"] = "lab"
    with pytest.raises(DuplicateRunError, match=r"runs\[1\]: duplicated run_id 'lab'"):
        read(npy, mapping=mapping)
    mapping = _base_mapping("npy", channels)
    mapping["skip"] = [{"source": "row 7", "reason": "?"}]
    with pytest.raises(MappingError, match=r"skip\[0\]: 'row 7' is not in lab\.npy \(has: row 0, row 1\)"):
        read(npy, mapping=mapping)
    mapping = _base_mapping("npy", channels)
    mapping["rig"]["sensors"] = [{"position_m": [0, 0, 0], "mounted_on": "base"}]
    with pytest.raises(MappingError, match=r"rig\.sensors\[0\]: missing key 'sensor_id'"):
        read(npy, mapping=mapping)


@pytest.mark.parametrize(("edit", "cls", "match"), [
    (lambda m: m.replace('source = "/acc"', "source = 3"), MappingError,
     r"'source' must be an HDF5 dataset path"),
    (lambda m: m.replace('source = "/acc"\n', ""), MappingError,
     r"runs\[0\]\.channels\[0\]: missing key 'source' \(the dataset path\)"),
    (lambda m: m.replace('source = "/acc"', 'source = "/name"'), MappingError,
     r"source '/name': dataset of dtype object is not numeric"),
    (lambda m: m.replace('source = "/acc"', 'source = "/data"'), SchemaError,
     r"/data: dataset 'shape': a channel must be 1-D \(or a MATLAB vector\), got shape \(3, 2000\)"),
    (lambda m: m.replace('{ source = "/meta/operator" }', '{ source = "/nope" }'), MappingError,
     r"\[campaign\]\.operator: source '/nope': not in"),
    (lambda m: m.replace('{ source = "/meta/operator" }', '{ source = "/meta", attr = "x" }'),
     MappingError, r"\[campaign\]\.operator: /meta: no attribute 'x'"),
    (lambda m: m.replace('{ source = "/meta/operator" }', '{ source = "/meta" }'), MappingError,
     r"\[campaign\]\.operator: source '/meta': must be a small dataset"),
    (lambda m: m.replace('{ source = "/meta/operator" }', '{ source = "/data" }'), MappingError,
     r"source '/data': expected one value, has shape \(3, 2000\)"),
])
def test_hdf5_mapping_errors(tmp_path, edit, cls, match):
    mat = tmp_path / "lab.mat"
    make_mat(mat)
    with h5py.File(mat, "a") as fh:
        fh["name"] = np.array(["a", "b"], dtype=object)
    mapping = tmp_path / "m.toml"
    mapping.write_text(edit(MAT_MAPPING))
    with pytest.raises(cls, match=match):
        read(mat, mapping=mapping)


def test_hdf5_mapping_reads_attributes_by_reference(tmp_path):
    mat = tmp_path / "lab.mat"
    make_mat(mat)
    with h5py.File(mat, "a") as fh:
        fh["meta"].attrs["who"] = "Bea"
    mapping = tmp_path / "m.toml"
    mapping.write_text(MAT_MAPPING.replace('{ source = "/meta/operator" }',
                                           '{ source = "/meta", attr = "who" }'))
    with read(mat, mapping=mapping) as rec:
        assert rec.operator == "Bea"


@pytest.mark.parametrize(("mapping", "cls", "match"), [
    (_base_mapping("npy", [{"name": "a", "source": "x", "quantity": "drive_signal"}]), MappingError,
     r"a \.npy array is selected with 'index' \(and 'axis'\), not 'source' or 'segment'"),
    (_base_mapping("npy", [{"name": "a", "quantity": "drive_signal"}]), MappingError,
     r"missing key 'index' \(the array has shape \(3, 50\)\)"),
    (_base_mapping("npy", [{"name": "a", "index": 3, "quantity": "drive_signal"}]), MappingError,
     r"key 'index': 3 along axis 0 is outside shape \(3, 50\)"),
    (_base_mapping("npy", [{"name": "a", "index": 0, "quantity": "drive_signal"},
                           {"name": "b", "index": 0, "axis": 1, "quantity": "drive_signal"}]),
     MappingError, r"channels\[1\]: key 'axis': channels must all run along one axis"),
    (_base_mapping("npy", [{"name": "a", "index": 1, "quantity": "drive_signal", "units": "V",
                            "timestamps": "t"}], timestamps={"t": {"index": 2}}),
     MappingError, r"timestamps\.t: timestamps must be float64 seconds, got int32"),
    (_base_mapping("npy", [{"name": "a", "index": 1, "quantity": "drive_signal",
                            "units": {"source": "/u"}}]), MappingError,
     r"channels\[0\]\.units: references into the file"),
])
def test_npy_mapping_errors(tmp_path, mapping, cls, match):
    path = tmp_path / "a.npy"
    np.save(path, np.arange(150, dtype=np.int32).reshape(3, 50))
    with pytest.raises(cls, match=match):
        read(path, mapping=mapping)


def test_npy_shapes(tmp_path):
    cube = tmp_path / "cube.npy"
    np.save(cube, np.zeros((2, 2, 2)))
    with pytest.raises(FileFormatError, match=r"a \.npy record must be a 1-D or 2-D numeric array, "
                                              r"got shape \(2, 2, 2\)"):
        read(cube, mapping=_base_mapping("npy", [{"name": "a", "index": 0, "quantity": "drive_signal"}]))
    line = tmp_path / "line.npy"
    np.save(line, np.sin(np.arange(100.0)))
    with pytest.raises(MappingError, match=r"key 'index': the array is 1-D \(one channel\)"):
        read(line, mapping=_base_mapping("npy", [{"name": "a", "index": 0, "quantity": "drive_signal"}]))
    ok = _base_mapping("npy", [{"name": "a", "quantity": "drive_signal", "units": "V",
                                "sample_rate_hz": 100.0, "start_time_s": 0.0}])
    with read(line, mapping=ok) as rec:
        np.testing.assert_array_equal(rec.run("r").channel("a").read(), np.sin(np.arange(100.0)))


def test_tdms_errors(tmp_path, monkeypatch):
    path = tmp_path / "rig.tdms"
    make_tdms(path)
    with TdmsWriter(tmp_path / "text.tdms") as writer:
        writer.write_segment([ChannelObject("g", "c", np.array(["a", "b"])),
                              ChannelObject("g", "zero", np.arange(3.0), properties={"wf_increment": 0.0})])
    for channel, match in [
        ({"index": 0}, r"a TDMS channel is selected with source = \"group/channel\""),
        ({"source": "run1/nope"}, r"no channel 'run1/nope' in rig\.tdms \(has: run1/base, run1/mic\)"),
        ({"source": "run1/base", "units": {"source": "x"}}, r"references into the file"),
    ]:
        with pytest.raises(MappingError, match=match):
            read(path, mapping=_base_mapping("tdms", [{"name": "a", "quantity": "drive_signal", **channel}]))
    m = _base_mapping("tdms", [{"name": "a", "source": "run1/base", "quantity": "base_acceleration",
                                "timestamps": "t"}], timestamps={"t": {"source": "run1/mic"}})
    with pytest.raises(MappingError, match=r"timestamps\.t: timestamps must be float64 seconds, got float32"):
        read(path, mapping=m)
    text = tmp_path / "text.tdms"
    with pytest.raises(MappingError, match=r"channel 'g/c' has non-numeric data \(object\)"):
        read(text, mapping=_base_mapping("tdms", [{"name": "a", "source": "g/c", "quantity": "drive_signal"}]))
    with pytest.raises(FileFormatError, match=r"text\.tdms: g/zero: property 'wf_increment': must be > 0"):
        read(text, mapping=_base_mapping("tdms", [{"name": "a", "source": "g/zero", "quantity": "drive_signal"}]))
    empty = tmp_path / "empty.tdms"
    with TdmsWriter(empty) as writer:
        writer.write_segment([RootObject({"title": "nothing"})])
    with pytest.raises(FileFormatError, match=r"empty\.tdms: TDMS file without channels"):
        read(empty)
    cut = tmp_path / "cut.tdms"
    cut.write_bytes(path.read_bytes()[:-5000])
    with pytest.raises(FileFormatError, match=r"cut\.tdms: damaged TDMS file \(truncated\?\): npTDMS says: "):
        read(cut)

    import nptdms

    def boom(*args, **kwargs):
        raise ValueError("bad segment")

    monkeypatch.setattr(nptdms.TdmsFile, "open", boom)
    monkeypatch.setattr("rattle_lab.records._readers.tdms.TdmsFile.open", boom)
    with pytest.raises(FileFormatError, match=r"rig\.tdms: not a readable TDMS file \(truncated or "
                                              r"damaged\?\): ValueError: bad segment"):
        read(path)


def test_tdms_read_failures_are_file_format_errors(tmp_path, monkeypatch):
    path = tmp_path / "rig.tdms"
    make_tdms(path)
    with read(path) as rec:
        ch = rec.run("run1").channel("base")
        monkeypatch.setattr(ch.data.channel, "read_data", lambda offset, length: np.zeros(length - 1))
        with pytest.raises(FileFormatError, match=r"rig\.tdms: run1/base: samples 0:10: cannot be read "
                                                  r"\(got 9\)"):
            ch.read(0, 10)

        def boom(offset, length):
            raise OSError("disk")

        monkeypatch.setattr(ch.data.channel, "read_data", boom)
        with pytest.raises(FileFormatError, match=r"run1/base: samples 0:10: cannot be read: disk"):
            ch.read(0, 10)


def test_wav_errors(tmp_path, monkeypatch):
    path = tmp_path / "room.wav"
    soundfile.write(path, np.zeros((100, 2)), 8000, subtype="PCM_16")
    for channel, match in [
        ({"source": "x"}, r"a WAV channel is selected with 'index' only"),
        ({"index": 2}, r"key 'index': 2; the file has 2 channel\(s\)"),
        ({"index": 0, "units": {"source": "x"}}, r"references into the file"),
    ]:
        with pytest.raises(MappingError, match=match):
            read(path, mapping=_base_mapping("wav", [{"name": "a", "quantity": "sound_pressure", **channel}]))
    m = _base_mapping("wav", [{"name": "a", "quantity": "sound_pressure", "timestamps": "t"}],
                      timestamps={"t": {"index": 0}})
    with pytest.raises(MappingError, match=r"timestamps\.t: a WAV file is regularly sampled"):
        read(path, mapping=m)
    bad = tmp_path / "bad.wav"
    bad.write_bytes(b"RIFF\x00\x00\x00\x00WAVEjunkjunkjunk")
    with pytest.raises(FileFormatError, match=r"bad\.wav: not a readable WAV file"):
        read(bad)
    with read(path) as rec:
        mic = rec.run("wav").channel("mic0")
        monkeypatch.setattr(mic.data.handle, "read", lambda *a, **k: np.zeros((5, 2), np.float32))
        with pytest.raises(FileFormatError, match=r"room\.wav: channel 0: samples 0:10: file ends after 5"):
            mic.read(0, 10)

        def boom(*args, **kwargs):
            raise RuntimeError("I/O error")

        monkeypatch.setattr(mic.data.handle, "read", boom)
        with pytest.raises(FileFormatError, match=r"room\.wav: channel 0: samples 0:10: cannot be read: "
                                                  r"I/O error"):
            mic.read(0, 10)
