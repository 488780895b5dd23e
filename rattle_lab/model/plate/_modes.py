"""Result objects of the plate solvers: one mode, and the modes of the Ritz solver."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError
from ._bases import plate_bases


@dataclass(frozen=True)
class PlateMode:
    """One normal mode of a thin rectangular plate (nondimensional).

    Attributes
    ----------
    lam : float
        ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25).
    Q1 : float
        ``int_0^1 int_0^{b/a} W dx_bar dy_bar`` (eq. 2.18), with ``x_bar = x/a``,
        ``y_bar = y/a`` and ``W = 1`` at the reference point.
    Q2 : float
        ``int_0^1 int_0^{b/a} W**2 dx_bar dy_bar`` (eq. 2.19), same normalisation.
    at_max : bool
        False: ``W`` is normalised to 1 at the plate centre.  True: the centre is a node
        and ``W`` is normalised to 1 at its maximum ``|W|`` (the tables' ``*``).
    ref_xi, ref_eta : float
        Reference point ``(x/a, y/b)`` where ``W = 1``.
    m, n : int
        Closed form: half-waves along x and y.  Ritz: 1-based indices of the beam
        functions in x and y with the largest coefficient (the mode's dominant term).
    """

    lam: float
    Q1: float
    Q2: float
    at_max: bool
    ref_xi: float
    ref_eta: float
    m: int
    n: int

    @property
    def participation(self) -> float:
        """``Q1 / Q2`` (eq. 2.16, 2.17, 2.27): ``L_s / m_s`` times ``rho h_p``."""
        return self.Q1 / self.Q2


@dataclass(frozen=True, eq=False)
class PlateModes:
    """The first modes of a plate from the Rayleigh-Ritz solver (nondimensional).

    Arrays are read-only; index ``k`` is the k-th mode in increasing ``lam``.

    Attributes
    ----------
    aspect_ratio : float
        ``b/a``.
    edges : str
        Boundary conditions of the edges y=0, x=a, y=b, x=0 (C, S or F each).
    nu : float
        Poisson's ratio used (it matters only where an edge is free).
    n_terms : tuple of int
        Beam functions used along x and along y.
    lam : numpy.ndarray
        ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25), shape (n_modes,).
    Q1, Q2 : numpy.ndarray
        Eq. 2.18 and 2.19 with ``W = 1`` at the reference point, shape (n_modes,).
    at_max : numpy.ndarray of bool
        True where the centre is a node and ``W`` is normalised at max ``|W|``.
    ref_xi, ref_eta : numpy.ndarray
        Reference points ``(x/a, y/b)``, shape (n_modes,).
    dominant : numpy.ndarray of int
        Shape (n_modes, 2): 1-based (x, y) indices of the largest beam-function term.
    xi, eta : numpy.ndarray
        Grid ``x/a`` (n_xi,) and ``y/b`` (n_eta,) of :attr:`shapes`, both from 0 to 1.
    shapes : numpy.ndarray
        Normalised mode shapes ``W`` on the grid, shape (n_modes, n_eta, n_xi).
    coefficients : numpy.ndarray
        Ritz coefficients of the normalised shapes, shape (n_modes, n_x, n_y), on the
        basis of :func:`rattle_lab.model.plate._bases.plate_bases` (beam functions, or
        orthonormal polynomials for a plate with a free edge).
    """

    aspect_ratio: float
    edges: str
    nu: float
    n_terms: tuple[int, int]
    lam: np.ndarray
    Q1: np.ndarray
    Q2: np.ndarray
    at_max: np.ndarray
    ref_xi: np.ndarray
    ref_eta: np.ndarray
    dominant: np.ndarray
    xi: np.ndarray
    eta: np.ndarray
    shapes: np.ndarray
    coefficients: np.ndarray

    def __len__(self) -> int:
        return int(self.lam.size)

    def __getitem__(self, k: int) -> PlateMode:
        return PlateMode(
            lam=float(self.lam[k]), Q1=float(self.Q1[k]), Q2=float(self.Q2[k]),
            at_max=bool(self.at_max[k]), ref_xi=float(self.ref_xi[k]), ref_eta=float(self.ref_eta[k]),
            m=int(self.dominant[k, 0]), n=int(self.dominant[k, 1]),
        )

    @property
    def participation(self) -> np.ndarray:
        """``Q1 / Q2`` of every mode (eq. 2.27 with 2.16, 2.17)."""
        return np.asarray(self.Q1 / self.Q2)

    def evaluate(self, xi: npt.ArrayLike, eta: npt.ArrayLike) -> np.ndarray:
        """Normalised mode shapes at points ``(x/a, y/b)``.

        Parameters
        ----------
        xi, eta : array_like
            Coordinates ``x/a`` and ``y/b`` in [0, 1], broadcast together.

        Returns
        -------
        numpy.ndarray
            Shape ``(n_modes,) + broadcast shape``.

        Raises
        ------
        ParameterError
            If a coordinate is outside [0, 1].
        """
        xi_b, eta_b = np.broadcast_arrays(np.asarray(xi, dtype=float), np.asarray(eta, dtype=float))
        for name, v in (("xi", xi_b), ("eta", eta_b)):
            if np.any(~((v >= 0) & (v <= 1))):
                raise ParameterError(f"`{name}` must lie in [0, 1], was {v[~((v >= 0) & (v <= 1))].flat[0]}")
        bx, by = plate_bases(self.edges, *self.n_terms)
        X = bx.evaluate(xi_b.ravel())
        Y = by.evaluate(eta_b.ravel())
        W = np.einsum("kij,ip,jp->kp", self.coefficients, X, Y)
        return np.asarray(W.reshape((len(self),) + xi_b.shape))
