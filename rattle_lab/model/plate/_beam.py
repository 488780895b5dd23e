"""Beam eigenfunctions on [0, 1] for the Rayleigh-Ritz plate solver.

Each end of the unit beam is clamped (``"C"``), simply supported (``"S"``) or
free (``"F"``).  The elastic eigenfunctions are written in the
well-conditioned form

    phi(s) = c1 cos(beta s) + c2 sin(beta s) + c3 exp(-beta s) + c4 exp(-beta (1 - s)),

which avoids the cancellation between ``cosh`` and ``sinh`` that ruins the
textbook form for ``beta`` above about 20.  The eigenvalues ``beta`` are the
roots of the 4x4 boundary-condition determinant, bracketed on a fine grid and
polished with :func:`scipy.optimize.brentq`.  Rigid-body modes (free-free:
translation and rotation; simply supported-free: rotation about the support)
are added in closed form.  Every function is normalised to ``int phi^2 = 1``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from rattle_lab.exceptions import ConvergenceError


#: Gauss-Legendre points on [0, 1] used for every beam integral.  The
#: integrands are products of two beam functions (and derivatives) with at
#: most ``2 * beta_max`` ~ 2 * 40 radians of oscillation on the unit interval;
#: 200 points integrate them to machine precision (checked in the tests
#: against an adaptive quadrature).
N_GAUSS = 200

_ROW_AT_0 = {
    # derivative order k -> row of (d/ds)^k phi / beta^k at s = 0, as a function of E = exp(-beta)
    0: lambda e: (1.0, 0.0, 1.0, e),
    1: lambda e: (0.0, 1.0, -1.0, e),
    2: lambda e: (-1.0, 0.0, 1.0, e),
    3: lambda e: (0.0, -1.0, -1.0, e),
}


def _rows_at_1(k: int, c: float, s: float, e: float) -> tuple[float, float, float, float]:
    return {
        0: (c, s, e, 1.0),
        1: (-s, c, -e, 1.0),
        2: (-c, -s, e, 1.0),
        3: (s, -c, -e, 1.0),
    }[k]


#: Boundary conditions as the derivative orders that vanish at the end.
_BC_ORDERS: dict[str, tuple[int, int]] = {"C": (0, 1), "S": (0, 2), "F": (2, 3)}


def _bc_matrix(beta: float, left: str, right: str) -> np.ndarray:
    e = math.exp(-beta)
    c, s = math.cos(beta), math.sin(beta)
    rows = [_ROW_AT_0[k](e) for k in _BC_ORDERS[left]]
    rows += [_rows_at_1(k, c, s, e) for k in _BC_ORDERS[right]]
    return np.array(rows, dtype=float)


def _det(beta: float, left: str, right: str) -> float:
    return float(np.linalg.det(_bc_matrix(beta, left, right)))


def _rigid_modes(left: str, right: str) -> list[tuple[float, float]]:
    """Rigid-body modes as (constant, slope) pairs of ``phi = p0 + p1 * s``, normalised."""
    if left == "F" and right == "F":
        return [(1.0, 0.0), (-math.sqrt(3.0), 2.0 * math.sqrt(3.0))]
    if left == "S" and right == "F":
        return [(0.0, math.sqrt(3.0))]
    if left == "F" and right == "S":
        return [(math.sqrt(3.0), -math.sqrt(3.0))]
    return []


@dataclass(frozen=True)
class BeamBasis:
    """The first ``n`` eigenfunctions of a beam on [0, 1] with given end conditions.

    Attributes
    ----------
    left, right : str
        End conditions at s = 0 and s = 1 (``"C"``, ``"S"`` or ``"F"``).
    beta : numpy.ndarray
        Nondimensional wavenumbers, shape (n,); 0 for rigid-body modes.
    coef : numpy.ndarray
        Shape (n, 4): ``(c1, c2, c3, c4)`` of the elastic form, or ``(p0, p1, 0, 0)``
        of ``phi = p0 + p1 s`` for a rigid-body mode (``beta == 0``).
    """

    left: str
    right: str
    beta: np.ndarray
    coef: np.ndarray

    def __len__(self) -> int:
        return int(self.beta.size)

    def evaluate(self, s: np.ndarray, order: int = 0) -> np.ndarray:
        """``(d/ds)^order phi_i(s)`` for every function i; shape (n, len(s))."""
        s = np.asarray(s, dtype=float)[None, :]
        beta = self.beta[:, None]
        c1, c2, c3, c4 = (self.coef[:, k][:, None] for k in range(4))
        elastic = beta[:, 0] > 0
        out = np.zeros((self.beta.size, s.shape[1]))
        with np.errstate(over="ignore", under="ignore"):
            b = np.where(elastic[:, None], beta, 1.0)
            bs = b * s
            cos_part = {0: c1 * np.cos(bs) + c2 * np.sin(bs),
                        1: -c1 * np.sin(bs) + c2 * np.cos(bs),
                        2: -c1 * np.cos(bs) - c2 * np.sin(bs),
                        3: c1 * np.sin(bs) - c2 * np.cos(bs)}[order % 4]
            sign3 = (-1.0) ** order
            exp_part = sign3 * c3 * np.exp(-bs) + c4 * np.exp(-b * (1.0 - s))
            val_elastic = b**order * (cos_part + exp_part)
        if order == 0:
            val_rigid = c1 + c2 * s
        elif order == 1:
            val_rigid = c2 + 0.0 * s
        else:
            val_rigid = 0.0 * s
        out[:] = np.where(elastic[:, None], val_elastic, val_rigid)
        return out


@functools.lru_cache(maxsize=4)
def gauss_points(n: int = N_GAUSS) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1] (cached; read-only arrays)."""
    x, w = np.polynomial.legendre.leggauss(n)
    s, ws = 0.5 * (x + 1.0), 0.5 * w
    s.setflags(write=False)
    ws.setflags(write=False)
    return s, ws


@functools.lru_cache(maxsize=64)
def beam_basis(left: str, right: str, n: int) -> BeamBasis:
    """First ``n`` normalised eigenfunctions of a beam on [0, 1].

    Parameters
    ----------
    left, right : {"C", "S", "F"}
        End conditions at s = 0 and s = 1.
    n : int
        Number of functions (rigid-body modes included), >= 1.

    Returns
    -------
    BeamBasis

    Raises
    ------
    ConvergenceError
        If the root bracketing finds fewer roots than needed (should not happen).
    """
    from scipy.optimize import brentq  # deferred: keeps `import rattle_lab.model.plate` light

    rigid = _rigid_modes(left, right)
    n_elastic = max(n - len(rigid), 0)
    # Elastic roots lie near (k + 1/2) pi or k pi; scan well beyond the last one.
    beta_max = (n_elastic + 2) * math.pi
    grid = np.arange(1.0, beta_max, 0.02)
    dets = np.array([_det(b, left, right) for b in grid])
    roots: list[float] = []
    for b0, b1, d0, d1 in zip(grid[:-1], grid[1:], dets[:-1], dets[1:]):
        if d0 == 0.0:
            roots.append(float(b0))
        elif d0 * d1 < 0.0:
            roots.append(brentq(_det, b0, b1, args=(left, right), xtol=1e-15, rtol=4 * np.finfo(float).eps))
        if len(roots) == n_elastic:
            break
    if len(roots) < n_elastic:
        raise ConvergenceError(
            f"beam basis {left}-{right}: found {len(roots)} of {n_elastic} eigenvalues below beta={beta_max:.1f}"
        )
    sg, wg = gauss_points()
    betas = [0.0] * len(rigid) + roots
    coefs = [np.array([p0, p1, 0.0, 0.0]) for p0, p1 in rigid]
    for beta in roots:
        # Null vector of the boundary-condition matrix.
        _, _, vt = np.linalg.svd(_bc_matrix(beta, left, right))
        coef = vt[-1]
        tmp = BeamBasis(left, right, np.array([beta]), coef[None, :])
        norm = math.sqrt(float(np.sum(wg * tmp.evaluate(sg)[0] ** 2)))
        coef = coef / norm
        # Deterministic sign: positive slope at s = 0 where it is not zero, else positive value.
        tmp = BeamBasis(left, right, np.array([beta]), coef[None, :])
        lead = tmp.evaluate(np.array([0.0]), order=1)[0, 0]
        if abs(lead) < 1e-8:
            lead = tmp.evaluate(np.array([0.0]))[0, 0]
        coefs.append(coef if lead >= 0 else -coef)
    basis = BeamBasis(left, right, np.array(betas[:n]), np.array(coefs[:n]))
    basis.beta.setflags(write=False)
    basis.coef.setflags(write=False)
    return basis
