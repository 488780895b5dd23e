"""The nondimensional SDF impact oscillator: parameters, exact simulator, closed form.

See :func:`simulate` and :mod:`rattle_lab.model.sdf._kernel` for the algorithm.
"""

from typing import TYPE_CHECKING, Any

from ._flow import flow, homogeneous_transition, particular_coeffs, particular_state
from ._types import Crossings, DenseSamples, SimImpacts, SDFParams, SDFState, SimResult
from ._simulate import simulate, simulate_pieces

if TYPE_CHECKING:
    from ._compiled import KERNELS, cold_kernels, jit_kernel, signals_deferred, warm_cache

__all__ = [
    "SDFParams",
    "SDFState",
    "SimImpacts",
    "Crossings",
    "DenseSamples",
    "SimResult",
    "simulate",
    "flow",
    "particular_coeffs",
    "particular_state",
    "homogeneous_transition",
    "simulate_pieces",
    # the compiled kernel and its on-disk cache, loaded on first use (numba)
    "jit_kernel",
    "signals_deferred",
    "KERNELS",
    "cold_kernels",
    "warm_cache",
]

#: Names of :mod:`._compiled`, imported on first use: ``import rattle_lab.model.sdf`` does not
#: load numba until a simulation runs.
_COMPILED_NAMES = ("jit_kernel", "signals_deferred", "KERNELS", "cold_kernels", "warm_cache")


def __getattr__(name: str) -> Any:
    if name in _COMPILED_NAMES:
        from . import _compiled

        return getattr(_compiled, name)
    raise AttributeError(f"module 'rattle_lab.model.sdf' has no attribute {name!r}")
