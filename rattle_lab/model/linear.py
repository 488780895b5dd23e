"""Linear (no-impact) predictions of the SDF model, nondimensional (thesis eq. 3.4, 4.6-4.11).

Without the stop, ``x'' + 2 zeta x' + x = F cos(omega tau)`` (eq. 4.6) settles to
``x = x_max cos(omega tau - psi)`` with the amplitude of eq. 4.7.  Linear theory
predicts impact where ``x_max >= 1``; the boundary ``x_max = 1`` is the grazing
curve of eq. 3.4.

All functions are pure and vectorised (numpy broadcasting).  NaN inputs give NaN
outputs; negative amplitudes, frequencies or damping raise
:class:`~rattle_lab.exceptions.ParameterError`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from rattle_lab.model._checks import _nonnegative, _positive

__all__ = [
    "grazing_F",
    "grazing_omegas",
    "threshold_accel_ms2",
    "threshold_accel_unchecked",
    "linear_amplitude",
    "linear_impact_velocity",
    "linear_v_im_over_F",
]

FloatOrArray = float | npt.NDArray[np.float64]


def _nonneg_or_nan(name: str, value: npt.ArrayLike) -> np.ndarray:
    """Float array of ``value``; NaN passes, anything < 0 (or -inf) raises."""
    arr = np.asarray(value, dtype=float)
    bad = arr < 0
    if np.any(bad):
        raise_on = arr[bad].flat[0] if arr.ndim else float(arr)
        _nonnegative(name, raise_on)  # raises ParameterError naming the argument
    return arr


def _out(arr: np.ndarray) -> FloatOrArray:
    return float(arr) if arr.ndim == 0 else arr


def _speed_or_nan(omega: npt.ArrayLike, radicand: npt.ArrayLike) -> np.ndarray:
    """``omega sqrt(radicand)`` where ``radicand >= 0``, NaN elsewhere (no linear impact).

    Parameters
    ----------
    omega : float or array
        Forcing frequency, nondimensional.
    radicand : float or array
        ``x_max**2 - 1`` (eq. 4.10) or its counterpart over ``F**2`` (eq. 4.11); NaN
        propagates.

    Returns
    -------
    ndarray
        The speed (broadcast shape), NaN where ``radicand`` is negative or NaN.
    """
    radicand = np.asarray(radicand)
    with np.errstate(invalid="ignore"):
        return np.where(radicand >= 0, omega * np.sqrt(np.where(radicand >= 0, radicand, np.nan)),
                        np.nan)


def grazing_F(omega: npt.ArrayLike, zeta: npt.ArrayLike) -> FloatOrArray:
    """Forcing amplitude at which the linear response just touches the stop (eq. 3.4).

    ``F_graze = sqrt((1 - omega**2)**2 + (2 zeta omega)**2)``: the linear amplitude of
    eq. 4.7 equals 1.  Impact occurs (linear theory) for ``F >= F_graze``.

    Parameters
    ----------
    omega : float or array
        Forcing frequency ``omega_e / omega_s``, nondimensional, >= 0.
    zeta : float or array
        Damping ratio, nondimensional, >= 0.

    Returns
    -------
    float or array
        ``F_graze``, nondimensional (broadcast shape).

    Raises
    ------
    ParameterError
        If ``omega`` or ``zeta`` is negative.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(grazing_F(1.0, 0.05), 0.1))
    True
    """
    w = _nonneg_or_nan("omega", omega)
    z = _nonneg_or_nan("zeta", zeta)
    # Eq. (3.4) of the thesis: grazing amplitude
    return _out(np.sqrt((1.0 - w**2) ** 2 + (2.0 * z * w) ** 2))


def grazing_omegas(F: npt.ArrayLike, zeta: npt.ArrayLike) -> tuple[FloatOrArray, FloatOrArray]:
    """Frequencies at which forcing ``F`` grazes: eq. 3.4 solved for ``omega``.

    With ``u = omega**2`` eq. 3.4 is ``u**2 + (4 zeta**2 - 2) u + 1 - F**2 = 0``, so
    ``u = 1 - 2 zeta**2 +- sqrt(F**2 - 4 zeta**2 (1 - zeta**2))``; only roots ``u >= 0``
    are frequencies.  Linear theory predicts impact for ``omega_low <= omega <= omega_high``:
    a slow up-sweep leaves the no-impact solution at ``omega_low`` and a down-sweep at
    ``omega_high`` (thesis section 4.2: 0.907 and 1.081 for ``F = 0.2``, ``zeta = 0.05``).

    Parameters
    ----------
    F : float or array
        Forcing amplitude, nondimensional, >= 0.
    zeta : float or array
        Damping ratio, nondimensional, >= 0.

    Returns
    -------
    omega_low, omega_high : float or array
        The two roots, NaN where there is none: both NaN when ``F`` is below the minimum
        of the grazing curve (no linear impact at any frequency); ``omega_low`` NaN when
        ``F > 1`` (the response reaches the stop at every ``omega < omega_high``, down
        to the static limit).

    Raises
    ------
    ParameterError
        If ``F`` or ``zeta`` is negative.

    Examples
    --------
    >>> import numpy as np
    >>> lo, hi = grazing_omegas(0.2, 0.05)
    >>> bool(np.isclose(lo, 0.9065, atol=1e-4)), bool(np.isclose(hi, 1.0809, atol=1e-4))
    (True, True)
    """
    F_a = _nonneg_or_nan("F", F)
    z = _nonneg_or_nan("zeta", zeta)
    # Eq. (3.4) squared, as a quadratic in u = omega^2
    half_b = 1.0 - 2.0 * z**2
    disc = F_a**2 - 4.0 * z**2 * (1.0 - z**2)
    # At the minimum of the curve (a double root) rounding can make disc ~ -1e-18:
    # a discriminant within a few ulp of the terms it is made of counts as zero.
    disc = np.where(np.abs(disc) <= 8.0 * np.finfo(float).eps * np.maximum(F_a**2, 4.0 * z**2), 0.0, disc)
    with np.errstate(invalid="ignore"):
        root = np.sqrt(np.where(disc >= 0, disc, np.nan))
        u_low = half_b - root
        u_high = half_b + root
        w_low = np.sqrt(np.where(u_low >= 0, u_low, np.nan))
        w_high = np.sqrt(np.where(u_high >= 0, u_high, np.nan))
    return _out(w_low), _out(w_high)


def threshold_accel_ms2(freq_hz: npt.ArrayLike, gap_m: float, f_s_hz: float, zeta: float,
                        participation: float) -> FloatOrArray:
    """Base-acceleration amplitude [m/s^2] at which linear theory predicts the first impact.

    Dimensional form of eq. 3.4 for fitting measured thresholds:
    ``A_e = h omega_s**2 F_graze(f / f_s, zeta) / (Q1/Q2)``, from ``F = (Q1/Q2) A_e /
    (omega_s**2 h)`` (eq. 2.27, 2.31) and ``omega = f / f_s`` (eq. 2.28).

    Parameters
    ----------
    freq_hz : float or array
        Excitation frequency [Hz], >= 0.
    gap_m : float
        Gap between plate and striker [m], > 0.
    f_s_hz : float
        Modal frequency [Hz], > 0.
    zeta : float
        Modal damping ratio, nondimensional, >= 0.
    participation : float
        ``Q1 / Q2`` of the mode, > 0 (sign only sets the phase; use ``abs`` if negative).

    Returns
    -------
    float or array
        Threshold acceleration amplitude [m/s^2].

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> a = threshold_accel_ms2(105.0, 1e-3, 105.0, 0.05, 1.25)
    >>> bool(np.isclose(a, 1e-3 * (2 * np.pi * 105.0)**2 * 0.1 / 1.25))
    True
    """
    f = _nonneg_or_nan("freq_hz", freq_hz)
    h = _positive("gap_m", gap_m)
    fs = _positive("f_s_hz", f_s_hz)
    z = _nonnegative("zeta", zeta)
    q = _positive("participation", participation)
    return _out(np.asarray(threshold_accel_unchecked(f, h, fs, z, q)))


def threshold_accel_unchecked(freq_hz: npt.ArrayLike, gap_m: FloatOrArray, f_s_hz: FloatOrArray,
                              zeta: FloatOrArray, participation: FloatOrArray) -> np.ndarray:
    """:func:`threshold_accel_ms2` without argument checks, for fitters (eq. 3.4, m/s^2).

    The one implementation of the dimensional eq. (3.4); ``zeta`` enters through
    ``|zeta|`` so that an optimiser's trial step to a negative value stays defined.
    """
    omega_s = 2.0 * np.pi * f_s_hz
    ratio = np.asarray(freq_hz, dtype=float) / f_s_hz
    return np.asarray(gap_m * omega_s**2 * np.asarray(grazing_F(ratio, np.abs(zeta))) / participation)


def linear_amplitude(F: npt.ArrayLike, omega: npt.ArrayLike, zeta: npt.ArrayLike) -> FloatOrArray:
    """Steady-state amplitude of the linear oscillator (eq. 4.7).

    ``x_max = F / sqrt((1 - omega**2)**2 + (2 zeta omega)**2)``, nondimensional (in units
    of the gap); ``inf`` at undamped resonance.

    Parameters
    ----------
    F : float or array
        Forcing amplitude, nondimensional, >= 0.
    omega : float or array
        Forcing frequency, nondimensional, >= 0.
    zeta : float or array
        Damping ratio, nondimensional, >= 0.

    Returns
    -------
    float or array
        ``x_max``, nondimensional.

    Raises
    ------
    ParameterError
        If an argument is negative.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(linear_amplitude(0.2, 1.0, 0.05), 2.0))
    True
    """
    F_a = _nonneg_or_nan("F", F)
    den = np.asarray(grazing_F(omega, zeta))
    with np.errstate(divide="ignore", invalid="ignore"):
        # Eq. (4.7) of the thesis
        return _out(np.asarray(F_a / den))


def linear_impact_velocity(F: npt.ArrayLike, omega: npt.ArrayLike, zeta: npt.ArrayLike) -> FloatOrArray:
    """Linear estimate of the impact velocity: the velocity at ``x = 1`` of the free response.

    The steady state ``x = x_max cos(omega tau)`` (eq. 4.8) passes the stop position with
    speed ``|v| = omega x_max |sin(omega tau)| = omega sqrt(x_max**2 - 1)`` (eq. 4.9, 4.10).

    Where ``x_max < 1`` linear theory predicts no impact and the result is NaN.  The
    thesis (after eq. 4.11) prints the impact condition as
    ``1/F < sqrt((1 + omega**2) / ((1 - omega**2)**2 + (2 zeta omega)**2))``; that is
    garbled (it would allow impact with ``x_max < 1``).  This function uses the
    physical condition ``x_max >= 1``, i.e. ``1/F <= 1/sqrt((1 - omega**2)**2 + (2 zeta omega)**2)``.
    The result is the approach speed (>= 0); eq. 4.11 carries a minus sign from
    eq. 4.9 that only fixes the direction.

    Parameters
    ----------
    F : float or array
        Forcing amplitude, nondimensional, >= 0.
    omega : float or array
        Forcing frequency, nondimensional, >= 0.
    zeta : float or array
        Damping ratio, nondimensional, >= 0.

    Returns
    -------
    float or array
        ``v_imp``, nondimensional (``dx/dtau``), NaN where no impact is predicted.

    Raises
    ------
    ParameterError
        If an argument is negative.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(linear_impact_velocity(0.2, 1.0, 0.05), np.sqrt(3.0)))
    True
    >>> bool(np.isnan(linear_impact_velocity(0.05, 1.0, 0.05)))
    True
    """
    x_max = np.asarray(linear_amplitude(F, omega, zeta))
    w = np.asarray(omega, dtype=float)
    # Eq. (4.8)-(4.10) with the condition x_max >= 1 (see the docstring); for x_max >= 0
    # (always) that is x_max**2 - 1 >= 0 also in floating point
    with np.errstate(invalid="ignore"):
        radicand = x_max**2 - 1.0
    return _out(np.asarray(_speed_or_nan(w, radicand)))


def linear_v_im_over_F(inv_F: npt.ArrayLike, omega: npt.ArrayLike, zeta: npt.ArrayLike) -> FloatOrArray:
    """Linear impact velocity over forcing, ``v_imp / F`` versus ``1/F`` (eq. 4.11, corrected).

    ``v_imp / F = omega sqrt(1 / ((1 - omega**2)**2 + (2 zeta omega)**2) - (1/F)**2)``:
    at fixed physical forcing ``F_es``, ``1/F`` is proportional to the gap and ``v_imp/F``
    to the physical velocity (eq. 4.5).  NaN where linear theory predicts no impact
    (``x_max < 1``); see :func:`linear_impact_velocity` for the deviation from the
    thesis's printed condition.

    Parameters
    ----------
    inv_F : float or array
        ``1/F``, nondimensional, > 0.
    omega : float or array
        Forcing frequency, nondimensional, >= 0.
    zeta : float or array
        Damping ratio, nondimensional, >= 0.

    Returns
    -------
    float or array
        ``v_imp / F`` (>= 0), NaN where no impact is predicted.

    Raises
    ------
    ParameterError
        If ``inv_F <= 0`` or another argument is negative.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(linear_v_im_over_F(5.0, 1.0, 0.05), np.sqrt(3.0) / 0.2))
    True
    """
    q = np.asarray(inv_F, dtype=float)
    finite_q = q[~np.isnan(q)] if q.ndim else (q if not np.isnan(q) else np.array(1.0))
    _positive("inv_F", finite_q)
    den2 = np.asarray(grazing_F(omega, zeta)) ** 2
    w = np.asarray(omega, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        radicand = 1.0 / den2 - q**2
    # Eq. (4.11) of the thesis (magnitude), impact where x_max = 1/(inv_F * den) >= 1
    return _out(np.asarray(_speed_or_nan(w, radicand)))
