"""UFF dataset 58: reading files from another tool, and ``rattle-lab export`` round trips.

The "other tool" file is written here with pyuff directly (not with our exporter), with
signals of known values; the round trip compares the exported and re-read samples with
the stored SI samples bit for bit (binary UFF 58 in double precision).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rattle_lab.exceptions import FileFormatError
from rattle_lab.store import open_stored_record, read_catalogue
from rattle_lab.records import Channel, Record, Run, detect_format, read, write_record

from record_factory import plate_rig, run_command

FS = 25600.0


def _foreign_uff(path) -> None:
    import pyuff

    t = np.arange(2048) / FS
    p = 0.3 * np.sin(2 * np.pi * 1000 * t)
    a = 9.0 * np.cos(2 * np.pi * 96 * t)
    sets = []
    for data, spec, node, name in ((p, 15, 7, "MIC"), (a, 12, 3, "ACC")):
        sets.append(pyuff.prepare_58(
            binary=0, func_type=1, rsp_node=node, rsp_dir=3, ref_node=0, ref_dir=0,
            rsp_ent_name=name, ref_ent_name="NONE", data=data, x=0.5 + t, id1="Test.Lab export",
            abscissa_spacing=1, abscissa_spec_data_type=17, ordinate_spec_data_type=spec,
            orddenom_spec_data_type=0))
    freq = np.arange(1, 11, dtype=float)
    sets.append(pyuff.prepare_58(  # an FRF: not a time signal, must be skipped
        binary=0, func_type=4, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, rsp_ent_name="FRF",
        ref_ent_name="NONE", data=freq * (1 + 1j), x=freq, abscissa_spacing=1,
        abscissa_spec_data_type=18, ordinate_spec_data_type=12, orddenom_spec_data_type=13))
    pyuff.UFF(str(path)).write_sets(sets, mode="add")


def test_read_uff_from_another_tool(tmp_path):
    path = tmp_path / "testlab.uff"
    _foreign_uff(path)
    assert detect_format(path) == "uff"
    with read(path) as rec:
        (run,) = rec.runs
        assert run.run_id == "uff" and run.protocol == "unspecified"
        by_q = {c.quantity: c for c in run.channels}
        mic, acc = by_q["sound_pressure"], by_q["plate_acceleration"]
        assert mic.name == "MIC_7_3" and mic.units == "Pa" and acc.units == "m/s^2"
        assert mic.sample_rate_hz == pytest.approx(FS, rel=1e-9)
        assert mic.start_time_s == pytest.approx(0.5)
        t = np.arange(2048) / FS
        # ASCII UFF keeps 13 significant digits (E13.5 / E20.12 fields): 1e-9 relative
        assert np.allclose(mic.read(), 0.3 * np.sin(2 * np.pi * 1000 * t), rtol=0, atol=1e-9)
        assert np.allclose(acc.read(), 9.0 * np.cos(2 * np.pi * 96 * t), rtol=0, atol=1e-8)
        assert [s.source for s in rec.origin.skipped] == ["dataset 2"]


def test_malformed_uff_is_a_file_format_error(tmp_path):
    path = tmp_path / "bad.uff"
    path.write_bytes(b"    -1\n    58\nthis is not a dataset 58\n")
    with pytest.raises(FileFormatError, match="bad.uff"):
        read(path)


def _record() -> Record:
    n = 8192
    t = np.arange(n) / FS
    rng = np.random.default_rng(11)
    common = dict(sample_rate_hz=FS, start_time_s=0.0)
    run = Run("dwell_096", "sine_dwell", (
        Channel("velocity", "plate_velocity", "m/s", 1e-3 * np.sin(2 * np.pi * 96 * t), **common),
        Channel("mic", "sound_pressure", "V", 0.05 * (0.2 * np.sin(2 * np.pi * 800 * t)
                                                      + 0.01 * rng.standard_normal(n)),
                sensitivity=50.0, sensitivity_units="mV/Pa", **common)),
        excitation_freq_hz=96.0, nominal_level=3.0, nominal_level_units="m/s^2",
        start_time_iso="2024-03-01T14:10:00Z")
    return Record("uffcamp", "measured", plate_rig(), (run,))


def test_export_round_trip_and_ingest_of_the_export(tmp_path):
    src = write_record(tmp_path / "rec.h5", _record())
    store = tmp_path / "store.h5"
    assert run_command("ingest", str(src), "-o", str(store), "--quiet").returncode == 0
    fitted = run_command("fit", str(store), "--json", "--quiet")
    assert fitted.returncode == 0, fitted.stderr
    bands = json.loads(fitted.stdout)["runs"][0]["acoustics"]["third_octave_db"]
    out = tmp_path / "runs.uff"
    proc = run_command("export", str(store), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == str(out) and "UFF 58 datasets" in proc.stderr

    key = str(read_catalogue(store, level="runs")["input_key"].iloc[0])
    stored = open_stored_record(store, key)
    try:
        expected = {c.name: c.read().astype(float) for c in stored.run("dwell_096").channels}
    finally:
        stored.close()
    with read(out) as rec:
        assert rec.campaign_id == "uffcamp"
        run = rec.run("dwell_096")
        assert (run.protocol, run.excitation_freq_hz, run.nominal_level, run.nominal_level_units,
                run.start_time_iso) == ("sine_dwell", 96.0, 3.0, "m/s^2", "2024-03-01T14:10:00Z")
        for ch in run.channels:
            assert np.array_equal(ch.read(), expected[ch.name])  # binary doubles: exact
        assert {c.quantity for c in run.channels} == {"plate_velocity", "sound_pressure"}
    # the fitted third-octave spectrum is in the file as band RMS pressures
    import pyuff

    sets = pyuff.UFF(str(out)).read_sets()
    (spec,) = [s for s in sets if "result=third_octave" in s["id2"]]
    got = dict(zip(np.round(spec["x"], 3), 20 * np.log10(spec["data"] / 20e-6)))
    for label, db in bands.items():
        assert got[round(float(label), 3)] == pytest.approx(db, abs=1e-9)
    # and the export is an input format: it ingests into a new store
    store2 = tmp_path / "store2.h5"
    proc = run_command("ingest", str(out), "-o", str(store2), "--quiet")
    assert proc.returncode == 0, proc.stderr


def test_export_of_a_non_store_is_one_line_exit_2(tmp_path):
    bogus = tmp_path / "x.h5"
    bogus.write_bytes(b"not hdf5")
    proc = run_command("export", str(bogus), "-o", str(tmp_path / "o.uff"))
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert not (tmp_path / "o.uff").exists()
