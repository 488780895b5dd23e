"""``rattle-lab ingest`` through the installed entry point."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from record_factory import RATTLE_LAB, make_record, replace_channel, run_cli, write

from rattle_lab.store import read_catalogue

LVM = ("LabVIEW Measurement\t\nSeparator\tTab\nDecimal_Separator\t.\nX_Columns\tOne\n"
       "***End_of_Header***\t\n\nChannels\t2\t\t\nSamples\t400\t3\t\nY_Unit_Label\tm/s^2\t\t\n"
       "X0\t0\t0\t\nDelta_X\t0.0005\t1\t\n***End_of_Header***\t\t\t\nX_Value\tacc\timpedance\tComment\n")
LVM_MAPPING = """
[mapping]
version = 1
[campaign]
campaign_id = "lvm-{stem}"
[rig]
apparatus = "other"
description = "a test table"
[[runs]]
run_id = "shock"
protocol = "transient"
[[runs.channels]]
name = "acc"
source = "acc"
quantity = "base_acceleration"
"""


def test_the_entry_point_is_installed_and_lists_ingest():
    assert RATTLE_LAB.is_file()
    proc = run_cli("--help")
    assert proc.returncode == 0 and "ingest" in proc.stdout


def test_table_output_and_clean_stderr(tmp_path):
    src = write(tmp_path)
    store = tmp_path / "store.h5"
    proc = run_cli("ingest", str(src), "-o", str(store))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""  # no progress bar without a terminal, no warnings for clean data
    lines = proc.stdout.splitlines()
    assert lines[0].split() == ["campaign_id", "run_id", "protocol", "channel", "quantity", "units",
                                "sample_rate_hz", "n_samples", "duration_s", "flags"]
    assert lines[2].split() == ["plate96", "dwell_094", "sine_dwell", "base", "base_acceleration",
                                "m/s^2", "51200", "4096", "0.08", "-"]
    assert lines[-1] == f"{store}: 1 added, 0 unchanged"
    assert len(read_catalogue(store)) == 5


def test_json_output_and_rerun_is_unchanged(tmp_path):
    src = write(tmp_path)
    store = tmp_path / "store.h5"
    first = run_cli("ingest", str(src), "-o", str(store), "--json", "--quiet")
    assert first.returncode == 0 and first.stderr == ""
    doc = json.loads(first.stdout)
    assert doc["changed"] is True and doc["inputs"][0]["status"] == "added"
    assert [row["channel"] for row in doc["catalogue"]] == ["base", "plate", "velocity", "mic", "drive"]
    assert doc["catalogue"][0]["excitation_freq_hz"] == 94.0
    stamp = store.stat().st_mtime_ns
    again = json.loads(run_cli("ingest", str(src), "-o", str(store), "--json").stdout)
    assert again["changed"] is False and again["inputs"][0]["status"] == "unchanged"
    assert store.stat().st_mtime_ns == stamp


@pytest.mark.slow  # > 8 s (measured under load)
def test_copy_flag_and_a_moved_input(tmp_path):
    src = write(tmp_path)
    store = tmp_path / "store.h5"
    linked = json.loads(run_cli("ingest", str(src), "-o", str(store), "--json").stdout)
    assert {row["storage"] for row in linked["catalogue"]} == {"link"}
    assert linked["inputs"][0]["file_hash"].startswith("xxh3_128:")
    other = tmp_path / "other.h5"
    shutil.copyfile(store, other)  # a second linked store (the bytes `ingest` wrote), kept linked
    copied = run_cli("ingest", str(src), "-o", str(store), "--copy")
    assert copied.returncode == 0, copied.stderr
    assert copied.stdout.splitlines()[-1] == f"{store}: 0 added, 1 updated, 0 unchanged"
    assert set(read_catalogue(store)["storage"]) == {"copy"}
    # a store whose linked input has gone: `fit` says so in one line, exit 2
    assert set(read_catalogue(other)["storage"]) == {"link"}
    src.unlink()
    proc = run_cli("fit", str(other))
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1
    assert "rec.h5 is missing; ingest it again to re-link it" in proc.stderr
    assert run_cli("fit", str(store)).returncode == 0  # the copied store stands alone


def test_allow_flagged_warns_on_stderr_and_flags_in_json(tmp_path):
    rec = make_record()
    mic = rec.runs[0].channel("mic").read(si=False).copy()
    mic[10] = np.nan
    src = write(tmp_path, record=replace_channel(rec, "dwell_094", "mic", data=mic))
    store = tmp_path / "store.h5"
    refused = run_cli("ingest", str(src), "-o", str(store))
    assert refused.returncode == 2 and not store.exists()
    assert refused.stderr.startswith("rattle-lab: error: ") and "--allow-flagged" in refused.stderr
    proc = run_cli("ingest", str(src), "-o", str(store), "--allow-flagged", "--json")
    assert proc.returncode == 0
    assert proc.stderr.splitlines() == [
        f"rattle-lab: warning: NaNGapWarning: {src}: /runs/dwell_094/channels/mic: data: nan: "
        "1 NaN sample(s) in 1 run(s), first at sample 10"]
    doc = json.loads(proc.stdout)
    [finding] = doc["inputs"][0]["findings"]
    assert (finding["flag"], finding["sample_index"], finding["fatal"]) == ("nan", 10, True)
    assert {row["channel"]: row["flags"] for row in doc["catalogue"]}["mic"] == "nan"


def test_mapping_option_and_skipped_columns(tmp_path):
    rows = [f"{k * 0.0005:.4f}\t{np.sin(k * 0.05) + 1e-4 * k:.6f}" + (f"\t{k + 1}" if k < 3 else "")
            for k in range(400)]
    lvm = tmp_path / "table.lvm"
    lvm.write_text(LVM + "\n".join(rows) + "\n")
    mapping = tmp_path / "table.toml"
    mapping.write_text(LVM_MAPPING)
    store = tmp_path / "store.h5"
    proc = run_cli("ingest", str(lvm), "-o", str(store), "--mapping", str(mapping))
    assert proc.returncode == 0, proc.stderr
    assert "  skipped impedance: not in the mapping (3 samples, Delta_X 1)" in proc.stdout.splitlines()
    assert "lvm-table" in proc.stdout and "2000" in proc.stdout
    doc = json.loads(run_cli("ingest", str(lvm), "-o", str(store), "--mapping", str(mapping),
                             "--json").stdout)
    assert doc["inputs"][0]["status"] == "unchanged"


def test_missing_output_option_is_a_usage_error(tmp_path):
    proc = run_cli("ingest", str(write(tmp_path)))
    assert proc.returncode == 2 and "-o/--output" in proc.stderr


def test_progress_bar_on_a_terminal_only(tmp_path):
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import termios

    src = write(tmp_path)
    leader, follower = pty.openpty()
    # A new pty is 0 columns wide, and tqdm draws nothing in no room: give it 80.
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    try:
        proc = subprocess.run([str(RATTLE_LAB), "ingest", str(src), "-o", str(tmp_path / "s.h5")],
                              stdout=subprocess.PIPE, stderr=follower, timeout=120)
        os.close(follower)
        follower = -1
        drawn = b""
        while True:
            try:
                chunk = os.read(leader, 65536)
            except OSError:  # the terminal closed
                break
            if not chunk:
                break
            drawn += chunk
    finally:
        if follower != -1:
            os.close(follower)
        os.close(leader)
    assert proc.returncode == 0
    assert b"rec.h5" in drawn and b"samples" in drawn  # tqdm drew a bar on the terminal
    quiet = run_cli("ingest", str(src), "-o", str(tmp_path / "q.h5"), "--quiet")
    assert quiet.returncode == 0 and quiet.stderr == ""
