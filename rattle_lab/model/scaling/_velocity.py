"""Impact velocity and the gap to and from their nondimensional forms (eq. 2.32, 3.x)."""

from __future__ import annotations

import numpy.typing as npt

from rattle_lab.model._checks import FloatOrArray, _finite, _positive


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


