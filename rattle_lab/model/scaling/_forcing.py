"""Forcing: pressure, base acceleration, modal force and nondimensional F (eq. 2.27-2.31)."""

from __future__ import annotations

import numpy.typing as npt

from rattle_lab.model._checks import FloatOrArray, _excited_participation, _finite, _nonnegative, _positive


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


