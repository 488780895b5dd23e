"""``rattle-lab --version`` and ``--help`` start without the heavy libraries (issue 13).

The installed entry point is run as a user runs it, with ``PYTHONPROFILEIMPORTTIME=1``:
Python then writes one ``import time:`` line per module it imports to stderr, so the
test reads the exact list of imported modules (no wall-clock assert; the start-up time
itself is measured by ``benchmarks/speed_goals.py``).
"""

from __future__ import annotations

import os
import subprocess

import pytest
from conftest import RATTLE_LAB

#: Libraries that take 0.1-1 s to import; none is needed to print a version or a help text.
HEAVY = ("numpy", "scipy", "numba", "llvmlite", "h5py", "matplotlib", "lmfit", "dask")


def _imported_modules(*args: str) -> tuple[subprocess.CompletedProcess[str], set[str]]:
    env = dict(os.environ, PYTHONPROFILEIMPORTTIME="1")
    proc = subprocess.run([str(RATTLE_LAB), *args], capture_output=True, text=True, env=env,
                          timeout=120)
    names = set()
    for line in proc.stderr.splitlines():
        if line.startswith("import time:") and line.count("|") == 2:
            name = line.rsplit("|", 1)[1].strip()
            if name != "imported package":  # the header line
                names.add(name)
    return proc, names


@pytest.mark.parametrize("args", [("--version",), ("--help",), ("model", "--help")])
def test_start_up_imports_no_heavy_library(args: tuple[str, ...]) -> None:
    proc, names = _imported_modules(*args)
    assert proc.returncode == 0, proc.stderr[-2000:]
    # the profile really ran: the CLI package itself is in the list
    assert "rattle_lab.cli" in names
    heavy = sorted(n for n in names if n.split(".")[0] in HEAVY)
    assert heavy == [], f"`rattle-lab {' '.join(args)}` imported {heavy[:10]}"


def test_version_prints_the_package_version() -> None:
    from rattle_lab import __version__

    proc = subprocess.run([str(RATTLE_LAB), "--version"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0
    assert proc.stdout.strip() == f"rattle-lab {__version__}"


def test_fit_start_up_imports_only_what_fit_runs(tmp_path) -> None:
    # issue 29, item 5: `rattle-lab fit` pays for the modules it runs; the report, the
    # model's analysis, the explorer, the rig and the Dask client are imported when used.
    # (The store is missing here, so the command stops after its imports, with exit 2.)
    proc, names = _imported_modules("fit", str(tmp_path / "missing.h5"))
    assert proc.returncode == 2, proc.stderr[-2000:]
    assert "rattle_lab.fit" in names and "rattle_lab.workflow.pipeline" in names
    lazy = ("rattle_lab.workflow._report", "rattle_lab.report", "rattle_lab.model.analysis",
            "rattle_lab.explorer", "rattle_lab.rig", "distributed", "mosqito")
    eager = sorted(n for n in names if n.startswith(lazy))
    assert eager == [], f"`rattle-lab fit` imported {eager[:10]}"


def test_the_report_does_not_import_scipy_signal() -> None:
    # `rattle-lab report` reads stored results and draws them: scipy.signal (about 1 s to
    # import, 20 % of a small report's time) is imported inside the functions that filter
    # samples, not by the modules the report imports for their helpers (energy_mean_db)
    import sys

    code = ("import sys, rattle_lab.workflow._report, rattle_lab.acoustics._levels, "
            "rattle_lab.detect._sound, rattle_lab.detect.thresholds, "
            "rattle_lab.acoustics._loudness; print('scipy.signal' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == "False"
