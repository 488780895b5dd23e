"""The installed ``rattle-lab model orbits`` / ``model bifsets`` entry points, run as a user would."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest
from conftest import RATTLE_LAB as EXE

from rattle_lab.model.analysis.orbits import one_over_n_orbits, saddle_node_forcing
from rattle_lab.model.sdf import SDFParams


def run(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(EXE), "model", *args], capture_output=True, text=True,
                          timeout=120, cwd=cwd)


def test_orbits_json() -> None:
    proc = run("orbits", "--n", "1..5", "--F", "0.2", "--omega", "0.98", "--zeta", "0.05",
               "--e", "0.6", "--json")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    doc = json.loads(proc.stdout)
    assert doc["params"] == {"F": 0.2, "omega": 0.98, "zeta": 0.05, "e": 0.6}
    assert [entry["n"] for entry in doc["orbits"]] == [1, 2, 3, 4, 5]
    by_n = {entry["n"]: entry["roots"] for entry in doc["orbits"]}
    # At omega = 0.98 only the 1/2 orbit is observed (thesis 4.2: 0.973 < omega < 0.985).
    hi2 = by_n[2][1]
    assert hi2["branch"] == "hi" and hi2["exists"] and hi2["stable"]
    ref = one_over_n_orbits(SDFParams(F=0.2, omega=0.98, zeta=0.05, e=0.6), 2)[1]
    assert hi2["v_im"] == pytest.approx(ref.v_im, rel=1e-15)
    assert hi2["phase"] == pytest.approx(ref.phase, rel=1e-15)
    assert by_n[1][1]["instability"] == "period-doubling" and not by_n[1][1]["stable"]
    assert not by_n[3][1]["exists"] and by_n[3][1]["clearance"] < 0  # intermediate contact
    # existence and stability are separate verdicts: a non-existent orbit has none
    for n in (3, 4, 5):
        assert not by_n[n][1]["exists"] and by_n[n][1]["v_im"] > 0
        assert by_n[n][1]["stable"] is None and by_n[n][1]["instability"] is None
    assert by_n[1][0]["stable"] is None  # v_im < 0: not a motion
    assert by_n[1][0]["v_im"] < 0 and by_n[1][0]["multipliers"] == [[None, None], [None, None]]


def test_orbits_single_n_and_table() -> None:
    proc = run("orbits", "--n", "3", "--omega", "0.9515", "--json")
    assert proc.returncode == 0 and proc.stderr == ""
    doc = json.loads(proc.stdout)
    assert [entry["n"] for entry in doc["orbits"]] == [3]
    assert doc["orbits"][0]["roots"][1]["stable"]
    table = run("orbits", "--n", "1..2", "--omega", "1.1")
    assert table.returncode == 0 and table.stderr == ""
    lines = table.stdout.splitlines()
    assert lines[1].split()[:3] == ["n", "branch", "v_im"]
    assert len(lines) == 2 + 4


@pytest.mark.slow  # > 8 s (measured under load)
def test_bifsets_json_and_plot(tmp_path: Path) -> None:
    proc = run("bifsets", "--n", "1..2", "--omega", "1.0:1.4", "--F", "0:0.4", "--n-omega", "41",
               "--n-F", "21", "--n-v", "21", "--json")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    doc = json.loads(proc.stdout)
    assert doc["ns"] == [1, 2] and doc["omega_range"] == [1.0, 1.4]
    sn = [c for c in doc["curves"] if c["n"] == 1 and c["kind"] == "saddle-node"]
    assert len(sn) == 1
    # The curve is eq. (3.11) itself; its F = 0.2 crossing is the thesis's 1.230.
    F_ref, _ = saddle_node_forcing(1, sn[0]["omega"], 0.05, 0.6)
    assert sn[0]["F"] == pytest.approx(list(F_ref), rel=1e-12)
    assert doc["area_fraction"]["2"]["exists"] == 0.0  # no 1/2 region for omega > 1 (Fig. 3-7)
    plot = tmp_path / "bif.png"
    proc = run("bifsets", "--n", "1", "--n-omega", "21", "--n-F", "11", "--n-v", "11",
               "--plot", str(plot))
    assert proc.returncode == 0, proc.stderr
    assert plot.read_bytes()[:4] == b"\x89PNG"
    assert proc.stderr.strip() == f"rattle-lab: wrote {plot}"
    assert "saddle-node" in proc.stdout


@pytest.mark.parametrize("args, needle", [
    (("orbits", "--n", "0..3"), "`--n` must satisfy 1 <= lo <= hi <= 50, was '0..3'"),
    (("orbits", "--n", "two"), "`--n` must be an integer, was 'two'"),
    (("orbits", "--n", "1..2..3"), "`--n` must be an integer or a range lo..hi, was '1..2..3'"),
    (("orbits", "--omega", "abc"), "`--omega` must be a number, was 'abc'"),
    (("orbits", "--omega", "-1"), "`omega` must be > 0, was -1.0"),
    (("orbits", "--e", "2"), "`e` must be in [0, 1], was 2.0"),
    (("bifsets", "--F", "0.6:0"), "`--F` must have lo < hi, was '0.6:0'"),
    (("bifsets", "--omega", "0.6"), "`--omega` must be a range lo:hi, was '0.6'"),
    (("bifsets", "--plot", "out.txt"), "plot file 'out.txt' must end in .png, .pdf or .svg"),
    (("bifsets", "--plot", "no/such/dir/x.png"), "output directory no/such/dir does not exist"),
])
def test_invalid_arguments_exit_2_with_one_line(args: tuple[str, ...], needle: str,
                                                tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    # In process (the same main() the console script calls) to keep the suite fast; the
    # installed script itself is exercised on invalid input below.
    from rattle_lab.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["model", *args]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("rattle-lab: error: ") and needle in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_installed_script_invalid_argument(tmp_path: Path) -> None:
    for args, needle in ((("orbits", "--n", "0..3"), "`--n` must satisfy"),
                         (("bifsets", "--plot", "no/such/dir/x.png"), "does not exist")):
        proc = run(*args, cwd=tmp_path)
        assert proc.returncode == 2
        assert proc.stdout == ""
        lines = proc.stderr.splitlines()
        assert len(lines) == 1 and lines[0].startswith("rattle-lab: error: ")
        assert needle in lines[0]
