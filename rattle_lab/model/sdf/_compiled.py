"""The two builds of :mod:`rattle_lab.model.sdf._kernel`: plain Python and numba.

The kernel package's files are loaded a second time as the package
``rattle_lab.model.sdf._kernel_jit`` (same folder, its own modules) with
``__rattle_jit__ = True`` among the package's globals, which makes the ``@jit`` of
every module of that package (:mod:`rattle_lab.model.sdf._kernel._jit`) compile its
functions with ``numba.njit(cache=True)``.  The modules import their siblings
relatively, so the compiled functions call compiled functions.  The plain import
:mod:`rattle_lab.model.sdf._kernel` stays pure Python: the reference the tests compare
the compiled kernel with.  Compilation is lazy (first call) and cached on disk by numba.
"""

from __future__ import annotations

import contextlib
import importlib.util
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from types import ModuleType

from . import _kernel as python_kernel

_NAME = "rattle_lab.model.sdf._kernel_jit"


def _load_jit() -> ModuleType:
    if _NAME in sys.modules:
        return sys.modules[_NAME]
    # the package's __init__, with the same folder to find its submodules in: its
    # relative imports load the siblings again, as modules of this package
    spec = importlib.util.spec_from_file_location(
        _NAME, python_kernel.__file__, submodule_search_locations=list(python_kernel.__path__))
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    module.__dict__["__rattle_jit__"] = True  # read by each submodule's copy of _jit
    sys.modules[_NAME] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        for name in [n for n in sys.modules if n == _NAME or n.startswith(_NAME + ".")]:
            del sys.modules[name]
        raise
    return module


jit_kernel = _load_jit()

__all__ = ["python_kernel", "jit_kernel", "signals_deferred", "cold_kernels", "warm_cache"]

_DEFERRED = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM until a long compiled call has returned its arrays.

    A Ctrl-C that arrives during a long compiled call is noticed while numba boxes the
    call's result (a tuple of arrays); the KeyboardInterrupt raised there left numba a
    broken tuple and the process died of a segmentation fault.  Inside this block the
    two signals only record that they came; at its end the previous handlers are back
    and the first signal that came is raised again, so the interrupt lands at the next
    Python instruction, as usual.  Handlers can be set in the main thread only; elsewhere
    nothing changes.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []

    def _note(signum: int, _frame: object) -> None:
        came.append(signum)

    previous = {sig: signal.signal(sig, _note) for sig in _DEFERRED}
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)
        if came:
            signal.raise_signal(came[0])


#: The compiled kernels :func:`warm_cache` compiles, in its order.
KERNELS = ("run", "run_packed", "run_pieces")


def cold_kernels() -> list[str]:
    """The kernels of :data:`KERNELS` that numba's on-disk cache does not hold (or holds for
    another version of their source): a call to one of them compiles it first.

    Empty where it cannot tell (a numba without this cache layout): no notice is better
    than a wrong one.
    """
    cold = []
    for name in KERNELS:
        try:
            index = getattr(jit_kernel, name)._cache._cache_file._load_index()
        except Exception:  # noqa: BLE001 - numba internals: unknown means "do not say"
            return []
        if not index:
            cold.append(name)
    return cold


def warm_cache(on_kernel: Callable[[int, str], None] | None = None) -> float:
    """Compile the kernels' signatures now and write numba's on-disk cache.

    Run once after installing (``python -m rattle_lab.model.sdf._compiled``), so that
    the first simulation of a fresh install loads the cache (about 1-2 s) instead
    of compiling (about 20 s).  ``on_kernel(i, name)`` is called before each kernel of
    :data:`KERNELS` (a progress line).  Returns the seconds it took.
    """
    import time

    import numpy as np

    def step(i: int) -> None:
        if on_kernel is not None:
            on_kernel(i, KERNELS[i])

    t0 = time.perf_counter()
    # each kernel has one signature (floats, booleans, ints, arrays): one call compiles it
    step(0)
    jit_kernel.run(0.2, 1.1, 0.05, 0.6, 0.0, 0.0, 0.0, 0.0, False, 1.0, True, True, 1000)
    # what simulate() calls (run, its result packed in one buffer)
    step(1)
    jit_kernel.run_packed(0.2, 1.1, 0.05, 0.6, 0.0, 0.0, 0.0, 0.0, False, 1.0, True, True, 1000)
    # the ramp replays' piece runner (rattle_lab.model.sdf._simulate.simulate_pieces)
    step(2)
    jit_kernel.run_pieces(np.array([0.2]), 1.1, 0.05, 0.6, 0.0, 0.0, 0.0, 0.0, False,
                          np.array([1.0]), -1.0, 4, -1.0, np.ones(1, dtype=np.bool_), np.nan)
    return time.perf_counter() - t0


if __name__ == "__main__":  # pragma: no cover - installation step
    print(f"rattle_lab: numba kernels compiled and cached in {warm_cache():.1f} s")
