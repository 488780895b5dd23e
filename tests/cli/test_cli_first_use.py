"""The first use of the compiled kernels (issue 27 item 7): a fresh install has no numba
cache, and the first command that simulates compiles them; it says so on stderr, with a
progress line per kernel, instead of sitting silent.

A fresh install is stood in for by an empty numba cache folder (``NUMBA_CACHE_DIR``): numba
then finds no cached kernel, as after ``pip install .``.
"""

from __future__ import annotations

import json
import os
import shutil
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


def _cache_folders(cache: Path | None) -> dict[str, str]:
    """Where numba keeps each kernel's cache, with ``NUMBA_CACHE_DIR=cache`` (or in the
    package's ``__pycache__``)."""
    code = ("import json; from rattle_lab.model.sdf._compiled import KERNELS, jit_kernel; "
            "print(json.dumps({n: getattr(jit_kernel, n)._cache._cache_path for n in KERNELS}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=_env(cache), timeout=300, check=True)
    return json.loads(out.stdout)


def _seed(cache: Path, names: tuple[str, ...]) -> None:
    """Copy the test environment's numba cache of the kernels ``names`` into the cache folder
    ``cache`` (numba's own layout below it); the kernels not named stay cold there."""
    from rattle_lab.model.sdf._compiled import jit_kernel

    ours, theirs = _cache_folders(None), _cache_folders(cache)
    for name in names:
        stem = getattr(jit_kernel, name)._cache._cache_file._index_name.removesuffix(".nbi")
        files = list(Path(ours[name]).glob(stem + ".*"))
        assert files, (name, stem)
        Path(theirs[name]).mkdir(parents=True, exist_ok=True)
        for f in files:
            shutil.copy2(f, Path(theirs[name]) / f.name)


def test_seeded_cache_leaves_only_the_unseeded_kernel_cold(tmp_path: Path) -> None:
    # what the test below relies on: a cache folder with two kernels copied in is warm for
    # those two and cold for the third
    _seed(tmp_path / "seeded", ("run", "run_packed"))
    assert _cold(tmp_path / "seeded") == ["run_pieces"]


@pytest.mark.slow
def test_the_first_simulation_says_it_compiles(tmp_path: Path) -> None:
    # A cache with one kernel missing stands for the fresh install (the notice and the
    # progress lines do not depend on how many are cold; compiling all three costs about a
    # minute of the suite): the two others are copied in from the test environment's cache.
    cache = tmp_path / "fresh"
    _seed(cache, ("run", "run_packed"))
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


def test_kernels_cold_tells_an_empty_cache_from_a_warm_one(tmp_path: Path) -> None:
    code = "from rattle_lab.detect import kernels_cold; print(kernels_cold())"
    for cache, cold in ((tmp_path / "empty", "True"), (None, "False")):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             env=_env(cache), timeout=300, check=True)
        assert out.stdout.strip() == cold, cache


@pytest.mark.parametrize("cold", [True, False])
def test_a_fit_says_when_it_compiles_the_detection(monkeypatch, capsys, cold: bool) -> None:
    # after a plain pip install the first fit compiled the detection's kernels (about 15 s)
    # without a word; now it says so first.  (The compiling itself is what the install's
    # warm-up runs, python -m rattle_lab._warmup; here it is stood in for.)
    # The compiling runs in spawned children, where these stand-ins do not reach: here the
    # children are run in this process (the subprocess test below covers the real ones).
    import rattle_lab.detect as detect
    import rattle_lab.model.sdf as sdf
    from rattle_lab.cli import _first_use

    calls = []
    monkeypatch.setattr(detect, "kernels_cold", lambda: cold)
    monkeypatch.setattr(detect, "warm_cache", lambda: calls.append("warm"))
    monkeypatch.setattr(sdf, "cold_kernels", lambda: [])
    monkeypatch.setattr(_first_use, "_run_children", lambda targets: any([t() for t in targets]))
    assert _first_use.compile_if_cold("fit") is cold
    err = capsys.readouterr().err.splitlines()
    if cold:
        assert calls == ["warm"] and err[0] == _first_use.DETECT_NOTICE
        assert err[1].startswith("rattle-lab: detection kernels compiled and cached in ")
    else:
        assert calls == [] and err == []
    calls.clear()
    assert _first_use.compile_if_cold("simulate") is False   # does not detect: not asked
    assert calls == []


def _compiles() -> bool:
    return True


def _finds_nothing() -> bool:
    return False


def _child_pid_is_not_ours() -> bool:
    # True only in another process than the test's (the parent's pid is in the environment)
    return os.getpid() != int(os.environ["RATTLE_LAB_TEST_PARENT_PID"])


def test_the_compiling_runs_in_child_processes(monkeypatch) -> None:
    # compile_if_cold hands each cold part to a spawned child (its compiler's memory goes
    # with it); the child's exit status says whether it compiled
    from rattle_lab.cli._first_use import _run_children

    monkeypatch.setenv("RATTLE_LAB_TEST_PARENT_PID", str(os.getpid()))
    assert _run_children([_finds_nothing]) is False
    assert _run_children([_compiles, _finds_nothing]) is True
    assert _run_children([_child_pid_is_not_ours]) is True
