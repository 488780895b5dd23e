"""Impulsiveness (ISO/PAS 1996-3, NT ACOU 112), rattle episodes and the loudness above the
campaign's background (issue 26).

The signals are made here with plain NumPy; the expected onsets come from the closed form
of the F time weighting (a first-order lag, IEC 61672-1), not from the code under test.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.acoustics import (adjustment_db, campaign_background, find_onsets, prominence,
                                  run_acoustics)

FS = 48000.0
P0 = 20e-6
TAU_F = 0.125


def tone_step(l1_db: float, l2_db: float, t_step: float = 1.0, dur: float = 2.5,
              fs: float = FS) -> np.ndarray:
    """A 1 kHz tone (A weighting 0 dB there) that steps from ``l1_db`` to ``l2_db``."""
    t = np.arange(round(dur * fs)) / fs
    amp = np.sqrt(2) * P0 * np.where(t < t_step, 10 ** (l1_db / 20), 10 ** (l2_db / 20))
    return amp * np.sin(2 * np.pi * 1000 * t)


def exact_step_onset(l1_db: float, l2_db: float) -> tuple[float, float]:
    """(LD, duration) of the F-weighted level after a step of mean square m1 -> m2.

    m(t) = m2 + (m1 - m2) x with x = exp(-t/tau); dL/dt = (10/ln 10)(m2 - m1) x / (tau m(t)).
    Its gradient is largest at the step and falls through 10 dB/s where
    x = 10 m2 / ((m2 - m1)(c + 10)), c = 10 / (tau ln 10).
    """
    m1, m2 = 10 ** (l1_db / 10), 10 ** (l2_db / 10)
    c = 10 / (TAU_F * math.log(10))
    x = 10 * m2 / ((m2 - m1) * (c + 10))
    return 10 * math.log10(m2 + (m1 - m2) * x) - l1_db, -TAU_F * math.log(x)


def test_prominence_and_adjustment_formulas():
    # P = 3 lg OR + 2 lg LD; K_I = 1.8 (P - 5) above 5 (NT ACOU 112 / ISO/PAS 1996-3);
    # exact arithmetic: tolerance is float rounding
    assert prominence(1000.0, 100.0) == pytest.approx(13.0, abs=1e-12)
    assert prominence(10.0, 10 ** 0.5) == pytest.approx(4.0, abs=1e-12)
    assert adjustment_db(4.0) == 0.0 and adjustment_db(5.0) == 0.0
    assert adjustment_db(13.0) == pytest.approx(14.4, abs=1e-12)
    assert math.isnan(prominence(0.0, 10.0)) and math.isnan(adjustment_db(float("nan")))


@pytest.mark.parametrize("l1, l2", [(40.0, 70.0), (50.0, 60.0), (30.0, 80.0)])
def test_step_onset_matches_the_f_weighting_closed_form(l1, l2):
    # The level is sampled every 10 ms: the onset's end is found within one step after
    # the exact end, where the gradient is 10 dB/s -> LD within 10 dB/s * 10 ms = 0.1 dB
    # (+0.01 for the A weighting's 1 kHz rounding); the duration within one step.
    # P then within 3 lg((d + 0.01)/d) + 2 lg((LD + 0.11)/LD) < 0.1.
    on = find_onsets(tone_step(l1, l2), FS)
    ld, dur = exact_step_onset(l1, l2)
    assert on.t_start_s.size == 1
    assert on.t_start_s[0] == pytest.approx(1.0, abs=0.0101)
    assert on.level_difference_db[0] == pytest.approx(ld, abs=0.11)
    assert on.t_end_s[0] - on.t_start_s[0] == pytest.approx(dur, abs=0.0101)
    assert on.prominence[0] == pytest.approx(prominence(ld / dur, ld), abs=0.1)


def test_prominence_does_not_depend_on_the_scale():
    # LD and OR are level differences: any gain leaves P unchanged (float noise only)
    x = tone_step(45.0, 65.0)
    a = find_onsets(x, FS).rating()
    b = find_onsets(x * 1234.5, FS).rating()
    assert a["impulse_prominence"] == pytest.approx(b["impulse_prominence"], abs=1e-9)


def test_steady_noise_has_no_prominent_impulse():
    # Stationary noise at 60 dB: the F-weighted level fluctuates by about
    # +-10 lg(1 +- 1/sqrt(2 B tau)) ~ 0.1 dB; any onset is far below P = 5 (no adjustment).
    rng = np.random.default_rng(7)
    x = rng.normal(0.0, P0 * 1000, int(3 * FS))
    r = find_onsets(x, FS).rating()
    assert r["impulse_onsets"] == 0 or r["impulse_penalty_db"] == 0.0


def clicks(t_impacts: np.ndarray, dur: float, noise_pa: float, click_pa: float,
           seed: int = 0, fs: float = FS) -> np.ndarray:
    """Background noise plus decaying 2 kHz clicks (2 ms decay) at ``t_impacts``."""
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, noise_pa, round(dur * fs))
    k = np.arange(round(0.012 * fs))
    click = click_pa * np.exp(-k / fs / 0.002) * np.sin(2 * np.pi * 2000 * k / fs)
    for ti in t_impacts:
        i = round(ti * fs)
        x[i:i + k.size] += click[:x.size - i]
    return x


def test_episodes_count_impacts_and_rate_them():
    # Two episodes of clicks at 10/s and 25/s with background between: the episodes'
    # impacts per second are the trains' rates (exact up to float rounding of the times);
    # isolated clicks every 0.1 s rise within one 10 ms step: P > 5 (an adjustment).
    t1 = 0.8 + np.arange(8) * 0.1
    t2 = 2.6 + np.arange(15) * 0.04
    x = clicks(np.concatenate([t1, t2]), 4.0, 2e-3, 0.5)
    ra = run_acoustics(x, FS, np.concatenate([t1, t2]), with_loudness=False)
    eps = ra.episodes
    assert [e["n_impacts"] for e in eps] == [8, 15]
    assert eps[0]["impacts_per_s"] == pytest.approx(10.0, rel=1e-9)
    assert eps[1]["impacts_per_s"] == pytest.approx(25.0, rel=1e-9)
    run = ra.summary()["acoustics"]
    assert run["impacts_per_s"] == pytest.approx((7 + 14) / (0.7 + 0.56), rel=1e-9)
    assert eps[0]["impulse_prominence"] > 5 and eps[0]["impulse_penalty_db"] > 0
    assert run["impulse_prominence"] == pytest.approx(
        max(e["impulse_prominence"] for e in eps), abs=1e-12)


@pytest.mark.slow  # ISO 532-1 loudness of 5 s of sound in stretches: ~10-30 s
def test_loudness_above_background_and_its_flag():
    # Three runs of one campaign: background noise only, a loud rattle, a rattle barely
    # above the noise.  The background stretches' N5 spread decides the flag.
    fs = FS
    quiet = clicks(np.zeros(0), 1.2, 2e-3, 0.0, seed=1, fs=fs)
    t_loud = 0.55 + np.arange(8) * 0.05
    loud = clicks(t_loud, 1.6, 2e-3, 0.5, seed=2, fs=fs)
    t_weak = 0.55 + np.arange(8) * 0.05
    weak = clicks(t_weak, 1.6, 2e-3, 0.0005, seed=3, fs=fs)
    runs = [run_acoustics(quiet, fs, np.zeros(0)),
            run_acoustics(loud, fs, t_loud), run_acoustics(weak, fs, t_weak)]
    out = campaign_background([r.summary() for r in runs])
    ac = [o["acoustics"] for o in out if o is not None]
    bg = [b["loudness_n5_sone"] for a in ac for b in a["background_stretches"]
          if b["loudness_n5_sone"] is not None and np.isfinite(b["loudness_n5_sone"])]
    assert len(bg) >= 3
    assert ac[1]["background_loudness_n5_sone"] == pytest.approx(np.mean(bg), rel=1e-12)
    assert ac[1]["loudness_above_background_sone"] == pytest.approx(
        ac[1]["rattle_loudness_n5_sone"] - np.mean(bg), rel=1e-12)
    # the loud rattle is far above the background; the weak one (clicks 60 dB below the
    # loud ones, under the noise) is not judged above it
    assert ac[1]["loudness_above_background_sone"] > 5 * ac[1]["background_loudness_spread_sone"]
    assert "background_too_close" not in ac[1]["psychoacoustic_flags"]
    assert "background_too_close" in ac[2]["psychoacoustic_flags"]
    assert ac[0]["rattle_loudness_n5_sone"] is None or not np.isfinite(
        ac[0]["rattle_loudness_n5_sone"])


def test_campaign_without_background_is_flagged():
    s = {"acoustics": {"rattle_loudness_n5_sone": 3.0, "background_stretches": [],
                       "episodes": [{"loudness_n5_sone": 3.0}]}}
    (o,) = campaign_background([s])
    assert o is not None
    assert o["acoustics"]["loudness_above_background_sone"] is None
    assert o["acoustics"]["psychoacoustic_flags"] == ["no_background"]
    one = {"acoustics": {"rattle_loudness_n5_sone": 3.0, "episodes": [],
                         "background_stretches": [{"loudness_n5_sone": 1.0}]}}
    (o,) = campaign_background([one])
    assert o is not None
    assert o["acoustics"]["loudness_above_background_sone"] == pytest.approx(2.0)
    assert o["acoustics"]["psychoacoustic_flags"] == ["background_spread_unknown"]


class _Uncalibrated:
    """A stand-in microphone channel in full-scale units (what ``channel_calibration`` reads)."""

    extra: dict = {}
    uncalibrated = True
    sensitivity = None
    sensitivity_units = None
    units = "1"


def test_uncalibrated_microphone_gives_no_loudness_but_a_flag():
    # (0.9 s: the run-level ISO 532-1 loudness of issue 17 is computed all the same)
    t_imp = 0.55 + np.arange(3) * 0.1
    x = clicks(t_imp, 0.9, 2e-3, 0.5)
    cal = run_acoustics(x, FS, t_imp, with_loudness=False).summary()["acoustics"]
    unc = run_acoustics(x, FS, t_imp, channel=_Uncalibrated()).summary()["acoustics"]
    assert "uncalibrated_no_loudness" in unc["psychoacoustic_flags"]
    assert not np.isfinite(unc["rattle_loudness_n5_sone"])
    assert all(not np.isfinite(e["loudness_n5_sone"]) for e in unc["episodes"])
    # impulsiveness and impacts per second do not need the sensitivity
    assert unc["impulse_prominence"] == pytest.approx(cal["impulse_prominence"], abs=1e-9)
    assert unc["impacts_per_s"] == pytest.approx(cal["impacts_per_s"], rel=1e-12)


@pytest.mark.slow  # the CLI's ingest and fit
def test_fit_json_has_the_psychoacoustic_keys(tmp_path):
    # `rattle-lab ingest` and `fit` on a record made here: a microphone hearing a steady 1 kHz tone of
    # 70 dB SPL (faded in over 50 ms) beside a plate that never reaches the striker.  No
    # impact: the whole run is background, whose ISO 532-1 N5 is the tone's
    # 2^((70 - 40)/10) = 8 sone (+-3 %: the standard's tables' rounding, as in
    # test_cli_fit_acoustics); no rattle, so no loudness above it and no impact rate.
    import json

    from rattle_lab.records import Channel, Record, Run, write_record

    from record_factory import plate_rig, run_command

    n = int(1.0 * FS)
    t = np.arange(n) / FS
    p = np.sqrt(2) * P0 * 10 ** (70 / 20) * np.sin(2 * np.pi * 1000 * t)
    n_on = round(0.05 * FS)
    p[:n_on] *= 0.5 - 0.5 * np.cos(np.pi * np.arange(n_on) / n_on)
    common = dict(sample_rate_hz=FS, start_time_s=0.0)
    run = Run("dwell_050", "sine_dwell", (
        Channel("velocity", "plate_velocity", "m/s", 1e-3 * np.sin(2 * np.pi * 50 * t), **common),
        Channel("mic", "sound_pressure", "Pa", p, **common)),
        excitation_freq_hz=50.0, nominal_level=1.0, nominal_level_units="m/s^2",
        start_time_iso="2024-03-01T14:10:00Z")
    src = write_record(tmp_path / "rec.h5", Record("tone", "measured", plate_rig(), (run,)))
    store = tmp_path / "store.h5"
    assert run_command("ingest", str(src), "-o", str(store), "--quiet").returncode == 0
    proc = run_command("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    (row,) = json.loads(proc.stdout)["runs"]
    ac = row["acoustics"]
    assert set(ac) >= {"roughness_asper", "tonality_tu", "loudness_ecma_sone",
                       "impulse_prominence", "impulse_penalty_db", "impacts_per_s",
                       "loudness_above_background_sone", "episodes", "background_stretches",
                       "psychoacoustic_flags"}
    assert ac["episodes"] == [] and ac["impacts_per_s"] is None
    assert ac["loudness_above_background_sone"] is None
    assert ac["roughness_asper"] is None   # ECMA-418-2 is off by default
    (bg,) = ac["background_stretches"]
    assert bg["loudness_n5_sone"] == pytest.approx(8.0, rel=0.03)
    assert ac["background_loudness_n5_sone"] == pytest.approx(8.0, rel=0.03)


def test_real_clap_is_one_prominent_impulse():
    # A real recording we did not make (../shared/realdata/clap: two wooden boards clapped in
    # a room, 44.1 kHz, uncalibrated), placed after 0.8 s of steady noise 50 dB below its
    # peak: one onset, where the clap starts (within one 10 ms step of L_AF), and a clap is
    # impulsive (P > 5: an adjustment).  The units are full scale: P needs no calibration.
    import warnings
    from pathlib import Path

    from rattle_lab.records import read

    from conftest import realdata

    root = Path(__file__).resolve().parents[2]
    path = realdata("clap/rir_clap.wav")   # the existing helper (RATTLE_LAB_REALDATA)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = read(path, mapping=root / "data_schema" / "mappings" / "clap_wav.toml")
    ch = rec.runs[0].channels[0]
    fs = ch.sample_rate_hz
    clap = ch.read()
    lead = round(0.8 * fs)
    noise = np.random.default_rng(3).normal(0.0, np.max(np.abs(clap)) * 10 ** (-50 / 20),
                                            lead + clap.size)
    x = noise + np.concatenate([np.zeros(lead), clap])
    on = find_onsets(x, fs)
    assert on.t_start_s.size >= 1
    i = int(np.nanargmax(on.prominence))
    assert on.t_start_s[i] == pytest.approx(0.8, abs=0.0101)
    assert on.prominence[i] > 5.0 and adjustment_db(on.prominence[i]) > 0.0
    assert find_onsets(x * 1e3, fs).prominence[i] == pytest.approx(on.prominence[i], abs=1e-9)


def test_episode_loudness_is_the_runs_curve_over_the_episode():
    # A 1 kHz tone at 60 dB (4 sone, ISO 532-1) switched on for the 2 s of an episode in a
    # run of quiet noise.  The episode's N5 is read off the run's N(t); it equals the tone's
    # loudness (ISO 532-1 anchor, 3 %) and the loudness function on the episode alone
    # from rest within 0.1 % (they differ only in the first milliseconds, which a 95th
    # percentile over 2 s does not see: 2e-8 measured).
    from rattle_lab.acoustics import loudness

    fs, dur = FS, 6.0
    t = np.arange(round(dur * fs)) / fs
    rng = np.random.default_rng(5)
    p = rng.normal(0.0, P0 * 10 ** (20 / 20), t.size)          # about 20 dB of noise
    on = (t >= 2.0) & (t < 4.0)
    p[on] += np.sqrt(2) * P0 * 10 ** (60 / 20) * np.sin(2 * np.pi * 1000 * t[on])
    impacts = np.arange(2.0, 3.951, 0.1)
    ra = run_acoustics(p, fs, impacts)
    (ep,) = ra.episodes
    assert ep["loudness_n5_sone"] == pytest.approx(4.0, rel=0.03)
    i0, i1 = round(ep["t_start_s"] * fs), round(ep["t_end_s"] * fs)
    alone = loudness(p[i0:i1], fs)
    assert ep["loudness_n5_sone"] == pytest.approx(alone.n5_sone, rel=1e-3)
    assert ep["loudness_max_sone"] == pytest.approx(alone.nmax_sone, rel=1e-3)
    # the run's N(t) is not kept unless asked for
    assert ra.loudness is not None and ra.loudness.curve is None


def test_laf_from_the_levels_weighted_signal_is_laf_of_the_record():
    # run_acoustics hands its F-weighted A mean square to the onset search: the same L_AF.
    from rattle_lab.acoustics import laf_db
    from rattle_lab.acoustics._levels import levels_bands_fast

    x = tone_step(40.0, 70.0)
    _, _, fast_a = levels_bands_fast(x, FS)
    np.testing.assert_array_equal(laf_db(x, FS, fast_a_ms=fast_a), laf_db(x, FS))


def test_the_ecma_packages_import_leaves_matplotlib_as_it_was(tmp_path, monkeypatch):
    # sottek-hearing-model sets Matplotlib's global font sizes (16-20 pt) and family when
    # imported, which broke the report's layout in the same process.  A stand-in package
    # that does the same (so this runs without the optional package): after
    # ecma418_available(), rcParams and the backend are what they were.
    import sys

    import matplotlib

    from rattle_lab.acoustics import ecma418_available

    pkg = tmp_path / "sottek_hearing_model"
    pkg.mkdir()
    (pkg / "__init__.py").write_text(
        "import matplotlib as mpl\n"
        "import matplotlib.pyplot as plt\n"
        "mpl.rcParams['font.family'] = 'sans-serif'\n"
        "mpl.rcParams['font.sans-serif'] = 'Arial'\n"
        "plt.rc('font', size=16)\n"
        "plt.rc('axes', titlesize=18)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "sottek_hearing_model", raising=False)
    before = dict(matplotlib.rcParams)
    backend = matplotlib.get_backend()
    assert ecma418_available()
    assert sys.modules["sottek_hearing_model"].__file__.startswith(str(tmp_path))
    assert dict(matplotlib.rcParams) == before
    assert matplotlib.get_backend() == backend
    monkeypatch.delitem(sys.modules, "sottek_hearing_model")
