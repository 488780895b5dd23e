"""Frequency, time and displacement to and from the nondimensional omega, tau and x (eq. 2.28-2.30)."""

from __future__ import annotations

import numpy.typing as npt

from rattle_lab.model._checks import FloatOrArray, _finite, _nonnegative, _positive
from rattle_lab.model._constants import TWO_PI


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


def angular_rad_s_from_freq(freq_hz: npt.ArrayLike) -> FloatOrArray:
    """Angular frequency ``2 pi f`` [rad/s] of a frequency [Hz] (e.g. ``omega_s`` of ``f_s``).

    Parameters
    ----------
    freq_hz : float or array
        Frequency [Hz], >= 0.

    Returns
    -------
    float or array
        Angular frequency [rad/s].

    Raises
    ------
    ParameterError
        If ``freq_hz`` is negative or NaN.

    Examples
    --------
    >>> round(float(angular_rad_s_from_freq(0.5)), 12)
    3.14159265359
    """
    return TWO_PI * _nonnegative("freq_hz", freq_hz)


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


