"""The Ritz bases of a plate: beam functions, or orthonormal polynomials where an edge is free.

See :mod:`rattle_lab.model.plate._ritz` (its docstring's "Free edges") for why.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from ._beam import BeamBasis, beam_basis, gauss_points
from ._edges import x_ends, y_ends


_END_POWER = {"C": 2, "S": 1, "F": 0}


@dataclass(frozen=True)
class PolyBasis:
    """Orthonormal polynomials on [0, 1] satisfying the geometric end conditions.

    ``phi_k`` is an orthonormal combination (Cholesky of the Gram matrix) of
    ``s^a (1 - s)^b P_k(2 s - 1)``, ``k < n``, with ``a, b`` = 2 (C), 1 (S),
    0 (F) at ``s = 0`` and ``s = 1``.  Same interface as
    :class:`rattle_lab.model.plate._beam.BeamBasis` (``left``, ``right``, ``len``,
    ``evaluate``).

    Attributes
    ----------
    left, right : str
        End conditions at s = 0 and s = 1.
    coef : numpy.ndarray
        Shape (n, degree + 1): Legendre-series coefficients of each function in
        ``u = 2 s - 1``.
    """

    left: str
    right: str
    coef: np.ndarray

    def __len__(self) -> int:
        return int(self.coef.shape[0])

    def evaluate(self, s: np.ndarray, order: int = 0) -> np.ndarray:
        """``(d/ds)^order phi_i(s)`` for every function i; shape (n, len(s))."""
        u = 2.0 * np.asarray(s, dtype=float) - 1.0
        c = self.coef
        if order:
            c = legendre.legder(c, m=order, scl=2.0, axis=1)
        return c @ legendre.legvander(u, c.shape[1] - 1).T


@functools.lru_cache(maxsize=64)
def poly_basis(left: str, right: str, n: int) -> PolyBasis:
    """The first ``n`` functions of :class:`PolyBasis` for the ends ``left``, ``right``."""
    # s = (1 + u) / 2 and 1 - s = (1 - u) / 2 as Legendre series in u
    factor = np.array([1.0])
    for _ in range(_END_POWER[left]):
        factor = legendre.legmul(factor, [0.5, 0.5])
    for _ in range(_END_POWER[right]):
        factor = legendre.legmul(factor, [0.5, -0.5])
    deg = n - 1 + factor.size - 1
    raw: np.ndarray = np.zeros((n, deg + 1))
    for k in range(n):
        unit = np.zeros(k + 1)
        unit[k] = 1.0
        prod = legendre.legmul(factor, unit)
        raw[k, :prod.size] = prod
    s, w = gauss_points()
    vander = legendre.legvander(2.0 * s - 1.0, deg)
    for _ in range(2):  # Gram-Schmidt by Cholesky, twice for orthonormality to rounding
        V = raw @ vander.T
        raw = np.linalg.solve(np.linalg.cholesky((V * w) @ V.T), raw)
    raw.setflags(write=False)
    return PolyBasis(left=left, right=right, coef=raw)


def plate_bases(edges: str, nx: int, ny: int) -> tuple[BeamBasis | PolyBasis,
                                                        BeamBasis | PolyBasis]:
    """The Ritz bases along x and y: polynomials if an edge is free, else beam functions."""
    kind = poly_basis if "F" in edges else beam_basis
    return kind(*x_ends(edges), nx), kind(*y_ends(edges), ny)
