"""A corpus of malformed inputs: each gets its own RattleLabError subclass and message.

Every case is generated into a temporary folder (no binary files are committed) and
checked twice: in-process with ``pytest.raises(..., match=...)``, and through the installed
``rattle-lab ingest`` entry point (exit status 2, one stderr line, no traceback, no store,
no temporary file left behind).
"""

from __future__ import annotations

import concurrent.futures
import re
from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np
import pytest
import soundfile
from record_factory import make_record, replace_channel, run_cli, write

from rattle_lab.cli import main
from rattle_lab.exceptions import FileFormatError, RattleLabError, SchemaError
from rattle_lab.store import ingest
from rattle_lab.records import (Channel, ClippingError, DropoutError, DuplicateRunError,
                                EmptyChannelError, InfValueError, MappingError, NaNGapError,
                                NonMonotonicTimestampsError, Record, Rig, Run,
                                SampleRateMismatchError)

MIC = "runs/dwell_094/channels/mic"


def _edit(fn: Callable[[h5py.File], None], record: Record | None = None):
    def build(d: Path) -> tuple[list[Path], Path | None]:
        path = write(d, "in.h5", record)
        with h5py.File(path, "a") as fh:
            fn(fh)
        return [path], None
    return build


def _record(record: Record):
    def build(d: Path) -> tuple[list[Path], Path | None]:
        return [write(d, "in.h5", record)], None
    return build


def _with_data(name: str, edit: Callable[[np.ndarray], np.ndarray], **changes):
    rec = make_record()
    data = rec.run("dwell_094").channel(name).read(si=False).copy()
    return _record(replace_channel(rec, "dwell_094", name, data=edit(data), **changes))


def _set(index, value):
    def edit(x: np.ndarray) -> np.ndarray:
        x[index] = value
        return x
    return edit


def _replace_dataset(path: str, data) -> Callable[[h5py.File], None]:
    def fn(fh: h5py.File) -> None:
        attrs = dict(fh[path].attrs)
        del fh[path]
        ds = fh.create_dataset(path, data=data)
        ds.attrs.update(attrs)
    return fn


def _ts_record(t: np.ndarray) -> Record:
    ch = Channel("mic", "sound_pressure", "Pa", np.sin(np.arange(t.size) * 0.1), timestamps="t")
    return Record("ts", "measured", Rig("other", description="timestamp test"),
                  [Run("r", "transient", [ch], timestamps={"t": t})])


def _timestamped(t: np.ndarray):
    return _record(_ts_record(t))


def _raw_file(name: str, content: bytes):
    def build(d: Path) -> tuple[list[Path], Path | None]:
        path = d / name
        path.write_bytes(content)
        return [path], None
    return build


def _truncated(fraction: float):
    def build(d: Path) -> tuple[list[Path], Path | None]:
        path = write(d, "full.h5")
        cut = d / "in.h5"
        data = path.read_bytes()
        cut.write_bytes(data[:int(len(data) * fraction)])
        path.unlink()
        return [cut], None
    return build


def _two_files_same_run(d: Path) -> tuple[list[Path], Path | None]:
    return [write(d, "a.h5", make_record("camp", seed=1)), write(d, "b.h5", make_record("camp", seed=2))], None


LVM = ("LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\nDecimal_Separator\t.\n"
       "X_Columns\tOne\n***End_of_Header***\t\n\nChannels\t1\t\nSamples\t{n}\t\n"
       "Y_Unit_Label\tm/s^2\t\nX0\t0.0\t\nDelta_X\t0.001\t\n***End_of_Header***\t\n"
       "X_Value\ta\tComment\n0.000\t1.0\n0.001\t2.0\n0.002\t1.5\n")
LVM_MAPPING = """
[mapping]
version = 1
[campaign]
campaign_id = "lvm-{{stem}}"
[rig]
apparatus = "other"
description = "test"
[[runs]]
run_id = "r"
protocol = "transient"
[[runs.channels]]
name = "a"
source = "a"
quantity = "base_acceleration"
{extra}
"""


def _lvm(samples: int, extra: str):
    def build(d: Path) -> tuple[list[Path], Path | None]:
        path = d / "in.lvm"
        path.write_text(LVM.format(n=samples))
        mapping = d / "map.toml"
        mapping.write_text(LVM_MAPPING.format(extra=extra))
        return [path], mapping
    return build


def _pickled_npy(d: Path) -> tuple[list[Path], Path | None]:
    path = d / "in.npy"
    np.save(path, np.array([{"a": 1}, None], dtype=object), allow_pickle=True)
    mapping = d / "map.toml"
    mapping.write_text(LVM_MAPPING.format(extra="").replace('source = "a"\n', "index = 0\n"))
    return [path], mapping


def _mat_file(d: Path) -> tuple[list[Path], Path | None]:
    path = d / "in.mat"
    with h5py.File(path, "w", userblock_size=512) as fh:
        ds = fh.create_dataset("acc", data=np.zeros((100, 1)))
        ds.attrs["MATLAB_class"] = np.bytes_(b"double")
    with open(path, "r+b") as fh:
        fh.write(b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 .")
    return [path], None


def _clipped_wav(d: Path) -> tuple[list[Path], Path | None]:
    path = d / "in.wav"
    x = 1.5 * np.sin(np.linspace(0, 20 * np.pi, 8000))
    soundfile.write(path, np.clip(x, -1.0, 32767 / 32768), 8000, subtype="PCM_16")
    return [path], None


def _copy_run(fh: h5py.File) -> None:
    fh.copy("runs/dwell_094", "runs/DWELL_094")


def _rename(src: str, dst: str) -> Callable[[h5py.File], None]:
    def fn(fh: h5py.File) -> None:
        fh.move(src, dst)
    return fn


def _rename_attr(path: str, old: str, new: str) -> Callable[[h5py.File], None]:
    def fn(fh: h5py.File) -> None:
        fh[path].attrs[new] = fh[path].attrs[old]
        del fh[path].attrs[old]
    return fn


def _attr(path: str, **values) -> Callable[[h5py.File], None]:
    def fn(fh: h5py.File) -> None:
        for k, v in values.items():
            if v is None:
                del fh[path].attrs[k]
            else:
                fh[path].attrs[k] = v
    return fn


def _chain(*fns):
    def fn(fh):
        for f in fns:
            f(fh)
    return fn


def _group_for_dataset(fh: h5py.File) -> None:
    attrs = dict(fh[MIC].attrs)
    del fh[MIC]
    fh.create_group(MIC).attrs.update(attrs)


def _short_truth(fh: h5py.File) -> None:
    del fh["truth/impacts/dwell_094/v_out_m_s"]
    fh["truth/impacts/dwell_094/v_out_m_s"] = np.array([-0.08])


TS = np.arange(1000) * 1e-4
TS_BACK = TS.copy()
TS_BACK[500] = TS_BACK[498]
TS_GAP = np.concatenate([TS[:500], TS[500:] + 5e-4])
TS_NAN = TS.copy()
TS_NAN[10] = np.nan

#: name -> (builder, exception class, match)
CASES: dict[str, tuple[Callable[[Path], tuple[list[Path], Path | None]], type[RattleLabError], str]] = {
    "truncated_file": (_truncated(0.6), FileFormatError,
                       r"in\.h5: not a readable HDF5 file \(truncated or damaged\?\)"),
    "truncated_to_superblock": (_truncated(0.02), FileFormatError,
                                r"in\.h5: not a readable HDF5 file \(truncated or damaged\?\)"),
    "missing_rig_group": (_edit(lambda fh: fh.__delitem__("rig")), SchemaError,
                          r"in\.h5: /: missing group or dataset 'rig'"),
    "missing_runs_group": (_edit(lambda fh: fh.__delitem__("runs")), SchemaError,
                           r"in\.h5: /: missing group or dataset 'runs'"),
    "missing_channels_group": (_edit(lambda fh: fh.__delitem__("runs/dwell_094/channels")), SchemaError,
                               r"in\.h5: /runs/dwell_094: missing group or dataset 'channels'"),
    "missing_units_attribute": (_edit(_attr(MIC, units=None)), SchemaError,
                                r"in\.h5: /runs/dwell_094/channels/mic: missing attribute 'units'"),
    "missing_campaign_id": (_edit(_attr("/", campaign_id=None)), SchemaError,
                            r"in\.h5: /: missing attribute 'campaign_id'"),
    "missing_shaker_frequency": (_edit(_attr("runs/dwell_094", excitation_freq_hz=None)), SchemaError,
                                 r"/runs/dwell_094: missing attribute 'excitation_freq_hz' \(a shaker "
                                 r"run needs"),
    "wrong_dtype_complex": (_edit(_replace_dataset(MIC, np.zeros(4096, dtype=np.complex64))),
                            SchemaError, r"channels/mic: dataset 'dtype': a channel must be one of "
                                         r"f4, f8, .* got '<c8'"),
    "wrong_dtype_strings": (_edit(_replace_dataset(MIC, np.array(["a", "b"], dtype=object))),
                            SchemaError, r"channels/mic: dataset 'dtype': a channel must be one of"),
    "wrong_dtype_float32_timestamps": (_edit(_replace_dataset("runs/r/timestamps/t",
                                                              TS.astype(np.float32)), _ts_record(TS)),
                                       SchemaError,
                                       r"/runs/r/timestamps/t: dataset 'dtype': a timestamps dataset "
                                       r"must be one of f8"),
    "wrong_units_string": (_edit(_attr(MIC, units="dB")), SchemaError,
                           r"channels/mic: attribute 'units': 'dB' is not one of \['Pa', 'V', '1'\]"),
    "wrong_sensitivity_units": (_edit(_attr(MIC, sensitivity_units="mV/g")), SchemaError,
                                r"channels/mic: attribute 'sensitivity_units': 'mV/g' is not one of"),
    "volts_without_sensitivity": (_edit(_attr(MIC, sensitivity=None, sensitivity_units=None)),
                                  SchemaError, r"channels/mic: missing attribute 'sensitivity' \(raw "
                                               r"volts \(units 'V'\) need"),
    "negative_sample_rate": (_edit(_attr(MIC, sample_rate_hz=-51200.0)), SchemaError,
                             r"channels/mic: attribute 'sample_rate_hz': -51200\.0 is less than or "
                             r"equal to the minimum of 0"),
    "typo_attribute_name": (_edit(_rename_attr(MIC, "sample_rate_hz", "sample_rate")), SchemaError,
                            r"channels/mic: unexpected attribute 'sample_rate' \(extra attributes "
                            r"must start with 'x_'\)"),
    "rate_and_timestamps": (_edit(_attr(MIC, timestamps="t")), SchemaError,
                            r"channels/mic: attributes do not fit \(a channel needs either "
                            r"sample_rate_hz and start_time_s, or timestamps \(not both\)\)"),
    "timestamps_not_found": (_edit(_attr(MIC, timestamps="t", sample_rate_hz=None, start_time_s=None)),
                             SchemaError, r"channels/mic: attribute 'timestamps': no dataset "
                                          r"/runs/dwell_094/timestamps/t"),
    "channel_is_2d": (_edit(_replace_dataset(MIC, np.zeros((2, 4096), dtype=np.float32))), SchemaError,
                      r"channels/mic: dataset 'shape': a channel must be 1-D, got \(2, 4096\)"),
    "channel_is_a_group": (_edit(_group_for_dataset), SchemaError,
                           r"channels/mic: node type: 'dataset' was expected \(must be an HDF5 dataset\)"),
    "missing_sensor": (_edit(_attr(MIC, sensor_id="nope")), SchemaError,
                       r"channels/mic: attribute 'sensor_id': no sensor /rig/sensors/nope"),
    "bad_calibration_date": (_edit(_attr(MIC, calibration_date="15/01/2024")), SchemaError,
                             r"channels/mic: attribute 'calibration_date': '15/01/2024' does not match "
                             r".* \(expected an ISO 8601 date"),
    "bad_edge_conditions": (_edit(_attr("rig", edge_conditions="CFXF")), SchemaError,
                            r"/rig: attribute 'edge_conditions': 'CFXF' does not match"),
    "infinite_attribute": (_edit(_attr("rig", plate_length_m=np.inf)), SchemaError,
                           r"/rig: attribute 'plate_length_m': must be finite, was inf"),
    "non_utf8_attribute": (_edit(_attr("runs/dwell_094", notes=np.bytes_(b"\xff\xfe bad"))), SchemaError,
                           r"/runs/dwell_094: attribute 'notes': text is not valid UTF-8 \(byte 0\)"),
    "huge_attribute": (_edit(_attr("runs/dwell_094", notes=np.bytes_(b"x" * 2_000_000))), SchemaError,
                       r"/runs/dwell_094: attribute 'notes': is 2000000 bytes, over the limit of "
                       r"1048576 bytes"),
    "long_text_attribute": (_edit(_attr("runs/dwell_094", notes="x" * 70_000)), SchemaError,
                            r"/runs/dwell_094: attribute 'notes': text of 70000 characters is longer "
                            r"than 65536"),
    "unicode_run_name": (_edit(_rename("runs/dwell_094", "runs/l\u00e4uf_1")), SchemaError,
                         r"/runs: invalid name 'l\u00e4uf_1' \(names and ids are 1-64 ASCII"),
    "unicode_campaign_id": (_edit(_attr("/", campaign_id="kampagne_\u00e4")), SchemaError,
                            r"/: attribute 'campaign_id': 'kampagne_\u00e4' does not match"),
    "schema_version_3": (_edit(_attr("/", schema_version=3)), SchemaError,
                         r"/: attribute 'schema_version': 3 is not one of \[1, 2\] \(this reader "
                         r"knows layout versions 1 and 2"),
    "synthetic_without_truth": (_edit(_attr("/", source="synthetic")), SchemaError,
                                r"/: missing group or dataset 'truth' \(a synthetic record needs a "
                                r"/truth group\)"),
    "truth_columns_differ": (_edit(_short_truth, make_record(synthetic=True)), SchemaError,
                             r"/truth/impacts/dwell_094: dataset 'shape': columns differ in length: "
                             r"t_s=2, v_in_m_s=2, v_out_m_s=1"),
    "not_a_rattle_hdf5": (_edit(_attr("/", schema=None)), FileFormatError,
                          r"in\.h5: is an HDF5 file without the rattle record attributes"),
    "matlab_without_mapping": (_mat_file, FileFormatError,
                               r"in\.mat: is a MATLAB v7\.3 \.mat file without the rattle record "
                               r"attributes"),
    "non_hdf5_file": (_raw_file("in.h5", b"time,acc\n0,1\n"), FileFormatError,
                      r"in\.h5: not a recognised record format"),
    "empty_file": (_raw_file("in.h5", b""), FileFormatError, r"in\.h5: file is empty \(0 bytes\)"),
    "nan_samples": (_with_data("mic", _set(1234, np.nan)), NaNGapError,
                    r"channels/mic: data: nan: 1 NaN sample\(s\) in 1 run\(s\), first at sample 1234"),
    "inf_samples": (_with_data("plate", _set(99, -np.inf)), InfValueError,
                    r"channels/plate: data: inf: 1 infinite sample\(s\), first at sample 99"),
    "clipped_at_declared_range": (_with_data("base", _set(slice(300, 320), 10.0)), ClippingError,
                                  r"channels/base: data: clipping: 20 samples in 1 flat run\(s\) at the "
                                  r"declared range \[-10, 10\], first at sample 300"),
    "clipped_flat_top": (_with_data("plate", _set(slice(500, 508), 25.0)), ClippingError,
                         r"channels/plate: data: clipping: 8 samples in 1 flat run\(s\) at the "
                         r"channel's own extreme"),
    "clipped_wav": (_clipped_wav, ClippingError,
                    r"in\.wav: /runs/wav/channels/mic: data: clipping: .* at the declared range "
                    r"\[-1, 0\.999969\]"),
    "dropout_zeros": (_with_data("mic", _set(slice(1000, 1200), 0.0)), DropoutError,
                      r"channels/mic: data: dropout: 1 run\(s\) of >= 51 identical samples: first at "
                      r"sample 1000, 200 samples of value 0"),
    "constant_channel": (_with_data("drive", lambda x: np.full_like(x, 0.5)), DropoutError,
                         r"channels/drive: data: dropout: channel is constant"),
    "empty_channel": (_with_data("drive", lambda x: x[:0]), EmptyChannelError,
                      r"channels/drive: data: empty: zero-length channel \(0 samples\)"),
    "mismatched_rates": (_edit(_attr("runs/dwell_094/channels/velocity", sample_rate_hz=48000.0)),
                         SampleRateMismatchError,
                         r"channels/velocity: sample_rate_hz: rate_mismatch: 48000 Hz differs from "
                         r"51200 Hz of channel 'base' in run 'dwell_094'"),
    "nonmonotonic_timestamps": (_timestamped(TS_BACK), NonMonotonicTimestampsError,
                                r"/runs/r/timestamps/t: timestamps: nonmonotonic_timestamps: 1 step\(s\) "
                                r"not strictly increasing, first at sample 500"),
    "timestamp_gap": (_timestamped(TS_GAP), DropoutError,
                      r"/runs/r/timestamps/t: timestamps: dropout: 1 gap\(s\) in the timestamps, 5 "
                      r"missing sample\(s\); first at sample 500"),
    "nan_timestamp": (_timestamped(TS_NAN), NaNGapError,
                      r"/runs/r/timestamps/t: timestamps: nan: 1 non-finite timestamp\(s\), first at "
                      r"sample 10"),
    "duplicated_run_ids_by_case": (_edit(_copy_run), DuplicateRunError,
                                   r"in\.h5: /runs: duplicated id: '(dwell|DWELL)_094' and "
                                   r"'(dwell|DWELL)_094' differ only by letter case"),
    "duplicated_run_across_files": (_two_files_same_run, DuplicateRunError,
                                    r"b\.h5: /runs/dwell_094: run id 'dwell_094' of campaign 'camp' "
                                    r"is already ingested from"),
    "mapping_unknown_key": (_lvm(3, 'unit = "g"'), MappingError,
                            r"map\.toml: runs\[0\]\.channels\[0\]: unknown key 'unit'"),
    "mapping_contradicts_file": (_lvm(3, 'units = "g"'), MappingError,
                                 r"map\.toml: runs\[0\]\.channels\[0\]: key 'units': the mapping says "
                                 r"'g' but a says 'm/s\^2'"),
    "lvm_samples_mismatch": (_lvm(4, ""), FileFormatError,
                             r"in\.lvm: segment 0: column 'a' has 3 values, the header 'Samples' says 4"),
    "npy_pickled_objects": (_pickled_npy, FileFormatError,
                            r"in\.npy: not a readable \.npy array \(truncated, or pickled objects\?\)"),
}


def _build(name: str, d: Path) -> tuple[list[Path], Path | None]:
    d.mkdir(parents=True, exist_ok=True)
    return CASES[name][0](d)


def test_the_corpus_is_large_enough():
    assert len(CASES) >= 30


@pytest.mark.parametrize("name", sorted(CASES))
def test_malformed_input_raises_its_error(name, tmp_path):
    inputs, mapping = _build(name, tmp_path / "case")
    _, cls, match = CASES[name]
    store = tmp_path / "store.h5"
    with pytest.raises(cls, match=match):
        ingest(inputs, store, mapping=mapping)
    assert not store.exists()
    assert not any(p.name.startswith(".store.h5") for p in tmp_path.iterdir())


def _cli_args(name: str, d: Path) -> tuple[list[str], Path]:
    inputs, mapping = _build(name, d / "case")
    out = d / "out.h5"
    args = ["ingest", *map(str, inputs), "-o", str(out)]
    if mapping is not None:
        args += ["--mapping", str(mapping)]
    return args, out


def _check_cli(name: str, returncode: int, stdout: str, stderr: str, out: Path) -> None:
    assert returncode == 2, stderr
    assert stdout == ""
    lines = stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rattle-lab: error: "), stderr
    assert "Traceback" not in stderr
    assert re.search(CASES[name][2], lines[0]), lines[0]
    assert not out.exists()
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".out.h5")]


@pytest.mark.parametrize("name", sorted(CASES))
def test_malformed_input_cli_exits_2_with_one_line(name, tmp_path, capsys):
    # The command's code path in-process (fast); the installed entry point runs below.
    args, out = _cli_args(name, tmp_path)
    returncode = main(args)
    captured = capsys.readouterr()
    _check_cli(name, returncode, captured.out, captured.err, out)


#: One case per error class, through the installed ``rattle-lab`` entry point.
ENTRY_POINT_CASES = sorted({cls: name for name, (_, cls, _) in sorted(CASES.items())}.values())


def test_malformed_inputs_through_the_installed_entry_point(tmp_path):
    assert len(ENTRY_POINT_CASES) >= 10
    commands = {name: _cli_args(name, tmp_path / name) for name in ENTRY_POINT_CASES}
    with concurrent.futures.ThreadPoolExecutor(max_workers=4) as pool:
        procs = dict(zip(commands, pool.map(lambda n: run_cli(*commands[n][0]), commands)))
    for name, proc in procs.items():
        _check_cli(name, proc.returncode, proc.stdout, proc.stderr, commands[name][1])


def test_a_good_file_after_a_bad_one_is_not_ingested_either(tmp_path):
    good = write(tmp_path, "good.h5")
    bad = write(tmp_path, "bad.h5", make_record("c2"))
    with h5py.File(bad, "a") as fh:
        fh[MIC].attrs["units"] = "dB"
    with pytest.raises(SchemaError, match=r"bad\.h5: /runs/dwell_094/channels/mic: attribute 'units'"):
        ingest([good, bad], tmp_path / "store.h5")
    assert not (tmp_path / "store.h5").exists()
