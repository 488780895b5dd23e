"""The rig's opt-in multi-mode model (``[model] kind = "modal"``, issue 14 item 5).

The scene synthetic/modal_lab.toml is written through ``rattle-lab simulate`` (in this
process, :func:`record_factory.run_command`); its truth is checked against a direct run of
:mod:`rattle_lab.model.modal` built here from the scene's numbers (the inertial pressure
``rho h A`` and the settling time computed independently), and ``rattle-lab ingest`` +
``fit`` must find its impacts.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import h5py
import numpy as np
import pytest
from scipy import signal

from record_factory import run_command
from rattle_lab.model.modal import KelvinVoigtContact, modal_channels, plate_system, simulate_modal
from rattle_lab.model.plate import Plate
from rattle_lab.rig import load_scene
from rattle_lab.rig._scene import SceneError, parse_scene

SCENE = Path(__file__).resolve().parents[2] / "synthetic" / "modal_lab.toml"


@pytest.fixture(scope="module")
def record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("modal") / "modal.h5"
    proc = run_command("simulate", str(SCENE), "-o", str(out), "--quiet")
    assert proc.returncode == 0, proc.stderr
    return out


def _direct_dwell() -> tuple[object, object, float]:
    """The dwell run of the scene, simulated directly (settle from rest, then 1 s)."""
    cfg = tomllib.loads(SCENE.read_text("utf-8"))
    p, m, run = cfg["plate"], cfg["model"], cfg["runs"][0]
    plate = Plate(a_m=p["length_m"], b_m=p["width_m"], h_p_m=p["thickness_m"], E_pa=p["E_pa"], nu=p["nu"],
                  rho_kg_m3=p["rho_kg_m3"], edges=p["edges"])
    system = plate_system(plate, n_modes=m["modes"], gap_m=m["gap_m"], zeta=m["zeta"],
                          pressure_pa=p["rho_kg_m3"] * p["thickness_m"] * run["level_m_s2"], freq_hz=run["freq_hz"],
                          omitted_modes=True)  # compliant contacts have the omitted modes' element (issue 24)
    assert system.corrected
    contact = KelvinVoigtContact()
    settle_s = cfg["simulation"]["settle_time_constants"] / (m["zeta"] * system.omega_rad_s[0])
    settled = simulate_modal(system, contact, duration_s=settle_s)
    return system, contact, settled.state


def test_truth_matches_a_direct_modal_run(record: Path) -> None:
    system, contact, state = _direct_dwell()
    direct = simulate_modal(system, contact, duration_s=1.0, state=state)
    with h5py.File(record, "r") as f:
        g = f["truth/impacts/dwell_099"]
        t, v_in, v_out = g["t_s"][()], g["v_in_m_s"][()], g["v_out_m_s"][()]
        attrs = dict(f["truth"].attrs)
    assert len(direct.impacts) > 10
    # same equations, same event times: only rounding differs (times shifted by t0 ~ 0.7 s)
    np.testing.assert_allclose(t, direct.impacts.t_s - state.t_s, rtol=0, atol=1e-9)
    np.testing.assert_allclose(v_in, direct.impacts.v_in_m_s, rtol=1e-9)
    np.testing.assert_allclose(v_out, direct.impacts.v_out_m_s, rtol=1e-9)
    assert attrs["model_kind"] == "modal" and attrs["modal_contact"] == "kelvin-voigt"
    assert attrs["f_s_hz"] == pytest.approx(system.omega_rad_s[0] / (2 * np.pi), rel=1e-12)
    assert 0.0 <= attrs["e"] <= 1.0


def test_sound_and_vibrometer_match_modal_channels(record: Path) -> None:
    system, contact, state = _direct_dwell()
    fs_hz = 20000.0
    t = state.t_s + np.arange(20000) / fs_hz
    chans = modal_channels(system, contact, t, state=state, n_grid=20,
                           mic_xyz_m=(0.127, 0.1143, 0.3), sensor_xy_m=(0.127, 0.1143))
    with h5py.File(record, "r") as f:
        mic = f["runs/dwell_099/channels/mic"][()].astype(float)
        vel = f["runs/dwell_099/channels/velocity"][()].astype(float)
    # modal_channels lacks the sound of the motion before the piece for the first R/c
    # (~1 ms); after 2 ms the rig's sound is the same integral plus 5 mPa rms noise
    # (tolerance 8 sigma) and float32 rounding (1e-7 of ~300 Pa).
    late = slice(40, None)
    assert np.abs(mic).max() > 10.0
    np.testing.assert_allclose(mic[late], chans.mic_pa[late], rtol=0, atol=0.04 + 1e-6 * np.abs(mic).max())
    # the vibrometer: the same velocity through the scene's 5 kHz band limit (4th-order
    # zero-phase Butterworth), plus 0.2 mm/s rms noise (tolerance 8 sigma)
    band = signal.sosfiltfilt(signal.butter(4, 5000.0, fs=fs_hz, output="sos"), chans.velocity_m_s)
    assert np.abs(band).max() > 0.3
    np.testing.assert_allclose(vel, band, rtol=0, atol=0.0016)
    # the sound's first peak after each impact arrives R/c after it (Rayleigh delay, 0.875 ms here).
    # With the omitted modes' element a contact lasts ~1.5 ms and the whole plate's low-frequency
    # sound is as loud as the impact's: the onset is looked for in the broadband part, through a
    # causal 4th-order 2 kHz high-pass (group delay < 0.1 ms above 4 kHz).
    t_imp = chans.impacts.t_s - state.t_s
    delay_s = 0.3 / 343.0
    hp = signal.sosfilt(signal.butter(4, 2000.0, btype="high", fs=fs_hz, output="sos"), mic)
    lag = []
    for ti in t_imp[(t_imp > 0.01) & (t_imp < 0.98)]:
        i0 = int(round(ti * fs_hz))
        win = np.abs(hp[i0: i0 + 60])
        onset = np.flatnonzero(win > 0.2 * win.max())[0]
        lag.append(onset / fs_hz)
    assert np.median(lag) == pytest.approx(delay_s, abs=2.5 / fs_hz)


def test_ingest_and_fit_detect_the_impacts(record: Path, tmp_path: Path) -> None:
    store = tmp_path / "store.h5"
    assert run_command("ingest", str(record), "-o", str(store), "--quiet").returncode == 0
    proc = run_command("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["n_ok"] == 2
    tp = n_det = n_true = 0
    with h5py.File(record, "r") as fr, h5py.File(store, "r") as fs:
        for run in ("dwell_099", "up_099"):
            truth = fr[f"truth/impacts/{run}/t_s"][()]
            key = next(k for k in fs["results/runs"] if run in fs[f"results/runs/{k}"])
            det = fs[f"results/runs/{key}/{run}/t_s"][()]
            n_det += det.size
            n_true += truth.size
            tp += sum(bool(np.any(np.abs(det - ti) < 1e-3)) for ti in truth)
    precision, recall = tp / n_det, tp / n_true
    print(f"modal_lab: {n_true} true, {n_det} detected, precision {precision:.3f}, recall {recall:.3f}")
    # default settings on a multi-mode record whose contacts last 0.2-0.8 ms (4-15 samples):
    # 111 of 113 found, none extra, on 2026-11-29.  Slow impacts are found only by their
    # contact pulse's ends (issue 24); the two missed are contacts whose largest
    # acceleration residual is not their own pulse
    assert recall >= 0.95 and precision >= 0.95


def test_default_scene_is_still_sdf() -> None:
    assert load_scene("default").model.kind == "sdf"


@pytest.mark.parametrize("key, value, why", [
    ("f_s_hz", 96.0, "must not be given"),
    ("modes", 0, "must be >= 1"),
    ("contact", "glue", "must be one of"),
    ("striker_x_m", 0.3, "striker"),
])
def test_bad_modal_options_are_refused(key: str, value: object, why: str) -> None:
    cfg = tomllib.loads(SCENE.read_text("utf-8"))
    cfg["model"][key] = value
    with pytest.raises(SceneError, match=why):
        load = parse_scene(cfg, "modal_lab.toml")
        from rattle_lab.rig._modal import build_system   # the striker is checked against the plate
        build_system(load)


def test_modal_scene_needs_a_plate_and_no_acoustic_table() -> None:
    cfg = tomllib.loads(SCENE.read_text("utf-8"))
    cfg["acoustic"] = {"pa_per_m_s": 5.0}
    with pytest.raises(SceneError, match="acoustic"):
        parse_scene(cfg, "modal_lab.toml")
    cfg = tomllib.loads(SCENE.read_text("utf-8"))
    del cfg["plate"]
    with pytest.raises(SceneError, match="plate"):
        parse_scene(cfg, "modal_lab.toml")


def test_modal_scene_with_a_measurement_chain() -> None:
    cfg = tomllib.loads(SCENE.read_text("utf-8"))
    cfg["runs"] = [{**cfg["runs"][0], "duration_s": 0.2}]
    cfg["chain"] = {"ring_velocity_per_m_s": 0.1, "decoder_delay_s": 18e-6, "hum_hz": 50.0, "hum_pa": 0.002}
    with pytest.raises(SceneError, match="ring_velocity_per_m_s"):   # would double the ringing
        parse_scene(cfg, "modal_lab.toml")
    cfg["chain"]["ring_velocity_per_m_s"] = 0.0
    from rattle_lab.rig import synthesize
    plain = synthesize(parse_scene({**cfg, "chain": {"ring_velocity_per_m_s": 0.0}}, "a")).record
    chained = synthesize(parse_scene(cfg, "b")).record
    v0 = {c.name: c for c in plain.runs[0].channels}["velocity"]
    v1 = {c.name: c for c in chained.runs[0].channels}["velocity"]
    assert v1.group_delay_s == pytest.approx(18e-6) and not v0.group_delay_s
    # same motion, same impacts: the chain changes only what the sensors report
    np.testing.assert_array_equal(plain.truth.impacts["dwell_099"].t_s, chained.truth.impacts["dwell_099"].t_s)


def test_off_centre_striker_moves_the_vibrometer_with_it() -> None:
    from rattle_lab.rig import synthesize
    cfg = tomllib.loads(SCENE.read_text("utf-8"))
    cfg["model"].update(striker_x_m=0.1, striker_y_m=0.1)
    cfg["runs"] = [{**cfg["runs"][0], "duration_s": 0.5, "level_m_s2": 40.0}]
    cfg["sensors"]["velocity"].pop("band_hz")
    rec = synthesize(parse_scene(cfg, "off-centre")).record
    assert (rec.rig.striker_x_m, rec.rig.striker_y_m) == (0.1, 0.1)
    assert {s.sensor_id: s.position_m[:2] for s in rec.rig.sensors}["velocity"] == (0.1, 0.1)
    vel = {c.name: c for c in rec.runs[0].channels}["velocity"]
    v = vel.data.read(0, vel.n_samples).astype(float)
    imp = rec.truth.impacts["dwell_099"]
    assert imp.t_s.size > 5
    # the vibrometer sees the contact point: the last sample before first touch is the
    # incoming velocity (positive towards the striker) to its change over one sample
    # (50 us at the main mode's ~0.5 m/s amplitude and the higher modes', < 10 %) and noise
    i = np.floor(imp.t_s * 20000.0).astype(int)
    np.testing.assert_allclose(v[i], imp.v_in_m_s, rtol=0.1, atol=0.01)
