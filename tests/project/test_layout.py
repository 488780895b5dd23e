"""The tests mirror the package (issue 25 item 6): each test file lives in ``tests/<name>/``,
where ``<name>`` is a subpackage of ``rattle_lab`` (``tests/model/`` for ``rattle_lab.model``)
or ``project`` (checks of the whole project: layers, public API, docs, resources).

The shared helpers (``conftest.py``, ``record_factory.py``, ``independent_campaign.py``,
``sdf_reference.py``, ...) and ``data/`` stay at ``tests/``.  pytest imports the test files
in its default "prepend" mode without ``__init__.py`` files, so the basenames must be unique.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

from conftest import CHECKOUT

TESTS = CHECKOUT / "tests"
PROJECT_CHECKS = "project"


def _packages() -> set[str]:
    return {p.parent.name for p in (CHECKOUT / "rattle_lab").glob("*/__init__.py")}


def _test_files() -> list[Path]:
    return sorted(p for p in TESTS.rglob("test_*.py") if "__pycache__" not in p.parts)


def test_the_packages_are_found() -> None:
    # guards the checks below against an empty set (a moved package folder, a wrong root)
    assert {"model", "records", "store", "detect", "fit", "cli"} <= _packages()


def test_every_test_file_is_in_a_folder_named_after_a_package() -> None:
    allowed = _packages() | {PROJECT_CHECKS}
    misplaced = [str(p.relative_to(TESTS)) for p in _test_files()
                 if len(p.relative_to(TESTS).parts) != 2 or p.parent.name not in allowed]
    assert _test_files(), TESTS
    assert not misplaced, f"move these into tests/<package>/ or tests/{PROJECT_CHECKS}/: {misplaced}"


def test_test_file_names_are_unique_and_there_is_no_init() -> None:
    # pytest's prepend import mode puts each test folder on sys.path and imports the file by
    # its basename: two files of one name would clash, and an __init__.py would change that
    counts = Counter(p.name for p in _test_files())
    assert not [name for name, n in counts.items() if n > 1]
    assert not list(TESTS.rglob("__init__.py"))
