"""A shock on top of a steady excitation (issue 15: the forced-shock record).

Independent generator (plain numpy, its own physics): a base-excited single-degree-of-freedom
board (natural frequency 60 Hz, 3 % damping) on a shaker driven by a steady 5 Hz sine with a
2nd harmonic, plus one shock: a half-sine base-acceleration pulse of 4 ms.  The board's
response is stepped exactly per sample (the damped oscillator's closed-form response to a
forcing held constant over each sample).  The shock is about twice the sine, as in the
real record.  Truth: the pulse's start time.  Without taking the steady sine off, the sine
was the noise floor and the shock was not found.
"""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.detect._shock import detect_shock, steady_periodic

FS = 2000.0


def _board(shock_at_s: float, sine_amp: float, shock_amp: float, noise: float, seed: int,
           n: int = 16000) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    base = sine_amp * (np.sin(2 * np.pi * 5.0 * t + 0.7) + 0.1 * np.sin(2 * np.pi * 10.0 * t))
    tp = t - shock_at_s
    pulse = np.where((tp >= 0) & (tp < 4e-3), shock_amp * np.sin(np.pi * tp / 4e-3), 0.0)
    # board relative motion: x'' + 2 z w x' + w^2 x = -pulse (the sine is far below 60 Hz and
    # moves the board with the base); exact step of a damped oscillator with constant forcing
    w, z = 2 * np.pi * 60.0, 0.03
    wd = w * np.sqrt(1 - z * z)
    dt = 1 / FS
    e, c, s = np.exp(-z * w * dt), np.cos(wd * dt), np.sin(wd * dt)
    x = v = 0.0
    acc = np.empty(n)
    for k in range(n):
        f = -pulse[k]
        xs = f / (w * w)                       # static deflection under constant forcing
        y0, y1 = x - xs, v
        x = xs + e * (y0 * c + (y1 + z * w * y0) / wd * s)
        v = e * (y1 * c - (z * w * y1 + w * w * y0) / wd * s)
        acc[k] = f - 2 * z * w * v - w * w * x
    return base + pulse + acc + noise * rng.standard_normal(n)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_shock_on_a_steady_sine_is_found_once_at_its_start(seed):
    at = 3.9 + 0.01 * seed
    x = _board(at, sine_amp=0.06, shock_amp=0.12, noise=0.002, seed=seed)
    shock = detect_shock(x, FS)
    assert shock.found
    # onset within 2 ms of the pulse's start (4 samples: the AIC picker on a 4 ms half-sine
    # with 0.002 noise), peak within the pulse or the board's first swing (10 ms)
    assert shock.onset_s == pytest.approx(at, abs=2e-3)
    assert at <= shock.peak_s <= at + 10e-3


def test_the_steady_sine_alone_is_no_shock():
    x = _board(3.9, sine_amp=0.06, shock_amp=0.0, noise=0.002, seed=3)
    assert not detect_shock(x, FS).found


def test_ringing_after_a_shock_is_not_taken_for_a_steady_line():
    # no sine: the shock's ringing (60 Hz) is the largest line, but not at the record's start
    x = _board(3.9, sine_amp=0.0, shock_amp=0.12, noise=0.002, seed=4)
    assert steady_periodic(x - np.median(x), FS) is None
    assert detect_shock(x, FS).onset_s == pytest.approx(3.9, abs=2e-3)
