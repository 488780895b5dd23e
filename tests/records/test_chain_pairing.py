"""Issue 15: channels at different rates and delays brought onto one time base before pairing.

References are closed forms: sums of sines (band-limited well below both Nyquist
frequencies) evaluated at the target sample times.  Tolerances, away from the record ends
(edge transients cut off by skipping 5 % at each end): 1e-3 for the FFT shift alone, 2e-3
with resampling (a signal of peak ~1.8; scipy's resample_poly default Kaiser FIR has a
passband ripple of order 1e-3).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.detect._pairing import base_velocity_at, fractional_delay, onto_grid
from rattle_lab.exceptions import ParameterError
from rattle_lab.detect import paired_plate_channels
from rattle_lab.records._model import Channel, Run

F_HZ = (97.0, 410.0, 1333.0)


def _sig(t: np.ndarray) -> np.ndarray:
    return sum(np.sin(2 * math.pi * f * t + 0.3 * k) / (k + 1) for k, f in enumerate(F_HZ))


def test_fractional_delay_is_exact_for_band_limited_signals():
    fs = 25600.0
    t = np.arange(8192) / fs
    y = fractional_delay(_sig(t), fs, 18e-6)
    mid = slice(400, -400)
    assert np.max(np.abs(y[mid] - _sig(t - 18e-6)[mid])) < 1e-3


@pytest.mark.parametrize("fs_x, fs_target", [(25600.0, 51200.0), (51200.0, 25600.0),
                                             (25600.0, 25600.0), (48000.0, 51200.0)])
def test_onto_grid_resamples_and_shifts(fs_x, fs_target):
    t0_x, t0_target = 0.0123, 0.0100
    x = _sig(t0_x + np.arange(int(0.4 * fs_x)) / fs_x)
    n = int(0.4 * fs_target)
    y = onto_grid(x, fs_x, t0_x, fs_target, t0_target, n)
    t = t0_target + np.arange(n) / fs_target
    # before the source record starts: NaN, never invented
    assert np.all(np.isnan(y[t < t0_x - 0.5 / fs_target]))
    ok = np.isfinite(y)
    k = np.flatnonzero(ok)
    mid = k[int(0.05 * k.size):int(0.95 * k.size)]
    assert np.max(np.abs(y[mid] - _sig(t[mid]))) < 2e-3


def test_onto_grid_refuses_an_irrational_rate_ratio():
    with pytest.raises(ParameterError, match="not in a ratio of integers"):
        onto_grid(np.zeros(100), 1000.0 * math.pi, 0.0, 25600.0, 0.0, 100)


def test_base_velocity_of_a_sine_base():
    # a_b = A sin(W t) + offset -> v_b = -A/W cos(W t)
    fs, f, A = 25600.0, 96.0, 7.0
    t = np.arange(int(0.5 * fs)) / fs
    a = A * np.sin(2 * math.pi * f * t) + 0.7
    ti = np.array([0.001, 0.1234, 0.25, 0.4999])
    vb = base_velocity_at(a, fs, 0.0, f, ti)
    assert vb == pytest.approx(-A / (2 * math.pi * f) * np.cos(2 * math.pi * f * ti), abs=1e-9)


def test_paired_plate_channels_at_different_rates_and_delays():
    # velocity at 25.6 kHz through a decoder of 18 us; acceleration at 51.2 kHz starting later
    fs_v, fs_a, delay = 25600.0, 51200.0, 18e-6
    t_v = np.arange(int(0.3 * fs_v)) / fs_v
    t_a = 0.002 + np.arange(int(0.3 * fs_a)) / fs_a
    vel = Channel("v", "plate_velocity", "m/s", _sig(t_v - delay), sample_rate_hz=fs_v,
                  start_time_s=0.0, group_delay_s=delay, measurand="panel_relative_to_striker")
    acc = Channel("a", "plate_acceleration", "m/s^2", 3.0 * _sig(t_a), sample_rate_hz=fs_a,
                  start_time_s=0.002)
    run = Run("r", "sine_dwell", (vel, acc), excitation_freq_hz=97.0, nominal_level=1.0,
              nominal_level_units="m/s^2", start_time_iso="2026-01-01T00:00:00")
    fs, t0, v, a = paired_plate_channels(run, vel, acc)
    assert fs == fs_a and v.size == a.size
    assert t0 >= 0.002 - 1e-12 and np.all(np.isfinite(v)) and np.all(np.isfinite(a))
    t = t0 + np.arange(v.size) / fs
    mid = slice(int(0.05 * v.size), int(0.95 * v.size))
    # both now sample the same physical instants: v(t) and a(t) / 3 are the same function
    assert np.max(np.abs(v[mid] - _sig(t[mid]))) < 2e-3
    assert np.max(np.abs(a[mid] / 3.0 - _sig(t[mid]))) < 1e-12
