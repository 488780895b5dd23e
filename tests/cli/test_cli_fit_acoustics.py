"""``rattle-lab fit --json``: the ``acoustics`` and ``calibration`` objects of a run with a mic.

The record is generated here (plain NumPy): a microphone in volts whose true
sensitivity (41.3 mV/Pa) differs from the declared one (50 mV/Pa), a 94 dB calibrator
record before the run, and a run where the microphone hears a 1 kHz tone of 80 dB
SPL.  The tone's expected values are closed forms: LAeq = L (A = 0 dB at 1 kHz),
LCpeak = L + 3.01 dB (crest factor sqrt 2; the tone fades in, so there is no click), the 1 kHz band holds it all, and
ISO 532-1 gives 2^((L - 40)/10) sone for a 1 kHz tone (16 sone at 80 dB).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from rattle_lab.records import Channel, Record, Run, write_record

from record_factory import plate_rig, run_cli

FS = 48000.0
P0 = 20e-6
S_TRUE_V_PA = 0.0413


def _record(with_calibrator: bool) -> Record:
    n = int(1.0 * FS)
    t = np.arange(n) / FS
    p_tone = np.sqrt(2) * P0 * 10 ** (80 / 20) * np.sin(2 * np.pi * 1000 * t)
    # switched on over 50 ms (raised cosine): an abrupt start would be a click whose
    # C-weighted peak overshoots the steady tone's (as on a sound level meter)
    n_on = round(0.05 * FS)
    p_tone[:n_on] *= 0.5 - 0.5 * np.cos(np.pi * np.arange(n_on) / n_on)
    p_cal = np.sqrt(2) * P0 * 10 ** (94 / 20) * np.sin(2 * np.pi * 1000 * t + 1.0)
    vel = 1e-3 * np.sin(2 * np.pi * 50 * t)  # a plate that never reaches the striker
    common = dict(sample_rate_hz=FS, start_time_s=0.0)
    runs = []
    if with_calibrator:
        runs.append(Run("cal_pre", "unspecified", (Channel(
            "mic", "sound_pressure", "V", S_TRUE_V_PA * p_cal, sensitivity=50.0,
            sensitivity_units="mV/Pa", **common),), extra={"x_calibrator_level_db": 94.0}))
    runs.append(Run("dwell_050", "sine_dwell", (
        Channel("velocity", "plate_velocity", "m/s", vel, **common),
        Channel("mic", "sound_pressure", "V", S_TRUE_V_PA * p_tone, sensitivity=50.0,
                sensitivity_units="mV/Pa", **common)),
        excitation_freq_hz=50.0, nominal_level=1.0, nominal_level_units="m/s^2",
        start_time_iso="2024-03-01T14:10:00Z"))
    return Record("acoustic", "measured", plate_rig(), tuple(runs))


@pytest.mark.parametrize("with_calibrator", [True, False])
def test_fit_json_acoustics_of_a_known_tone(tmp_path, with_calibrator):
    src = write_record(tmp_path / "rec.h5", _record(with_calibrator))
    store = tmp_path / "store.h5"
    assert run_cli("ingest", str(src), "-o", str(store), "--quiet").returncode == 0
    proc = run_cli("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    (row,) = [r for r in summary["runs"] if r["run_id"] == "dwell_050"]
    ac, cal = row["acoustics"], row["calibration"]
    assert set(ac) >= {"laeq_db", "lafmax_db", "lcpeak_db", "third_octave_db", "loudness_n5_sone",
                       "loudness_max_sone", "sharpness_acum"}
    if with_calibrator:
        # with the calibrator, the tone reads at its true level (0.05 dB: window edges)
        assert cal["source"] == "calibrator" and cal["sensitivity_units"] == "V/Pa"
        assert cal["sensitivity"] == pytest.approx(S_TRUE_V_PA, rel=1e-3)
        level = 80.0
    else:
        # declared 50 mV/Pa instead of 41.3: the tone reads 20 log10(41.3/50) = -1.66 dB low
        assert cal["source"] == "declared" and cal["sensitivity"] == 50.0
        level = 80.0 + 20 * np.log10(S_TRUE_V_PA / 0.050)
    # the 50 ms onset ramp lowers the mean square by 10 log10(1 - 0.05 * 5/8) = 0.137 dB
    leq = level + 10 * np.log10(1 - 0.05 * 5 / 8)
    assert ac["laeq_db"] == pytest.approx(leq, abs=0.02)
    assert ac["third_octave_db"]["1000"] == pytest.approx(leq, abs=0.02)
    assert ac["lafmax_db"] == pytest.approx(level, abs=0.1)  # steady after 1 s (tau 0.125 s)
    assert ac["lcpeak_db"] == pytest.approx(level + 3.01, abs=0.1)
    # ISO 532-1 at 1 kHz: 2^((L-40)/10) sone; +-3 % (the standard's tables' rounding)
    assert ac["loudness_n5_sone"] == pytest.approx(2 ** ((level - 40) / 10), rel=0.03)
    assert ac["loudness_max_sone"] >= ac["loudness_n5_sone"]
    assert 0.5 < ac["sharpness_acum"] < 1.5  # a 1 kHz tone is ~1 acum (DIN 45692 reference)
    assert list(ac["third_octave_db"])[0] == "20" and "20000" in ac["third_octave_db"]
