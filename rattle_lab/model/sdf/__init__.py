"""The nondimensional SDF impact oscillator: parameters, exact simulator, closed form.

See :func:`simulate` and :mod:`rattle_lab.model.sdf._kernel` for the algorithm.
"""

from ._flow import flow, homogeneous_transition, particular_coeffs, particular_state
from ._types import Crossings, DenseSamples, SimImpacts, SDFParams, SDFState, SimResult
from ._simulate import simulate

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
]
