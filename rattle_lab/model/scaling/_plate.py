"""Plate rigidity, modal frequency and participation (eq. 2.18-2.25)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from rattle_lab.model._checks import FloatOrArray, _finite, _nonnegative, _poisson, _positive
from rattle_lab.model._constants import TWO_PI


# --------------------------------------------------------------------------- plate and frequency
def flexural_rigidity_nm(E_pa: float, h_p_m: float, nu: float) -> float:
    """Flexural rigidity ``D = E h_p**3 / (12 (1 - nu**2))`` [N m] (eq. 2.22).

    Parameters
    ----------
    E_pa : float
        Young's modulus [Pa], > 0.
    h_p_m : float
        Plate thickness [m], > 0.
    nu : float
        Poisson's ratio, -1 < nu < 0.5.

    Returns
    -------
    float
        ``D`` [N m].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(flexural_rigidity_nm(7e10, 1e-3, 0.34), 6.5958, rtol=1e-4))
    True
    """
    E = _positive("E_pa", E_pa)
    h = _positive("h_p_m", h_p_m)
    nu_f = _poisson(nu)
    # Eq. (2.22) of the thesis
    return float(E * h**3 / (12.0 * (1.0 - nu_f**2)))


def omega_s_rad_s(lam: npt.ArrayLike, a_m: float, h_p_m: float, E_pa: float, nu: float,
                  rho_kg_m3: float) -> FloatOrArray:
    """Modal angular frequency ``omega_s = lam / a**2 * sqrt(D / (rho h_p))`` [rad/s] (eq. 2.25).

    Parameters
    ----------
    lam : float or array
        Nondimensional modal frequency ``lambda`` (eq. 2.25), >= 0.
    a_m : float
        Plate side along x [m] (the length used in ``lambda``), > 0.
    h_p_m, E_pa, nu, rho_kg_m3 : float
        Thickness [m], Young's modulus [Pa], Poisson's ratio, density [kg/m^3].

    Returns
    -------
    float or array
        ``omega_s`` [rad/s].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> w = omega_s_rad_s(27.4, 0.254, 1e-3, 7e10, 0.34, 2710.0)
    >>> bool(np.isclose(w / (2 * np.pi), 105.45, atol=0.01))
    True
    """
    lam_c = _nonnegative("lam", lam)
    a = _positive("a_m", a_m)
    rho = _positive("rho_kg_m3", rho_kg_m3)
    D = flexural_rigidity_nm(E_pa, h_p_m, nu)
    # Eq. (2.25) of the thesis solved for omega
    return lam_c / a**2 * np.sqrt(D / (rho * float(h_p_m)))


def f_s_hz(lam: npt.ArrayLike, a_m: float, h_p_m: float, E_pa: float, nu: float,
           rho_kg_m3: float) -> FloatOrArray:
    """Modal frequency ``f_s = omega_s / (2 pi)`` [Hz]; see :func:`omega_s_rad_s` (eq. 2.25).

    Parameters
    ----------
    lam, a_m, h_p_m, E_pa, nu, rho_kg_m3
        As in :func:`omega_s_rad_s`.

    Returns
    -------
    float or array
        ``f_s`` [Hz].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(f_s_hz(27.4, 0.254, 1e-3, 7e10, 0.34, 2710.0), 105.45, atol=0.01))
    True
    """
    return omega_s_rad_s(lam, a_m, h_p_m, E_pa, nu, rho_kg_m3) / TWO_PI


def lam_from_f_s(f_s_hz: npt.ArrayLike, a_m: float, h_p_m: float, E_pa: float, nu: float,
                 rho_kg_m3: float) -> FloatOrArray:
    """Nondimensional frequency ``lambda = 2 pi f_s a**2 sqrt(rho h_p / D)`` (eq. 2.25).

    Parameters
    ----------
    f_s_hz : float or array
        Modal frequency [Hz], >= 0.
    a_m, h_p_m, E_pa, nu, rho_kg_m3
        As in :func:`omega_s_rad_s`.

    Returns
    -------
    float or array
        ``lambda``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(lam_from_f_s(f_s_hz(27.4, 0.254, 1e-3, 7e10, 0.34, 2710.0),
    ...                              0.254, 1e-3, 7e10, 0.34, 2710.0), 27.4))
    True
    """
    f = _nonnegative("f_s_hz", f_s_hz)
    a = _positive("a_m", a_m)
    rho = _positive("rho_kg_m3", rho_kg_m3)
    D = flexural_rigidity_nm(E_pa, h_p_m, nu)
    # Eq. (2.25) of the thesis
    return TWO_PI * f * a**2 * np.sqrt(rho * float(h_p_m) / D)


def participation_factor(Q1: npt.ArrayLike, Q2: npt.ArrayLike) -> FloatOrArray:
    """Participation factor ``Q1 / Q2 = (L_s / m_s) rho h_p`` (eq. 2.16, 2.17), nondimensional.

    Parameters
    ----------
    Q1 : float or array
        Integral of the normalised mode shape (eq. 2.18), finite.
    Q2 : float or array
        Integral of its square (eq. 2.19), > 0.

    Returns
    -------
    float or array
        ``Q1 / Q2``.

    Raises
    ------
    ParameterError
        If ``Q1`` is not finite or ``Q2 <= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(participation_factor(0.5, 0.402), 1.2438, rtol=1e-4))
    True
    """
    q1 = _finite("Q1", Q1)
    q2 = _positive("Q2", Q2)
    return q1 / q2


