"""Scene parsing and strict validation of the synthetic rig."""

from __future__ import annotations

import copy
import tomllib
from importlib import resources
from pathlib import Path

import pytest

from rattle_lab.exceptions import ParameterError, RattleLabError
from rattle_lab.rig import SceneError, load_scene, parse_scene

SCENES = Path(__file__).resolve().parents[2] / "synthetic"


def default_dict() -> dict:
    text = resources.files("rattle_lab").joinpath("data/scenes/default.toml").read_text("utf-8")
    return tomllib.loads(text)


def test_scene_error_is_parameter_and_value_error():
    assert issubclass(SceneError, ParameterError)
    assert issubclass(SceneError, RattleLabError)
    assert issubclass(SceneError, ValueError)


@pytest.mark.parametrize("path", sorted(SCENES.glob("*.toml")), ids=lambda p: p.stem)
def test_shipped_scenes_are_valid(path):
    scene = load_scene(path)
    assert scene.source == str(path)
    assert len(scene.runs) >= 1


def test_shipped_scene_set():
    assert {p.stem for p in SCENES.glob("*.toml")} >= {
        "thesis_cfcf_1p3mm", "fem_ch5", "threshold_only", "noisy_lab"}


def test_default_scene_is_embedded_and_small():
    scene = load_scene("default")
    assert scene.source == "default"
    assert scene.campaign_id == "demo-cfcf"
    # demo budget: at most ~40 simulated seconds at <= 25 kHz
    assert sum(r.duration_s for r in scene.runs) <= 40.0
    assert scene.sample_rate_hz <= 25000.0
    assert sum(r.protocol.startswith("amplitude_ramp") for r in scene.runs) == 10
    assert scene.sensor("mic") is not None


def test_thesis_scene_values():
    scene = load_scene(SCENES / "thesis_cfcf_1p3mm.toml")
    assert scene.model.gap_m == 0.0013
    assert 2 * scene.model.zeta == pytest.approx(0.017, rel=1e-12)
    assert scene.plate is not None and scene.plate.thickness_m == 0.00096
    assert scene.plate.edges == "CFCF"
    assert scene.acoustic is not None and scene.acoustic.distance_m == 0.3


@pytest.mark.parametrize("mutate, match", [
    (lambda d: d["model"].__setitem__("gapp_m", 1.0), r"<t>: `model\.gapp_m` is not a known key, was 1\.0"),
    (lambda d: d["model"].__setitem__("gap_m", "1 mm"), r"<t>: `model\.gap_m` must be a number, was '1 mm'"),
    (lambda d: d["model"].__setitem__("e", 1.5), r"<t>: `model\.e` must be <= 1\.0, was 1\.5"),
    (lambda d: d["model"].__setitem__("zeta", True), r"`model\.zeta` must be a number, was True"),
    (lambda d: d["runs"][2].__setitem__("protocol", "ramp"),
     r"`runs\[2\]\.protocol` must be one of \[.*\], was 'ramp'"),
    (lambda d: d["runs"][0].pop("level_end_m_s2"),
     r"`runs\[0\]\.level_end_m_s2` is required for ramps and only for ramps, was None"),
    (lambda d: d["runs"][1].__setitem__("run_id", "UP_095"), r"`runs\[1\]\.run_id` is a duplicate, was 'UP_095'"),
    (lambda d: d["sensors"].__setitem__("laser", {"noise_rms": 1.0}),
     r"`sensors\.laser` is not a known sensor"),
    (lambda d: d["sensors"]["mic"].__setitem__("noise_rms", 0.0),
     r"`sensors\.mic\.noise_rms` must be > 0 \(exact zeros are read as dropouts\), was 0\.0"),
    (lambda d: d["sensors"]["base"].pop("sensitivity_units"),
     r"`sensors\.base\.sensitivity` must come with `sensitivity_units`"),
    (lambda d: d.pop("acoustic"), r"`sensors\.mic` needs an \[acoustic\] table"),
    (lambda d: d["scene"].pop("sample_rate_hz"), r"<t>: missing key `scene\.sample_rate_hz`"),
    (lambda d: d["artefacts"].__setitem__("harmonics", [0.1, "x"]),
     r"`artefacts\.harmonics` must be a list of finite numbers >= 0, was \[0\.1, 'x'\]"),
    (lambda d: d.__setitem__("extra", {}), r"`extra` is not a known key, was \{\}"),
    (lambda d: d.__setitem__("runs", []), r"`runs` must be a non-empty array of tables"),
    (lambda d: d["plate"].__setitem__("edges", "CXCF"), r"`plate\.edges` must be four letters"),
])
def test_invalid_scene_names_file_key_and_value(mutate, match):
    data = copy.deepcopy(default_dict())
    mutate(data)
    with pytest.raises(SceneError, match=match):
        parse_scene(data, "<t>")


def test_direct_modal_parameters_need_f_s_and_participation():
    data = default_dict()
    del data["plate"]
    del data["model"]["f_s_hz"]
    with pytest.raises(SceneError, match=r"`model\.f_s_hz` is required when the scene has no \[plate\]"):
        parse_scene(data, "<t>")


def test_load_scene_file_errors(tmp_path):
    with pytest.raises(SceneError, match=r"missing\.toml: cannot read the scene"):
        load_scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[scene\n")
    with pytest.raises(SceneError, match=r"bad\.toml: not valid TOML"):
        load_scene(bad)
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("[scene]\ncampaign_id = 'a'\nsample_rate_hz = 1000.0\ncolour = 'red'\n")
    with pytest.raises(SceneError, match=r"unknown\.toml: `scene\.colour` is not a known key, was 'red'"):
        load_scene(unknown)
