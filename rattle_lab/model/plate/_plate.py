"""The :class:`Plate` description: geometry, material, edges, and its modes and frequencies."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError
from rattle_lab.model import scaling
from ._checks import positive_float
from ._edges import check_edges
from ._modes import PlateModes
from ._ritz import ritz_modes


@dataclass(frozen=True)
class Plate:
    """A thin rectangular plate ``0 <= x <= a``, ``0 <= y <= b``.

    Attributes
    ----------
    a_m : float
        Side along x [m]; ``lambda`` (eq. 2.25) is scaled with it.
    b_m : float
        Side along y [m].
    h_p_m : float
        Thickness [m].
    E_pa : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio, -1 < nu < 0.5.
    rho_kg_m3 : float
        Density [kg/m^3].
    edges : str
        Four letters C (clamped), S (simply supported), F (free) for the edges
        y=0, x=a, y=b, x=0 in that order.  ``"CFCF"``: the sides of length ``a``
        clamped, the sides of length ``b`` free (the thesis's Table 2.1 plate).

    Examples
    --------
    >>> import numpy as np
    >>> p = Plate(a_m=0.254, b_m=0.2286, h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0, edges="CFCF")
    >>> bool(np.isclose(p.aspect_ratio, 0.9))
    True
    >>> bool(np.isclose(p.frequency_hz(27.4), 105.45, atol=0.01))
    True
    """

    a_m: float
    b_m: float
    h_p_m: float
    E_pa: float
    nu: float
    rho_kg_m3: float
    edges: str = "CFCF"

    def __post_init__(self) -> None:
        for name in ("a_m", "b_m", "h_p_m", "E_pa", "rho_kg_m3"):
            object.__setattr__(self, name, positive_float(name, getattr(self, name)))
        nu = float(self.nu)
        if not (-1.0 < nu < 0.5):
            raise ParameterError(f"`nu` must satisfy -1 < nu < 0.5, was {self.nu}")
        object.__setattr__(self, "nu", nu)
        object.__setattr__(self, "edges", check_edges(self.edges))

    @property
    def aspect_ratio(self) -> float:
        """``b / a``."""
        return self.b_m / self.a_m

    @property
    def flexural_rigidity_nm(self) -> float:
        """``D = E h_p**3 / (12 (1 - nu**2))`` [N m] (eq. 2.22)."""
        return scaling.flexural_rigidity_nm(self.E_pa, self.h_p_m, self.nu)

    @property
    def mass_per_area_kg_m2(self) -> float:
        """``rho h_p`` [kg/m^2] (eq. 2.3)."""
        return self.rho_kg_m3 * self.h_p_m

    def modes(self, n_modes: int = 6, n_terms: int | tuple[int, int] | None = None) -> PlateModes:
        """The first modes by Rayleigh-Ritz; see :func:`rattle_lab.model.plate.ritz_modes`.

        Parameters
        ----------
        n_modes : int
            Number of modes, >= 1.
        n_terms : int or (int, int) or None
            Basis functions along x and y; None: chosen by the solver's convergence check.

        Returns
        -------
        PlateModes
            Nondimensional; use :meth:`frequency_hz` on ``lam`` for frequencies.
        """
        return ritz_modes(self.aspect_ratio, self.edges, nu=self.nu, n_modes=n_modes,
                          n_terms=n_terms)

    def omega_rad_s(self, lam: npt.ArrayLike) -> float | np.ndarray:
        """Angular frequency [rad/s] of a nondimensional ``lambda`` (eq. 2.25)."""
        return scaling.omega_s_rad_s(lam, self.a_m, self.h_p_m, self.E_pa, self.nu, self.rho_kg_m3)

    def frequency_hz(self, lam: npt.ArrayLike) -> float | np.ndarray:
        """Frequency [Hz] of a nondimensional ``lambda`` (eq. 2.25)."""
        return scaling.f_s_hz(lam, self.a_m, self.h_p_m, self.E_pa, self.nu, self.rho_kg_m3)
