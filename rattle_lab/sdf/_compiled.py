"""The two builds of :mod:`rattle_lab.sdf._kernel`: plain Python and numba.

The kernel source is executed a second time as the module
``rattle_lab.sdf._kernel_jit`` with ``__rattle_jit__ = True`` in its globals,
which makes its ``@jit`` decorator compile every function with
``numba.njit(cache=True)``.  The plain import :mod:`rattle_lab.sdf._kernel`
stays pure Python: the reference the tests compare the compiled kernel with.
Compilation is lazy (first call) and cached on disk by numba.
"""

from __future__ import annotations

import importlib.util
import sys
from types import ModuleType

from . import _kernel as python_kernel

_NAME = "rattle_lab.sdf._kernel_jit"


def _load_jit() -> ModuleType:
    if _NAME in sys.modules:
        return sys.modules[_NAME]
    origin = python_kernel.__file__
    spec = importlib.util.spec_from_file_location(_NAME, origin)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    module.__dict__["__rattle_jit__"] = True
    sys.modules[_NAME] = module
    spec.loader.exec_module(module)
    return module


jit_kernel = _load_jit()

__all__ = ["python_kernel", "jit_kernel"]
