"""Session fixtures: synthetic rattle records built once per test session.

Each fixture returns the path of a written record (a rattle HDF5 file with ``/truth``),
made by the synthetic rig (:mod:`rattle_lab.rig`) from a scene with its own seed.
Treat the files as read-only: they are shared by every test in the session, in every
test process (each is simulated once, :func:`_simulated_once`).

* ``synthetic_campaign_record``: the embedded default scene (``rattle-lab simulate
  default``): thesis CFCF plate, 1.3 mm gap, 8 ramps (up/down at 95-98 Hz, 3 s) and 2
  dwells (96 and 98 Hz, 2 s); channels base, plate, velocity, mic, drive at 20 kHz.
* ``synthetic_threshold_record``: ``synthetic/threshold_only.toml``: 20 s ramps up and
  down at 8 frequencies (92-102 Hz), base accelerometer only at 2 kHz; thresholds in
  ``/truth/thresholds``.
* ``synthetic_noisy_record``: ``synthetic/noisy_lab.toml``: fan tone, strong shaker
  harmonics, strong noise, input ranges close to the signals.
* ``small_campaign_record``: ``tests/data/small_campaign.toml``, the default scene shortened
  to 18 s for the tests of plumbing.

Real records measured by others are found in one place, :data:`REALDATA`
(:func:`realdata` skips a test when its file is absent).
"""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import pytest

from rattle_lab.rig import write_synthetic

CHECKOUT = Path(__file__).resolve().parents[1]
SCENES = CHECKOUT / "synthetic"
#: The real records measured by others (``shared/realdata`` beside the checkout, see its
#: README; not committed): ``RATTLE_LAB_REALDATA`` points elsewhere.
REALDATA = Path(os.environ.get("RATTLE_LAB_REALDATA",
                               CHECKOUT.parent / "shared" / "realdata")).resolve()


def realdata(relative: str) -> Path:
    """The real record ``relative`` to :data:`REALDATA`; the test is skipped if it is absent."""
    path = REALDATA / relative
    if not path.is_file():
        pytest.skip(f"real data not available: {path} (set RATTLE_LAB_REALDATA to the "
                    "shared/realdata folder)")
    return path


def find_entry_point(name: str = "rattle-lab") -> Path:
    """The installed console script ``name``, as a user would run it.

    Looked for next to the running interpreter (the ``bin/`` or ``Scripts/`` folder of the
    venv that runs the tests), then in this checkout's ``.venv``, then on ``PATH``.  If it is
    nowhere, the bare name comes back and the tests that run it fail saying so.
    """
    here = Path(sys.executable).parent  # not resolved: a venv's python is a symlink
    venv = CHECKOUT / ".venv"
    for candidate in (here / name, here / f"{name}.exe", venv / "bin" / name,
                      venv / "Scripts" / f"{name}.exe"):
        if candidate.is_file():
            return candidate
    found = shutil.which(name)
    return Path(found) if found else Path(name)


#: The installed ``rattle-lab`` entry point; CLI tests import it (``from conftest import
#: RATTLE_LAB``) rather than look for it themselves.
RATTLE_LAB = find_entry_point()


#: Test modules whose results pass through rounding that another machine does differently:
#: dense eigensolvers and least squares (the BLAS kernel), the exact simulator and the flow
#: (libm, the CPU features numba compiles for), fits and thresholds of simulated records
#: (which inherit both, and in irregular regimes amplify them).  Their tests carry the
#: ``numerics`` marker; ``make test-foreign`` runs
#: them again with ``OPENBLAS_CORETYPE=Nehalem`` and ``NUMBA_CPU_NAME=generic``, so a test
#: that pins a machine's last bit fails on the developer's own machine.
NUMERICS_MODULES = frozenset({
    # plate and multi-mode models: eigensolvers, the modal integrator
    "test_plate", "test_modal", "test_modal_sound", "test_modal_cli", "test_rig_modal",
    "test_modal_convergence",
    # the exact simulator, its flow and its references
    "test_sdf_flow", "test_sdf_properties", "test_sdf_simulate", "test_sdf_long_time",
    "test_sdf_kernel_below_stop", "test_sdf_kernel_memo", "test_sdf_kernel_work",
    "test_reference", "test_rk4_thesis",
    # analysis: orbits, stability, maps, sweeps, chaos
    "test_orbits", "test_bifsets", "test_lyapunov", "test_maps", "test_sweep",
    "test_sweep_classify_compiled", "test_linear", "test_scaling",
    # fits and thresholds of simulated records, and what the report draws from them
    "test_fit", "test_fit_grazing_ramp", "test_ramp_model", "test_ramp_fit_search",
    "test_ramp_one_call", "test_thresholds", "test_flights", "test_up_down_run",
    "test_shock_steady", "test_report", "test_independent_campaign", "test_detect_physics",
    "test_detect_rig", "test_rig",
    # the compiled impact loops against the Python path and the rules written out
    "test_jump_kernels",
})


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark the tests of :data:`NUMERICS_MODULES` ``numerics``; run the files that hold a
    ``slow`` test first.

    ``make test`` hands whole files to its processes (pytest-xdist ``--dist loadfile``), so
    that a file's module and session fixtures (the report's stores, a simulated campaign)
    are built once rather than in each process; the long files go first so that the
    processes end together.  The order within a file is kept.
    """
    for item in items:
        module = getattr(item, "module", None)
        name = getattr(module, "__name__", "").rpartition(".")[2]
        if name in NUMERICS_MODULES:
            item.add_marker(pytest.mark.numerics)
    slow_files = {item.path for item in items if item.get_closest_marker("slow") is not None}
    items.sort(key=lambda item: item.path not in slow_files)  # stable: order kept otherwise


def _simulated_once(tmp_path_factory: pytest.TempPathFactory, scene: str | Path,
                    name: str) -> Path:
    """The record of ``scene``, simulated once for the whole session, whatever the number
    of test processes.

    ``make test`` runs the files in several processes (pytest-xdist), and a session fixture
    is a per-process thing: each process used to simulate the same seeded scene again.  The
    first process to need the record writes it (atomically, as every output) into the
    session's common base folder, under a lock; the others wait for it and read that file.
    Without ``fcntl`` (not POSIX) each process simulates its own.
    """
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # popen-gwN's parent: this session's folder, common to all
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        path = tmp_path_factory.mktemp("synthetic") / name
        write_synthetic(scene, path)
        return path
    folder = base / "simulated-once"
    folder.mkdir(exist_ok=True)
    path = folder / name
    with open(folder / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if not path.is_file():
            write_synthetic(scene, path)
    return path


@pytest.fixture(scope="session")
def synthetic_campaign_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Path of the default scene's record (all five channels, ramps and dwells)."""
    return _simulated_once(tmp_path_factory, "default", "campaign.h5")


SMALL_CAMPAIGN = Path(__file__).resolve().parent / "data" / "small_campaign.toml"


@pytest.fixture(scope="session")
def small_campaign_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Path of the shortened default scene's record (``tests/data/small_campaign.toml``): for
    the tests of plumbing (caching, Dask, progress, exit codes), where 18 s of record serve
    as well as the default scene's 40 s."""
    return _simulated_once(tmp_path_factory, SMALL_CAMPAIGN, "small_campaign.h5")


@pytest.fixture(scope="session")
def synthetic_threshold_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Path of the threshold-only record (slow ramps, base accelerometer only)."""
    return _simulated_once(tmp_path_factory, SCENES / "threshold_only.toml", "thresholds.h5")


@pytest.fixture(scope="session")
def synthetic_noisy_record(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Path of the noisy real-world record (fan, harmonics, strong noise)."""
    return _simulated_once(tmp_path_factory, SCENES / "noisy_lab.toml", "noisy.h5")


# --- the report the report tests look at (built once per session) -----------------------------

@pytest.fixture(scope="session")
def report_stores(synthetic_campaign_record: Path, tmp_path_factory: pytest.TempPathFactory
                  ) -> dict[str, Path]:
    """An ingest-only store of the default scene's record and a fitted copy of it
    (``tests/report_fixture.py``, as ``tests/regen_reference_images.py`` builds them)."""
    from report_fixture import build_stores

    return build_stores(synthetic_campaign_record, tmp_path_factory.mktemp("report"))


@pytest.fixture(scope="session")
def report_content(report_stores: dict[str, Path]):
    """The fitted store's full report content (model pages included), computed once."""
    from rattle_lab.workflow import build_report_content, gather

    return build_report_content(gather(report_stores["fitted"]), model=True)


@pytest.fixture(scope="session")
def full_report(report_content, tmp_path_factory: pytest.TempPathFactory):
    """``(ReportResult, path)`` of the full report's PDF, written once."""
    from rattle_lab.report import write_pdf

    out = tmp_path_factory.mktemp("pdf") / "report.pdf"
    return write_pdf(report_content, out), out


@pytest.fixture(scope="session")
def snapshot_report(tmp_path_factory: pytest.TempPathFactory):
    """``(content, ReportResult, path)`` of the content snapshot the reference images were
    drawn from (``tests/report_images.py``), written to a PDF once."""
    from report_images import load_content_snapshot

    from rattle_lab.report import write_pdf

    content = load_content_snapshot()
    out = tmp_path_factory.mktemp("snapshot") / "report.pdf"
    return content, write_pdf(content, out), out


@pytest.fixture(scope="session")
def snapshot_rasters(snapshot_report) -> list:
    """The snapshot report's pages as images of their drawn structure (rendered once)."""
    from report_images import structure_rasters

    return structure_rasters(snapshot_report[2])
