"""The v1 record schema: its file, its rules, units, and write/read round trips."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import h5py
import jsonschema
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from record_factory import make_record, replace_channel, write

from rattle_lab.exceptions import FileFormatError, SchemaError
from rattle_lab.records import (Channel, GeneratedData, Record, Rig, Run, load_schema, read,
                                scale_to_si, validate_tree, write_record)
from rattle_lab.records._convert import record_to_tree
from rattle_lab.records._units import (ALLOWED_SENSITIVITY_UNITS, ALLOWED_UNITS, G0_MS2,
                                       SENSITIVITY_UNITS, SI_UNITS, UNIT_TO_SI)

REPO = Path(__file__).resolve().parents[2]
PACKAGED = REPO / "rattle_lab" / "data" / "schema" / "rattle_record.v1.schema.json"
TOP_LEVEL = REPO / "data_schema" / "rattle_record.v1.schema.json"


def test_records_public_surface_is_pinned():
    import rattle_lab.records

    assert rattle_lab.records.__all__ == [
        "read", "write_record", "detect_format", "load_schema", "validate_tree", "load_mapping",
        "MappingSpec", "Record", "Rig", "Sensor", "Run", "Channel", "Truth", "ImpactTable",
        "ThresholdTable", "Skipped", "Origin", "ArraySource", "ArrayData", "GeneratedData",
        "Finding", "QualityLimits", "FLAGS", "FATAL_FLAGS", "SI_UNITS", "scale_to_si",
        # StoreError moved to rattle_lab.store (issue 25)
        "MappingError", "DuplicateRunError", "DataQualityError", "NaNGapError",
        "InfValueError", "ClippingError", "DropoutError", "SampleRateMismatchError",
        "NonMonotonicTimestampsError", "EmptyChannelError", "NaNGapWarning", "InfValueWarning",
        "ClippingWarning", "DropoutWarning", "SampleRateMismatchWarning",
        "NonMonotonicTimestampsWarning", "EmptyChannelWarning", "UncalibratedWarning",
        # issue 25: what the store and the fit import from records
        "write_tree", "record_to_tree", "record_from_tree", "load_group", "as_source",
        "DEFAULT_CHUNK_SAMPLES", "LinkPolicy", "link_policy", "ChannelChecker", "TimestampChecker",
        "Participation", "PlateF1", "plate_model_f1", "resolve_participation",
        "channel_time_offset_s", "declared_delay_s", "filter_group_delay_s", "FILTER_TYPES",
        "FLAG_PARTICIPATION_ASSUMED", "FLAG_MEASURAND_UNDECLARED",
        "FLAG_MEASURAND_ABSOLUTE"]
    assert all(hasattr(rattle_lab.records, name) for name in rattle_lab.records.__all__)


def test_top_level_schema_is_a_relative_link_to_the_packaged_file():
    assert TOP_LEVEL.is_symlink()
    assert not os.path.isabs(os.readlink(TOP_LEVEL))
    assert TOP_LEVEL.resolve() == PACKAGED.resolve()
    assert TOP_LEVEL.read_bytes() == PACKAGED.read_bytes()


def test_packaged_schema_loads_and_is_a_valid_2020_12_schema():
    schema = load_schema()
    assert schema == json.loads(PACKAGED.read_text("utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"


def _then_enums(key: str) -> dict[str, list[str]]:
    """quantity -> enum of ``key`` in the schema's per-quantity if/then rules."""
    out = {}
    for rule in load_schema()["$defs"]["channel_attrs"]["allOf"]:
        cond = rule.get("if", {}).get("properties", {}).get("quantity", {})
        quantities = cond.get("enum") or ([cond["const"]] if "const" in cond else [])
        enum = rule.get("then", {}).get("properties", {}).get(key, {}).get("enum")
        for q in quantities:
            if enum is not None:
                out[q] = enum
    return out


def test_unit_tables_agree_with_the_schema():
    schema = load_schema()
    quantities = schema["$defs"]["channel_attrs"]["properties"]["quantity"]["enum"]
    assert sorted(quantities) == sorted(SI_UNITS)
    assert {q: sorted(v) for q, v in _then_enums("units").items()} == {
        q: sorted(v) for q, v in ALLOWED_UNITS.items()}
    assert {q: sorted(v) for q, v in _then_enums("sensitivity_units").items()} == {
        q: sorted(v) for q, v in ALLOWED_SENSITIVITY_UNITS.items()}
    assert set(schema["$defs"]["level_units"]["enum"]) <= set(UNIT_TO_SI)
    assert {u for units in ALLOWED_SENSITIVITY_UNITS.values() for u in units} == set(SENSITIVITY_UNITS)


@pytest.mark.parametrize(("quantity", "units", "sens", "sens_units", "volts", "expected_si", "si"), [
    ("base_acceleration", "V", 100.0, "mV/g", 0.1, G0_MS2, "m/s^2"),        # 100 mV at 100 mV/g: 1 g
    ("plate_acceleration", "V", 10.2, "mV/(m/s^2)", 0.102, 10.0, "m/s^2"),  # 102 mV / 10.2 mV per m/s^2
    ("plate_acceleration", "V", 1.0, "V/g", 2.0, 2 * G0_MS2, "m/s^2"),
    ("plate_velocity", "V", 25.0, "(mm/s)/V", 2.0, 0.05, "m/s"),          # 2 V x 25 mm/s per V
    ("plate_velocity", "V", 5.0, "mV/(mm/s)", 0.5, 0.1, "m/s"),          # 500 mV / 5 mV per mm/s
    ("sound_pressure", "V", 50.0, "mV/Pa", 0.025, 0.5, "Pa"),
    ("excitation_force", "V", 2.25, "mV/N", 0.0045, 2.0, "N"),
    ("plate_acceleration", "g", None, None, 3.0, 3 * G0_MS2, "m/s^2"),
    ("plate_velocity", "mm/s", None, None, 250.0, 0.25, "m/s"),
    ("drive_signal", "mV", None, None, 1500.0, 1.5, "V"),
    ("drive_signal", "V", None, None, 1.5, 1.5, "V"),
    ("sound_pressure", "1", None, None, 0.5, 0.5, "1"),
])
def test_scale_to_si_matches_hand_computed_values(quantity, units, sens, sens_units, volts,
                                                  expected_si, si):
    scale, unit = scale_to_si(quantity, units, sens, sens_units)
    assert unit == si
    # Products of a few decimal numbers: a couple of roundings, hence 4*eps relative.
    assert math.isclose(scale * volts, expected_si, rel_tol=4 * np.finfo(float).eps)


@pytest.mark.parametrize(("args", "match"), [
    (("sound_pressure", "m/s"), r"attribute 'units': 'm/s' is not a unit of sound_pressure"),
    (("sound_pressure", "V"), r"attribute 'sensitivity': raw volts need sensitivity"),
    (("sound_pressure", "V", 50.0, "mV/g"), r"attribute 'sensitivity_units': 'mV/g' does not fit"),
    (("sound_pressure", "V", -1.0, "mV/Pa"), r"attribute 'sensitivity': must be > 0, was -1.0"),
    (("weight", "kg"), r"attribute 'quantity': unknown quantity 'weight'"),
])
def test_scale_to_si_rejects_inconsistent_units(args, match):
    with pytest.raises(SchemaError, match=match):
        scale_to_si(*args, where="f.h5: /runs/r/channels/c")


def test_round_trip_of_a_measured_record(tmp_path):
    record = make_record(run_ids=("dwell_094", "ramp_up"))
    path = write(tmp_path, record=record)
    with read(path) as back:
        assert back == record
        for run in record.runs:
            for ch in run.channels:
                got = back.run(run.run_id).channel(ch.name)
                np.testing.assert_array_equal(got.read(si=False), ch.read(si=False))
                assert got.data.dtype == np.float32


def test_round_trip_of_a_synthetic_record_with_truth(tmp_path):
    record = make_record(synthetic=True)
    path = write(tmp_path, record=record)
    with read(path) as back:
        assert back == record
        assert back.truth is not None and back.truth.extra == {"acoustic_delay_s": 0.00087}
        assert np.isnan(back.truth.thresholds.disappearance_level[1])
    with h5py.File(path, "r") as fh:
        assert fh["truth/impacts/dwell_094/t_s"].shape == (2,)
        assert fh["truth"].attrs["gap_m"] == 0.00034


def test_channel_read_converts_raw_volts_with_the_sensitivity(tmp_path):
    path = write(tmp_path)
    with read(path) as rec:
        base = rec.run("dwell_094").channel("base")
        volts = base.read(si=False)
        # 100 mV/g: SI = V / 0.1 V/g * g0.  float32 data, scale applied in float32: 2 roundings.
        np.testing.assert_allclose(base.read(), volts.astype(np.float64) / 0.1 * G0_MS2,
                                   rtol=2 * np.finfo(np.float32).eps)
        assert base.si_units == "m/s^2" and base.read().dtype == np.float32
        chunks = list(base.iter_chunks(1000))
        assert [s for s, _ in chunks] == [0, 1000, 2000, 3000, 4000]
        np.testing.assert_array_equal(np.concatenate([c for _, c in chunks]), base.read())


def test_write_record_validates_first_and_writes_nothing_invalid(tmp_path):
    bad = replace_channel(make_record(), "dwell_094", "mic", units="dB")
    with pytest.raises(SchemaError, match=r"/runs/dwell_094/channels/mic: attribute 'units': 'dB' "
                                          r"is not one of \['Pa', 'V', '1'\]"):
        write_record(tmp_path / "bad.h5", bad)
    assert list(tmp_path.iterdir()) == []


def test_write_record_streams_generated_data(tmp_path):
    n = 10_000

    def ramp(start: int, stop: int) -> np.ndarray:
        return np.arange(start, stop, dtype=np.float64) * 1e-3

    ch = Channel("drive", "drive_signal", "V", GeneratedData(n, np.float64, ramp),
                 sample_rate_hz=1000.0, start_time_s=0.0)
    rec = Record("gen", "measured", Rig("other", description="generated"),
                 [Run("r", "transient", [ch])])
    path = write_record(tmp_path / "gen.h5", rec, n_chunk_samples=999)
    with read(path) as back:
        np.testing.assert_array_equal(back.run("r").channel("drive").read(), np.arange(n) * 1e-3)


def _tree():
    tree, _ = record_to_tree(make_record(synthetic=True))
    return tree


def _chan_attrs(tree):
    return tree["members"]["runs"]["members"]["dwell_094"]["members"]["channels"]["members"]["mic"]["attrs"]


@pytest.mark.parametrize(("edit", "match"), [
    (lambda t: t["members"].pop("rig"), r"^f\.h5: /: missing group or dataset 'rig'"),
    (lambda t: _chan_attrs(t).pop("quantity"),
     r"^f\.h5: /runs/dwell_094/channels/mic: missing attribute 'quantity'"),
    (lambda t: _chan_attrs(t).update(sample_rate=1.0),
     r"unexpected attribute 'sample_rate' \(extra attributes must start with 'x_'\)"),
    (lambda t: _chan_attrs(t).update(timestamps="t"),
     r"/runs/dwell_094/channels/mic: attributes do not fit \(a channel needs either sample_rate_hz"),
    (lambda t: _chan_attrs(t).pop("sensitivity"),
     r"missing attribute 'sensitivity' \(raw volts \(units 'V'\) need sensitivity"),
    (lambda t: t["attrs"].update(source="measured"),
     r"/: attribute 'source': 'synthetic' was expected \(a /truth group is only allowed"),
    (lambda t: t["members"]["rig"]["attrs"].update(edge_conditions="CFXF"),
     r"/rig: attribute 'edge_conditions': 'CFXF' does not match"),
    (lambda t: t["members"]["runs"]["members"].update(
        {"Run 1": t["members"]["runs"]["members"]["dwell_094"]}),
     r"/runs: invalid name 'Run 1' \(names and ids are 1-64 ASCII"),
])
def test_validate_tree_names_file_path_and_field(edit, match):
    tree = _tree()
    edit(tree)
    with pytest.raises(SchemaError, match=match):
        validate_tree(tree, "f.h5")


def test_validate_tree_reports_how_many_more_errors():
    tree = _tree()
    _chan_attrs(tree).pop("quantity")
    _chan_attrs(tree)["units"] = "dB"
    tree["members"]["rig"]["attrs"]["plate_length_m"] = -1.0
    with pytest.raises(SchemaError, match=r"\(and \d+ more schema errors\)$"):
        validate_tree(tree, "f.h5")


@settings(max_examples=30, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.lists(st.floats(-1e6, 1e6, width=32), min_size=1, max_size=300),
       fs_hz=st.floats(1.0, 1e6), start_s=st.floats(-10.0, 10.0),
       units=st.sampled_from(["m/s^2", "g", "V", "1"]), notes=st.text(max_size=50))
def test_round_trip_property(tmp_path, data, fs_hz, start_s, units, notes):
    sens = {"sensitivity": 10.0, "sensitivity_units": "mV/g"} if units == "V" else {}
    ch = Channel("acc", "plate_acceleration", units, np.asarray(data, dtype=np.float32),
                 sample_rate_hz=fs_hz, start_time_s=start_s, **sens)
    rec = Record("prop", "measured", Rig("other", description="property test"),
                 [Run("r", "transient", [ch], notes=notes)])
    path = write_record(tmp_path / "prop.h5", rec)
    with read(path) as back:
        assert back == rec
        np.testing.assert_array_equal(back.runs[0].channels[0].read(si=False), ch.read(si=False))
        np.testing.assert_array_equal(back.runs[0].channels[0].read(), ch.read())


# --- errors of the raw HDF5 layer, the code checks and the model objects -----------------------


def _edited(tmp_path, fn, record=None):
    path = write(tmp_path, record=record)
    with h5py.File(path, "a") as fh:
        fn(fh)
    return path


@pytest.mark.parametrize(("fn", "cls", "match"), [
    (lambda fh: fh["runs/dwell_094"].attrs.__setitem__("notes", h5py.Empty("f8")), SchemaError,
     r"/runs/dwell_094: attribute 'notes': has no value \(HDF5 empty dataspace\)"),
    (lambda fh: fh["rig"].attrs.__setitem__("x_pair", np.zeros(1, dtype=[("a", "f8"), ("b", "i4")])[0]),
     SchemaError, r"/rig: attribute 'x_pair': unsupported attribute type void"),
    (lambda fh: fh["runs/dwell_094"].attrs.__setitem__("notes", "y" * (1_048_576 + 1)), SchemaError,
     r"/runs/dwell_094: attribute 'notes': is 1048577 characters, over the limit of 1048576"),
    (lambda fh: fh.create_group("x_deep/" + "/".join("g" * 13)), SchemaError,
     r"rec\.h5: /x_deep/g/g/g/g/g/g/g/g/g/g/g/g: groups nested deeper than 12 levels"),
    (lambda fh: fh.__setitem__("x_link", h5py.SoftLink("/nowhere")), FileFormatError,
     r"rec\.h5: /x_link: cannot be read \(dangling soft or external link, or damaged file\)"),
    (lambda fh: fh.__setitem__("x_type", np.dtype("f8")), SchemaError,
     r"rec\.h5: /x_type: named datatypes are not part of the layout"),
    (lambda fh: fh["runs/dwell_094/channels/base"].attrs.__delitem__("range_max"), SchemaError,
     r"channels/base: attribute 'range_min': range_min and range_max go together"),
    (lambda fh: fh["runs/dwell_094/channels/base"].attrs.__setitem__("range_max", -10.0), SchemaError,
     r"channels/base: attribute 'range_max': must be > range_min \(-10\.0\), was -10\.0"),
])
def test_raw_layer_and_code_check_errors(tmp_path, fn, cls, match):
    path = _edited(tmp_path, fn)
    with pytest.raises(cls, match=match):
        read(path)


def test_timestamps_must_be_as_long_as_their_channel(tmp_path):
    t = np.arange(10) * 0.1
    ch = Channel("mic", "sound_pressure", "Pa", np.arange(9.0), timestamps="t")
    rec = Record("ts", "measured", Rig("other", description="x"), [Run("r", "transient", [ch],
                                                                      timestamps={"t": t})])
    with pytest.raises(SchemaError, match=r"/runs/r/channels/mic: attribute 'timestamps': "
                                          r"/runs/r/timestamps/t has shape \[10\], the channel \[9\]"):
        write_record(tmp_path / "ts.h5", rec)


def test_truth_impacts_must_belong_to_a_run(tmp_path):
    import dataclasses

    rec = make_record(synthetic=True)
    truth = dataclasses.replace(rec.truth, impacts={"ghost": rec.truth.impacts["dwell_094"]})
    with pytest.raises(SchemaError, match=r"/truth/impacts/ghost: group name: no run /runs/ghost"):
        write_record(tmp_path / "t.h5", dataclasses.replace(rec, truth=truth))


def test_attribute_read_failures_are_file_format_errors(tmp_path, monkeypatch):
    path = write(tmp_path)

    def boom(self, name):
        raise OSError("checksum error")

    monkeypatch.setattr(h5py._hl.attrs.AttributeManager, "__getitem__", boom)
    with pytest.raises(FileFormatError, match=r"rec\.h5: /: attribute 'schema': cannot be read: "
                                              r"checksum error"):
        read(path)
    monkeypatch.undo()
    from rattle_lab.records._h5 import read_attrs

    with h5py.File(path, "r") as fh:
        monkeypatch.setattr(h5py._hl.attrs.AttributeManager, "__getitem__", boom)
        with pytest.raises(FileFormatError, match=r"rec\.h5: /rig: attribute '\w+': cannot be read: "
                                                  r"checksum error"):
            read_attrs(fh["rig"], "rec.h5: /rig")


def test_h5_source_errors(tmp_path, monkeypatch):
    from rattle_lab.records._h5 import H5Handle, H5Source
    from rattle_lab.records._readers.native import load_group

    path = write(tmp_path)
    handle = H5Handle(path)
    with pytest.raises(SchemaError, match=r"rec\.h5: /runs: not a dataset"):
        H5Source(handle, "/runs")
    with pytest.raises(FileFormatError, match=r"rec\.h5: /nope: no such group"):
        load_group(path, "/nope")
    with read(path) as rec:
        mic = rec.run("dwell_094").channel("mic")

        def boom(self, sel):
            raise OSError("truncated")

        monkeypatch.setattr(h5py.Dataset, "__getitem__", boom)
        with pytest.raises(FileFormatError, match=r"rec\.h5: /runs/dwell_094/channels/mic: data "
                                                  r"'samples 0:10': cannot be read \(truncated file\?\)"):
            mic.read(0, 10)
    handle.close()


def test_model_argument_errors():
    from rattle_lab.exceptions import ParameterError
    from rattle_lab.records import ArrayData

    with pytest.raises(ParameterError, match=r"channel data must be 1-D, got shape \(2, 2\)"):
        ArrayData(np.zeros((2, 2)))
    with pytest.raises(ParameterError, match=r"`n_samples` must be >= 0, was -1"):
        GeneratedData(-1, np.float32, lambda a, b: np.zeros(b - a))
    bad = GeneratedData(10, np.float32, lambda a, b: np.zeros(3))
    with pytest.raises(ParameterError, match=r"generator returned shape \(3,\) for samples 0:10"):
        bad.read(0, 10)
    rec = make_record()
    run = rec.run("dwell_094")
    with pytest.raises(ParameterError, match=r"`start`:`stop` must lie in 0:4096, was 10:5"):
        run.channel("mic").read(10, 5)
    with pytest.raises(ParameterError, match=r"`n_chunk_samples` must be >= 1, was 0"):
        next(run.channel("mic").iter_chunks(0))
    with pytest.raises(ParameterError, match=r"run 'dwell_094' has no channel 'x' \(has: base, plate"):
        run.channel("x")
    with pytest.raises(ParameterError, match=r"campaign 'plate96' has no run 'x' \(has: dwell_094\)"):
        rec.run("x")


def test_missing_and_non_regular_inputs(tmp_path):
    with pytest.raises(FileFormatError, match=r"nope\.h5: no such file"):
        read(tmp_path / "nope.h5")
    with pytest.raises(FileFormatError, match=r": not a regular file"):
        read(tmp_path)
