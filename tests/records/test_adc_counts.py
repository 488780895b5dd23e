"""Issue 15: raw ADC counts with gain and offset (schema v2 channel attributes).

A channel whose dataset holds integer ADC counts declares ``adc_gain`` (units per count, > 0)
and optionally ``adc_offset`` (in the channel's ``units``); the reader gives
``SI = scale(units) * (adc_gain * count + adc_offset)``.  The files here are written by hand
with h5py (not by rattle_lab's writer), as a lab's own acquisition script would write them.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np
import pytest

from rattle_lab.exceptions import SchemaError
from rattle_lab.records import read
from record_factory import run_command

G0 = 9.80665
FS_HZ = 10000.0
N = 2000
#: A +-10 V 16-bit ADC: one count is 10 / 32768 V.
GAIN_V = 10.0 / 32768
OFFSET_V = -0.0125
#: 100 mV/g accelerometer; 25 (mm/s)/V vibrometer.
ACC_MV_PER_G = 100.0
VEL_MM_S_PER_V = 25.0


def _counts(volts: np.ndarray) -> np.ndarray:
    return np.clip(np.round((volts - OFFSET_V) / GAIN_V), -32768, 32767).astype("<i2")


def _signals() -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(N) / FS_HZ
    acc_v = 0.8 * np.sin(2 * np.pi * 96.0 * t)            # volts at the ADC input
    vel_v = 3.0 * np.cos(2 * np.pi * 96.0 * t) + 0.5
    return acc_v, vel_v


def _write(path: Path, *, version: int = 2, acc_dtype: str = "<i2", offset: bool = True,
           gain: bool = True) -> Path:
    acc_v, vel_v = _signals()
    with h5py.File(path, "w") as fh:
        fh.attrs.update(schema="rattle_record", schema_version=version, campaign_id="adc-test",
                        source="measured", description="hand-written ADC counts")
        rig = fh.create_group("rig")
        rig.attrs.update(apparatus="other", description="a lab bench")
        run = fh.create_group("runs/dwell_096")
        run.attrs.update(protocol="sine_dwell", excitation_freq_hz=96.0, nominal_level=5.0,
                         nominal_level_units="m/s^2", start_time_iso="2024-03-01T14:10:00Z")
        ch = run.create_group("channels")
        counts = _counts(acc_v)
        acc = ch.create_dataset("plate", data=counts.astype(acc_dtype))
        acc.attrs.update(quantity="plate_acceleration", units="V", sensitivity=ACC_MV_PER_G,
                         sensitivity_units="mV/g", sample_rate_hz=FS_HZ, start_time_s=0.0)
        if gain:
            acc.attrs["adc_gain"] = GAIN_V
        if offset:
            acc.attrs["adc_offset"] = OFFSET_V
        vel = ch.create_dataset("velocity", data=_counts(vel_v))
        vel.attrs.update(quantity="plate_velocity", units="V", sensitivity=VEL_MM_S_PER_V,
                         sensitivity_units="(mm/s)/V", sample_rate_hz=FS_HZ, start_time_s=0.0,
                         adc_gain=GAIN_V, adc_offset=OFFSET_V, range_min=-32768.0,
                         range_max=32767.0)
    return path


def test_counts_read_back_in_si_with_gain_and_offset(tmp_path):
    path = _write(tmp_path / "adc.h5")
    rec = read(path)
    acc_v, vel_v = _signals()
    chans = {c.name: c for c in rec.runs[0].channels}
    acc, vel = chans["plate"], chans["velocity"]
    assert (acc.adc_gain, acc.adc_offset) == (GAIN_V, OFFSET_V)
    # the stored numbers stay counts
    raw = acc.read(si=False)
    assert raw.dtype == np.int16
    np.testing.assert_array_equal(raw, _counts(acc_v))
    # Reference: volts -> g -> m/s^2 by hand.  Tolerance: half a count of quantisation
    # (GAIN_V / 2 V) in SI, plus float32 rounding of the SI values (int16 reads as float32).
    acc_si = acc.read()
    expect_acc = acc_v / (ACC_MV_PER_G * 1e-3) * G0
    q_acc = 0.5 * GAIN_V / (ACC_MV_PER_G * 1e-3) * G0
    np.testing.assert_allclose(acc_si, expect_acc, rtol=0, atol=q_acc * 1.001 + 1e-5)
    vel_si = vel.read()
    expect_vel = vel_v * VEL_MM_S_PER_V * 1e-3
    q_vel = 0.5 * GAIN_V * VEL_MM_S_PER_V * 1e-3
    np.testing.assert_allclose(vel_si, expect_vel, rtol=0, atol=q_vel * 1.001 + 1e-7)
    # the offset matters: without it the mean is off by OFFSET_V (12.5 mV = 1.23 m/s^2)
    assert abs(float(np.mean(acc_si)) - float(np.mean(expect_acc))) < 0.01
    assert abs(OFFSET_V / (ACC_MV_PER_G * 1e-3) * G0) > 1.0


def test_gain_without_offset_means_zero_offset(tmp_path):
    rec = read(_write(tmp_path / "adc.h5", offset=False))
    acc = next(c for c in rec.runs[0].channels if c.name == "plate")
    assert acc.adc_offset is None and acc.offset_si == 0.0
    np.testing.assert_allclose(acc.read(), acc.read(si=False) * GAIN_V / 0.1 * G0, rtol=1e-6)


@pytest.mark.parametrize("kwargs, match", [
    ({"version": 1}, "needs schema_version 2"),
    ({"acc_dtype": "<f4"}, "raw ADC counts are integers"),
    ({"gain": False}, "'adc_offset': needs 'adc_gain'"),
])
def test_bad_adc_metadata_is_refused_naming_the_channel(tmp_path, kwargs, match):
    path = _write(tmp_path / "bad.h5", **kwargs)
    with pytest.raises(SchemaError, match=match) as info:
        read(path)
    assert "bad.h5" in str(info.value)
    assert "/runs/dwell_096/channels/plate" in str(info.value)


def test_negative_gain_is_refused(tmp_path):
    path = _write(tmp_path / "neg.h5")
    with h5py.File(path, "r+") as fh:
        fh["runs/dwell_096/channels/plate"].attrs["adc_gain"] = -GAIN_V
    with pytest.raises(SchemaError, match="adc_gain"):
        read(path)


def test_ingested_counts_read_back_in_si_from_the_store(tmp_path):
    # Through `rattle-lab ingest`: the store keeps the counts (linked) and the reader of the
    # store applies gain and offset.
    path = _write(tmp_path / "adc.h5")
    store = tmp_path / "store.h5"
    proc = run_command("ingest", str(path), "-o", str(store))
    assert proc.returncode == 0, proc.stderr
    from rattle_lab.store import open_stored_record, read_catalogue
    cat = read_catalogue(store)
    row = cat[cat["channel"] == "plate"].iloc[0] if "channel" in cat else cat.iloc[0]
    rec = open_stored_record(store, str(row["input_key"]))
    acc = next(c for c in rec.runs[0].channels if c.name == "plate")
    acc_v, _ = _signals()
    np.testing.assert_allclose(acc.read(), acc_v / 0.1 * G0,
                               rtol=0, atol=0.5 * GAIN_V / 0.1 * G0 * 1.001 + 1e-5)
    # the counts never reach the int16 limits: no clipping finding
    assert "clipping" not in proc.stdout + proc.stderr
