"""The ``@jit`` of the kernel's modules: the identity, or ``numba.njit`` in the compiled build.

The kernel's files are loaded as two packages (see :mod:`rattle_lab.model.sdf._kernel`):
``rattle_lab.model.sdf._kernel`` and, by :mod:`rattle_lab.model.sdf._compiled`,
``rattle_lab.model.sdf._kernel_jit``, whose package global ``__rattle_jit__`` is True.
Each sibling imports this module relatively, so each package has its own copy, and the
copy reads the flag of the package it was loaded in.
"""

import sys

#: True in the compiled build (the package this copy belongs to has ``__rattle_jit__``).
_JIT = bool(getattr(sys.modules[__name__.rpartition(".")[0]], "__rattle_jit__", False))

if _JIT:
    import numba

    def jit(func):
        return numba.njit(cache=True, nogil=True)(func)
else:

    def jit(func):
        return func
