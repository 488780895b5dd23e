"""Issue 15: one run that ramps up then down is read (and ingested) as its up and down parts.

The files are written by hand with h5py.  The drive is a sine whose amplitude (or frequency)
rises linearly to a peak and falls linearly; the turn found on it is checked against the
time the drive was built with.
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from rattle_lab.exceptions import SchemaError
from rattle_lab.records import read
from record_factory import run_command

FS_DRIVE_HZ = 5000.0
FS_VEL_HZ = 8000.0
T_UP_S, T_DOWN_S = 2.0, 1.2
F_HZ = 96.0


def _drive(kind: str) -> np.ndarray:
    t = np.arange(int((T_UP_S + T_DOWN_S) * FS_DRIVE_HZ)) / FS_DRIVE_HZ
    tent = np.where(t < T_UP_S, t / T_UP_S, 1.0 - (t - T_UP_S) / T_DOWN_S)   # 0 -> 1 -> 0
    if kind == "amplitude":
        return (0.2 + 0.8 * tent) * np.sin(2 * np.pi * F_HZ * t)
    f = 60.0 + 80.0 * tent                                   # 60 -> 140 -> 60 Hz
    return 0.5 * np.sin(2 * np.pi * np.cumsum(f) / FS_DRIVE_HZ)


def _write(path, kind: str = "amplitude", *, turn_time_s: float | None = None,
           drive: bool = True, version: int = 2, fs_vel_hz: float = FS_VEL_HZ):
    n_vel = int((T_UP_S + T_DOWN_S) * fs_vel_hz) - 40
    with h5py.File(path, "w") as fh:
        fh.attrs.update(schema="rattle_record", schema_version=version, campaign_id="updown",
                        source="measured", description="hand-written up-down run")
        fh.create_group("rig").attrs.update(apparatus="other", description="a bench")
        run = fh.create_group("runs/r1")
        attrs = dict(excitation_freq_hz=F_HZ if kind == "amplitude" else 60.0, nominal_level=1.0,
                     nominal_level_units="m/s^2", start_time_iso="2024-03-01T14:10:00Z")
        if kind == "amplitude":
            attrs.update(protocol="amplitude_ramp_up_down", level_peak=5.0, level_end=1.0)
        else:
            attrs.update(protocol="swept_frequency_up_down", freq_peak_hz=140.0, freq_end_hz=60.0)
        if turn_time_s is not None:
            attrs["turn_time_s"] = turn_time_s
        run.attrs.update(attrs)
        ch = run.create_group("channels")
        if drive:
            d = ch.create_dataset("drive", data=_drive(kind))
            d.attrs.update(quantity="drive_signal", units="V", sample_rate_hz=FS_DRIVE_HZ,
                           start_time_s=0.0)
        v = ch.create_dataset("velocity", data=np.arange(n_vel, dtype="f8"))  # value = index
        v.attrs.update(quantity="plate_velocity", units="m/s", sample_rate_hz=fs_vel_hz,
                       start_time_s=0.005)
    return path


@pytest.mark.parametrize("kind", ["amplitude", "frequency"])
def test_turn_found_on_the_drive_and_every_channel_cut_there(tmp_path, kind):
    rec = read(_write(tmp_path / f"{kind}.h5", kind))
    assert [r.run_id for r in rec.runs] == ["r1_up", "r1_down"]
    up, down = rec.runs
    turn = up.extra["x_turn_time_s"]
    # Tolerance: one block of the drive's envelope is 8 forcing periods (83 ms at 96 Hz);
    # the two fitted lines place the turn to a small part of a block.  Half a forcing period
    # of the lowest frequency (5.2 ms at 96 Hz, 8.3 ms at 60 Hz) is asked.
    f_low = F_HZ if kind == "amplitude" else 60.0
    assert turn == pytest.approx(T_UP_S, abs=0.5 / f_low)
    if kind == "amplitude":
        assert (up.protocol, up.nominal_level, up.level_end) == ("amplitude_ramp_up", 1.0, 5.0)
        assert (down.protocol, down.nominal_level, down.level_end) == ("amplitude_ramp_down",
                                                                       5.0, 1.0)
    else:
        assert (up.protocol, up.excitation_freq_hz, up.freq_end_hz) == ("swept_frequency",
                                                                        60.0, 140.0)
        assert (down.excitation_freq_hz, down.freq_end_hz) == (140.0, 60.0)
    # each channel cut at its own first sample at or after the turn, on its own clock
    for name, fs, t0 in (("drive", FS_DRIVE_HZ, 0.0), ("velocity", FS_VEL_HZ, 0.005)):
        cu = next(c for c in up.channels if c.name == name)
        cd = next(c for c in down.channels if c.name == name)
        k = int(np.ceil((turn - t0) * fs - 1e-9))
        assert cu.n_samples == k
        assert cd.start_time_s == pytest.approx(t0 + k / fs, abs=1e-12)
        assert cd.start_time_s >= turn > cd.start_time_s - 1.0 / fs
        assert cu.n_samples + cd.n_samples == int(np.round(
            (T_UP_S + T_DOWN_S) * fs)) - (40 if name == "velocity" else 0)
    vel_down = next(c for c in down.channels if c.name == "velocity").read()
    assert vel_down[0] == next(c for c in up.channels if c.name == "velocity").n_samples


def test_declared_turn_time_is_used(tmp_path):
    rec = read(_write(tmp_path / "t.h5", turn_time_s=1.5, drive=False))
    up, down = rec.runs
    vel = next(c for c in up.channels if c.name == "velocity")
    assert vel.n_samples == int(np.ceil((1.5 - 0.005) * FS_VEL_HZ))
    assert up.extra["x_turn_time_s"] == 1.5


@pytest.mark.parametrize("kwargs, match", [
    ({"drive": False}, "needs the time of its turn, or a drive_signal"),
    ({"turn_time_s": 9.0}, "is not inside the channel"),
    ({"version": 1}, "needs schema_version 2"),
])
def test_an_up_down_run_that_cannot_be_split_is_refused(tmp_path, kwargs, match):
    with pytest.raises(SchemaError, match=match) as info:
        read(_write(tmp_path / "bad.h5", **kwargs))
    assert "bad.h5" in str(info.value) and "/runs/r1" in str(info.value)


def test_ingest_stores_the_up_and_down_runs(tmp_path):
    store = tmp_path / "store.h5"
    # (ingest refuses channels of one run at different rates: one rate here)
    proc = run_command("ingest", str(_write(tmp_path / "a.h5", fs_vel_hz=FS_DRIVE_HZ)), "-o",
                   str(store))
    assert proc.returncode == 0, proc.stderr
    from rattle_lab.store import read_catalogue
    runs = read_catalogue(store, level="runs")
    got = dict(zip(runs["run_id"], runs["protocol"]))
    assert got == {"r1_up": "amplitude_ramp_up", "r1_down": "amplitude_ramp_down"}
    # the stored record reads back as the two parts, with the original's samples
    from rattle_lab.store import open_stored_record
    rec = open_stored_record(store, str(runs["input_key"].iloc[0]))
    down = next(r for r in rec.runs if r.run_id == "r1_down")
    vel = next(c for c in down.channels if c.name == "velocity").read()
    assert vel[0] == next(c for r in rec.runs if r.run_id == "r1_up"
                          for c in r.channels if c.name == "velocity").n_samples


@pytest.mark.parametrize("kind, f_low_hz", [("amplitude", F_HZ), ("frequency", 60.0)])
def test_turn_on_a_noisy_drive(kind, f_low_hz):
    # White noise of 4 % of the drive's peak amplitude (it adds spurious zero crossings):
    # the turn is still within one forcing period of the lowest frequency.
    from rattle_lab.records._updown import turn_from_drive
    d = _drive(kind)
    noisy = d + 0.04 * np.max(np.abs(d)) * np.random.default_rng(7).standard_normal(d.size)
    assert turn_from_drive(noisy, FS_DRIVE_HZ, 0.0, f_low_hz, kind) == pytest.approx(
        T_UP_S, abs=1.0 / f_low_hz)


def test_split_ids_that_collide_with_another_run_are_refused(tmp_path):
    from rattle_lab.records import DuplicateRunError
    path = _write(tmp_path / "dup.h5", turn_time_s=1.5)
    with h5py.File(path, "r+") as fh:
        fh.copy(fh["runs/r1"], "runs/R1_down")
        attrs = fh["runs/R1_down"].attrs
        for key in ("level_peak", "turn_time_s"):
            del attrs[key]
        attrs["protocol"] = "amplitude_ramp_down"
    with pytest.raises(DuplicateRunError, match="'R1_down' and 'r1_down'|'r1_down' and 'R1_down'"):
        read(path)
