"""The first use of the compiled kernels (issue 27 item 7): a fresh install has no numba
cache, and the first command that simulates compiles them; it says so on stderr, with a
progress line per kernel, instead of sitting silent.

A fresh install is stood in for by an empty numba cache folder (``NUMBA_CACHE_DIR``): numba
then finds no cached kernel, as after ``pip install .``.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import RATTLE_LAB

from rattle_lab.cli._first_use import NOTICE


def _env(cache: Path | None) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    return env


def _cold(cache: Path | None) -> list[str]:
    code = "from rattle_lab.model.sdf._compiled import cold_kernels; print(cold_kernels())"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=_env(cache), timeout=300, check=True)
    return eval(out.stdout)  # a printed list of names  # noqa: S307


def test_cold_kernels_tells_an_empty_cache_from_a_warm_one(tmp_path: Path) -> None:
    assert _cold(tmp_path / "empty") == ["run", "run_packed", "run_pieces"]
    assert _cold(None) == []  # the test environment's install compiled them (make)


def test_commands_that_do_not_simulate_say_nothing(tmp_path: Path) -> None:
    proc = subprocess.run([str(RATTLE_LAB), "model", "plate", "--help"], capture_output=True,
                          text=True, env=_env(tmp_path / "empty"), timeout=120)
    assert proc.returncode == 0 and "compiling" not in proc.stderr


@pytest.mark.slow
def test_the_first_simulation_says_it_compiles(tmp_path: Path) -> None:
    cache = tmp_path / "fresh"
    args = [str(RATTLE_LAB), "model", "run", "--F", "0.2", "--omega", "1.1", "--zeta", "0.05",
            "--e", "0.6", "--cycles", "5"]
    first = subprocess.run(args, capture_output=True, text=True, env=_env(cache), timeout=900)
    assert first.returncode == 0, first.stderr[-2000:]
    lines = first.stderr.splitlines()
    assert lines[0] == NOTICE
    assert [ln.split(" (")[0] for ln in lines[1:4]] == [
        f"rattle-lab: compiling kernel {i} of 3" for i in (1, 2, 3)]
    assert lines[4].startswith("rattle-lab: kernels compiled and cached in ")
    again = subprocess.run(args, capture_output=True, text=True, env=_env(cache), timeout=300)
    assert again.returncode == 0 and "compiling" not in again.stderr  # cached now
    assert again.stdout == first.stdout
