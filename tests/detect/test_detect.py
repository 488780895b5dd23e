"""Detection: impacts, triggers, sound peaks, delays, SPL and A-weighting, impact patterns.

Hand-built signals with exact answers; the synthetic scenes come from
:mod:`rattle_lab.rig._handbuilt` (analytic signals around chosen impacts).
"""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.detect import (ImpactParams, a_weight, a_weighting_db, cross_correlation_delay,
                               detect_impacts, impact_pattern, impulse_train, n_samples_of,
                               parabolic_peak, rms_spl_db, sound_peaks, spl_db, trigger_onsets)
from rattle_lab.rig._handbuilt import Acoustics, synthetic_signals
from rattle_lab.exceptions import ParameterError

FS_HZ = 25600.0


# --- helpers -----------------------------------------------------------------------------------

def test_n_samples_rounds_not_truncates():
    assert n_samples_of(2.9999e-3, 1000.0) == 3
    assert n_samples_of(0.0, 1000.0) == 0


@pytest.mark.parametrize("kwargs, match", [
    ({"duration_s": 1.0, "fs_hz": 0.0}, r"`fs_hz` must be > 0, was 0.0"),
    ({"duration_s": -1.0, "fs_hz": 10.0}, r"`duration_s` must be >= 0, was -1.0"),
])
def test_n_samples_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        n_samples_of(**kwargs)


def test_parabolic_peak_exact_for_a_parabola():
    x = np.arange(9.0)
    loc, h = parabolic_peak(2.0 - (x - 4.25) ** 2, 4)
    assert loc == pytest.approx(4.25, abs=1e-12) and h == pytest.approx(2.0, abs=1e-12)
    assert parabolic_peak(np.ones(3), 0) == (0.0, 1.0)  # edge: no refinement


def test_trigger_onsets_merge_within_separation():
    cf = np.zeros(40)
    cf[[5, 8]] = 20.0          # two triggers 3 samples apart: merged with n_min_sep = 5
    cf[30] = 15.0
    assert trigger_onsets(cf, 10.0, 3.0, 5) == [(5, 5, 8), (30, 30, 30)]
    assert trigger_onsets(np.zeros(10), 10.0, 3.0, 5) == []


# --- impacts -----------------------------------------------------------------------------------

def test_single_step_exact_velocities():
    """A step from -0.1 to +0.08 m/s between samples 99 and 100: t = 99.5 / fs, e = 0.8."""
    v = np.r_[np.full(100, -0.1), np.full(100, 0.08)]
    log = detect_impacts(10000.0, velocity_m_s=v)
    assert log.n_impacts == 1
    assert log.t_s[0] == pytest.approx(99.5 / 10000.0, abs=1e-15)
    assert log.v_in_m_s[0] == pytest.approx(-0.1, rel=1e-12)
    assert log.v_out_m_s[0] == pytest.approx(0.08, rel=1e-12)
    assert log.e[0] == pytest.approx(0.8, rel=1e-12)
    assert log.channels == ("velocity",)


def test_linear_velocity_is_extrapolated_to_the_impact():
    """Linear ramps either side: a degree-1 fit recovers v at the sub-sample impact time."""
    fs = 1000.0
    t = np.arange(200) / fs
    t_imp = 0.0995
    v = np.where(t < t_imp, -0.1 + 0.5 * (t - t_imp), 0.07 + 0.3 * (t - t_imp))
    log = detect_impacts(fs, velocity_m_s=v, params=ImpactParams(poly_degree=1, fit_window_s=0.02))
    # the cubic detrending is not symmetric where the slope changes: 1e-3 sample of bias
    assert log.t_s[0] == pytest.approx(t_imp, abs=1e-3 / fs)
    # the fits are exact for lines; evaluated at the estimated time, v moves by slope * 1e-6 s
    assert log.v_in_m_s[0] == pytest.approx(-0.1, abs=1e-6)
    assert log.v_out_m_s[0] == pytest.approx(0.07, abs=1e-6)


def test_accelerometer_spike_subsample_centroid():
    """A symmetric 3-sample spike centred between samples: centroid at the exact centre."""
    a = np.zeros(300)
    a[[150, 151]] = 50.0
    a[[149, 152]] = 10.0
    # the detrending window must span more than the spike (here 21 samples)
    log = detect_impacts(1000.0, accel_ms2=a, start_time_s=2.0,
                         params=ImpactParams(detrend_window_s=0.021))
    assert log.n_impacts == 1
    assert log.t_s[0] == pytest.approx(2.0 + 150.5 / 1000.0, abs=1e-12)
    assert np.isnan(log.v_in_m_s[0]) and log.channels == ("acceleration",)


@pytest.mark.parametrize("channels", ["velocity", "acceleration", "both"])
def test_synthetic_scene_all_impacts_found(channels):
    rng = np.random.default_rng(1)
    f_hz, n = 100.0, 12800
    ti = (np.arange(50) + 0.3137) / f_hz
    vin = -rng.uniform(0.05, 0.2, ti.size)
    s = synthetic_signals(FS_HZ, n, f_hz, ti, vin, 0.8, noise_v_m_s=5e-4, noise_a_ms2=1.0,
                          rng=np.random.default_rng(2))
    kw = {"velocity": {"velocity_m_s": s["velocity"]}, "acceleration": {"accel_ms2": s["plate_acc"]},
          "both": {"velocity_m_s": s["velocity"], "accel_ms2": s["plate_acc"]}}[channels]
    log = detect_impacts(FS_HZ, **kw)
    assert log.n_impacts == ti.size
    # time resolution: a jump between two samples is known to +-0.5 sample
    assert np.max(np.abs(log.t_s - ti)) <= 0.5 / FS_HZ
    if channels != "acceleration":
        # 2 % budget: noise 5e-4 m/s on >= 0.05 m/s, plus the quadratic-fit bias of the cosine segment
        assert np.max(np.abs(log.v_in_m_s / vin - 1)) < 0.02
        assert np.median(log.e) == pytest.approx(0.8, abs=0.01)


def test_no_impacts_is_valid_empty_log():
    t = np.arange(5000) / FS_HZ
    log = detect_impacts(FS_HZ, velocity_m_s=0.05 * np.sin(2 * np.pi * 100 * t))
    assert log.n_impacts == 0 and log.t_s.shape == (0,) and log.e.shape == (0,)
    assert detect_impacts(FS_HZ, velocity_m_s=np.zeros(100)).n_impacts == 0   # constant
    assert detect_impacts(FS_HZ, velocity_m_s=np.zeros(0)).n_impacts == 0     # empty


def test_read_only_input_is_not_modified():
    v = np.r_[np.full(100, -0.1), np.full(100, 0.08)]
    v.setflags(write=False)
    assert detect_impacts(10000.0, velocity_m_s=v).n_impacts == 1


@pytest.mark.parametrize("kwargs, match", [
    ({}, r"needs `velocity_m_s` or `accel_ms2`"),
    ({"velocity_m_s": [0.0, np.nan, 1.0]}, r"`velocity_m_s` must be finite, has NaN/Inf at sample 1"),
    ({"accel_ms2": np.zeros((2, 2))}, r"`accel_ms2` must be 1-D"),
    ({"velocity_m_s": np.zeros(5), "accel_ms2": np.zeros(4)}, r"`accel_ms2` has 4 samples"),
])
def test_detect_impacts_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        detect_impacts(1000.0, **kwargs)


@pytest.mark.parametrize("kwargs, match", [
    ({"off": 0.0}, r"`off` must be > 0, was 0.0"),
    ({"on": 2.0, "off": 3.0}, r"`on` must be > `off` \(3.0\), was 2.0"),
    ({"fit_window_s": -1.0}, r"`fit_window_s` must be >= 0, was -1.0"),
    ({"poly_degree": 5}, r"`poly_degree` must be 0, 1, 2 or 3, was 5"),
])
def test_impact_params_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        ImpactParams(**kwargs)


# --- sound peaks and delays --------------------------------------------------------------------

def test_sound_peaks_first_and_max():
    p = np.zeros(200)
    p[12], p[20] = 0.6, -1.0        # first peak 0.6 Pa, maximum 1.0 Pa (sign ignored)
    p[150] = 0.3
    pk = sound_peaks(p, 1000.0, [0.010, 0.140], window_s=0.05)
    assert pk.p_first_pa.tolist() == [0.6, 0.3] and pk.p_max_pa.tolist() == [1.0, 0.3]
    np.testing.assert_allclose(pk.delay_first_s, [0.002, 0.010], atol=1e-15)
    np.testing.assert_allclose(pk.delay_max_s, [0.010, 0.010], atol=1e-15)
    np.testing.assert_allclose(pk.spl_max_db, 20 * np.log10(np.array([1.0, 0.3]) / 20e-6))


def test_sound_window_is_cut_at_the_next_impact():
    p = np.zeros(100)
    p[40] = 1.0
    pk = sound_peaks(p, 1000.0, [0.010, 0.030], window_s=0.05)
    assert np.isnan(pk.p_max_pa[0]) and pk.p_max_pa[1] == 1.0   # the 1st window is silent


def test_sound_peaks_error():
    with pytest.raises(ParameterError, match=r"`first_fraction` must be in \(0, 1\], was 0.0"):
        sound_peaks(np.zeros(10), 1000.0, [0.0], first_fraction=0.0)


def test_synthetic_sound_peaks_and_law():
    ac = Acoustics()
    u_peak, g_peak, _, _ = ac.peaks()
    ti = (np.arange(20) + 0.25) / 100.0
    vin = -np.linspace(0.05, 0.2, ti.size)
    s = synthetic_signals(FS_HZ, 6000, 100.0, ti, vin, 0.8, acoustics=ac)
    pk = sound_peaks(s["pressure"], FS_HZ, ti)
    # parabolic refinement of a sampled 1.5 kHz sine at 25.6 kHz: peak height within 0.5 %
    np.testing.assert_allclose(pk.p_max_pa, ac.gain_pa_per_m_s * g_peak * np.abs(vin), rtol=5e-3)
    np.testing.assert_allclose(pk.delay_max_s, ac.delay_s + u_peak, atol=0.1 / FS_HZ)


def test_cross_correlation_delay_subsample():
    x = np.zeros(400)
    x[100] = 1.0
    y = np.zeros(400)
    y[130], y[131] = 0.5, 0.5          # symmetric pair: delay 30.5 samples
    # mean removal over a finite record tilts the correlation by O(1/n): 1e-4 sample
    assert cross_correlation_delay(x, y, 1000.0, max_lag_s=0.1) == pytest.approx(0.0305, abs=1e-7)


def test_impulse_train_splits_subsample_weight():
    np.testing.assert_allclose(impulse_train([0.0025], 5, 1000.0), [0, 0, 0.5, 0.5, 0])


@pytest.mark.parametrize("kwargs, match", [
    ({"cause": np.zeros(3), "response": np.zeros(4)}, r"equal length, had 3 and 4 samples"),
    ({"cause": np.zeros(10), "response": np.zeros(10), "min_lag_s": 0.5},
     r"no lag in \[`min_lag_s`, `max_lag_s`\]"),
])
def test_cross_correlation_errors(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        cross_correlation_delay(fs_hz=10.0, max_lag_s=0.2, **kwargs)


# --- SPL and A-weighting -----------------------------------------------------------------------

# IEC 61672-1:2013 Table 3: nominal frequency, A-weighting (dB), class-1 tolerance (+, -) dB.
# (-inf lower limits at 10/12.5 Hz are written as -inf.)
IEC_A = [
    (10, -70.4, 3.5, np.inf), (12.5, -63.4, 3.0, np.inf), (16, -56.7, 2.5, 4.5), (20, -50.5, 2.5, 2.5),
    (25, -44.7, 2.5, 2.0), (31.5, -39.4, 2.0, 2.0), (40, -34.6, 1.5, 1.5), (50, -30.2, 1.5, 1.5),
    (63, -26.2, 1.5, 1.5), (80, -22.5, 1.5, 1.5), (100, -19.1, 1.5, 1.5), (125, -16.1, 1.5, 1.5),
    (160, -13.4, 1.5, 1.5), (200, -10.9, 1.5, 1.5), (250, -8.6, 1.4, 1.4), (315, -6.6, 1.4, 1.4),
    (400, -4.8, 1.4, 1.4), (500, -3.2, 1.4, 1.4), (630, -1.9, 1.4, 1.4), (800, -0.8, 1.4, 1.4),
    (1000, 0.0, 1.1, 1.1), (1250, 0.6, 1.4, 1.4), (1600, 1.0, 1.6, 1.6), (2000, 1.2, 1.6, 1.6),
    (2500, 1.3, 1.6, 1.6), (3150, 1.2, 1.6, 1.6), (4000, 1.0, 1.6, 1.6), (5000, 0.5, 2.1, 2.1),
    (6300, -0.1, 2.1, 2.6), (8000, -1.1, 2.1, 3.1), (10000, -2.5, 2.6, 3.6), (12500, -4.3, 3.0, 6.0),
    (16000, -6.6, 3.5, 17.0), (20000, -9.3, 4.0, np.inf),
]


def _exact_freq(nominal: float) -> float:
    """Base-10 exact frequency of a nominal one-third-octave frequency (IEC 61672-1, 5.5.9)."""
    k = round(10 * np.log10(nominal / 1000.0))
    return 1000.0 * 10 ** (k / 10)


@pytest.mark.parametrize("nominal, a_db, tol_plus, tol_minus", IEC_A)
def test_a_weighting_formula_matches_iec_table(nominal, a_db, tol_plus, tol_minus):
    # The table lists A(f) rounded to 0.1 dB: the formula agrees to 0.05 dB.
    assert a_weighting_db(_exact_freq(nominal)) == pytest.approx(a_db, abs=0.05 + 1e-9)


@pytest.mark.parametrize("fs_hz", [48000.0, 51200.0])
@pytest.mark.parametrize("nominal, a_db, tol_plus, tol_minus", [r for r in IEC_A if r[0] >= 25])
def test_a_weighting_filter_response_within_class1(fs_hz, nominal, a_db, tol_plus, tol_minus):
    """The filter applied to a sine at each tabulated frequency: gain within class-1 tolerance.

    One second of signal, a whole number of cycles of the exact frequency is not guaranteed, so
    the RMS is taken over the middle half (edges of the circular weighting excluded).
    """
    f = _exact_freq(nominal)
    n = int(fs_hz)
    t = np.arange(n) / fs_hz
    x = np.sin(2 * np.pi * f * t)
    y = a_weight(x, fs_hz)
    mid = slice(n // 4, 3 * n // 4)
    gain_db = 20 * np.log10(np.sqrt(np.mean(y[mid] ** 2)) / np.sqrt(np.mean(x[mid] ** 2)))
    assert a_db - tol_minus <= gain_db <= a_db + tol_plus
    assert gain_db == pytest.approx(a_db, abs=0.15)   # in fact much tighter than class 1


def test_spl_values():
    assert spl_db(20e-6) == pytest.approx(0.0, abs=1e-12)
    assert spl_db(1.0) == pytest.approx(93.9794000867, abs=1e-9)
    t = np.arange(48000) / 48000.0
    x = np.sqrt(2) * np.sin(2 * np.pi * 1000 * t)     # 1 Pa RMS at 1 kHz: A-weighting 0 dB
    assert rms_spl_db(x) == pytest.approx(93.9794000867, abs=1e-6)
    assert rms_spl_db(x, 48000.0, a_weighted=True) == pytest.approx(93.9794, abs=1e-3)
    with pytest.raises(ParameterError, match=r"`fs_hz` is needed for an A-weighted level"):
        rms_spl_db(x, a_weighted=True)


# --- patterns ----------------------------------------------------------------------------------

@pytest.mark.parametrize("times, expected", [
    ([], ("no impact", 0)),
    ((np.arange(50) + 0.3) / 100.0, ("1/1", 1)),
    ((np.arange(0, 50, 3) + 0.3) / 100.0, ("1/n", 3)),
    (np.sort(np.r_[np.arange(50) + 0.2, np.arange(50) + 0.7]) / 100.0, ("several per cycle", 0)),
    (np.array([0.3, 1.3, 4.2, 4.8, 9.1, 13.5, 14.1, 14.6, 30.2, 31.1]) / 100.0, ("irregular", 0)),
])
def test_impact_patterns(times, expected):
    r = impact_pattern(np.asarray(times, dtype=float), 100.0, 0.0, 0.5)
    assert (r.pattern, r.n) == expected
    assert r.counts.size == 50


@pytest.mark.parametrize("args, kwargs, match", [
    ((0.0, 0.0, 1.0), {}, r"`freq_hz` must be > 0, was 0.0"),
    ((10.0, 1.0, 1.0), {}, r"`t_stop_s` must be > `t_start_s` \(1.0\), was 1.0"),
    ((10.0, 0.0, 1.0), {"tolerance": 0.5}, r"`tolerance` must be in \(0.5, 1\], was 0.5"),
    ((10.0, 0.0, 1.0), {"settle_cycles": -1}, r"`settle_cycles` must be an integer >= 0, was -1"),
    ((10.0, 0.0, 1.0), {"settle_cycles": 1.5}, r"`settle_cycles` must be an integer >= 0, was 1.5"),
])
def test_impact_pattern_errors(args, kwargs, match):
    with pytest.raises(ParameterError, match=match):
        impact_pattern([], *args, **kwargs)


def test_impact_pattern_settle_cycles_skip_the_transient():
    t = np.r_[0.001, 0.002, 0.003, (np.arange(2, 50) + 0.3) / 100.0]   # chatter, then 1/1
    assert impact_pattern(t, 100.0, 0.0, 0.5).pattern == "1/1"          # 48 of 50 cycles
    r = impact_pattern(t, 100.0, 0.0, 0.5, settle_cycles=2, tolerance=1.0)
    assert (r.pattern, r.counts.size) == ("1/1", 48)
