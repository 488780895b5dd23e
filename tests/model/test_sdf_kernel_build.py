"""The exact kernel's two builds: the same files, each calling only its own functions.

The kernel is the package ``rattle_lab.model.sdf._kernel``; ``_compiled`` loads its files
a second time as the package ``rattle_lab.model.sdf._kernel_jit``, compiled with numba.
A sibling imported by an absolute name, or a module loaded once for both, would make one
build call the other's functions (the pure-Python reference would then run compiled
code, or the compiled code would fail to compile).  The results of the two are compared
with each other and with mpmath in ``test_sdf_flow.py`` and ``test_sdf_simulate.py``;
here the wiring, and numba's cache stamp: the compiled code of a function holds the code
of the functions it calls from other files, so its cache must go stale when any kernel
file changes, not only its own.
"""

from __future__ import annotations

import inspect
import shutil
from pathlib import Path
from types import ModuleType

import pytest
from numba.core.dispatcher import Dispatcher

from rattle_lab.model.sdf._compiled import jit_kernel, python_kernel
from rattle_lab.model.sdf._kernel import _jit

MODULES = ["_constants", "_flight", "_search", "_stop", "_run", "_drivers"]
#: the kernel's functions: one ``@jit`` (or ``@jit_inline``) line each
N_FUNCTIONS = sum(p.read_text().count("\n@jit\n") + p.read_text().count("\n@jit_inline\n")
                  for p in Path(_jit.FOLDER).glob("*.py"))


def _functions(module: ModuleType) -> dict[str, object]:
    """The functions a kernel module defines (not those it imports)."""
    own = {}
    for name, obj in vars(module).items():
        py_func = getattr(obj, "py_func", obj)
        if inspect.isfunction(py_func) and py_func.__module__ == module.__name__:
            own[name] = obj
    return own


@pytest.mark.parametrize("name", MODULES)
def test_each_build_loads_the_same_file_as_its_own_module(name: str) -> None:
    plain = getattr(python_kernel, name)
    compiled = getattr(jit_kernel, name)
    assert plain.__name__ == f"rattle_lab.model.sdf._kernel.{name}"
    assert compiled.__name__ == f"rattle_lab.model.sdf._kernel_jit.{name}"
    assert plain is not compiled and plain.__file__ == compiled.__file__


def test_the_plain_build_is_python_and_the_other_compiled() -> None:
    n = 0
    for name in MODULES:
        for fname, func in _functions(getattr(python_kernel, name)).items():
            assert inspect.isfunction(func), fname
            compiled = getattr(getattr(jit_kernel, name), fname)
            assert isinstance(compiled, Dispatcher), fname
            n += 1
    assert n == N_FUNCTIONS > 30


def test_each_build_calls_its_own_functions() -> None:
    # every name a module takes from a sibling is the sibling's object of the same build
    for build in (python_kernel, jit_kernel):
        for name in MODULES:
            module = getattr(build, name)
            for other in MODULES:
                for fname, func in _functions(getattr(build, other)).items():
                    if other != name and fname in vars(module):
                        assert vars(module)[fname] is func, (build.__name__, name, fname)
    # the names callers use, from the package
    assert python_kernel.run is python_kernel._run.run
    assert jit_kernel.run is jit_kernel._run.run and jit_kernel.run is not python_kernel.run
    assert inspect.isfunction(python_kernel.run_packed)
    assert isinstance(jit_kernel.run_packed, Dispatcher)


def test_sources_digest_changes_with_any_kernel_file(tmp_path: Path) -> None:
    folder = tmp_path / "_kernel"
    shutil.copytree(Path(_jit.__file__).parent, folder, ignore=shutil.ignore_patterns("__pycache__"))
    before = _jit.sources_digest(str(folder))
    assert before == _jit.sources_digest(_jit.FOLDER)
    (folder / "notes.txt").write_text("not a source")
    assert _jit.sources_digest(str(folder)) == before
    for name in sorted(p.name for p in folder.glob("*.py")):
        text = (folder / name).read_text()
        (folder / name).write_text(text + "\n")
        assert _jit.sources_digest(str(folder)) != before, name
        (folder / name).write_text(text)
    assert _jit.sources_digest(str(folder)) == before


def test_numba_stamps_each_kernel_function_with_all_kernel_files() -> None:
    # numba's cache of each compiled function (a private attribute of numba's dispatcher:
    # if numba renames it, this test says so rather than the stamp silently going back
    # to one file's)
    digest = _jit.sources_digest()
    n = 0
    for name in MODULES:
        for fname, dispatcher in _functions(getattr(jit_kernel, name)).items():
            locator = dispatcher._cache._impl.locator  # type: ignore[attr-defined]
            assert locator.get_source_stamp() == digest, fname
            assert Path(locator.get_cache_path()).exists()
            n += 1
    assert n == N_FUNCTIONS > 30
