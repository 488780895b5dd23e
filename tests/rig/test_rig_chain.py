"""Issue 15, part C: the synthetic rig's measurement chain ([chain] table), effect by effect.

Each effect is switched on alone on a short dwell of the default scene and compared with
the same scene and seed without it: the sensor noise streams are the same, so the
difference is the effect itself.  References: closed forms (offset, hum amplitude, ADC
step, the base velocity -A/W sin(theta) of a -A cos(theta) acceleration) and the chain's
own declaration (group_delay_s, measurand).
"""

from __future__ import annotations

import math
import re
from importlib import resources

import numpy as np
import pytest

from rattle_lab.rig import synthesize
from rattle_lab.rig._chain import fractional_delay
from rattle_lab.rig._scene import SceneError, load_scene

F_HZ, LEVEL, DUR = 98.0, 25.0, 0.3


def _scene(tmp_path, chain: str):
    text = resources.files("rattle_lab").joinpath("data/scenes/default.toml").read_text("utf-8")
    text = text[:text.index("[[runs]]")]
    text += (f'[[runs]]\nrun_id = "dwell"\nprotocol = "sine_dwell"\nfreq_hz = {F_HZ}\n'
             f"level_m_s2 = {LEVEL}\nduration_s = {DUR}\n")
    if chain:
        text += "\n[chain]\n" + chain
    path = tmp_path / f"s{abs(hash(chain))}.toml"
    path.write_text(text)
    return load_scene(path)


def _channels(tmp_path, chain: str) -> dict:
    syn = synthesize(_scene(tmp_path, chain))
    return {c.name: c for c in syn.record.runs[0].channels}


@pytest.fixture(scope="module")
def ideal(tmp_path_factory):
    return _channels(tmp_path_factory.mktemp("ideal"), "")


def test_ideal_scene_declares_a_differential_vibrometer(ideal):
    v = ideal["velocity"]
    assert (v.measurand, v.group_delay_s) == ("panel_relative_to_striker", None)


def test_decoder_delay_is_applied_and_declared(tmp_path, ideal):
    real = _channels(tmp_path, "decoder_delay_s = 18e-6\n")["velocity"]
    assert real.group_delay_s == 18e-6
    fs = real.sample_rate_hz
    expected = fractional_delay(ideal["velocity"].read().astype(np.float64), fs, 18e-6)
    # float32 storage: 1e-6 of the 10 V range
    assert np.max(np.abs(real.read() - expected)) < 1e-5


def test_offsets_and_hum(tmp_path, ideal):
    real = _channels(tmp_path, "offset_plate_m_s2 = 0.7\nhum_m_s2 = 0.05\nhum_hz = 50.0\n")
    d = real["plate"].read().astype(np.float64) - ideal["plate"].read()
    fs = real["plate"].sample_rate_hz
    t = np.arange(d.size) / fs
    # least squares: offset + hum at 50 Hz (15 whole periods in 0.3 s + settling)
    design = np.column_stack([np.ones_like(t), np.cos(2 * np.pi * 50 * t), np.sin(2 * np.pi * 50 * t)])
    c = np.linalg.lstsq(design, d, rcond=None)[0]
    assert c[0] == pytest.approx(0.7, rel=1e-4)
    assert math.hypot(c[1], c[2]) == pytest.approx(0.05, rel=1e-3)


def test_adc_quantisation_16_bit(tmp_path):
    real = _channels(tmp_path, "adc_bits = 16\n")
    mic = real["mic"]                 # stored in volts over a +-10 V range
    lsb = 2 * 10.0 / 2**16
    steps = mic.read(si=False).astype(np.float64) / lsb
    assert np.max(np.abs(steps - np.round(steps))) < 1e-3
    assert np.unique(np.round(steps)).size > 10


def test_absolute_vibrometer_adds_the_base_velocity(tmp_path, ideal):
    real = _channels(tmp_path, 'vibrometer = "absolute"\n')
    assert real["velocity"].measurand == "panel_absolute"
    d = real["velocity"].read().astype(np.float64) - ideal["velocity"].read()
    fs = real["velocity"].sample_rate_hz
    t = np.arange(d.size) / fs
    # the difference is a sine at the excitation frequency of amplitude A / W
    design = np.column_stack([np.cos(2 * np.pi * F_HZ * t), np.sin(2 * np.pi * F_HZ * t)])
    c, res, *_ = np.linalg.lstsq(design, d, rcond=None)
    assert math.hypot(*c) == pytest.approx(LEVEL / (2 * np.pi * F_HZ), rel=1e-3)
    assert np.sqrt(res[0] / d.size) < 1e-3 * math.hypot(*c)


def test_floor_reflection_repeats_the_sound_later(tmp_path, ideal):
    real = _channels(tmp_path, "floor_extra_path_m = 0.9\nfloor_gain = 0.3\n")
    d = real["mic"].read().astype(np.float64) - ideal["mic"].read()
    p = ideal["mic"].read().astype(np.float64)
    fs = real["mic"].sample_rate_hz
    lag = 0.9 / 343.0
    k = int(round(lag * fs))
    # the difference is 0.3 times the (noise-free) sound delayed by the extra path
    g = np.dot(d[k:], p[:-k]) / np.dot(p[:-k], p[:-k])
    assert g == pytest.approx(0.3, rel=0.05)      # 5 %: the ideal mic carries its noise


def test_velocity_ringing_follows_each_impact(tmp_path, ideal):
    real = _channels(tmp_path, "ring_velocity_per_m_s = 0.1\n")
    d = real["velocity"].read().astype(np.float64) - ideal["velocity"].read()
    assert np.max(np.abs(d)) > 0.01        # m/s: 0.1 of velocity changes of ~0.3 m/s


@pytest.mark.parametrize("line, why", [('vibrometer = "laser"\n', "must be one of"),
                                       ("adc_bits = 12\n", "must be 0 \\(off\\), 16 or 24"),
                                       ("floor_gain = 2.0\n", "must be <= 1"),
                                       ("decoder_delay = 1e-5\n", "decoder_delay")])
def test_bad_chain_is_refused(tmp_path, line, why):
    with pytest.raises(SceneError, match=why):
        _scene(tmp_path, line)


def test_realistic_scene_turns_everything_on():
    from pathlib import Path

    scene = load_scene(Path(__file__).resolve().parents[2] / "synthetic" / "realistic_lab.toml")
    c = scene.chain
    assert c.decoder_delay_s > 0 and c.vibrometer == "absolute" and c.ring_velocity_per_m_s > 0
    assert c.hum_m_s > 0 and c.hum_m_s2 > 0 and c.hum_pa > 0 and c.adc_bits == 16
    assert c.offset_velocity_m_s and c.offset_plate_m_s2 and c.offset_base_m_s2 and c.offset_mic_pa
    assert c.floor_extra_path_m > 0 and c.floor_gain > 0
    assert re.search(r"noise_rms", Path(scene.source).read_text())


def test_absolute_vibrometer_is_smooth_across_ramp_pieces(tmp_path):
    """A ramp is simulated in pieces of one forcing period, and the simulator wraps the
    forcing phase by 2 pi at each piece; the base velocity added by an absolute vibrometer
    once took the phase's numerical slope as its frequency and spiked by ~A/W there (once
    per period, 19 mm/s on the realistic scene).  The base velocity -A/W sin(theta) changes
    by at most A/fs per sample (its slope is -A cos(theta)) plus the level step of one piece
    over W; the bound below is that, with 10 % slack for the noise-free difference."""
    text = resources.files("rattle_lab").joinpath("data/scenes/default.toml").read_text("utf-8")
    text = text[:text.index("[[runs]]")]
    lo, hi, dur = 20.0, 26.0, 0.3         # above grazing: it rattles
    text += (f'[[runs]]\nrun_id = "up"\nprotocol = "amplitude_ramp_up"\nfreq_hz = {F_HZ}\n'
             f"level_m_s2 = {lo}\nlevel_end_m_s2 = {hi}\nduration_s = {dur}\n")
    chans = []
    for chain in ("", '\n[chain]\nvibrometer = "absolute"\n'):
        path = tmp_path / f"ramp{len(chain)}.toml"
        path.write_text(text + chain)
        chans.append({c.name: c for c in synthesize(load_scene(path)).record.runs[0].channels})
    d = chans[1]["velocity"].read().astype(np.float64) - chans[0]["velocity"].read()
    fs = chans[1]["velocity"].sample_rate_hz
    w = 2 * np.pi * F_HZ
    step = (hi - lo) / (dur * F_HZ)          # level change over one piece (one period)
    bound = 1.1 * (hi / fs + step / w)
    assert np.max(np.abs(np.diff(d))) < bound
    assert np.max(np.abs(d)) == pytest.approx(hi / w, rel=0.02)
