"""The installed ``rattle-lab model plate | scale | grazing`` commands, run as subprocesses."""

from __future__ import annotations

import json
import subprocess

import pytest

from rattle_lab.model.plate import ritz_modes

from conftest import RATTLE_LAB

EXE = str(RATTLE_LAB) if RATTLE_LAB.is_file() else None

THESIS_PLATE = ["--a", "0.254", "--b", "0.2286", "--h", "0.001", "--E", "7e10", "--nu", "0.34", "--rho", "2710"]


def run(*args: str) -> subprocess.CompletedProcess[str]:
    assert EXE is not None, "the rattle-lab entry point is not installed"
    return subprocess.run([EXE, "model", *args], capture_output=True, text=True, timeout=120)


def run_json(*args: str) -> dict:
    proc = run(*args, "--json")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    return json.loads(proc.stdout)


def test_plate_json_thesis_plate():
    out = run_json("plate", *THESIS_PLATE, "--edges", "CFCF", "--modes", "6")
    assert out["edges"] == "CFCF" and out["edge_order"] == ["y=0", "x=a", "y=b", "x=0"]
    assert out["aspect_ratio"] == pytest.approx(0.9, rel=1e-12)
    modes = out["modes"]
    assert [m["mode"] for m in modes] == [1, 2, 3, 4, 5, 6]
    library = ritz_modes(0.9, "CFCF", nu=0.34)
    assert [m["lambda"] for m in modes] == pytest.approx(library.lam.tolist(), rel=1e-12)
    assert modes[0]["f_hz"] == pytest.approx(105.0, rel=0.015)  # thesis section 5.1.1
    assert modes[0]["Q1"] == pytest.approx(0.5, rel=0.03) and modes[0]["Q2"] == pytest.approx(0.402, rel=0.03)
    assert [m["normalised_at_max"] for m in modes] == [False, True, False, True, True, True]


def test_plate_table_and_closed_form():
    proc = run("plate", *THESIS_PLATE, "--edges", "SSSS", "--modes", "3")
    assert proc.returncode == 0 and proc.stderr == ""
    lines = proc.stdout.splitlines()
    assert "closed form" in proc.stdout
    assert lines[2].split()[:4] == ["mode", "lambda", "f", "[Hz]"]
    assert len(lines) == 2 + 2 + 3  # two header lines, table head and rule, 3 modes


def test_plate_help_documents_edge_order(capsys):
    from rattle_lab.cli import main

    with pytest.raises(SystemExit, match="0"):
        main(["model", "plate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "y=0, x=a, y=b, x=0" in text and "CFCF clamps the two sides of length a" in text


def test_scale_json():
    out = run_json("scale", *THESIS_PLATE, "--edges", "CFCF", "--gap", "0.001", "--pressure", "285", "--freq", "100")
    assert out["f_s_hz"] == pytest.approx(105.0, rel=0.015)
    assert out["participation"] == pytest.approx(out["Q1"] / out["Q2"], rel=1e-12)
    assert out["omega"] == pytest.approx(100.0 / out["f_s_hz"], rel=1e-12)
    assert out["F"] == pytest.approx(0.3, abs=0.01)  # thesis section 5.3.2: F = 0.3 for 285 Pa
    given = run_json("scale", *THESIS_PLATE, "--lam", "27.4", "--Q1", "0.5", "--Q2", "0.402", "--gap", "0.001",
                     "--accel", "9.81")
    assert given["F"] / given["pressure_pa"] == pytest.approx(1.05e-3, abs=0.005e-3)  # eq. 5.3
    assert given["omega"] is None


def test_grazing_json():
    out = run_json("grazing", "--zeta", "0.05", "--F", "0.2", "--omega", "0.9", "1.0")
    assert out["omega_low"] == pytest.approx(0.907, abs=0.001)
    assert out["omega_high"] == pytest.approx(1.081, abs=0.0005)
    assert [r["omega"] for r in out["curve"]] == [0.9, 1.0]
    assert out["curve"][1]["F_graze"] == pytest.approx(0.1, rel=1e-14)
    no_root = run_json("grazing", "--zeta", "0.05", "--F", "0.01")
    assert no_root["omega_low"] is None and no_root["omega_high"] is None and "curve" not in no_root


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["plate", "--a", "0.254", "--b", "0.2286", "--h", "-0.001", "--E", "7e10", "--nu", "0.34", "--rho", "2710"],
         "`h_p_m` must be finite and > 0, was -0.001"),
        (["plate", *THESIS_PLATE[:-4], "--nu", "0.5", "--rho", "2710"], "`nu` must satisfy -1 < nu < 0.5, was 0.5"),
        (["plate", *THESIS_PLATE, "--edges", "CFXF"], "`edges` must be 4 letters"),
        (["grazing", "--zeta", "-1", "--F", "0.2"], "`zeta` must be >= 0, was -1.0"),
        (["scale", *THESIS_PLATE, "--lam", "27.4", "--gap", "0.001", "--accel", "1"],
         "give all of --lam, --Q1, --Q2 or none"),
    ],
)
def test_invalid_input_is_one_line_exit_2(args, needle):
    proc = run(*args)
    assert proc.returncode == 2
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("rattle-lab: error: ") and needle in lines[0]
    assert "Traceback" not in proc.stderr and proc.stdout == ""


# In-process: the argument checks that live in the CLI layer itself.
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["scale", *THESIS_PLATE[:2], *THESIS_PLATE[4:], "--gap", "0.001", "--accel", "1"],
         "rattle-lab: error: --b and --edges are needed to solve for the mode (or give --lam, --Q1, --Q2), "
         "was b=None, edges=None"),
        (["scale", *THESIS_PLATE, "--edges", "CFCF", "--mode", "0", "--gap", "0.001", "--accel", "1"],
         "rattle-lab: error: `--mode` must be >= 1, was 0"),
        (["scale", *THESIS_PLATE, "--lam", "27.4", "--Q1", "0.5", "--gap", "0.001", "--accel", "1"],
         "rattle-lab: error: give all of --lam, --Q1, --Q2 or none, was lam=27.4, Q1=0.5, Q2=None"),
    ],
)
def test_cli_argument_errors(args, message, capsys):
    from rattle_lab.cli import main

    assert main(["model", *args]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == [message]
