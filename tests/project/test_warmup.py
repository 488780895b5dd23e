"""``python -m rattle_lab._warmup`` (run by ``make`` after installing) names every compiled
function of the package, so that none is left to compile at a user's first call."""

from __future__ import annotations

import importlib
from pathlib import Path

import numba
from numba.core.caching import NullCache

from rattle_lab._warmup import COMPILED

PACKAGE = Path(__file__).resolve().parents[2] / "rattle_lab"
#: the simulator's kernel, compiled by rattle_lab.model.sdf.warm_cache and the sweeps
KERNEL = ("rattle_lab.model.sdf._kernel", "rattle_lab.model.sdf._compiled")


def _cached_dispatchers() -> set[tuple[str, str]]:
    found = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if "numba" not in text or "__pycache__" in path.parts:
            continue
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        if name.startswith(KERNEL):
            continue
        module = importlib.import_module(name)
        for attr, obj in vars(module).items():
            if (isinstance(obj, numba.core.dispatcher.Dispatcher) and obj.__module__ == name
                    and not isinstance(obj._cache, NullCache)):
                found.add((name, attr))
    return found


def test_the_warm_up_names_every_cached_compiled_function():
    found = _cached_dispatchers()
    assert len(found) >= 30   # the walk found them (37 when this test was written)
    listed = {(module, name) for module, names in COMPILED.items() for name in names}
    assert found - listed == set(), "add the new compiled functions to rattle_lab._warmup"
    assert listed - found == set(), "rattle_lab._warmup names functions that are gone"



def test_no_cached_compiled_function_is_imported_from_another_module():
    # numba's cache is checked against the source file of the function compiled, not of the
    # compiled functions it calls: a callee from another file that changes leaves a stale
    # copy in the caller's cache, which failed at run time ("'descr' is NULL") after an edit
    modules = {module for module, _ in _cached_dispatchers()}
    imported = []
    for name in sorted(modules):
        module = importlib.import_module(name)
        for attr, obj in vars(module).items():
            if isinstance(obj, numba.core.dispatcher.Dispatcher) and obj.__module__ != name:
                imported.append(f"{name}.{attr} (from {obj.__module__})")
    assert imported == []
