"""ECMA-418-2:2025 loudness, tonality and roughness against the standard's reference signals.

The standard fixes its calibration factors so that its reference signals give exactly 1:
a 1 kHz tone at 40 dB SPL is 1 sone_HMS and 1 tu_HMS; a 1 kHz tone at 60 dB SPL, 100 %
amplitude-modulated at 70 Hz, is 1 asper_HMS (free frontal field).  The signals are made
here with NumPy from those definitions.  Tolerance 0.1 %: the calibration factors are
printed with four to five significant digits, and 1 s of signal (instead of the
standard's longer ones) moves the time averages by less than 3e-4 (measured on 1 s, 2 s
and 5 s: docs/explanation/psychoacoustics.md).  Needs the optional package sottek-hearing-model;
each metric costs several seconds of CPU per second of sound, hence ``slow``.
"""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.acoustics import ecma418, ecma418_available, run_acoustics
from rattle_lab.exceptions import ParameterError

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(not ecma418_available(),
                                 reason="optional package sottek-hearing-model not installed")]

P0 = 20e-6


def reference(fs: float, am: bool, dur: float = 1.0) -> np.ndarray:
    t = np.arange(round(dur * fs)) / fs
    if not am:
        return np.sqrt(2) * P0 * 10 ** (40 / 20) * np.sin(2 * np.pi * 1000 * t)
    x = (1 + np.sin(2 * np.pi * 70 * t)) * np.sin(2 * np.pi * 1000 * t)
    return x / np.sqrt(np.mean(x**2)) * P0 * 10 ** (60 / 20)


@pytest.mark.parametrize("fs", [48000.0, 51200.0])
def test_reference_signals_give_one(fs):
    tone = ecma418(reference(fs, am=False), fs)
    assert tone.loudness_sone == pytest.approx(1.0, rel=1e-3)
    assert tone.tonality_tu == pytest.approx(1.0, rel=1e-3)
    assert tone.roughness_asper < 0.05        # a steady tone is not rough
    mod = ecma418(reference(fs, am=True), fs)
    assert mod.roughness_asper == pytest.approx(1.0, rel=1e-3)


def test_too_short_is_refused():
    with pytest.raises(ParameterError, match="at least"):
        ecma418(np.zeros(1000), 48000.0)


def test_run_rates_its_episodes_within_the_budget():
    # one episode of 1.2 s, budget 0.8 s: rated on its first 0.8 s only, and said so
    fs = 48000.0
    x = np.concatenate([np.zeros(int(0.5 * fs)), reference(fs, am=True, dur=1.2)])
    t_imp = 0.5 + np.arange(12) * 0.1
    ac = run_acoustics(x, fs, t_imp, with_loudness=False, ecma418_s=0.8).summary()["acoustics"]
    assert ac["ecma418_s"] == pytest.approx(0.8, abs=1 / fs)
    assert ac["episodes"][0]["ecma418_s"] == pytest.approx(0.8, abs=1 / fs)
    assert ac["roughness_asper"] == pytest.approx(ac["episodes"][0]["roughness_asper"])
    assert ac["roughness_asper"] > 0.5
