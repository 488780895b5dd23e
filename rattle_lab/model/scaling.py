"""Conversions between the physical plate-striker problem and the nondimensional SDF model.

Chapter 2 of the thesis reduces the plate to one mode ``s`` with the modal
equation (eq. 2.26)::

    x_s'' + 2 zeta omega_s x_s' + omega_s**2 x_s = F_es cos(omega_e t + phi),   stop at x_s = h,

and nondimensionalises it (eq. 2.28-2.32)::

    omega = omega_e / omega_s,   tau = omega_s t,   x = x_s / h,   F = F_es / (omega_s**2 h).

Every conversion here is a pure function with the unit in its name; each has
its inverse.  :class:`SDFScaling` bundles them for one mode and one gap.

Symbols and units
-----------------
``lam``
    Nondimensional modal frequency ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25).
``Q1``, ``Q2``
    Nondimensional modal integrals (eq. 2.18, 2.19); ``participation = Q1 / Q2``.
``F_es_ms2``
    Modal forcing amplitude ``F_es = (L_s / m_s) P_e`` [m/s^2] (eq. 2.27).
``mass_per_area_kg_m2``
    ``rho h_p`` [kg/m^2].

All functions accept floats or numpy arrays (broadcast) and return the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError

__all__ = [
    "flexural_rigidity_nm",
    "omega_s_rad_s",
    "f_s_hz",
    "lam_from_f_s",
    "participation_factor",
    "pressure_pa_from_accel",
    "accel_ms2_from_pressure",
    "F_es_from_pressure",
    "F_es_from_accel",
    "F_from_F_es",
    "F_es_from_F",
    "F_from_accel",
    "accel_ms2_from_F",
    "F_from_pressure",
    "pressure_pa_from_F",
    "omega_from_freq",
    "freq_hz_from_omega",
    "tau_from_time",
    "time_s_from_tau",
    "x_from_displacement",
    "displacement_m_from_x",
    "impact_velocity_ms",
    "v_im_from_velocity",
    "inv_F_from_gap",
    "gap_m_from_inv_F",
    "v_im_over_F_from_velocity",
    "velocity_ms_from_v_im_over_F",
    "NondimensionalExcitation",
    "PhysicalExcitation",
    "SDFScaling",
]

FloatOrArray = float | npt.NDArray[np.float64]
TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------- validation
def _as_checked(name: str, value: npt.ArrayLike, *, strict: bool) -> FloatOrArray:
    """Return ``value`` as float (scalar input) or float array; reject NaN and values <= 0 / < 0."""
    arr = np.asarray(value, dtype=float)
    bad = ~(arr > 0) if strict else ~(arr >= 0)
    if np.any(bad):
        first = arr[bad].flat[0] if arr.ndim else float(arr)
        rel = "> 0" if strict else ">= 0"
        raise ParameterError(f"`{name}` must be {rel}, was {first}")
    return float(arr) if arr.ndim == 0 else arr


def _positive(name: str, value: npt.ArrayLike) -> FloatOrArray:
    return _as_checked(name, value, strict=True)


def _nonnegative(name: str, value: npt.ArrayLike) -> FloatOrArray:
    return _as_checked(name, value, strict=False)


def _poisson(nu: float) -> float:
    nu_f = float(nu)
    if not (-1.0 < nu_f < 0.5):
        raise ParameterError(f"`nu` must satisfy -1 < nu < 0.5, was {nu}")
    return nu_f


def _finite(name: str, value: npt.ArrayLike) -> FloatOrArray:
    arr = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        first = arr[~np.isfinite(arr)].flat[0] if arr.ndim else float(arr)
        raise ParameterError(f"`{name}` must be finite, was {first}")
    return float(arr) if arr.ndim == 0 else arr


def _excited_participation(participation: npt.ArrayLike) -> FloatOrArray:
    """``participation`` (``Q1 / Q2``) checked finite and != 0: a mode with Q1 = 0 is not excited.

    Parameters
    ----------
    participation : float
        ``Q1 / Q2`` of the mode.

    Returns
    -------
    float
        ``participation`` as a float.

    Raises
    ------
    ParameterError
        If it is not finite or is 0.
    """
    q = _finite("participation", participation)
    if q == 0.0:
        raise ParameterError("`participation` must be != 0 (a mode with Q1 = 0 is not excited), was 0.0")
    return q


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


# --------------------------------------------------------------------------- forcing
def pressure_pa_from_accel(accel_ms2: npt.ArrayLike, rho_kg_m3: float, h_p_m: float) -> FloatOrArray:
    """Equivalent pressure amplitude ``P_e = rho h_p A_e`` [Pa] of a base acceleration (eq. 2.3).

    Parameters
    ----------
    accel_ms2 : float or array
        Base-acceleration amplitude ``A_e`` [m/s^2], >= 0.
    rho_kg_m3 : float
        Plate density [kg/m^3], > 0.
    h_p_m : float
        Plate thickness [m], > 0.

    Returns
    -------
    float or array
        ``P_e`` [Pa].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(pressure_pa_from_accel(9.81, 2710.0, 1e-3), 26.5851))
    True
    """
    A = _nonnegative("accel_ms2", accel_ms2)
    # Eq. (2.3) of the thesis
    return _positive("rho_kg_m3", rho_kg_m3) * _positive("h_p_m", h_p_m) * A


def accel_ms2_from_pressure(pressure_pa: npt.ArrayLike, rho_kg_m3: float, h_p_m: float) -> FloatOrArray:
    """Base acceleration ``A_e = P_e / (rho h_p)`` [m/s^2] equivalent to a pressure (eq. 2.3 inverted).

    Parameters
    ----------
    pressure_pa : float or array
        Pressure amplitude ``P_e`` [Pa], >= 0.
    rho_kg_m3, h_p_m : float
        Density [kg/m^3] and thickness [m], > 0.

    Returns
    -------
    float or array
        ``A_e`` [m/s^2].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(accel_ms2_from_pressure(pressure_pa_from_accel(9.81, 2710.0, 1e-3),
    ...                                         2710.0, 1e-3), 9.81))
    True
    """
    P = _nonnegative("pressure_pa", pressure_pa)
    return P / (_positive("rho_kg_m3", rho_kg_m3) * _positive("h_p_m", h_p_m))


def F_es_from_pressure(pressure_pa: npt.ArrayLike, participation: float,
                       mass_per_area_kg_m2: float) -> FloatOrArray:
    """Modal forcing ``F_es = (L_s/m_s) P_e = (Q1/Q2) P_e / (rho h_p)`` [m/s^2] (eq. 2.16, 2.17, 2.27).

    Parameters
    ----------
    pressure_pa : float or array
        Pressure amplitude ``P_e`` [Pa], >= 0.
    participation : float
        ``Q1 / Q2`` of the mode, finite.
    mass_per_area_kg_m2 : float
        ``rho h_p`` [kg/m^2], > 0.

    Returns
    -------
    float or array
        ``F_es`` [m/s^2].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(F_es_from_pressure(285.0, 0.5 / 0.402, 2.71), 130.80, rtol=1e-4))
    True
    """
    P = _nonnegative("pressure_pa", pressure_pa)
    q = _finite("participation", participation)
    mu = _positive("mass_per_area_kg_m2", mass_per_area_kg_m2)
    # Eq. (2.27) with L_s = a^2 Q1 (2.16) and m_s = rho h_p a^2 Q2 (2.17)
    return q * P / mu


def F_es_from_accel(accel_ms2: npt.ArrayLike, participation: float) -> FloatOrArray:
    """Modal forcing ``F_es = (Q1/Q2) A_e`` [m/s^2] of a base acceleration (eq. 2.3, 2.27).

    Parameters
    ----------
    accel_ms2 : float or array
        Base-acceleration amplitude ``A_e`` [m/s^2], >= 0.
    participation : float
        ``Q1 / Q2`` of the mode, finite.

    Returns
    -------
    float or array
        ``F_es`` [m/s^2].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(F_es_from_accel(1.0, 2.0), 2.0))
    True
    """
    A = _nonnegative("accel_ms2", accel_ms2)
    return _finite("participation", participation) * A


def F_from_F_es(F_es_ms2: npt.ArrayLike, omega_s_rad_s: float, gap_m: float) -> FloatOrArray:
    """Nondimensional forcing ``F = F_es / (omega_s**2 h)`` (eq. 2.31).

    Parameters
    ----------
    F_es_ms2 : float or array
        Modal forcing amplitude [m/s^2], finite.
    omega_s_rad_s : float
        Modal angular frequency [rad/s], > 0.
    gap_m : float
        Gap ``h`` between plate and striker [m], > 0.

    Returns
    -------
    float or array
        ``F``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(F_from_F_es(100.0, 10.0, 1.0), 1.0))
    True
    """
    Fes = _finite("F_es_ms2", F_es_ms2)
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    h = _positive("gap_m", gap_m)
    # Eq. (2.31) of the thesis
    return Fes / (w**2 * h)


def F_es_from_F(F: npt.ArrayLike, omega_s_rad_s: float, gap_m: float) -> FloatOrArray:
    """Modal forcing ``F_es = F omega_s**2 h`` [m/s^2] (eq. 2.31 inverted).

    Parameters
    ----------
    F : float or array
        Nondimensional forcing amplitude, finite.
    omega_s_rad_s, gap_m : float
        As in :func:`F_from_F_es`.

    Returns
    -------
    float or array
        ``F_es`` [m/s^2].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(F_es_from_F(1.0, 10.0, 1.0), 100.0))
    True
    """
    F_c = _finite("F", F)
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    h = _positive("gap_m", gap_m)
    return F_c * w**2 * h


def F_from_accel(accel_ms2: npt.ArrayLike, participation: float, omega_s_rad_s: float,
                 gap_m: float) -> FloatOrArray:
    """Nondimensional ``F = (Q1/Q2) A_e / (omega_s**2 h)`` of a base acceleration (eq. 2.27, 2.31).

    Parameters
    ----------
    accel_ms2 : float or array
        Base-acceleration amplitude [m/s^2], >= 0.
    participation : float
        ``Q1 / Q2`` of the mode.
    omega_s_rad_s : float
        Modal angular frequency [rad/s], > 0.
    gap_m : float
        Gap [m], > 0.

    Returns
    -------
    float or array
        ``F``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(F_from_accel(accel_ms2_from_F(0.2, 1.24, 660.0, 1e-3), 1.24, 660.0, 1e-3), 0.2))
    True
    """
    return F_from_F_es(F_es_from_accel(accel_ms2, participation), omega_s_rad_s, gap_m)


def accel_ms2_from_F(F: npt.ArrayLike, participation: float, omega_s_rad_s: float,
                     gap_m: float) -> FloatOrArray:
    """Base-acceleration amplitude ``A_e = F omega_s**2 h / (Q1/Q2)`` [m/s^2] giving ``F``.

    Parameters
    ----------
    F : float or array
        Nondimensional forcing amplitude, >= 0.
    participation : float
        ``Q1 / Q2`` of the mode, != 0.
    omega_s_rad_s, gap_m : float
        Modal angular frequency [rad/s] and gap [m], > 0.

    Returns
    -------
    float or array
        ``A_e`` [m/s^2] (negative where ``participation < 0``: opposite phase).

    Raises
    ------
    ParameterError
        If an argument is out of range or ``participation == 0`` (the mode is not excited).

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(accel_ms2_from_F(1.0, 2.0, 10.0, 1.0), 50.0))
    True
    """
    F_c = _nonnegative("F", F)
    q = _excited_participation(participation)
    return F_es_from_F(F_c, omega_s_rad_s, gap_m) / q


def F_from_pressure(pressure_pa: npt.ArrayLike, participation: float, mass_per_area_kg_m2: float,
                    omega_s_rad_s: float, gap_m: float) -> FloatOrArray:
    """Nondimensional ``F = (Q1/Q2) P_e / (rho h_p omega_s**2 h)`` of a pressure (eq. 2.27, 2.31).

    Parameters
    ----------
    pressure_pa : float or array
        Pressure amplitude ``P_e`` [Pa], >= 0.
    participation : float
        ``Q1 / Q2`` of the mode.
    mass_per_area_kg_m2 : float
        ``rho h_p`` [kg/m^2], > 0.
    omega_s_rad_s, gap_m : float
        Modal angular frequency [rad/s] and gap [m], > 0.

    Returns
    -------
    float or array
        ``F``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> w = 2 * np.pi * 105.0
    >>> bool(np.isclose(F_from_pressure(1.0, 0.5 / 0.402, 2.71, w, 1e-3), 1.05e-3, atol=0.005e-3))
    True
    """
    return F_from_F_es(F_es_from_pressure(pressure_pa, participation, mass_per_area_kg_m2),
                       omega_s_rad_s, gap_m)


def pressure_pa_from_F(F: npt.ArrayLike, participation: float, mass_per_area_kg_m2: float,
                       omega_s_rad_s: float, gap_m: float) -> FloatOrArray:
    """Pressure amplitude ``P_e = F omega_s**2 h rho h_p / (Q1/Q2)`` [Pa] giving ``F``.

    Parameters
    ----------
    F : float or array
        Nondimensional forcing amplitude, >= 0.
    participation : float
        ``Q1 / Q2`` of the mode, != 0.
    mass_per_area_kg_m2 : float
        ``rho h_p`` [kg/m^2], > 0.
    omega_s_rad_s, gap_m : float
        Modal angular frequency [rad/s] and gap [m], > 0.

    Returns
    -------
    float or array
        ``P_e`` [Pa].

    Raises
    ------
    ParameterError
        If an argument is out of range or ``participation == 0``.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(pressure_pa_from_F(1.0, 2.0, 3.0, 10.0, 1.0), 150.0))
    True
    """
    A = accel_ms2_from_F(F, participation, omega_s_rad_s, gap_m)
    return A * _positive("mass_per_area_kg_m2", mass_per_area_kg_m2)


# --------------------------------------------------------------------------- frequency, time, state
def omega_from_freq(freq_hz: npt.ArrayLike, f_s_hz: float) -> FloatOrArray:
    """Nondimensional forcing frequency ``omega = omega_e / omega_s = f / f_s`` (eq. 2.28).

    Parameters
    ----------
    freq_hz : float or array
        Excitation frequency [Hz], >= 0.
    f_s_hz : float
        Modal frequency [Hz], > 0.

    Returns
    -------
    float or array
        ``omega``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(omega_from_freq(99.75, 105.0))
    0.95
    """
    return _nonnegative("freq_hz", freq_hz) / _positive("f_s_hz", f_s_hz)


def freq_hz_from_omega(omega: npt.ArrayLike, f_s_hz: float) -> FloatOrArray:
    """Excitation frequency ``f = omega f_s`` [Hz] (eq. 2.28 inverted).

    Parameters
    ----------
    omega : float or array
        Nondimensional forcing frequency, >= 0.
    f_s_hz : float
        Modal frequency [Hz], > 0.

    Returns
    -------
    float or array
        ``f`` [Hz].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(freq_hz_from_omega(1.1, 105.0), 115.5))
    True
    """
    return _nonnegative("omega", omega) * _positive("f_s_hz", f_s_hz)


def tau_from_time(time_s: npt.ArrayLike, omega_s_rad_s: float) -> FloatOrArray:
    """Nondimensional time ``tau = omega_s t``.

    The thesis prints eq. (2.29) as ``tau = t / omega_s``, which is dimensionally
    wrong; ``tau = omega_s t`` is the scaling that turns eq. 2.26 into eq. 2.33.

    Parameters
    ----------
    time_s : float or array
        Time [s], finite.
    omega_s_rad_s : float
        Modal angular frequency [rad/s], > 0.

    Returns
    -------
    float or array
        ``tau``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(tau_from_time(0.5, 4.0))
    2.0
    """
    return _finite("time_s", time_s) * _positive("omega_s_rad_s", omega_s_rad_s)


def time_s_from_tau(tau: npt.ArrayLike, omega_s_rad_s: float) -> FloatOrArray:
    """Time ``t = tau / omega_s`` [s] (inverse of :func:`tau_from_time`).

    Parameters
    ----------
    tau : float or array
        Nondimensional time, finite.
    omega_s_rad_s : float
        Modal angular frequency [rad/s], > 0.

    Returns
    -------
    float or array
        ``t`` [s].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(time_s_from_tau(2.0, 4.0))
    0.5
    """
    return _finite("tau", tau) / _positive("omega_s_rad_s", omega_s_rad_s)


def x_from_displacement(displacement_m: npt.ArrayLike, gap_m: float) -> FloatOrArray:
    """Nondimensional modal displacement ``x = x_s / h`` (eq. 2.30).

    Parameters
    ----------
    displacement_m : float or array
        Modal displacement ``x_s`` at the reference point [m], finite.
    gap_m : float
        Gap ``h`` [m], > 0.

    Returns
    -------
    float or array
        ``x``; the striker is at ``x = 1``.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(x_from_displacement(5e-4, 1e-3))
    0.5
    """
    return _finite("displacement_m", displacement_m) / _positive("gap_m", gap_m)


def displacement_m_from_x(x: npt.ArrayLike, gap_m: float) -> FloatOrArray:
    """Modal displacement ``x_s = x h`` [m] (eq. 2.30 inverted).

    Parameters
    ----------
    x : float or array
        Nondimensional displacement, finite.
    gap_m : float
        Gap ``h`` [m], > 0.

    Returns
    -------
    float or array
        ``x_s`` [m].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(displacement_m_from_x(0.5, 1e-3))
    0.0005
    """
    return _finite("x", x) * _positive("gap_m", gap_m)


# --------------------------------------------------------------------------- impact velocity
def impact_velocity_ms(v_im: npt.ArrayLike, omega_s_rad_s: float, gap_m: float) -> FloatOrArray:
    """Physical impact velocity ``v = omega_s h v_im`` [m/s] (eq. 4.4).

    Parameters
    ----------
    v_im : float or array
        Nondimensional impact velocity ``dx/dtau``, finite.
    omega_s_rad_s, gap_m : float
        Modal angular frequency [rad/s] and gap [m], > 0.

    Returns
    -------
    float or array
        Velocity at the reference point [m/s].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(impact_velocity_ms(1.0, 660.0, 1e-3), 0.66))
    True
    """
    # Eq. (4.4) of the thesis
    return _finite("v_im", v_im) * _positive("omega_s_rad_s", omega_s_rad_s) * _positive("gap_m", gap_m)


def v_im_from_velocity(velocity_ms: npt.ArrayLike, omega_s_rad_s: float, gap_m: float) -> FloatOrArray:
    """Nondimensional velocity ``v_im = v / (omega_s h)`` (eq. 4.4).

    Parameters
    ----------
    velocity_ms : float or array
        Physical velocity at the reference point [m/s], finite.
    omega_s_rad_s, gap_m : float
        Modal angular frequency [rad/s] and gap [m], > 0.

    Returns
    -------
    float or array
        ``v_im``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(v_im_from_velocity(0.66, 660.0, 1e-3), 1.0))
    True
    """
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    h = _positive("gap_m", gap_m)
    return _finite("velocity_ms", velocity_ms) / (w * h)


def inv_F_from_gap(gap_m: npt.ArrayLike, omega_s_rad_s: float, F_es_ms2: float) -> FloatOrArray:
    """``1/F = omega_s**2 h / F_es`` (eq. 4.5, first line): the gap at fixed physical forcing.

    Parameters
    ----------
    gap_m : float or array
        Gap [m], > 0.
    omega_s_rad_s : float
        Modal angular frequency [rad/s], > 0.
    F_es_ms2 : float
        Modal forcing amplitude [m/s^2], > 0.

    Returns
    -------
    float or array
        ``1/F``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(inv_F_from_gap(1.0, 10.0, 50.0))
    2.0
    """
    h = _positive("gap_m", gap_m)
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    Fes = _positive("F_es_ms2", F_es_ms2)
    # Eq. (4.5) of the thesis, first line
    return w**2 * h / Fes


def gap_m_from_inv_F(inv_F: npt.ArrayLike, omega_s_rad_s: float, F_es_ms2: float) -> FloatOrArray:
    """Gap ``h = (1/F) F_es / omega_s**2`` [m] (eq. 4.5 inverted).

    Parameters
    ----------
    inv_F : float or array
        ``1/F``, > 0.
    omega_s_rad_s, F_es_ms2 : float
        Modal angular frequency [rad/s] and modal forcing [m/s^2], > 0.

    Returns
    -------
    float or array
        Gap [m].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(gap_m_from_inv_F(2.0, 10.0, 50.0))
    1.0
    """
    q = _positive("inv_F", inv_F)
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    return q * _positive("F_es_ms2", F_es_ms2) / w**2


def v_im_over_F_from_velocity(velocity_ms: npt.ArrayLike, omega_s_rad_s: float,
                              F_es_ms2: float) -> FloatOrArray:
    """``v_im / F = omega_s v / F_es`` (eq. 4.5, second line): the velocity at fixed physical forcing.

    Parameters
    ----------
    velocity_ms : float or array
        Physical impact velocity [m/s], finite.
    omega_s_rad_s, F_es_ms2 : float
        Modal angular frequency [rad/s] and modal forcing [m/s^2], > 0.

    Returns
    -------
    float or array
        ``v_im / F``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(v_im_over_F_from_velocity(1.0, 10.0, 5.0))
    2.0
    """
    v = _finite("velocity_ms", velocity_ms)
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    # Eq. (4.5) of the thesis, second line
    return w * v / _positive("F_es_ms2", F_es_ms2)


def velocity_ms_from_v_im_over_F(v_im_over_F: npt.ArrayLike, omega_s_rad_s: float,
                                 F_es_ms2: float) -> FloatOrArray:
    """Physical velocity ``v = (v_im/F) F_es / omega_s`` [m/s] (eq. 4.5 inverted).

    Parameters
    ----------
    v_im_over_F : float or array
        ``v_im / F``, finite.
    omega_s_rad_s, F_es_ms2 : float
        Modal angular frequency [rad/s] and modal forcing [m/s^2], > 0.

    Returns
    -------
    float or array
        Velocity [m/s].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> float(velocity_ms_from_v_im_over_F(2.0, 10.0, 5.0))
    1.0
    """
    r = _finite("v_im_over_F", v_im_over_F)
    w = _positive("omega_s_rad_s", omega_s_rad_s)
    return r * _positive("F_es_ms2", F_es_ms2) / w


# --------------------------------------------------------------------------- bundled scaling
@dataclass(frozen=True)
class NondimensionalExcitation:
    """A sinusoidal excitation in the nondimensional SDF model.

    Attributes
    ----------
    F : float or numpy.ndarray
        Forcing amplitude ``F_es / (omega_s**2 h)`` (eq. 2.31), nondimensional.
    omega : float or numpy.ndarray
        Forcing frequency ``omega_e / omega_s`` (eq. 2.28), nondimensional.
    """

    F: FloatOrArray
    omega: FloatOrArray


@dataclass(frozen=True)
class PhysicalExcitation:
    """A sinusoidal base excitation in physical units.

    Attributes
    ----------
    freq_hz : float or numpy.ndarray
        Excitation frequency ``f = omega f_s`` [Hz].
    accel_ms2 : float or numpy.ndarray
        Base-acceleration amplitude ``A_e`` [m/s^2] (eq. 2.1).
    pressure_pa : float or numpy.ndarray or None
        Equivalent pressure amplitude ``P_e = rho h_p A_e`` [Pa] (eq. 2.3); None when the
        scaling has no ``mass_per_area_kg_m2``.
    """

    freq_hz: FloatOrArray
    accel_ms2: FloatOrArray
    pressure_pa: FloatOrArray | None


@dataclass(frozen=True)
class SDFScaling:
    """Scales of one plate mode with one gap: physical <-> nondimensional SDF model.

    Built on the pure functions of :mod:`rattle_lab.model.scaling`.

    Attributes
    ----------
    omega_s_rad_s : float
        Modal angular frequency ``omega_s`` [rad/s] (eq. 2.25), > 0.
    gap_m : float
        Gap ``h`` between plate and striker [m], > 0.
    participation : float
        ``Q1 / Q2`` of the mode (eq. 2.16-2.19, 2.27), != 0.
    mass_per_area_kg_m2 : float or None
        ``rho h_p`` [kg/m^2]; needed only for pressures.

    Examples
    --------
    >>> import numpy as np
    >>> s = SDFScaling.from_modal_data(lam=27.4, Q1=0.5, Q2=0.402, gap_m=1e-3, a_m=0.254,
    ...                                h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0)
    >>> bool(np.isclose(s.f_s_hz, 105.45, atol=0.01))
    True
    >>> ex = s.to_nondimensional(freq_hz=105.45, pressure_pa=285.0)
    >>> bool(np.isclose(ex.F, 0.30, atol=0.005))
    True
    """

    omega_s_rad_s: float
    gap_m: float
    participation: float
    mass_per_area_kg_m2: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega_s_rad_s", float(_positive("omega_s_rad_s", self.omega_s_rad_s)))
        object.__setattr__(self, "gap_m", float(_positive("gap_m", self.gap_m)))
        object.__setattr__(self, "participation", float(_excited_participation(self.participation)))
        if self.mass_per_area_kg_m2 is not None:
            object.__setattr__(self, "mass_per_area_kg_m2",
                               float(_positive("mass_per_area_kg_m2", self.mass_per_area_kg_m2)))

    @classmethod
    def from_modal_data(cls, *, lam: float, Q1: float, Q2: float, gap_m: float, a_m: float,
                        h_p_m: float, E_pa: float, nu: float, rho_kg_m3: float) -> SDFScaling:
        """Scaling of a plate mode given by ``lambda``, ``Q1``, ``Q2`` (eq. 2.16-2.25).

        Parameters
        ----------
        lam, Q1, Q2 : float
            Modal data (eq. 2.18, 2.19, 2.25), nondimensional; ``lam > 0``.
        gap_m : float
            Gap [m].
        a_m, h_p_m, E_pa, nu, rho_kg_m3 : float
            Plate side along x [m], thickness [m], Young's modulus [Pa], Poisson's
            ratio, density [kg/m^3].

        Returns
        -------
        SDFScaling

        Raises
        ------
        ParameterError
            If an argument is out of range or ``Q1 == 0``.
        """
        _positive("lam", lam)
        return cls(
            omega_s_rad_s=float(omega_s_rad_s(lam, a_m, h_p_m, E_pa, nu, rho_kg_m3)),
            gap_m=gap_m,
            participation=float(participation_factor(Q1, Q2)),
            mass_per_area_kg_m2=float(_positive("rho_kg_m3", rho_kg_m3) * _positive("h_p_m", h_p_m)),
        )

    @property
    def f_s_hz(self) -> float:
        """Modal frequency ``omega_s / (2 pi)`` [Hz]."""
        return self.omega_s_rad_s / TWO_PI

    def _mass_per_area(self) -> float:
        if self.mass_per_area_kg_m2 is None:
            raise ParameterError("`pressure_pa` needs `mass_per_area_kg_m2` (rho h_p) in the SDFScaling, was None")
        return self.mass_per_area_kg_m2

    def to_nondimensional(self, *, freq_hz: npt.ArrayLike, accel_ms2: npt.ArrayLike | None = None,
                          pressure_pa: npt.ArrayLike | None = None) -> NondimensionalExcitation:
        """``F`` and ``omega`` of a base acceleration or a pressure (eq. 2.3, 2.27, 2.28, 2.31).

        Parameters
        ----------
        freq_hz : float or array
            Excitation frequency [Hz].
        accel_ms2, pressure_pa : float or array
            Exactly one of them: base-acceleration amplitude [m/s^2] or pressure amplitude [Pa].

        Returns
        -------
        NondimensionalExcitation

        Raises
        ------
        ParameterError
            If neither or both amplitudes are given, or a value is out of range.
        """
        if (accel_ms2 is None) == (pressure_pa is None):
            raise ParameterError(
                f"give exactly one of `accel_ms2` and `pressure_pa`, was accel_ms2={accel_ms2!r}, "
                f"pressure_pa={pressure_pa!r}"
            )
        if accel_ms2 is not None:
            F = F_from_accel(accel_ms2, self.participation, self.omega_s_rad_s, self.gap_m)
        else:
            F = F_from_pressure(pressure_pa, self.participation, self._mass_per_area(),  # type: ignore[arg-type]
                                self.omega_s_rad_s, self.gap_m)
        return NondimensionalExcitation(F=F, omega=omega_from_freq(freq_hz, self.f_s_hz))

    def to_physical(self, F: npt.ArrayLike, omega: npt.ArrayLike) -> PhysicalExcitation:
        """Frequency, base acceleration and pressure giving nondimensional ``F``, ``omega``.

        Parameters
        ----------
        F : float or array
            Nondimensional forcing amplitude, >= 0.
        omega : float or array
            Nondimensional forcing frequency, >= 0.

        Returns
        -------
        PhysicalExcitation
            ``pressure_pa`` is None when ``mass_per_area_kg_m2`` is None.

        Raises
        ------
        ParameterError
            If a value is out of range.
        """
        accel = accel_ms2_from_F(F, self.participation, self.omega_s_rad_s, self.gap_m)
        pressure = None if self.mass_per_area_kg_m2 is None else accel * self.mass_per_area_kg_m2
        return PhysicalExcitation(freq_hz=freq_hz_from_omega(omega, self.f_s_hz), accel_ms2=accel,
                                  pressure_pa=pressure)

    def velocity_ms(self, v_im: npt.ArrayLike) -> FloatOrArray:
        """Physical velocity of a nondimensional one (eq. 4.4); see :func:`impact_velocity_ms`."""
        return impact_velocity_ms(v_im, self.omega_s_rad_s, self.gap_m)

    def v_im(self, velocity_ms: npt.ArrayLike) -> FloatOrArray:
        """Nondimensional velocity of a physical one (eq. 4.4); see :func:`v_im_from_velocity`."""
        return v_im_from_velocity(velocity_ms, self.omega_s_rad_s, self.gap_m)

    def tau(self, time_s: npt.ArrayLike) -> FloatOrArray:
        """Nondimensional time ``omega_s t``; see :func:`tau_from_time`."""
        return tau_from_time(time_s, self.omega_s_rad_s)

    def time_s(self, tau: npt.ArrayLike) -> FloatOrArray:
        """Time [s] of a nondimensional time; see :func:`time_s_from_tau`."""
        return time_s_from_tau(tau, self.omega_s_rad_s)

    def x(self, displacement_m: npt.ArrayLike) -> FloatOrArray:
        """Nondimensional displacement ``x_s / h`` (eq. 2.30)."""
        return x_from_displacement(displacement_m, self.gap_m)

    def displacement_m(self, x: npt.ArrayLike) -> FloatOrArray:
        """Modal displacement ``x h`` [m] (eq. 2.30 inverted)."""
        return displacement_m_from_x(x, self.gap_m)
