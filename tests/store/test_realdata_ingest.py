"""Real records measured by others (see ``shared/realdata/README.md``), ingested through the readers.

The files are read in place (never copied into the repository); the tests skip when the folder
is absent.  ``RATTLE_LAB_REALDATA`` points elsewhere.  The mappings used are the documented ones
in ``data_schema/mappings/``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import realdata

from rattle_lab.store import ingest, open_stored_record, read_catalogue
from rattle_lab.records import UncalibratedWarning, read

REPO = Path(__file__).resolve().parents[2]
MAPPINGS = REPO / "data_schema" / "mappings"


def _unchanged(path: Path):
    return path.stat().st_mtime_ns, path.stat().st_size


def test_droptable_lvm_through_its_mapping(tmp_path):
    """Source: High-Rate-SHM-Working-Group/Dataset-5-Extended-Impact-Testing,
    data/dataset-2/data-1/Test_001.lvm (Downey et al. 2022), CC BY-SA 4.0."""
    lvm = realdata("droptable/Test_001.lvm")
    before = _unchanged(lvm)
    store = tmp_path / "store.h5"
    report = ingest([lvm], store, mapping=MAPPINGS / "droptable_lvm.toml")
    assert _unchanged(lvm) == before
    [result] = report.inputs
    assert result.format == "lvm" and result.findings == ()
    assert [(s.source, s.reason) for s in result.skipped] == [
        (f"Untitled{suffix}", "impedance value with 5 samples, not a time series")
        for suffix in ("", " 1", " 2", " 3")]
    cat = read_catalogue(store)
    assert list(cat["channel"]) == ["table", "board"]
    assert list(cat["units"]) == ["m/s^2", "m/s^2"]
    assert list(cat["sample_rate_hz"]) == [51200.0, 51200.0]  # 1 / Delta_X (1.953125E-5)
    assert list(cat["n_samples"]) == [51200, 51200] and list(cat["flags"]) == ["", ""]
    assert set(cat["run_start_iso"]) == {"2023-05-05T13:39:50.887019931"}
    with open_stored_record(store, result.input_key) as rec:
        table = rec.run("shock").channel("table").read()
        board = rec.run("shock").channel("board").read()
    assert table[:3].tolist() == [2.525674, 1.069960, 0.569558]  # the file's first rows
    # README: one shock at about 0.09 s; the board responds after the table.
    t_table, t_board = np.argmax(np.abs(table)) / 51200, np.argmax(np.abs(board)) / 51200
    assert 0.085 < t_table < 0.095 and t_table < t_board < t_table + 0.002


def test_hammer_npy_through_its_mapping(tmp_path):
    """Source: ladisk/pyFRF at commit 55431fd, data/measurements_1.npy (LGPL-3.0 at that commit,
    MIT now)."""
    npy = realdata("hammer/measurements_1.npy")
    before = _unchanged(npy)
    store = tmp_path / "store.h5"
    with pytest.warns(UncalibratedWarning, match=r"channels/(force|response): units: units_assumed: "
                                                 r"units '(N|m/s\^2)' were assumed by the mapping"):
        report = ingest([npy], store, mapping=MAPPINGS / "hammer_npy.toml")
    assert _unchanged(npy) == before
    cat = read_catalogue(store)
    assert list(cat["channel"]) == ["force", "response"]
    assert list(cat["timing"]) == ["timestamps", "timestamps"]
    assert list(cat["flags"]) == ["units_assumed", "units_assumed"]
    # The time row steps by 1/25600 s (to 1e-14 s): the mean rate is 25.6 kHz.
    assert cat["sample_rate_hz"].tolist() == pytest.approx([25600.0, 25600.0], rel=1e-9)
    with open_stored_record(store, report.inputs[0].input_key) as rec:
        run = rec.run("hit")
        t = run.timestamps["t"].read(0, 25600)
        force = run.channel("force").read()
    raw = np.load(npy)
    np.testing.assert_array_equal(force, raw[1])
    assert 0.0005 < t[np.argmax(force)] < 0.0012  # README: one hammer hit near 0.85 ms


def test_clap_wav_is_flagged_uncalibrated(tmp_path):
    """Source: spatialaudio/selected-topics-in-audio-signal-processing-exercises,
    data/rir_clap.wav, CC0 1.0."""
    wav = realdata("clap/rir_clap.wav")
    before = _unchanged(wav)
    store = tmp_path / "store.h5"
    with pytest.warns(UncalibratedWarning, match=r"rir_clap\.wav: /runs/wav/channels/mic: units: "
                                                 r"uncalibrated: amplitude in full-scale units '1'"):
        report = ingest([wav], store)
    assert _unchanged(wav) == before
    [row] = read_catalogue(store).to_dict(orient="records")
    assert (row["quantity"], row["units"], row["flags"]) == ("sound_pressure", "1", "uncalibrated")
    assert (row["sample_rate_hz"], row["n_samples"]) == (44100.0, 44100)
    assert -1.0 <= row["min_si"] < 0 < row["max_si"] < 1.0
    with open_stored_record(store, report.inputs[0].input_key) as rec:
        x = rec.run("wav").channel("mic").read()
    assert np.argmax(np.abs(x)) / 44100 < 0.01  # README: the impact is near t = 0


def test_clap_wav_with_the_documented_mapping(tmp_path):
    """Source: spatialaudio/selected-topics-in-audio-signal-processing-exercises,
    data/rir_clap.wav, CC0 1.0."""
    wav = realdata("clap/rir_clap.wav")
    with read(wav, mapping=MAPPINGS / "clap_wav.toml") as rec:
        mic = rec.run("clap").channel("mic")
        assert rec.campaign_id == "clap-rir_clap" and mic.uncalibrated and mic.units == "1"


def test_all_three_in_one_store(tmp_path):
    """Sources: the three records above (droptable, hammer, clap; see shared/realdata/README.md)."""
    files = [realdata("clap/rir_clap.wav")]
    store = tmp_path / "store.h5"
    with pytest.warns(UncalibratedWarning):
        ingest(files, store)
    ingest([realdata("droptable/Test_001.lvm")], store, mapping=MAPPINGS / "droptable_lvm.toml")
    runs = read_catalogue(store, level="runs")
    assert list(runs["run_id"]) == ["wav", "shock"]
    assert list(runs["flags"]) == ["uncalibrated", ""]
