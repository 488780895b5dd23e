"""`rattle-lab --version/--help` and `rattle-lab model run`, through the installed entry point."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from conftest import RATTLE_LAB
from record_factory import run_cli_on_terminal

from rattle_lab import __version__
from rattle_lab.model.sdf import SDFParams, SDFState, simulate


def _exe() -> str:
    assert RATTLE_LAB.is_file(), "the rattle-lab entry point must be installed (pip install -e .)"
    return str(RATTLE_LAB)


def run(*args: str, check_rc: int | None = 0) -> subprocess.CompletedProcess[str]:
    proc = subprocess.run([_exe(), *args], capture_output=True, text=True, timeout=300)
    if check_rc is not None:
        assert proc.returncode == check_rc, proc.stderr
    return proc


def test_version_and_help():
    out = run("--version")
    assert out.stdout.strip() == f"rattle-lab {__version__}"
    out = run("--help")
    for command in ("model", "ingest", "demo"):
        assert command in out.stdout
    assert "run" in run("model", "--help").stdout


def test_model_run_json_has_full_precision():
    out = run("model", "run", "--F", "0.2", "--omega", "0.95", "--zeta", "0.05", "--e", "0.6",
              "--cycles", "15", "--x0", "0.1", "--v0", "-0.2", "--phase", "0.3", "--json")
    assert out.stderr == ""
    doc = json.loads(out.stdout)
    ref = simulate(SDFParams(0.2, 0.95, 0.05, 0.6), cycles=15,
                   state=SDFState(x=0.1, v=-0.2, theta=0.3))
    assert len(doc["impacts"]) == len(ref.impacts) > 0
    # the printed floats round-trip exactly
    np.testing.assert_array_equal([i["t"] for i in doc["impacts"]], ref.impacts.t)
    np.testing.assert_array_equal([i["v_in"] for i in doc["impacts"]], ref.impacts.v_in)
    np.testing.assert_array_equal([i["v_out"] for i in doc["impacts"]], ref.impacts.v_out)
    assert doc["x_end"] == ref.state.x and doc["v_end"] == ref.state.v


def test_model_run_table_and_plot(tmp_path):
    png = tmp_path / "run.png"
    out = run("model", "run", "--F", "2", "--omega", "0.5", "--zeta", "0.1", "--e", "0.5",
              "--cycles", "3", "--plot", str(png))
    assert "impacts" in out.stdout and out.stderr == ""
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".run.png*"))  # no temporary file left behind


@pytest.mark.parametrize("args,message", [
    (["--F", "-1", "--omega", "1", "--zeta", "0.05", "--e", "0.6"], "`F` must be >= 0, was -1.0"),
    (["--F", "0.2", "--omega", "1", "--zeta", "0.05", "--e", "2"], r"`e` must be in [0, 1], was 2.0"),
    (["--F", "0.2", "--omega", "1", "--zeta", "0.05", "--e", "0.6", "--cycles", "-3"],
     "`cycles` must be finite and >= 1, was -3.0"),  # issue 16: cycles >= 1
    (["--F", "0.2", "--omega", "1", "--zeta", "0.05", "--e", "0.6", "--cycles", "0"],
     "`cycles` must be finite and >= 1, was 0.0"),
    (["--F", "0.2", "--omega", "1", "--zeta", "0.05", "--e", "0.6", "--plot", "out.gif"],
     "must end in .png, .pdf or .svg"),
])
def test_model_run_bad_input_exits_2_with_one_line(tmp_path, args, message):
    proc = subprocess.run([_exe(), "model", "run", *args], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""
    assert list(tmp_path.iterdir()) == []


def _demo_checks(text: str, out_dir: Path) -> None:
    import pypdf

    lines = [line.strip() for line in text.replace("\r", "\n").splitlines() if line.strip()]
    assert lines[-1] == f"report: {(out_dir / 'report.pdf').resolve()}"
    assert len(pypdf.PdfReader(out_dir / "report.pdf").pages) == 11  # 2 summary pages, acoustics 2
    head = next(i for i, line in enumerate(lines) if line.startswith("quantity"))
    assert lines[head].split()[1:5] == ["fitted", "std.", "error", "rig"]
    end = next(i for i, line in enumerate(lines) if line.startswith("report: "))
    rows = {line.split()[0]: line.split() for line in lines[head + 1:end]}
    assert {"gap", "f_s", "zeta", "e", "SPL"} <= set(rows)
    assert rows["f_s"][3] == "96" and rows["f_s"][-1] == "Hz"  # the rig's truth, 96 Hz
    assert abs(float(rows["f_s"][1]) - 96.0) < 0.1
    # the ramp-corrected eq. (3.4) fit: the ramp lag that makes the raw fit's zeta 7 % high
    # is removed (its zeta within 2 % of the rig's 0.0085; its gap within 0.5 % of 1.3 mm)
    corrected = {line.split("(ramp-corrected)")[0].strip(): line.split("(ramp-corrected)")[1].split()
                 for line in lines[head + 1:end] if "(ramp-corrected)" in line}
    assert set(corrected) == {"gap", "zeta"}
    assert abs(float(corrected["zeta"][0]) / 0.0085 - 1) < 0.02
    assert abs(float(corrected["gap"][0]) / 1.3e-3 - 1) < 0.005


_ROW = re.compile(r"^(.*?)\s+(\S+)\s+(\S+)\s+(\S+)\s+([+-]?\d+\.\d+) %\s+(\S+)$")


def _fitted_rows(text: str) -> dict[str, tuple[float, float]]:
    """``quantity: (fitted, std. error)`` of a demo table (the lines after "quantity")."""
    lines = text.splitlines()
    head = next(i for i, line in enumerate(lines) if line.strip().startswith("quantity"))
    rows = {}
    for line in lines[head + 1:]:
        m = _ROW.match(line.strip())
        if not m:
            break
        rows[m.group(1)] = (float(m.group(2)), float(m.group(3)))
    return rows


@pytest.mark.slow  # > 8 s (measured under load)
def test_demo_piped_prints_the_table_and_the_pdf_path_last(tmp_path):
    out = run("demo", "--out", str(tmp_path / "demo"))
    _demo_checks(out.stdout, tmp_path / "demo")
    assert "[4/4] report" in out.stderr
    assert "%|" not in out.stderr  # no progress bars when not on a terminal
    # README shows this table: its numbers are the demo's, each value within half its
    # standard error and each standard error within 10 %.  Other rounding moves them less:
    # with OpenBLAS's Nehalem kernels and numba for a generic CPU, e 0.59993 +- 0.00208
    # against 0.59979 +- 0.00214 (0.07 of a standard error) and the SPL slope 5.0510 against
    # 5.0517 (0.21), the standard errors by up to 2.8 %.  It had gone stale by the fifteenth
    # session: e's standard error 0.00083 printed, 0.00214 made.  (Since the nineteenth
    # session's sound windows open two samples early the SPL slope is 5.0287, 7 standard
    # errors from the 5.0517 before and half as far from the rig's 5)
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    block = readme[readme.index("fitted values against the rig's truth:"):]
    want, got = _fitted_rows(block), _fitted_rows(out.stdout)
    assert len(want) >= 9 and set(want) == set(got), (sorted(want), sorted(got))
    for name, (value, stderr) in want.items():
        assert abs(got[name][0] - value) <= 0.5 * stderr, (name, got[name], value, stderr)
        assert got[name][1] == pytest.approx(stderr, rel=0.10), (name, got[name], stderr)


def test_demo_with_a_missing_scene_is_one_line_exit_2_and_writes_nothing(tmp_path):
    out = tmp_path / "demo"
    proc = run("demo", "--scene", str(tmp_path / "absent.toml"), "--out", str(out), check_rc=2)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "absent.toml" in lines[0] and "cannot read the scene" in lines[0]
    assert not out.exists()


@pytest.mark.slow  # > 8 s (measured under load)
def test_demo_on_a_terminal_shows_progress_bars(tmp_path):
    # the bars, not the fit's accuracy (the piped test above checks that on the default
    # scene): the shortened default scene (--scene) makes the same stages
    from conftest import SMALL_CAMPAIGN

    rc, text = run_cli_on_terminal("demo", "--out", str(tmp_path / "demo"), "--scene",
                                   str(SMALL_CAMPAIGN))
    assert rc == 0, text[-2000:]
    for bar in ("simulate:", "raw.h5:", "detect:", "model sweeps:"):  # tqdm: "desc:  40%|"
        assert re.search(re.escape(bar) + r" +\d+%\|", text), bar
    assert f"scene {SMALL_CAMPAIGN}" in text
    lines = [line.strip() for line in text.replace("\r", "\n").splitlines() if line.strip()]
    assert lines[-1] == f"report: {(tmp_path / 'demo' / 'report.pdf').resolve()}"
    assert any(line.startswith("quantity") for line in lines)
