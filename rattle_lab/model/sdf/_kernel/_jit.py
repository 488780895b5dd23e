"""The ``@jit`` of the kernel's modules: the identity, or ``numba.njit`` in the compiled build.

The kernel's files are loaded as two packages (see :mod:`rattle_lab.model.sdf._kernel`):
``rattle_lab.model.sdf._kernel`` and, by :mod:`rattle_lab.model.sdf._compiled`,
``rattle_lab.model.sdf._kernel_jit``, whose package global ``__rattle_jit__`` is True.
Each sibling imports this module relatively, so each package has its own copy, and the
copy reads the flag of the package it was loaded in.

numba's on-disk cache (``cache=True``) marks a function's compiled code stale when the
file that defines the function changes, and only then; but the compiled code of a
function holds the code of the functions it calls, which now live in other files (a
changed :func:`._flight.evaluate` left :func:`._run.run` loading its old code from the
cache, silently).  So in the compiled build every kernel function's cache is stamped
with a digest of all the kernel's files (:func:`sources_digest`): a change to any one
of them recompiles them all, as when the kernel was one file.

``@jit_inline`` (the small functions called in the searches' inner loops: the
evaluation of the flight, its derivative bounds, a search chunk) compiles with numba's
``inline="always"``: they are inlined in numba's IR into their callers, so a call passes
no arrays (each array passed to a compiled call costs an atomic reference-count
increment and decrement, 13 % of the Fig. 4-3 sweep's time before).  Inlining does not
change an operation or its order (no fastmath, no fused multiply-add), so the numbers
are the same to the last bit.  It costs compile time on the first run only (numba's
cache serves later runs): each inlined call site is typed again, so the rare call sites
call a non-inlined twin instead (``evaluate`` in the event loop,
``level_values_called``); a first ``simulate`` and sweep then compile in ~44 s of CPU
instead of ~30 s (inlining everywhere: ~70 s).
"""

import hashlib
import os
import sys
from collections.abc import Callable

#: True in the compiled build (the package this copy belongs to has ``__rattle_jit__``).
_JIT = bool(getattr(sys.modules[__name__.rpartition(".")[0]], "__rattle_jit__", False))

#: The kernel's folder (both packages load their files from it).
FOLDER = os.path.dirname(os.path.abspath(__file__))


def sources_digest(folder: str = FOLDER) -> bytes:
    """SHA-256 of the names and contents of the ``*.py`` files in ``folder``, in name order."""
    h = hashlib.sha256()
    for name in sorted(n for n in os.listdir(folder) if n.endswith(".py")):
        h.update(name.encode() + b"\0")
        with open(os.path.join(folder, name), "rb") as f:
            h.update(hashlib.sha256(f.read()).digest())
    return h.digest()


class _KernelCacheLocator:
    """numba cache locator for the kernel's files: numba's own choice of cache folder
    (the next locator in numba's list that accepts the function), with the freshness
    stamp of the whole kernel, :func:`sources_digest`, instead of the one file's."""

    folder = FOLDER
    digest = b""  # of the kernel's files as this process loads them
    numba_locators: list = []  # numba's list; this class is its first entry

    @classmethod
    def from_function(cls, py_func: Callable, py_file: str) -> object | None:
        if os.path.dirname(os.path.abspath(py_file)) != cls.folder:
            return None
        for other in cls.numba_locators[cls.numba_locators.index(cls) + 1:]:
            locator = other.from_function(py_func, py_file)
            if locator is not None:
                locator.get_source_stamp = lambda: cls.digest
                return locator
        return None


def _stamp_whole_kernel() -> None:
    """Put :class:`_KernelCacheLocator` first in numba's list of cache locators (where
    this numba has such a list; else numba's own stamps, one file each, stay)."""
    from numba.core import caching

    # CacheImpl since numba 0.68, _CacheImpl before
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    locators = getattr(impl, "_locator_classes", None)
    if not isinstance(locators, list):
        return
    if any(getattr(known, "folder", None) == FOLDER for known in locators):
        return  # already there (the compiled build is loaded once per process)
    _KernelCacheLocator.digest = sources_digest()
    _KernelCacheLocator.numba_locators = locators
    locators.insert(0, _KernelCacheLocator)


if _JIT:
    import numba

    _stamp_whole_kernel()

    def jit(func):
        return numba.njit(cache=True, nogil=True)(func)

    def jit_inline(func):
        return numba.njit(cache=True, nogil=True, inline="always")(func)
else:

    def jit(func):
        return func

    def jit_inline(func):
        return func
