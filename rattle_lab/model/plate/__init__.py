"""Modal data of thin rectangular plates (thesis chapter 2).

* :func:`simply_supported_mode` / :func:`simply_supported_modes`: closed form (eq. 2.20-2.25).
* :func:`table_modes`: the thesis's Tables 2.1 (CFCF) and 2.2 (CCCC).
* :func:`ritz_modes`: Rayleigh-Ritz with beam functions, any C/S/F edges, any aspect ratio.

Edges are four letters C (clamped), S (simply supported), F (free) for the edges
y=0, x=a, y=b, x=0 in that order; ``"CFCF"`` has the two sides of length ``a``
clamped (the thesis's Table 2.1 plate).  All modal data are nondimensional:
``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25) and ``Q1``, ``Q2`` (eq. 2.18,
2.19) with ``W = 1`` at the centre, or at max ``|W|`` when the centre is a node.
"""

# in the order of their imports: checks and bases, the mode types, the solvers, then the
# Plate, which uses the Ritz solver
from ._edges import EDGE_ORDER
from ._modes import PlateMode, PlateModes
from ._simply_supported import simply_supported_mode, simply_supported_modes
from ._tables import TABLE_ASPECT_RATIOS, TableMode, table_modes
from ._ritz import DEFAULT_N_TERMS, ritz_modes
from ._plate import Plate

__all__ = [
    "Plate",
    "PlateMode",
    "PlateModes",
    "TableMode",
    "EDGE_ORDER",
    "DEFAULT_N_TERMS",
    "TABLE_ASPECT_RATIOS",
    "simply_supported_mode",
    "simply_supported_modes",
    "table_modes",
    "ritz_modes",
]
