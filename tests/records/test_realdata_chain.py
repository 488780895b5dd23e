"""Issue 15, part B: real records through ``rattle-lab ingest`` and ``fit`` with default settings.

Sources (../shared/realdata, see its README; not ours, not committed):
- droptable/Test_001.lvm: High-Rate-SHM-Working-Group/Dataset-5-Extended-Impact-Testing,
  data/dataset-2/data-1/Test_001.lvm (Downey et al. 2022), CC BY-SA 4.0.
- hammer/measurements_1.npy: ladisk/pyFRF at commit 55431fd, data/measurements_1.npy
  (LGPL-3.0 then, MIT now).
- forced_shock/vibration_0.2.lvm: High-Rate-SHM-Working-Group/Dataset-7-forced-vibration-
  and-shock at commit 81e7be7, data/testset-B/amplitude_3/Impact_1/vibration_0.2.lvm,
  CC BY-SA 4.0.

The onset references are independent of the detector.  Drop table: the first sample after
the quiet stretch whose excursion from the baseline exceeds the largest excursion of the
quiet stretch (the signal has left its noise band), and the first that exceeds twice it
(it certainly has).  Hammer: fractions of the pulse's peak (see the test).  The detected
onset must lie in between.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import realdata

from rattle_lab.records import read
from rattle_lab.records._readers.lvm import LvmHeaderWarning, parse_lvm
from record_factory import run_command

ROOT = Path(__file__).resolve().parents[2]
MAPPINGS = ROOT / "data_schema" / "mappings"



def _bracket(x: np.ndarray, fs: float, t0: float, quiet: slice, after: int) -> tuple[float, float]:
    dev = x - np.median(x[quiet])
    m = np.abs(dev[quiet]).max()
    k1 = after + int(np.argmax(np.abs(dev[after:]) > m))
    k2 = after + int(np.argmax(np.abs(dev[after:]) > 2 * m))
    return t0 + k1 / fs, t0 + k2 / fs


def _fit(store: Path, *extra: str) -> dict:
    proc = run_command("fit", str(store), "--json", "--quiet", *extra)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


def test_droptable_one_shock_per_channel_at_its_onset(tmp_path):
    lvm = realdata("droptable/Test_001.lvm")
    store = tmp_path / "drop.h5"
    proc = run_command("ingest", str(lvm), "--mapping", str(MAPPINGS / "droptable_lvm.toml"),
                   "-o", str(store))
    assert proc.returncode == 0, proc.stderr
    out = _fit(store)
    assert [r["n_impacts"] for r in out["runs"]] == [1]          # one event, not its ringing
    assert out["runs"][0]["pattern"] == "single shock"
    rows = {c["channel"]: c for c in out["transients"][0]["channels"]}
    assert rows["table"]["role"] == "cause"                      # the base is the cause
    assert rows["board"]["role"] == "response"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = read(lvm, mapping=MAPPINGS / "droptable_lvm.toml").runs[0]
    for name in ("table", "board"):
        ch = run.channel(name)
        fs = ch.sample_rate_hz
        lo, hi = _bracket(ch.read(), fs, ch.start_time_s, slice(0, int(0.08 * fs)),
                          int(0.08 * fs))
        assert rows[name]["found"]
        assert lo - 0.5 / fs <= rows[name]["onset_s"] <= hi, name
    # the board answers the table within a millisecond (README: base-to-board delay)
    assert 0.0 <= rows["board"]["delay_s"] < 1e-3
    # the table: no rattle fits are attempted on a store of single shocks
    table = run_command("fit", str(store), "--quiet").stdout
    assert "transient records only (single shocks)" in table and "not fitted" not in table
    assert "participation" not in table


def test_hammer_folder_detects_on_the_force_and_pairs_the_response(tmp_path):
    npy = realdata("hammer/measurements_1.npy")
    hits = tmp_path / "hits"
    hits.mkdir()
    data = np.load(npy)
    for k in (1, 2):                       # a folder of hits: two files, two campaigns
        scaled = data.copy()
        scaled[1:] *= 1.0 + 0.1 * k
        np.save(hits / f"hit_{k:02d}.npy", scaled)
    store = tmp_path / "hammer.h5"
    proc = run_command("ingest", *sorted(str(p) for p in hits.iterdir()), "--mapping",
                   str(MAPPINGS / "hammer_npy.toml"), "-o", str(store))
    assert proc.returncode == 0, proc.stderr          # no "run id already ingested"
    out = _fit(store)
    assert len(out["transients"]) == 2
    t = data[0]
    fs = 1.0 / float(np.median(np.diff(t)))
    # The force rises within two samples from 1 % to 50 % of its 69 N peak; before it the
    # ADC's linear-phase anti-alias filter pre-rings at the Nyquist frequency (0.1-0.3 N of
    # alternating sign), which is no force.  Reference: the onset lies between the last
    # sample below 1 % of the peak and the first above 10 %.
    f = data[1] - np.median(data[1])
    pk = int(np.argmax(np.abs(f)))
    below = np.flatnonzero(np.abs(f[:pk]) < 0.01 * abs(f[pk]))[-1]
    above = np.flatnonzero(np.abs(f[:pk + 1]) > 0.10 * abs(f[pk]))[0]
    lo, hi = float(t[below]), float(t[above])
    for tr in out["transients"]:
        force, resp = tr["channels"]
        assert (force["channel"], force["role"]) == ("force", "cause")
        assert lo - 0.5 / fs <= force["onset_s"] <= hi
        assert force["peak_s"] == pytest.approx(0.85e-3, abs=0.1e-3)   # README: near 0.85 ms
        assert resp["role"] == "response"
        assert 0.0 <= resp["delay_s"] < 0.2e-3                         # response after its cause
    # the channel to detect on can be chosen on the command line
    chosen = _fit(store, "--detect-channel", "response")
    assert chosen["transients"][0]["channels"][0]["channel"] == "response"


def test_forced_shock_lvm_without_x_column_reads():
    lvm = realdata("forced_shock/vibration_0.2.lvm")
    parsed = parse_lvm(lvm)
    names = [c.name for c in parsed.channels]
    # X_Columns No, but an empty first field under X_Value on every row: nothing shifts
    assert names == ["time", "excitation_vibration", "excitation_shock", "excitation_composite",
                     "accelerometer_base", "accelerometer_board"]
    sizes = {c.name: c.values.size for c in parsed.channels}
    assert sizes["time"] == 12376 and sizes["excitation_shock"] == 13216
    assert sizes["accelerometer_board"] == 12375
    shock = next(c for c in parsed.channels if c.name == "excitation_shock").values
    assert int(np.argmax(shock)) == 6600 and shock.max() == 1.0          # README: peak at 6600
    # (a Gaussian pulse: above 1 % of its peak from sample ~6350 to ~6850, as the README says)
    nz = np.flatnonzero(shock > 0.01)
    assert abs(nz[0] - 6350) <= 5 and abs(nz[-1] - 6850) <= 5
    time = next(c for c in parsed.channels if c.name == "time").values
    assert time[1] == pytest.approx(0.000605)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = read(lvm, mapping=MAPPINGS / "forced_shock_lvm.toml")
    run = rec.runs[0]
    assert run.channel("board").uncalibrated and run.channel("board").units == "1"
    # the two clocks the header declares are kept, each channel its own
    assert run.channel("shock_command").sample_rate_hz == pytest.approx(1 / 0.000606)
    assert run.channel("board").sample_rate_hz == pytest.approx(1 / 0.000586)


def test_forced_shock_one_shock_per_accelerometer_none_in_the_sine(tmp_path):
    """A 5 Hz shaker sine with one shock pulse added (the commanded pulse is the truth).

    With default settings: exactly one shock on each accelerometer (base, board), none in
    the commanded sine.  Before the steady sine was taken off, the sine was the noise
    floor and neither accelerometer's shock (about twice the sine) was found.  Timing
    reference, independent of the detector: the commanded pulse, from its first sample
    above 0.1 % of its peak (sample 6294) to its peak (6600).  The file's two Delta_X
    disagree by 3.4 % (0.1 s at 4 s), so the comparison is in samples of one acquisition.
    """
    lvm = realdata("forced_shock/vibration_0.2.lvm")
    store = tmp_path / "forced.h5"
    # the quality scan flags the commanded pulse's exact zeros as clipping (and the two
    # clocks): ingested with the flags kept
    proc = run_command("ingest", str(lvm), "--mapping", str(MAPPINGS / "forced_shock_lvm.toml"),
                   "-o", str(store), "--allow-flagged")
    assert proc.returncode == 0, proc.stderr
    out = _fit(store)
    assert [r["n_impacts"] for r in out["runs"]] == [1]
    assert out["runs"][0]["pattern"] == "single shock"
    channels = out["transients"][0]["channels"]
    rows = {c["channel"]: c for c in channels}
    # issue 27: the commanded pulse (a drive channel) is the cause, listed first; the base
    # accelerometer responds to it
    assert channels[0]["channel"] == "shock_command" and rows["shock_command"]["role"] == "cause"
    assert rows["base"]["role"] == "response" and rows["board"]["role"] == "response"
    assert rows["base"]["found"] and rows["board"]["found"]
    assert not rows["sine_command"]["found"]                     # nothing in the sine
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = read(lvm, mapping=MAPPINGS / "forced_shock_lvm.toml").runs[0]
    cmd = run.channel("shock_command").read()
    lo = int(np.flatnonzero(cmd > 1e-3 * cmd.max())[0])
    hi = int(np.argmax(cmd))
    for name in ("base", "board"):
        ch = run.channel(name)
        k_onset = (rows[name]["onset_s"] - ch.start_time_s) * ch.sample_rate_hz
        assert lo <= k_onset <= hi, (name, k_onset)
        assert rows[name]["onset_sample"] == round(k_onset)
    # the pulse rests at exactly zero: its onset is the rise through 0.1 % of its peak, not
    # the first denormal of its tail (sample 3416, values of 5e-324), and it precedes its peak
    assert rows["shock_command"]["onset_sample"] == lo and rows["shock_command"]["peak_sample"] == hi
    # two clocks (Delta_X 0.000606 s and 0.000586 s): named; across them the delay is given in
    # samples, never in seconds
    assert rows["shock_command"]["clock"] != rows["base"]["clock"] == rows["board"]["clock"]
    assert rows["base"]["delay_samples"] == rows["base"]["onset_sample"] - lo
    assert rows["base"]["delay_s"] is None or not np.isfinite(rows["base"]["delay_s"])
    # one shock, not a train: the board answers the base within 20 samples of their clock
    assert 0 <= rows["board"]["onset_sample"] - rows["base"]["onset_sample"] < 20


def test_unknown_lvm_header_fields_warn(tmp_path):
    text = ("LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\nX_Columns\tOne\n"
            "Shaker_Serial\tXY-1\n***End_of_Header***\t\n\nChannels\t1\t\nSamples\t2\t\n"
            "Delta_X\t0.001\t\nGain_Setting\t3\t\n***End_of_Header***\t\t\nX_Value\ta\tComment\n"
            "0\t1.0\n0.001\t2.0\n")
    path = tmp_path / "extra.lvm"
    path.write_text(text)
    with pytest.warns(LvmHeaderWarning) as caught:
        parsed = parse_lvm(path)
    messages = [str(w.message) for w in caught]
    assert any("file header: field 'Shaker_Serial' not defined" in m for m in messages)
    assert any("segment 0 header: field 'Gain_Setting' not defined" in m for m in messages)
    assert parsed.channels[0].values.tolist() == [1.0, 2.0]
