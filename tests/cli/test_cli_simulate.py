"""``rattle-lab simulate``: the installed entry point, run as a subprocess."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rattle_lab.records import read
from rattle_lab.rig import load_scene
from record_factory import run_cli

SCENES = Path(__file__).resolve().parents[2] / "synthetic"


def test_simulate_default_writes_record_and_summary(tmp_path):
    out = tmp_path / "raw.h5"
    proc = run_cli("simulate", "default", "-o", str(out), "--seed", "7")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""                             # no TTY: no progress bar
    lines = proc.stdout.splitlines()
    scene = load_scene("default")
    assert len(lines) == len(scene.runs) + 1
    assert lines[-1] == str(out)
    with read(out) as rec:
        assert [r.run_id for r in rec.runs] == [r.run_id for r in scene.runs]
        assert rec.truth.extra["seed"] == 7.0
        for line, run in zip(lines, rec.runs):
            n = rec.truth.impacts[run.run_id].t_s.size if run.run_id in rec.truth.impacts else 0
            assert line.startswith(f"{run.run_id}: {run.protocol} ")
            assert f", {n} impacts" in line
        up = rec.truth.thresholds
        k = int(np.flatnonzero(up.freq_hz == 96.0)[0])
        assert f"onset {up.onset_level[k]:.4g} m/s^2" in lines[2]
    assert [p.name for p in tmp_path.iterdir()] == ["raw.h5"]      # no temporary left


def test_simulate_bad_scene_exits_2_with_one_line(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text((SCENES / "fem_ch5.toml").read_text().replace("zeta = 0.05", "zeta = 'x'"))
    out = tmp_path / "raw.h5"
    proc = run_cli("simulate", str(scene), "-o", str(out))
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.count("\n") == 1
    assert proc.stderr == f"rattle-lab: error: {scene}: `model.zeta` must be a number, was 'x'\n"
    assert not out.exists()


def test_simulate_missing_output_dir_exits_2(tmp_path):
    proc = run_cli("simulate", "default", "-o", str(tmp_path / "nodir" / "raw.h5"))
    assert proc.returncode == 2
    assert proc.stderr.startswith("rattle-lab: error: ") and proc.stderr.count("\n") == 1
    assert "does not exist" in proc.stderr
