"""The installed ``rattle-lab model sweep`` / ``model map`` entry points (subprocess).

Each run checks the exit code, JSON on stdout and an empty stderr; numbers are
checked against the closed-form 1/n orbits.
"""

from __future__ import annotations

import csv
import json
import subprocess
from pathlib import Path

import pytest

from rattle_lab.model.analysis import one_over_n_orbits
from rattle_lab.model.sdf import SDFParams

from conftest import RATTLE_LAB as EXE


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(EXE), "model", *args], capture_output=True, text=True,
                          timeout=120)


def test_sweep_json_matches_closed_form() -> None:
    out = _run("sweep", "--start", "1.0", "--stop", "1.2", "--step", "0.1", "--F", "0.2",
               "--zeta", "0.05", "--e", "0.6", "--direction", "up", "--json")
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""
    doc = json.loads(out.stdout)
    (sw,) = doc["sweeps"]
    assert sw["param"] == "omega" and sw["direction"] == "up"
    assert [p["value"] for p in sw["points"]] == pytest.approx([1.0, 1.1, 1.2])
    for entry in sw["points"]:
        assert entry["classification"] == "1/1" and entry["lyapunov"] is None
        hi = one_over_n_orbits(SDFParams(F=0.2, omega=entry["value"], zeta=0.05, e=0.6), 1)[1]
        assert entry["impact_velocities"][-1] == pytest.approx(hi.v_im, rel=1e-8)
        assert len(entry["crossing_velocities"]) >= 29
        assert entry["mean_impact_velocity"] > 0


@pytest.mark.slow  # > 8 s (measured under load)
def test_sweep_gap_csv_and_plot(tmp_path: Path) -> None:
    csv_path, png = tmp_path / "g.csv", tmp_path / "g.png"
    out = _run("sweep", "--param", "gap", "--start", "4", "--stop", "6", "--step", "1",
               "--omega", "1.1", "--csv", str(csv_path), "--plot", str(png), "--quiet")
    assert out.returncode == 0, out.stderr
    assert out.stderr == "" and out.stdout == ""
    with open(csv_path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["direction"] for r in rows] == ["up"] * 3 + ["down"] * 3
    assert [float(r["F"]) for r in rows[:3]] == [1 / 4, 1 / 5, 1 / 6]
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize(("args", "needle"), [
    (["--param", "zeta"], "`--param` must be one of omega, F, e, gap, was 'zeta'"),
    (["--param", "gap", "--F", "0.3"], "`--F` must not be given with --param gap, was '0.3'"),
    (["--step", "0.07"], "`step` = 0.07 must divide"),
])
def test_sweep_invalid_arguments_exit_2(args: list[str], needle: str) -> None:
    base = {"--start": "1.0", "--stop": "1.2", "--step": "0.1"}
    for i in range(0, len(args), 2):
        base[args[i]] = args[i + 1]
    out = _run("sweep", *[x for kv in base.items() for x in kv], "--json")
    assert out.returncode == 2
    assert out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0]


def test_map_regime_and_basin_json() -> None:
    out = _run("map", "--kind", "regime", "--F", "0.05:0.2", "--n-F", "2", "--omega",
               "1.0:1.1", "--n-omega", "2", "--cycles", "100", "--discard", "70", "--json")
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""
    doc = json.loads(out.stdout)
    assert doc["kind"] == "regime"
    assert doc["labels"] == [["no impact", "no impact"], ["1/1", "1/1"]]
    hi = one_over_n_orbits(SDFParams(F=0.2, omega=1.1, zeta=0.05, e=0.6), 1)[1]
    assert doc["max_impact_velocity"][1][1] == pytest.approx(hi.v_im, rel=1e-8)
    out = _run("map", "--kind", "basin", "--F", "0.2", "--omega", "1.15", "--x0", "0:0.5",
               "--n-x0", "2", "--v0", "0:1.5", "--n-v0", "2", "--cycles", "100", "--discard",
               "70", "--json")
    assert out.returncode == 0 and out.stderr == ""
    doc = json.loads(out.stdout)
    assert doc["labels"][0][0] == "no impact" and doc["labels"][1][0] == "1/1"


def test_map_disturbance_json_and_errors() -> None:
    out = _run("map", "--kind", "disturbance", "--F", "0.15:0.3", "--n-F", "2", "--omega",
               "1.1:1.15", "--n-omega", "2", "--kick-tol", "0.01", "--json")
    assert out.returncode == 0, out.stderr
    assert out.stderr == ""
    doc = json.loads(out.stdout)
    assert doc["kind"] == "disturbance"
    # eq. (3.4): the grazing forcing is 0.237 at omega = 1.1 and 0.342 at 1.15, so
    # F = 0.3 has no impact-free response at 1.1 (null) but has one at 1.15
    assert doc["threshold"][1][0] is None
    for j in range(2):
        assert isinstance(doc["threshold"][0][j], float) and 0 < doc["threshold"][0][j] < 2
    for args, needle in ((["--kind", "chaos"], "`--kind` must be one of regime, basin, "
                          "disturbance, was 'chaos'"),
                         (["--kind", "regime", "--omega", "1.2:1.1"],
                          "`--omega` must have lo < hi, was '1.2:1.1'")):
        out = _run("map", *args, "--json")
        assert out.returncode == 2 and out.stdout == ""
        assert needle in out.stderr and len(out.stderr.splitlines()) == 1
