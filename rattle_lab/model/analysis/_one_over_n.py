"""Closed-form 1/n orbits of the SDF impact oscillator (thesis 3.1-3.3), vectorised.

A 1/n orbit has one impact every ``n`` forcing periods, ``T = 2 n pi / omega``.
Put the impact at ``t = 0`` and forcing phase ``phi``; write the forced
response's state at the impact as ``x_p(0) = c1``, ``x_p'(0) = omega s1``, so
``x_p(t) = c1 cos(omega t) + s1 sin(omega t)`` is T-periodic and
``c1^2 + s1^2 = R^2 = F^2 / D``, ``D = (1 - omega^2)^2 + (2 zeta omega)^2``.

The free part ``y = x - x_p`` starts at ``u0 = (1 - c1, -e v - omega s1)`` just
after the impact (``v = v_im`` the incoming velocity) and must arrive at
``u1 = (1 - c1, v - omega s1)`` just before the next one.  With the flight's
transition matrix ``Phi = Phi(T)`` (see :mod:`._saltation`), ``Phi u0 = u1`` is
linear::

    (Phi - I) (1 - c1, -omega s1) = v w,    w = (e Es, 1 + e (Ec - zeta Es))

so ``(1 - c1, -omega s1) = v p`` with ``p = (Phi - I)^-1 w``.  Writing
``p1 = p[0]``, ``q = p[1] / omega``: ``c1 = 1 - p1 v``, ``s1 = -q v``, and the
amplitude constraint ``c1^2 + s1^2 = F^2 / D`` is the quadratic (thesis eq. 3.5)::

    a v^2 + b v + c = 0,   a = -D (p1^2 + q^2) < 0,   b = 2 D p1,
                           c = F^2 + c',   c' = -D < 0

(in the thesis's variable ``v0 = e v``: divide ``a`` by ``e^2`` and ``b`` by
``e``).  ``c = 0`` is the grazing curve ``F = sqrt(D)`` (eq. 3.4); the
discriminant vanishes at ``F_sn = sqrt(D) |q| / sqrt(p1^2 + q^2)`` (eq. 3.11),
at ``v = p1 / (p1^2 + q^2)`` (eq. 3.13), which is positive iff ``b > 0``.

Conversely every ``v`` fixes the whole orbit and the forcing that carries it:
``F(omega, v) = sqrt(D) hypot(1 - p1 v, q v)``; the bifurcation sets use this.

The monodromy matrix from just after an impact to just after the next is
``S Phi(T)`` with ``S`` the impact's saltation matrix, whose corner is
``k = (1 + e)(F cos(phi) - 1) / v`` and ``F cos(phi) = (1 - omega^2) c1 +
2 zeta omega s1`` (the equation of motion at ``t = 0``).  Hence::

    tr = -2 e Ec + k Es,    det = e^2 exp(-2 zeta T)

Multipliers are the roots of ``lambda^2 - tr lambda + det``; ``P(1) = 1 - tr +
det`` vanishes when one multiplier is +1 (saddle-node), ``P(-1) = 1 + tr + det``
when one is -1 (period doubling).  With ``0 <= det < 1`` the orbit is stable
iff ``P(1) > 0`` and ``P(-1) > 0``; complex multipliers have modulus
``sqrt(det) < 1``, so no Neimark-Sacker bifurcation occurs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab.model.sdf import homogeneous_transition
from . import _motion


@dataclass(frozen=True)
class Family:
    """``(n, omega)``-dependent coefficients of the 1/n orbit family (arrays; nondimensional).

    Attributes
    ----------
    n : int
        Forcing periods per impact.
    omega, zeta, e : ndarray
        Frequency, damping ratio and restitution, broadcast together.
    T : ndarray
        Orbit period ``2 n pi / omega``.
    Ec, Es : ndarray
        Free-flight transition entries over ``T``.
    p1, q : ndarray
        ``x_p(0) = 1 - p1 v``, ``x_p'(0) / omega = -q v`` on the family.
    D : ndarray
        ``(1 - omega^2)^2 + (2 zeta omega)^2``.
    """

    n: int
    omega: np.ndarray
    zeta: np.ndarray
    e: np.ndarray
    T: np.ndarray
    Ec: np.ndarray
    Es: np.ndarray
    p1: np.ndarray
    q: np.ndarray
    D: np.ndarray


def family(n: int, omega: ArrayLike, zeta: ArrayLike, e: ArrayLike) -> Family:
    """The coefficients of the 1/n family at ``omega`` (module docstring)."""
    w, z, ee = np.broadcast_arrays(*(np.asarray(q, dtype=float) for q in (omega, zeta, e)))
    T = 2.0 * math.pi * n / w
    Ec, Es = homogeneous_transition(z, T)
    Ec, Es = np.asarray(Ec), np.asarray(Es)
    m11 = Ec + z * Es - 1.0
    m12 = Es
    m21 = -Es
    m22 = Ec - z * Es - 1.0
    w1 = ee * Es
    w2 = 1.0 + ee * (Ec - z * Es)
    with np.errstate(divide="ignore", invalid="ignore"):
        det = m11 * m22 - m12 * m21
        p1 = (m22 * w1 - m12 * w2) / det
        p2 = (m11 * w2 - m21 * w1) / det
        q = p2 / w
    one_m_w2 = (1.0 - w) * (1.0 + w)
    D = one_m_w2 ** 2 + (2.0 * z * w) ** 2
    return Family(n, w, z, ee, T, Ec, Es, p1, q, D)


def quadratic(fam: Family) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(a, b, c')`` of eq. (3.5) in the variable ``v_im`` (``c = F^2 + c'``)."""
    return -fam.D * (fam.p1 ** 2 + fam.q ** 2), 2.0 * fam.D * fam.p1, -fam.D


def roots(fam: Family, F: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(v_lo, v_hi)``: the smaller and larger real root of eq. (3.5); NaN where complex.

    The root of larger magnitude comes from the quadratic formula and the
    other from the product of roots, so neither suffers cancellation.
    """
    F = np.asarray(F, dtype=float)
    A = fam.p1 ** 2 + fam.q ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        R2 = F * F / fam.D
        disc = A * R2 - fam.q ** 2
        sq = np.sqrt(np.where(disc >= 0.0, disc, np.nan))
        big = (fam.p1 + np.copysign(sq, fam.p1)) / A
        small = (1.0 - R2) / (A * big)
        small = np.where(big == 0.0, fam.p1 / A, small)
    lo = np.where(fam.p1 >= 0.0, small, big)
    hi = np.where(fam.p1 >= 0.0, big, small)
    return lo, hi


def discriminant(fam: Family, F: ArrayLike) -> np.ndarray:
    """``(p1^2 + q^2) F^2 / D - q^2``: the discriminant of eq. (3.5) over ``4 D^2``."""
    F = np.asarray(F, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (fam.p1 ** 2 + fam.q ** 2) * F * F / fam.D - fam.q ** 2


def forced_state(fam: Family, v: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(c1, s1)``: the forced response at the impact, ``x_p(0)``, ``x_p'(0) / omega``."""
    v = np.asarray(v, dtype=float)
    return 1.0 - fam.p1 * v, -fam.q * v


def forcing(fam: Family, v: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(F, phase)`` for which ``v`` is the impact velocity of a 1/n orbit.

    ``x_p = R cos(theta - psi)`` with ``psi = atan2(2 zeta omega, 1 - omega^2)``;
    at the impact ``c1 = R cos(phi - psi)``, ``s1 = -R sin(phi - psi)``.
    """
    c1, s1 = forced_state(fam, v)
    F = np.sqrt(fam.D) * np.hypot(c1, s1)
    psi = np.arctan2(2.0 * fam.zeta * fam.omega, (1.0 - fam.omega) * (1.0 + fam.omega))
    phase = np.mod(psi + np.arctan2(-s1, c1), 2.0 * math.pi)
    return F, phase


def trace_det(fam: Family, v: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Trace and determinant of the monodromy ``S Phi(T)`` (module docstring)."""
    v = np.asarray(v, dtype=float)
    c1, s1 = forced_state(fam, v)
    f_cos = (1.0 - fam.omega) * (1.0 + fam.omega) * c1 + 2.0 * fam.zeta * fam.omega * s1
    with np.errstate(divide="ignore", invalid="ignore"):
        k = (1.0 + fam.e) * (f_cos - 1.0) / v
    tr = -2.0 * fam.e * fam.Ec + k * fam.Es
    det = fam.e ** 2 * np.exp(-2.0 * fam.zeta * fam.T)
    return tr, np.broadcast_to(det, np.shape(tr))


def monodromy(fam: Family, v: ArrayLike) -> np.ndarray:
    """The monodromy matrix ``S Phi(T)`` itself, shape ``(..., 2, 2)``."""
    from ._saltation import impact_saltation, transition_matrix

    v = np.asarray(v, dtype=float)
    c1, s1 = forced_state(fam, v)
    f_cos = (1.0 - fam.omega) * (1.0 + fam.omega) * c1 + 2.0 * fam.zeta * fam.omega * s1
    # impact_saltation wants F and theta; only F cos(theta) enters, so pass (f_cos, 0).
    S = impact_saltation(f_cos, fam.zeta, fam.e, 0.0, v)
    return S @ transition_matrix(fam.zeta, fam.T)


def multipliers(tr: np.ndarray, det: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roots of ``lambda^2 - tr lambda + det``, larger modulus first (complex arrays)."""
    tr = np.asarray(tr, dtype=complex)
    sq = np.sqrt(tr * tr / 4.0 - det)
    l1, l2 = tr / 2.0 + sq, tr / 2.0 - sq
    swap = np.abs(l2) > np.abs(l1)
    return np.where(swap, l2, l1), np.where(swap, l1, l2)


def flights_of(fam: Family, v: ArrayLike) -> _motion.Flights:
    """The free flight from just after the impact, ``t`` in ``[0, T]``."""
    v = np.asarray(v, dtype=float)
    c1, s1 = forced_state(fam, v)
    y0 = fam.p1 * v
    yd0 = -fam.e * v - fam.omega * s1
    return _motion.flights(fam.omega, fam.zeta, c1, s1, y0, yd0)


def clearance(fam: Family, v: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(1 - x_max, t_max)`` over the interior local maxima of ``x`` on ``(0, T)``.

    ``+inf`` (and NaN time) where ``x`` has no interior local maximum, NaN
    where ``v`` is not finite.  The thesis's ``r`` (eq. 3.15) is ``-clearance``.
    """
    v = np.asarray(v, dtype=float)
    shape = np.broadcast(fam.omega, v).shape
    v_b = np.broadcast_to(v, shape)
    fam_b = Family(fam.n, *(np.broadcast_to(getattr(fam, f), shape) for f in
                            ("omega", "zeta", "e", "T", "Ec", "Es", "p1", "q", "D")))
    ok = np.isfinite(v_b)
    out = np.full(shape, np.nan)
    t_out = np.full(shape, np.nan)
    if np.any(ok):
        sub = Family(fam.n, *(getattr(fam_b, f)[ok] for f in
                              ("omega", "zeta", "e", "T", "Ec", "Es", "p1", "q", "D")))
        x_max, t_max = _motion.interior_maxima(flights_of(sub, v_b[ok]), sub.T)
        out[ok] = 1.0 - x_max
        t_out[ok] = t_max
    return out, t_out
