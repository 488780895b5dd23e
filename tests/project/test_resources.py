"""Scenes, pipelines and mappings are addressable by name, in the checkout and in a wheel."""

from __future__ import annotations

import runpy
import subprocess
import sys
import zipfile
from pathlib import Path

import h5py
import pytest
from conftest import CHECKOUT, RATTLE_LAB

from rattle_lab._resources import (RESOURCE_KINDS, find_resource, resolve_resource, resource_file,
                                  resource_names)
from rattle_lab.workflow.pipeline import load_pipeline_file
from rattle_lab.records import load_mapping
from rattle_lab.rig import load_scene

# every resource file of the checkout, by kind (what the wheel must carry)
SHIPPED = {kind: sorted(p.name for p in (CHECKOUT / folder).glob(f"*{suffix}"))
           for kind, (folder, suffix) in RESOURCE_KINDS.items()}


def test_the_checkout_has_resources_of_every_kind() -> None:
    for kind, names in SHIPPED.items():
        assert names, kind
    assert "thesis_cfcf_1p3mm.toml" in SHIPPED["scenes"]
    assert "full_campaign.toml" in SHIPPED["pipelines"]


@pytest.mark.parametrize("kind", sorted(RESOURCE_KINDS))
def test_every_file_is_found_by_name_with_or_without_suffix(kind: str) -> None:
    folder, _ = RESOURCE_KINDS[kind]
    for file_name in SHIPPED[kind]:
        stem = Path(file_name).stem
        assert stem in resource_names(kind)
        for name in (stem, file_name):
            found = find_resource(kind, name)
            assert found is not None, (kind, name)
            assert found.read_bytes() == (CHECKOUT / folder / file_name).read_bytes()


def test_unknown_names_and_paths_are_not_resolved() -> None:
    assert find_resource("scenes", "no_such_scene") is None
    assert find_resource("scenes", "") is None
    # a name with a folder part is a path, never looked up
    assert find_resource("scenes", "synthetic/thesis_cfcf_1p3mm") is None
    with pytest.raises(KeyError):
        find_resource("no_such_kind", "x")


def test_resolve_resource_prefers_a_file_and_names_what_is_shipped(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert resource_file("pipelines", "full_campaign") == CHECKOUT / "pipelines" / "full_campaign.toml"
    (tmp_path / "full_campaign").write_text("x", encoding="utf-8")
    assert resource_file("pipelines", "full_campaign") == Path("full_campaign")  # the file wins
    assert resource_file("pipelines", "no_such_pipeline") is None
    with pytest.raises(LookupError, match=r"^spl_studdy: cannot read: no such file, and no shipped "
                                          r"pipeline 'spl_studdy'; shipped: .*\(closest: 'spl_study'\)$"):
        resolve_resource("pipelines", "spl_studdy", LookupError, "cannot read")
    with pytest.raises(LookupError, match=r"^sub/x.toml: cannot read: No such file or directory$"):
        resolve_resource("pipelines", "sub/x.toml", LookupError, "cannot read")


def test_setup_py_copies_the_resource_list(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """setup.py's build hook (what ``pip install .`` runs) copies every resource file of the
    checkout into ``rattle_lab/data/<kind>/``: its list is :data:`RESOURCE_KINDS`."""
    setuptools = pytest.importorskip("setuptools")
    from setuptools.command import build_py

    captured: dict[str, object] = {}
    monkeypatch.setattr(setuptools, "setup", lambda **kw: captured.update(kw))
    monkeypatch.setattr(build_py.build_py, "run", lambda self: None)   # the package's own files
    runpy.run_path(str(CHECKOUT / "setup.py"), run_name="setup_probe")
    hook = captured["cmdclass"]["build_py"]  # type: ignore[index]
    command = hook.__new__(hook)
    command.build_lib = str(tmp_path)
    command.editable_mode = False
    command.run()
    data = tmp_path / "rattle_lab" / "data"
    assert sorted(p.name for p in data.iterdir()) == sorted(RESOURCE_KINDS)
    for kind, files in SHIPPED.items():
        copied = sorted(p.name for p in (data / kind).iterdir())
        assert copied == files, kind
        folder, _ = RESOURCE_KINDS[kind]
        for name in files:
            assert (data / kind / name).read_bytes() == (CHECKOUT / folder / name).read_bytes()


def test_loaders_take_names(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # any folder: nothing there
    scene = load_scene("thesis_cfcf_1p3mm")
    assert scene == load_scene(CHECKOUT / "synthetic" / "thesis_cfcf_1p3mm.toml")
    assert load_pipeline_file("full_campaign").name == "full_campaign"
    from rattle_lab.fit import load_pipeline  # `fit --pipeline NAME` reads the same file
    assert load_pipeline("threshold_campaign") == load_pipeline(
        CHECKOUT / "pipelines" / "threshold_campaign.toml")
    assert load_mapping("hammer_npy").data == load_mapping(
        CHECKOUT / "data_schema" / "mappings" / "hammer_npy.toml").data


def test_an_existing_file_wins_over_a_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "full_campaign").write_text("not = [valid", encoding="utf-8")
    from rattle_lab.exceptions import ParameterError

    with pytest.raises(ParameterError, match="full_campaign"):
        load_pipeline_file("full_campaign")


@pytest.mark.slow  # > 8 s (measured under load)
def test_cli_simulates_a_scene_by_name_from_another_folder(tmp_path: Path) -> None:
    proc = subprocess.run([str(RATTLE_LAB), "simulate", "no_such_scene", "-o", "x.h5"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "no_such_scene" in proc.stderr
    proc = subprocess.run([str(RATTLE_LAB), "simulate", "fem_ch5", "-o", "f.h5", "--quiet"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert proc.returncode == 0, proc.stderr
    with h5py.File(tmp_path / "f.h5", "r") as f:
        assert f.attrs["campaign_id"] == load_scene("fem_ch5").campaign_id
        assert "truth" in f


@pytest.mark.slow
def test_the_wheel_ships_every_resource(tmp_path: Path) -> None:
    """Build the wheel as ``pip install .`` would and list what it carries."""
    proc = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet",
                           "-w", str(tmp_path), str(CHECKOUT)],
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0 and "No matching distribution" in proc.stderr:
        pytest.skip("no network for the build requirements (setuptools)")
    assert proc.returncode == 0, proc.stderr
    assert "deprecat" not in (proc.stdout + proc.stderr).lower()
    (wheel,) = tmp_path.glob("rattle_lab-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "rattle_lab/py.typed" in names
    assert "rattle_lab/data/scenes/default.toml" in names
    for kind, files in SHIPPED.items():
        for file_name in files:
            assert f"rattle_lab/data/{kind}/{file_name}" in names, (kind, file_name)


def test_a_pipeline_takes_a_scene_by_name(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from rattle_lab import read_catalogue
    from rattle_lab.workflow.pipeline import parse_pipeline, run_pipeline

    monkeypatch.chdir(tmp_path)  # the scene name resolves from any folder
    pipeline = parse_pipeline({"pipeline": {"name": "t", "outputs": ["store"]}}, "t.toml")
    run = run_pipeline(pipeline, ["fem_ch5"], out_dir=tmp_path, quiet=True)
    assert run.executed == ["simulate", "ingest"]
    assert (tmp_path / "fem_ch5.h5").is_file()  # named after the scene file's stem
    catalogue = read_catalogue(run.store)
    assert set(catalogue["campaign_id"]) == {load_scene("fem_ch5").campaign_id}
