"""Calibration from calibrator records: sensitivity derived, applied at ingest, drift flagged.

The calibrator and measurement signals are generated here with plain NumPy: a
microphone of a *true* sensitivity (V/Pa) records a 94 dB (1.0024 Pa RMS) 1 kHz tone
and then a measurement tone of known SPL; the record declares a wrong sensitivity.
After ingest the stored channel must read the measurement tone at its true level.
"""

from __future__ import annotations

import dataclasses
import json

import h5py
import numpy as np
import pytest

from rattle_lab.acoustics.calibration import (apply_campaign_calibration, campaign_calibration,
                                              tone_rms)
from rattle_lab.exceptions import SchemaError
from rattle_lab.store import ingest, open_stored_record, read_catalogue
from rattle_lab.records import Channel, Record, Run, write_record

from record_factory import plate_rig

FS = 51200.0
P0 = 20e-6


def _tone(freq_hz: float, rms: float, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    phase = rng.uniform(0, 2 * np.pi)
    return np.sqrt(2) * rms * np.sin(2 * np.pi * freq_hz * t + phase) + 1e-4 * rms * \
        rng.standard_normal(n)


def _campaign(s_pre_v_per_pa: float, s_post_v_per_pa: float | None, *, declared_mv_pa: float = 50.0,
              acc_s_v_per_ms2: float = 0.0102, cal_level_db: float = 94.0) -> Record:
    n = int(FS)  # 1 s
    p_cal = P0 * 10 ** (cal_level_db / 20)
    mic_meas = _tone(250.0, 0.5, n, 1)  # 0.5 Pa RMS = 87.96 dB
    runs = [
        Run("cal_mic_pre", "unspecified", (Channel(
            "mic", "sound_pressure", "V", (s_pre_v_per_pa * _tone(1000.0, p_cal, n, 2)),
            sample_rate_hz=FS, start_time_s=0.0, sensitivity=declared_mv_pa,
            sensitivity_units="mV/Pa"),),
            extra={"x_calibrator_level_db": cal_level_db, "x_calibrator_freq_hz": 1000.0}),
        Run("cal_acc_pre", "unspecified", (Channel(
            "base", "base_acceleration", "V", acc_s_v_per_ms2 * _tone(159.2, 10.0, n, 3),
            sample_rate_hz=FS, start_time_s=0.0, sensitivity=100.0, sensitivity_units="mV/g"),),
            extra={"x_calibrator_accel_ms2": 10.0}),
        Run("dwell", "sine_dwell", (
            Channel("mic", "sound_pressure", "V", s_pre_v_per_pa * mic_meas, sample_rate_hz=FS,
                    start_time_s=0.0, sensitivity=declared_mv_pa, sensitivity_units="mV/Pa"),
            Channel("base", "base_acceleration", "V", acc_s_v_per_ms2 * _tone(94.0, 3.0, n, 4),
                    sample_rate_hz=FS, start_time_s=0.0, sensitivity=100.0,
                    sensitivity_units="mV/g")),
            excitation_freq_hz=94.0, nominal_level=3.0, nominal_level_units="m/s^2",
            start_time_iso="2024-03-01T14:10:00Z"),
    ]
    if s_post_v_per_pa is not None:
        runs.append(Run("cal_mic_post", "unspecified", (Channel(
            "mic", "sound_pressure", "V", s_post_v_per_pa * _tone(1000.0, p_cal, n, 5),
            sample_rate_hz=FS, start_time_s=0.0, sensitivity=declared_mv_pa,
            sensitivity_units="mV/Pa"),),
            extra={"x_calibrator_level_db": cal_level_db}))
    return Record("calcamp", "measured", plate_rig(), tuple(runs))


def test_tone_rms_of_a_tone_amid_hum():
    # A 1 kHz tone of 1 V RMS plus 50 Hz hum of 0.5 V RMS: only the tone counts (1e-3).
    t = np.arange(int(FS)) / FS
    x = np.sqrt(2) * np.sin(2 * np.pi * 1000 * t + 0.3) + np.sqrt(2) * 0.5 * np.sin(2 * np.pi * 50 * t)
    assert tone_rms(x, FS, 1000.0) == pytest.approx(1.0, rel=1e-3)


@pytest.mark.parametrize("level_db", [94.0, 114.0])
def test_sensitivity_from_mic_and_accelerometer_calibrators(level_db):
    rec = _campaign(0.0471, 0.0472, cal_level_db=level_db)
    cals = campaign_calibration(rec)
    mic, base = cals["mic"], cals["base"]
    assert mic.source == "calibrator" and mic.sensitivity_units == "V/Pa"
    # tolerance 1e-3 relative: spectral RMS estimate of a 1 s tone with 1e-4 noise
    assert mic.sensitivity == pytest.approx(0.0471, rel=1e-3)
    assert mic.declared_sensitivity == pytest.approx(0.050, rel=1e-12)
    assert mic.drift_db == pytest.approx(20 * np.log10(0.0472 / 0.0471), abs=1e-3)
    assert mic.flags == ()
    assert base.source == "calibrator" and base.sensitivity == pytest.approx(0.0102, rel=1e-3)
    assert base.sensitivity_units == "V/(m/s^2)"


def test_drift_above_half_a_db_is_flagged():
    cals = campaign_calibration(_campaign(0.0471, 0.0471 * 10 ** (0.6 / 20)))
    assert cals["mic"].drift_db == pytest.approx(0.6, abs=1e-3)
    assert cals["mic"].flags == ("drift",)
    cals = campaign_calibration(_campaign(0.0471, 0.0471 * 10 ** (0.4 / 20)))
    assert cals["mic"].flags == ()


def test_no_calibrator_uses_declared_sensitivity():
    rec = _campaign(0.0471, None)
    rec = dataclasses.replace(rec, runs=tuple(r for r in rec.runs if r.run_id == "dwell"))
    cal = campaign_calibration(rec)["mic"]
    assert cal.source == "declared" and cal.sensitivity == 50.0 and cal.sensitivity_units == "mV/Pa"
    out = apply_campaign_calibration(rec)
    mic = out.run("dwell").channels[0]
    assert mic.sensitivity == 50.0
    assert mic.extra["ingest_calibration_source"] == "declared"


def test_calibrator_run_without_its_channel_is_a_schema_error():
    rec = _campaign(0.0471, None)
    bad = dataclasses.replace(rec.runs[0], extra={"x_calibrator_level_db": 94.0,
                                                  "x_calibrator_channel": "nope"})
    rec = dataclasses.replace(rec, runs=(bad,) + rec.runs[1:])
    with pytest.raises(SchemaError, match="cal_mic_pre.*x_calibrator_channel"):
        campaign_calibration(rec)


def test_ingest_applies_calibration_and_records_provenance(tmp_path):
    # The record declares 50 mV/Pa; the true sensitivity is 47.1 mV/Pa.  Read with the
    # declared value the 0.5 Pa measurement tone would be 0.471 Pa (-0.52 dB); after
    # calibration it must be 0.5 Pa within 0.1 % (the calibrator reading's precision).
    src = write_record(tmp_path / "cal.h5", _campaign(0.0471, 0.0474))
    store = tmp_path / "store.h5"
    ingest([src], store)
    key = str(read_catalogue(store, level="runs")["input_key"].iloc[0])
    rec = open_stored_record(store, key)
    try:
        mic = rec.run("dwell").channels[0]
        p = mic.read()
        assert np.sqrt(np.mean(p**2)) == pytest.approx(0.5, rel=1e-3)
        assert mic.sensitivity == pytest.approx(0.0471, rel=1e-3) and mic.sensitivity_units == "V/Pa"
        assert mic.extra["ingest_calibration_source"] == "calibrator"
        assert mic.extra["ingest_calibration_declared_sensitivity"] == pytest.approx(0.05)
        assert mic.extra["ingest_calibration_runs"] == "cal_mic_pre,cal_mic_post"
        base = rec.run("dwell").channels[1]
        assert np.sqrt(np.mean(base.read() ** 2)) == pytest.approx(3.0, rel=1e-3)
    finally:
        rec.close()
    with h5py.File(store, "r") as fh:
        summary = json.loads(fh[f"records/{key}"].attrs["ingest_calibration"])
    assert summary["mic"]["source"] == "calibrator"
    assert summary["mic"]["drift_db"] == pytest.approx(20 * np.log10(0.0474 / 0.0471), abs=1e-3)
