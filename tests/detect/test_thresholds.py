"""Ramp thresholds: lock-in amplitude of the base acceleration, sustained onset, tabulation."""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.detect import detect_impacts
from rattle_lab.rig._handbuilt import ramp_impacts, synthetic_signals
from rattle_lab.exceptions import ParameterError
from rattle_lab.detect.thresholds import (Threshold, fundamental_amplitude, ramp_line, ramp_threshold,
                                   sustained_impact_time, tabulate_thresholds,
                                   threshold_uncertainty_ms2)

FS_HZ = 12800.0


def test_lock_in_rejects_harmonics_and_follows_a_ramp():
    t = np.arange(int(2 * FS_HZ)) / FS_HZ
    amp = 1.0 + 2.0 * t                                   # linear ramp, m/s^2
    x = amp * np.sin(2 * np.pi * 90 * t) + 3.0 * np.sin(2 * np.pi * 180 * t + 0.3)   # strong 2nd harmonic
    est = fundamental_amplitude(x, FS_HZ, 90.0)
    mid = slice(int(0.3 * FS_HZ), int(1.7 * FS_HZ))
    # zero-phase low-pass at 18 Hz: a linear ramp passes exactly; the 180 Hz product is
    # attenuated by > 100 dB; what is left is the filter's edge transient: 1e-3 relative
    np.testing.assert_allclose(est[mid], amp[mid], rtol=1e-3)


@pytest.mark.parametrize("kwargs, match", [
    ({"fs_hz": 0.0, "freq_hz": 10.0}, r"`fs_hz` must be > 0, was 0.0"),
    ({"fs_hz": 100.0, "freq_hz": 60.0}, r"`freq_hz` must be in \(0, fs_hz/2 = 50.0\), was 60.0"),
    ({"fs_hz": 100.0, "freq_hz": 10.0, "lowpass_hz": 80.0}, r"`lowpass_hz` must be in \(0, fs_hz/2\)"),
])
def test_lock_in_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        fundamental_amplitude(np.zeros(1000), **kwargs)


def test_lock_in_too_short():
    with pytest.raises(ParameterError, match=r"`x` has 10 samples, too few for the low-pass"):
        fundamental_amplitude(np.zeros(10), 1000.0, 100.0)


def test_sustained_time_up_and_down():
    t = np.r_[0.05, np.arange(0.5, 0.6, 0.01), 0.9]      # stray hits before and after
    assert sustained_impact_time(t, 100.0, "up", max_gap_cycles=2.5) == pytest.approx(0.5)
    assert sustained_impact_time(t, 100.0, "down", max_gap_cycles=2.5) == pytest.approx(0.59)
    assert np.isnan(sustained_impact_time([0.1, 0.5], 100.0, "up"))
    # default: isolated means more than 100 cycles away
    t = np.r_[0.05, 2.0 + 0.01 * np.arange(10), 4.0]
    assert sustained_impact_time(t, 100.0, "up") == pytest.approx(2.0)
    assert sustained_impact_time(t, 100.0, "down") == pytest.approx(2.09)


def test_sustained_time_accepts_intermittent_impacting():
    """Below resonance the first impacts near grazing come every few to tens of cycles
    (the rig's 95 Hz ramps): they belong to the onset, not to stray hits."""
    t = np.r_[1.0, 1.09, 1.17, 1.23, 1.26, np.arange(1.3, 1.4, 0.01)]
    assert sustained_impact_time(t, 100.0, "up") == pytest.approx(1.0)
    # the mirror image on a downward ramp: the last impact is 3.0 - 1.0
    assert sustained_impact_time(3.0 - t, 100.0, "down") == pytest.approx(2.0)
    with pytest.raises(ParameterError, match=r"`direction` must be 'up' or 'down', was 'sideways'"):
        sustained_impact_time(t, 100.0, "sideways")  # type: ignore[arg-type]


@pytest.mark.parametrize("direction", ["up", "down"])
def test_ramp_threshold_from_synthetic_ramp(direction):
    f_hz, n = 95.0, int(1.0 * FS_HZ)
    t = np.arange(n) / FS_HZ
    amp = 0.5 + 3.0 * t if direction == "up" else 3.5 - 3.0 * t     # m/s^2
    a_thr = 2.0
    ti, vin = ramp_impacts(f_hz, amp, FS_HZ, a_thr, direction)
    s = synthetic_signals(FS_HZ, n, f_hz, ti, vin, 0.8, base_amp_ms2=amp, noise_v_m_s=2e-4,
                          noise_base_ms2=0.01, rng=np.random.default_rng(5))
    log = detect_impacts(FS_HZ, velocity_m_s=s["velocity"])
    assert log.n_impacts == ti.size
    thr = ramp_threshold("r1", s["base_acc"], FS_HZ, f_hz, log.t_s, direction)
    # one forcing cycle of the ramp changes A by 3.0/95 = 0.032 m/s^2: the threshold is known
    # to within one cycle (impacts happen once per cycle)
    assert thr.accel_ms2 == pytest.approx(a_thr, abs=3.0 / f_hz)
    assert thr.direction == direction and thr.run_id == "r1" and not thr.censored
    # the measured ramp: the lock-in passes a line; the base noise (0.01 m/s^2 over a
    # 4.75 Hz band of a 6.4 kHz Nyquist) leaves ~1e-3 m/s^2 about it
    start, end = (0.5, 3.5) if direction == "up" else (3.5, 0.5)
    assert (thr.ramp_start_ms2, thr.ramp_end_ms2) == pytest.approx((start, end), abs=5e-3)
    assert thr.ramp_duration_s == 1.0 and 0 < thr.ramp_rms_ms2 < 5e-3
    assert thr.ramp_rate_ms2_s == pytest.approx(end - start, abs=1e-2)


@pytest.mark.parametrize("direction", ["up", "down"])
def test_ramp_threshold_censored_at_the_record_edge(direction):
    """Impact from the first cycle of an upward ramp (or to the last of a downward one):
    the onset (disappearance) lies outside the ramp and is not reported."""
    f_hz, n = 95.0, int(1.0 * FS_HZ)
    t = np.arange(n) / FS_HZ
    amp = 2.0 + 1.0 * t if direction == "up" else 3.0 - 1.0 * t      # above 1.5 throughout
    ti, vin = ramp_impacts(f_hz, amp, FS_HZ, 1.5, direction)
    s = synthetic_signals(FS_HZ, n, f_hz, ti, vin, 0.8, base_amp_ms2=amp, noise_v_m_s=2e-4,
                          noise_base_ms2=0.01, rng=np.random.default_rng(2))
    log = detect_impacts(FS_HZ, velocity_m_s=s["velocity"])
    thr = ramp_threshold("c", s["base_acc"], FS_HZ, f_hz, log.t_s, direction)
    assert thr.censored and np.isnan(thr.accel_ms2) and np.isnan(thr.t_s)
    assert thr.ramp_duration_s == 1.0 and np.isfinite(thr.ramp_start_ms2)
    # with no margin at the edge, the same impacts give a threshold
    kept = ramp_threshold("c", s["base_acc"], FS_HZ, f_hz, log.t_s, direction, edge_cycles=0.0)
    assert not kept.censored and np.isfinite(kept.accel_ms2)


def test_ramp_line_exact_and_errors():
    env = 16.0 - 4.0 * np.arange(3000) / 1000.0
    env[:50] += 1.0                                   # an edge transient: left out of the rms
    start, end, dur, rms = ramp_line(env, 1000.0, edge_s=0.1)
    assert dur == 3.0 and rms < 1e-12
    assert (start, end) == pytest.approx((16.0, 4.0), abs=1e-9)
    assert ramp_line(env, 1000.0)[3] > 0.1               # without the edge margin it counts
    with pytest.raises(ParameterError, match=r"`fs_hz` must be > 0, was -1.0"):
        ramp_line(env, -1.0)
    with pytest.raises(ParameterError, match=r"`envelope_ms2` needs >= 2 samples, had 1"):
        ramp_line([1.0], 1000.0)


def test_ramp_threshold_without_impacts_is_nan():
    thr = ramp_threshold("r", np.zeros(1000), 1000.0, 50.0, [], "up")
    assert np.isnan(thr.accel_ms2) and np.isnan(thr.t_s) and not thr.censored
    assert np.isnan(thr.ramp_start_ms2) and np.isnan(thr.ramp_rate_ms2_s)


def test_tabulate_hysteresis():
    th = [Threshold("a", 90.0, "up", 2.0, 0.1), Threshold("b", 90.0, "down", 1.5, 0.2),
          Threshold("c", 100.0, "up", 1.0, 0.1), Threshold("d", 100.0, "up", 1.2, 0.1),
          Threshold("e", 110.0, "down", float("nan"), float("nan"))]
    curve = tabulate_thresholds(th)
    np.testing.assert_array_equal(curve.freq_hz, [90.0, 100.0, 110.0])
    np.testing.assert_allclose(curve.up_ms2, [2.0, 1.1, np.nan])
    np.testing.assert_allclose(curve.hysteresis_ms2, [0.5, np.nan, np.nan])
    # no measured ramp: no uncertainty of one run; two runs at 100 Hz: their scatter
    np.testing.assert_allclose(curve.up_se_ms2, [np.nan, 0.1, np.nan])
    assert tabulate_thresholds([]).freq_hz.size == 0


def test_threshold_uncertainty_is_a_cycle_of_ramp_and_the_envelope_scatter():
    ramp = dict(ramp_start_ms2=4.0, ramp_end_ms2=16.0, ramp_duration_s=3.0, ramp_rms_ms2=0.03)
    th = [Threshold("a", 100.0, "up", 10.0, 1.5, **ramp),
          Threshold("b", 100.0, "up", 10.2, 1.55, **ramp),
          Threshold("c", 100.0, "down", 9.0, 2.0, **ramp)]
    one = float(np.hypot(4.0 / 100.0, 0.03))  # 4 m/s^3 over one 10 ms cycle, and the scatter
    assert threshold_uncertainty_ms2(th[0]) == pytest.approx(one, rel=1e-12)
    curve = tabulate_thresholds(th)
    # two runs: the larger of their own combined (one / sqrt 2) and their scatter (0.1)
    assert curve.up_se_ms2[0] == pytest.approx(max(one / np.sqrt(2.0), 0.1), rel=1e-12)
    assert curve.down_se_ms2[0] == pytest.approx(one, rel=1e-12)
    # intermittent impacts near the threshold (an irregular regime): the level change over
    # their mean interval, here 5 cycles
    loose = Threshold("e", 100.0, "down", 9.0, 2.0, **ramp, impact_gap_cycles=5.0)
    assert threshold_uncertainty_ms2(loose) == pytest.approx(np.hypot(0.2, 0.03), rel=1e-12)


def test_ramp_threshold_measures_the_impact_interval_at_the_threshold():
    fs, f = 2000.0, 50.0
    t = np.arange(int(6 * fs)) / fs
    base = (2.0 + t) * np.sin(2 * np.pi * f * t)  # a ramp of 1 m/s^3
    # impacts every cycle from 2 s, every 4th cycle from 4 s
    hits = np.r_[np.arange(2.0, 4.0, 1 / f), np.arange(4.0, 5.9, 4 / f)]
    up = ramp_threshold("u", base, fs, f, hits, "up")
    down = ramp_threshold("d", base, fs, f, hits, "down")
    assert up.impact_gap_cycles == pytest.approx(1.0, rel=1e-9)
    assert down.impact_gap_cycles == pytest.approx(4.0, rel=1e-9)
    assert threshold_uncertainty_ms2(down) > 3.5 * threshold_uncertainty_ms2(up)
