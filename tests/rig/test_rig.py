"""The synthetic rig: physics against independent references, realism, skipping, determinism."""

from __future__ import annotations

import dataclasses

import copy
import hashlib
import math
import tomllib
from importlib import resources

import h5py
import numpy as np
import pytest

from rattle_lab.store import ingest
from rattle_lab.model.linear import threshold_accel_ms2
from rattle_lab.records import read
from rattle_lab.rig import (Piece, RunMotion, StageCounter, parse_scene, schedule,
                            synthesize, write_synthetic)
from rattle_lab.rig._channels import (contact_kernel, plate_acceleration, sound_pressure,
                                      vibrometer_velocity)
from rattle_lab.rig._scene import AcousticSpec, ArtefactSpec, ModelSpec, RunSpec
from rattle_lab.model.sdf import SDFParams, simulate

TWO_PI = 2 * math.pi


def default_dict() -> dict:
    return tomllib.loads(resources.files("rattle_lab").joinpath("data/scenes/default.toml")
                         .read_text("utf-8"))


def small_scene(sensors: tuple[str, ...] = ("base", "plate", "velocity", "mic", "drive"),
                seed: int = 3):
    """The default scene cut to three 0.4 s runs (one ramp up, one ramp down, one dwell)."""
    d = copy.deepcopy(default_dict())
    d["scene"]["seed"] = seed
    d["runs"] = [dict(d["runs"][6], duration_s=0.4), dict(d["runs"][7], duration_s=0.4),
                 dict(d["runs"][9], duration_s=0.4)]
    d["sensors"] = {k: v for k, v in d["sensors"].items() if k in sensors}
    if "mic" not in sensors:
        d.pop("acoustic")
    return parse_scene(d, "<small>")


def channel_hashes(record) -> dict[str, str]:
    return {f"{run.run_id}/{c.name}": hashlib.sha256(c.read(si=False).tobytes()).hexdigest()
            for run in record.runs for c in run.channels}


def ramp_tolerance_m_s2(run, f_s_hz: float, zeta: float, n_samples: int, fs_hz: float,
                        piece_periods: int = 2) -> float:
    """How far a ramp's first impact may lag the quasi-static threshold.

    The response amplitude follows a slow ramp with a delay of about one modal time
    constant 1 / (zeta omega_s) (the group delay at resonance, smaller off resonance);
    we allow two, plus one piece of constant level (the ramp's resolution).
    """
    duration_s = n_samples / fs_hz
    rate = abs(run.level_end - run.nominal_level) / duration_s
    return rate * (2.0 / (zeta * TWO_PI * f_s_hz) + piece_periods / run.excitation_freq_hz)


# ----------------------------------------------------------------------------- pure pieces
def test_schedule_ramp_is_contiguous_with_midpoint_levels():
    run = RunSpec("r", "amplitude_ramp_up", 96.0, 2.0, 1.0, level_end_m_s2=12.0)
    pieces = schedule(run, 2)
    assert pieces[0].t0_s == 0.0 and pieces[-1].t1_s == 1.0
    assert all(a.t1_s == b.t0_s for a, b in zip(pieces, pieces[1:]))
    mids = np.array([(p.t0_s + p.t1_s) / 2 for p in pieces])
    np.testing.assert_allclose([p.level_m_s2 for p in pieces], 2.0 + 10.0 * mids, rtol=1e-14)
    np.testing.assert_allclose([p.t1_s - p.t0_s for p in pieces[:-1]], 2 / 96.0, rtol=1e-12)


def test_schedule_stepped_frequencies():
    run = RunSpec("s", "stepped_frequency", 102.0, 5.0, 2.6, freq_end_hz=90.0, freq_step_hz=1.0)
    pieces = schedule(run, 2)
    assert [p.freq_hz for p in pieces] == [102.0 - k for k in range(13)]
    np.testing.assert_allclose([p.t1_s - p.t0_s for p in pieces], 0.2, rtol=1e-12)


def test_contact_pulse_has_unit_area():
    fs = 20000.0
    k = contact_kernel(0.0002, fs)
    assert k.size == 4                                   # round(0.2 ms * 20 kHz)
    assert k.sum() / fs == pytest.approx(1.0, rel=1e-14)


def one_impact_motion(n: int, t_s: float, v_in: float, v_out: float) -> RunMotion:
    return RunMotion(pieces=(Piece(0.0, n / 20000.0, 1.0, 96.0),), impact_t_s=np.array([t_s]),
                     impact_v_in_m_s=np.array([v_in]), impact_v_out_m_s=np.array([v_out]),
                     impact_level_m_s2=np.array([1.0]), piece_impacts=np.array([1]),
                     theta=np.zeros(n), level_m_s2=np.ones(n), freq_hz=np.full(n, 96.0),
                     v_rel_m_s=np.zeros(n), a_rel_m_s2=np.zeros(n))


def test_plate_pulse_area_is_the_momentum_change():
    fs, n = 20000.0, 2000
    motion = one_impact_motion(n, 0.01, 0.5, 0.3)
    model = ModelSpec(gap_m=1e-3, e=0.6, zeta=0.01, contact_s=0.0003)
    a = plate_acceleration(motion, np.zeros(n), model, (), fs)
    # area = -(v_in + v_out) = -(1 + e) v_in: the velocity jump of the impact
    assert a.sum() / fs == pytest.approx(-0.8, rel=1e-12)
    # the contact is centred on the impact (t = 200 samples, +-3 samples), each sample the mean
    # over its sampling interval: samples 197..203, symmetric, centroid at the impact
    assert np.flatnonzero(np.abs(a) > 1e-9 * np.abs(a).max()).tolist() == list(range(197, 204))
    np.testing.assert_allclose(a[197:204], a[197:204][::-1], rtol=1e-12)
    assert np.sum(np.arange(n) * a) / np.sum(a) == pytest.approx(200.0, abs=1e-9)


def test_vibrometer_spreads_the_jump_over_the_contact_like_the_accelerometer():
    """The simulated (rigid) jump of -(v_in + v_out) at t_i becomes the running integral of
    the plate accelerometer's contact pulse: the rigid velocity outside the contact, the
    same momentum change, both centred on the impact (sub-sample position kept)."""
    fs, n = 20000.0, 2000
    t_i = 0.01 + 0.3 / fs
    t = np.arange(n) / fs
    motion = one_impact_motion(n, t_i, 0.5, 0.3)
    rigid = np.where(t < t_i, 0.5, -0.3)
    motion = dataclasses.replace(motion, v_rel_m_s=rigid)
    model = ModelSpec(gap_m=1e-3, e=0.6, zeta=0.01, contact_s=0.0003)
    v = vibrometer_velocity(motion, None, fs, model.contact_s)
    outside = np.abs(t - t_i) > 0.5 * model.contact_s
    np.testing.assert_array_equal(v[outside], rigid[outside])
    assert not np.array_equal(v, rigid)
    a = plate_acceleration(motion, np.zeros(n), model, (), fs)
    dv = np.diff(v)
    assert dv.sum() == pytest.approx(-0.8, rel=1e-12) and a.sum() / fs == pytest.approx(-0.8, rel=1e-12)
    # centroids (in samples; a velocity increment k sits between samples k and k+1)
    c_v = np.sum((np.arange(n - 1) + 0.5) * dv) / dv.sum()
    c_a = np.sum(np.arange(n) * a) / a.sum()
    assert c_a == pytest.approx(t_i * fs, abs=0.01)     # box-averaged samples of the pulse
    assert c_v == pytest.approx(t_i * fs, abs=0.01)     # point samples of the smooth step
    # without a contact the vibrometer is the rigid jump itself
    np.testing.assert_array_equal(vibrometer_velocity(motion, None, fs, 0.0), rigid)


def test_sound_pulse_follows_the_linear_law_after_the_delay():
    fs, n = 20000.0, 4000
    motion = one_impact_motion(n, 0.05, 0.4, 0.24)
    ac = AcousticSpec(pa_per_m_s=5.0, intercept_pa=0.1, distance_m=0.3, c_m_s=343.0,
                      radiation_lag_s=0.0003, mode_pa_per_m_s2=0.0)
    p, second = sound_pressure(motion, ac, ArtefactSpec(), fs, np.random.default_rng(0), 0.0)
    assert not second.any()
    k = int(np.argmax(np.abs(p)))
    assert k == round((0.05 + 0.3 / 343.0 + 0.0003) * fs)
    assert p[k] == pytest.approx(5.0 * 0.4 + 0.1, rel=1e-12)
    assert np.all(np.abs(p[:k]) < 1e-9 * p[k])            # nothing before the arrival


# ----------------------------------------------------------------------------- realism
def test_records_ingest_without_fatal_flags(synthetic_campaign_record, synthetic_threshold_record,
                                            synthetic_noisy_record, tmp_path):
    report = ingest([synthetic_campaign_record, synthetic_threshold_record, synthetic_noisy_record],
                    tmp_path / "store.h5")
    assert [r.status for r in report.inputs] == ["added"] * 3
    assert [f for r in report.inputs for f in r.findings if f.fatal] == []


def test_truth_impacts_match_direct_simulation(synthetic_campaign_record):
    """dwell_096 (9 m/s^2 at 96 Hz, above grazing): one uninterrupted simulation from rest
    over the settling time plus the run, converted by hand, is the reference."""
    with read(synthetic_campaign_record) as rec:
        truth = rec.truth
        run = rec.run("dwell_096")
        duration_s = run.channels[0].n_samples / run.channels[0].sample_rate_hz
    w_s = TWO_PI * truth.f_s_hz
    F = truth.participation * 9.0 / (w_s**2 * truth.gap_m)          # eq. 2.27, 2.31
    settle = 8.0 / truth.zeta
    ref = simulate(SDFParams(F=F, omega=96.0 / truth.f_s_hz, zeta=truth.zeta, e=truth.e),
                   duration=settle + w_s * duration_s)
    keep = ref.impacts.t >= settle
    got = truth.impacts["dwell_096"]
    assert got.t_s.size == int(keep.sum()) > 100
    np.testing.assert_allclose(got.t_s, (ref.impacts.t[keep] - settle) / w_s, rtol=0, atol=1e-9)
    # v = omega_s h v_nd (eq. 4.4); 1e-9 relative: round-off of the split at the settle time
    np.testing.assert_allclose(got.v_in_m_s, ref.impacts.v_in[keep] * w_s * truth.gap_m, rtol=1e-9)
    np.testing.assert_allclose(got.v_out_m_s, truth.e * got.v_in_m_s, rtol=1e-12)


def test_vibrometer_is_the_relative_modal_velocity(synthetic_campaign_record):
    with read(synthetic_campaign_record) as rec:
        truth = rec.truth
        ch = rec.run("dwell_096").channel("velocity")
        v = ch.read().astype(float)
        fs = ch.sample_rate_hz
    w_s = TWO_PI * truth.f_s_hz
    F = truth.participation * 9.0 / (w_s**2 * truth.gap_m)
    settle = 8.0 / truth.zeta
    t = np.arange(v.size) / fs
    ref = simulate(SDFParams(F=F, omega=96.0 / truth.f_s_hz, zeta=truth.zeta, e=truth.e),
                   duration=settle + w_s * v.size / fs, dense_t=settle + w_s * t, dense_fields=("v",))
    v_ref = ref.dense.v * w_s * truth.gap_m
    # away from impacts (the 5 kHz band limit smears the velocity jumps over ~1 ms)
    far = np.ones(v.size, bool)
    for ti in truth.impacts["dwell_096"].t_s:
        far[max(0, round((ti - 2e-3) * fs)):round((ti + 2e-3) * fs)] = False
    assert far.mean() > 0.5
    # noise 0.2 mm/s rms: 6 sigma; plus 0.5 % of the amplitude for the filter's passband ripple
    tol = 6 * 0.0002 + 0.005 * np.abs(v_ref).max()
    assert np.max(np.abs(v - v_ref)[far]) < tol


def test_base_fundamental_is_the_nominal_level(synthetic_campaign_record):
    with read(synthetic_campaign_record) as rec:
        ch = rec.run("dwell_098").channel("base")
        a = ch.read().astype(float)
        fs = ch.sample_rate_hz
    t = np.arange(a.size) / fs
    basis = np.column_stack([np.cos(TWO_PI * 98.0 * t), np.sin(TWO_PI * 98.0 * t)])
    coef, *_ = np.linalg.lstsq(basis, a, rcond=None)
    # 2 s window: the 88 Hz fan and the harmonics are orthogonal to 98 Hz; noise 0.02 m/s^2
    assert np.hypot(*coef) == pytest.approx(25.0, rel=1e-3)


def test_sound_peak_follows_each_impact(synthetic_campaign_record):
    with read(synthetic_campaign_record) as rec:
        truth = rec.truth
        ch = rec.run("dwell_098").channel("mic")
        p = ch.read().astype(float)
        fs = ch.sample_rate_hz
    delay = truth.extra["acoustic_delay_s"]
    assert delay == pytest.approx(0.3 / 343.0 + 0.0003, rel=1e-12)
    imp = truth.impacts["dwell_098"]
    gaps_before = np.diff(imp.t_s, prepend=-1.0)
    gaps_after = np.diff(imp.t_s, append=1e9)
    isolated = (gaps_before > 5e-3) & (gaps_after > 5e-3) & (imp.v_in_m_s > 0.05)
    assert isolated.sum() > 50
    half = round(0.5e-3 * fs)
    checked = 0
    for ti, vi in zip(imp.t_s[isolated], imp.v_in_m_s[isolated]):
        k = round((ti + delay) * fs)
        if k + half >= p.size:
            continue
        window = np.abs(p[k - half:k + half + 1])
        assert int(np.argmax(window)) - half == 0
        # linear law 5 Pa/(m/s) + 0.1 Pa; tolerance: mode radiation (0.0002 Pa per m/s^2 of
        # <= 700 m/s^2), 6 sigma of 5 mPa noise, 5 % of a previous pulse's tail
        assert abs(p[k] - (5.0 * vi + 0.1)) < 0.14 + 0.03 + 0.05
        checked += 1
    assert checked > 50


@pytest.mark.parametrize("fixture", ["synthetic_threshold_record", "synthetic_campaign_record"])
def test_onset_matches_grazing_curve(fixture, request):
    path = request.getfixturevalue(fixture)
    with read(path) as rec:
        truth = rec.truth
        table = truth.thresholds
        n_checked = 0
        for run in rec.runs:
            if run.protocol != "amplitude_ramp_up":
                continue
            ch = run.channels[0]
            k = int(np.flatnonzero(table.freq_hz == run.excitation_freq_hz)[0])
            expected = threshold_accel_ms2(run.excitation_freq_hz, truth.gap_m, truth.f_s_hz,
                                           truth.zeta, truth.participation)
            tol = ramp_tolerance_m_s2(run, truth.f_s_hz, truth.zeta, ch.n_samples, ch.sample_rate_hz)
            assert table.onset_level[k] >= expected - 1e-9       # never before grazing
            assert table.onset_level[k] - expected <= tol
            first = truth.impacts[run.run_id].t_s[0]
            assert first > 0.0
            n_checked += 1
    assert n_checked >= 4


def test_down_ramp_hysteresis_above_resonance(synthetic_threshold_record):
    with read(synthetic_threshold_record) as rec:
        table = rec.truth.thresholds
        f_s = rec.truth.f_s_hz
    above = table.freq_hz >= f_s + 2.0
    assert above.sum() >= 3
    # the impacting branch survives well below the linear grazing level above resonance
    assert np.all(table.disappearance_level[above] < 0.8 * table.onset_level[above])


def test_threshold_record_has_only_what_the_scene_asks(synthetic_threshold_record):
    with read(synthetic_threshold_record) as rec:
        for run in rec.runs:
            assert [c.name for c in run.channels] == ["base"]
            assert run.channels[0].sample_rate_hz == 2000.0
            assert run.channels[0].n_samples == 40000                # 20 s at 2 kHz exactly


# ----------------------------------------------------------------------------- skipping
def test_skipped_stages_are_never_evaluated():
    full, no_mic, thr = StageCounter(), StageCounter(), StageCounter()
    r_full = synthesize(small_scene(), counter=full)
    r_nomic = synthesize(small_scene(("base", "plate", "velocity", "drive")), counter=no_mic)
    r_thr = synthesize(small_scene(("base",)), counter=thr)
    n_runs = 3
    assert full["acoustic"] == full["mic"] == n_runs and full["motion_dense"] == full["simulate"]
    assert no_mic["acoustic"] == no_mic["mic"] == 0 and no_mic["plate"] == n_runs
    assert thr["motion_dense"] == 0 and thr["simulate"] == full["simulate"]
    assert thr["plate"] == thr["velocity"] == thr["mic"] == thr["acoustic"] == thr["drive"] == 0
    assert thr["base"] == n_runs
    # skipping changes nothing the skipped stages do not make: same impacts, same base channel
    for run_id, table in r_full.record.truth.impacts.items():
        assert r_thr.record.truth.impacts[run_id] == table
        assert r_nomic.record.truth.impacts[run_id] == table
    assert channel_hashes(r_thr.record) == {k: v for k, v in channel_hashes(r_full.record).items()
                                            if k.endswith("/base")}
    assert r_thr.record.truth.acoustic_law.startswith("none")
    assert [r.n_impacts for r in r_thr.runs] == [r.n_impacts for r in r_full.runs]


# ----------------------------------------------------------------------------- determinism
def dataset_hashes(path) -> dict[str, str]:
    out = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset):
            out[name] = hashlib.sha256(obj[()].tobytes()).hexdigest()

    with h5py.File(path, "r") as fh:
        fh.visititems(visit)
    return out


def test_same_scene_and_seed_give_identical_datasets(tmp_path):
    scene = small_scene()
    write_synthetic(scene, tmp_path / "a.h5")
    write_synthetic(scene, tmp_path / "b.h5")
    write_synthetic(scene, tmp_path / "c.h5", seed=4)
    a, b, c = (dataset_hashes(tmp_path / n) for n in ("a.h5", "b.h5", "c.h5"))
    assert len(a) > 15 and a == b
    # the writer stores no timestamps: even the file bytes are identical
    assert (hashlib.sha256((tmp_path / "a.h5").read_bytes()).digest()
            == hashlib.sha256((tmp_path / "b.h5").read_bytes()).digest())
    # another seed: other noise, the same physics (truth)
    assert all(a[k] != c[k] for k in a if "/channels/" in k)
    assert all(a[k] == c[k] for k in a if k.startswith("truth/impacts"))


def test_scene_summary_lines():
    result = synthesize(small_scene())
    lines = [r.line() for r in result.runs]
    assert lines[0].startswith("up_098: amplitude_ramp_up 98 Hz, 0.4 s, ")
    assert all("impacts" in line for line in lines)


@pytest.mark.parametrize("protocol, extra", [
    ("swept_frequency", {"freq_end_hz": 100.0}),
    ("stepped_frequency", {"freq_end_hz": 100.0, "freq_step_hz": 2.0}),
])
def test_frequency_runs_keep_the_forcing_phase_continuous(protocol, extra):
    from rattle_lab.rig import Modal, simulate_run

    fs = 10000.0
    run = RunSpec("f", protocol, 90.0, 5.0, 0.5, **extra)
    modal = Modal(f_s_hz=96.0, zeta=0.0085, participation=1.2442, gap_m=0.0013, e=0.6)
    motion = simulate_run(modal, run, piece_periods=2, settle_time_constants=8.0, sample_rate_hz=fs)
    # the phase advances by 2 pi f / fs per sample, also across piece boundaries (no jumps);
    # at a boundary the step mixes the two frequencies: bounded by the larger one
    step = (np.diff(motion.theta) + np.pi) % TWO_PI - np.pi     # theta is carried modulo 2 pi
    f_lo = np.minimum(motion.freq_hz[:-1], motion.freq_hz[1:])
    f_hi = np.maximum(motion.freq_hz[:-1], motion.freq_hz[1:])
    assert np.all(step >= TWO_PI * f_lo / fs - 1e-9) and np.all(step <= TWO_PI * f_hi / fs + 1e-9)
    # first piece: the sweep's frequency at its midpoint, 20 Hz/s * (2 / 90 s) / 2 above 90 Hz
    assert motion.freq_hz[0] == pytest.approx(90.0, abs=0.25) and motion.freq_hz[-1] >= 98.0


def test_dropout_artefact_is_a_fatal_dropout_at_ingest(tmp_path):
    from rattle_lab.records import DropoutError

    d = copy.deepcopy(default_dict())
    d["runs"] = [dict(d["runs"][8], duration_s=0.2)]
    d["artefacts"]["dropout_s"] = 0.005
    path = tmp_path / "drop.h5"
    write_synthetic(parse_scene(d, "<drop>"), path)
    with pytest.raises(DropoutError, match=r"mic"):
        ingest([path], tmp_path / "store.h5")


def test_noisy_record_fan_harmonics_and_tight_range(synthetic_noisy_record):
    with read(synthetic_noisy_record) as rec:
        run = rec.run("dwell_098")
        base = run.channel("base")
        a = base.read().astype(float)
        t = np.arange(a.size) / base.sample_rate_hz
        mic = run.channel("mic")
        peak_fraction = max(float(np.abs(r.channel("mic").read(si=False)).max()) / mic.range_max
                            for r in rec.runs)

    def amplitude(freq_hz: float) -> float:
        basis = np.column_stack([np.cos(TWO_PI * freq_hz * t), np.sin(TWO_PI * freq_hz * t)])
        return float(np.hypot(*np.linalg.lstsq(basis, a, rcond=None)[0]))

    # 3 s window: 88, 98 and 196 Hz are orthogonal; noise 0.3 m/s^2 rms adds ~0.002
    assert amplitude(88.0) == pytest.approx(0.8, rel=0.02)                 # the fan
    assert amplitude(98.0) == pytest.approx(25.0, rel=0.002)               # the drive level
    # 2nd harmonic with impacts all along: 25 * (0.03 + 0.12 * load), load -> 1 with a
    # 0.05 s lag, i.e. its mean over 3 s is 1 - 0.05 / 3
    assert amplitude(196.0) == pytest.approx(25.0 * (0.03 + 0.12 * (1 - 0.05 / 3)), rel=0.03)
    assert 0.5 < peak_fraction < 1.0                                     # close to range, unclipped
