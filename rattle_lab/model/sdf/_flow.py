"""Closed-form free flight of the SDF oscillator (pure, numpy-vectorised).

Between impacts the motion solves the linear equation (thesis eq. 3.1-3.2)::

    x'' + 2 zeta x' + x = F cos(theta0 + omega s)

whose solution is the particular (forced) part plus the homogeneous part::

    x_p(s) = A_c cos(theta) + A_s sin(theta),      theta = theta0 + omega s
    A_c = F (1 - omega^2) / D,   A_s = 2 zeta omega F / D,
    D = (1 - omega^2)^2 + (2 zeta omega)^2                (so A_c^2 + A_s^2 = F^2 / D)

    y(s)  = (Ec + zeta Es) y0 + Es yd0                     (homogeneous part)
    y'(s) = -Es y0 + (Ec - zeta Es) yd0

with ``Ec = exp(-zeta s) c(s)`` and ``Es = exp(-zeta s) sn(s)`` where

* zeta < 1: ``c = cos(w_d s)``, ``sn = sin(w_d s) / w_d``, ``w_d = sqrt(1 - zeta^2)``;
* zeta = 1: ``c = 1``, ``sn = s``;
* zeta > 1: ``c = cosh(mu s)``, ``sn = sinh(mu s) / mu``, ``mu = sqrt(zeta^2 - 1)``,
  evaluated as sums of the two decaying exponentials ``exp(r1 s)``,
  ``exp(r2 s)`` (``r1 = -1/(zeta + mu)``, ``r2 = -zeta - mu``) so that no
  ``cosh * exp`` overflow or cancellation occurs.

The same formulas are written once more, scalar and compiled, in
:mod:`rattle_lab.model.sdf._kernel`; the tests check the two against each other and
against mpmath at 50 digits.

The undamped resonance (zeta = 0, omega = 1, D = 0) has the secular particular
solution ``x_p = (F/2) s sin(theta)``; :func:`flow` handles it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def particular_coeffs(F: ArrayLike, omega: ArrayLike, zeta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients ``(A_c, A_s)`` of the steady forced response (nondimensional).

    ``x_p = A_c cos(theta) + A_s sin(theta)`` solves
    ``x'' + 2 zeta x' + x = F cos(theta)``, ``theta' = omega``.  Undefined (inf)
    at the undamped resonance ``zeta = 0, omega = 1``.

    Examples
    --------
    >>> import numpy as np
    >>> A_c, A_s = particular_coeffs(0.2, 1.0, 0.05)
    >>> bool(np.isclose(A_c, 0.0) and np.isclose(A_s, 2.0))
    True
    """
    F = np.asarray(F, dtype=float)
    w = np.asarray(omega, dtype=float)
    z = np.asarray(zeta, dtype=float)
    one_m_w2 = (1.0 - w) * (1.0 + w)  # exact near w = 1
    two_zw = 2.0 * z * w
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        D = one_m_w2 * one_m_w2 + two_zw * two_zw
        A_c, A_s = F * one_m_w2 / D, F * two_zw / D
        # the squares underflow to D = 0 for a tiny (e.g. subnormal-scale) damping at
        # resonance: scale by the larger term instead (the same values, no 0/0)
        tiny = (D == 0.0) & ((one_m_w2 != 0.0) | (two_zw != 0.0))
        if np.any(tiny):
            big = np.maximum(np.abs(one_m_w2), np.abs(two_zw))
            a, b = one_m_w2 / big, two_zw / big
            den = big * (a * a + b * b)
            A_c = np.where(tiny, F * a / den, A_c)
            A_s = np.where(tiny, F * b / den, A_s)
        return A_c, A_s


def homogeneous_transition(zeta: ArrayLike, s: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(Ec, Es)`` of the homogeneous flow over time ``s`` (see module docstring).

    Examples
    --------
    >>> import numpy as np
    >>> Ec, Es = homogeneous_transition(0.0, np.pi / 2)
    >>> bool(np.isclose(Ec, 0.0) and np.isclose(Es, 1.0))
    True
    """
    z = np.asarray(zeta, dtype=float)
    s = np.asarray(s, dtype=float)
    z, s = np.broadcast_arrays(z, s)
    Ec = np.empty(z.shape)
    Es = np.empty(z.shape)
    under = z < 1.0
    crit = z == 1.0
    over = z > 1.0
    if np.any(under):
        zu, su = z[under], s[under]
        wd = np.sqrt((1.0 - zu) * (1.0 + zu))
        damp = np.exp(-zu * su)
        Ec[under] = damp * np.cos(wd * su)
        Es[under] = damp * np.sin(wd * su) / wd
    if np.any(crit):
        damp = np.exp(-s[crit])
        Ec[crit] = damp
        Es[crit] = damp * s[crit]
    if np.any(over):
        zo, so = z[over], s[over]
        mu = np.sqrt((zo - 1.0) * (zo + 1.0))
        r1 = -1.0 / (zo + mu)
        e1 = np.exp(r1 * so)
        e2 = np.exp((-zo - mu) * so)
        Ec[over] = 0.5 * (e1 + e2)
        Es[over] = e1 * (-np.expm1(-2.0 * mu * so)) / (2.0 * mu)
    if Ec.ndim == 0:
        return Ec[()], Es[()]
    return Ec, Es


def particular_state(F: ArrayLike, omega: ArrayLike, zeta: ArrayLike, theta: ArrayLike,
                     s: ArrayLike = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Displacement and velocity of the particular solution at phase ``theta``.

    ``s`` (time since the flight started) matters only for the undamped
    resonance, where the particular solution is secular.
    """
    F = np.asarray(F, dtype=float)
    w = np.asarray(omega, dtype=float)
    z = np.asarray(zeta, dtype=float)
    theta = np.asarray(theta, dtype=float)
    s = np.asarray(s, dtype=float)
    resonant = (z == 0.0) & (w == 1.0)
    A_c, A_s = particular_coeffs(F, np.where(resonant, 0.5, w), z)
    c, sn = np.cos(theta), np.sin(theta)
    xp = A_c * c + A_s * sn
    vp = w * (-A_c * sn + A_s * c)
    if np.any(resonant):
        xp = np.where(resonant, 0.5 * F * s * sn, xp)
        vp = np.where(resonant, 0.5 * F * (sn + s * c), vp)
    return xp, vp


def flow(F: ArrayLike, omega: ArrayLike, zeta: ArrayLike, x0: ArrayLike, v0: ArrayLike,
         theta0: ArrayLike, s: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """State ``(x, v)`` after a free flight of duration ``s`` (no impact check).

    Parameters
    ----------
    F, omega, zeta : array_like
        Nondimensional forcing amplitude, frequency and damping ratio.
    x0, v0 : array_like
        Displacement and velocity at the start of the flight.
    theta0 : array_like
        Forcing phase at the start of the flight.
    s : array_like
        Flight duration (nondimensional time), >= 0.

    Returns
    -------
    x, v : ndarray
        Displacement and velocity at time ``s``.

    Examples
    --------
    >>> import numpy as np
    >>> x, v = flow(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, np.pi)   # free undamped half period
    >>> bool(np.isclose(x, -1.0) and np.isclose(v, 0.0, atol=1e-15))
    True
    """
    xp0, vp0 = particular_state(F, omega, zeta, theta0, 0.0)
    theta = np.asarray(theta0, dtype=float) + np.asarray(omega, dtype=float) * np.asarray(s, dtype=float)
    xp, vp = particular_state(F, omega, zeta, theta, s)
    y0 = np.asarray(x0, dtype=float) - xp0
    yd0 = np.asarray(v0, dtype=float) - vp0
    Ec, Es = homogeneous_transition(zeta, s)
    z = np.asarray(zeta, dtype=float)
    y = (Ec + z * Es) * y0 + Es * yd0
    yd = -Es * y0 + (Ec - z * Es) * yd0
    return xp + y, vp + yd
