"""Exact event location on exponential sums (compiled with numba).

Every quantity the modal impact model watches for an event, between two events,
is an *exponential sum*::

    h(s) = c0 + Re sum_j a_j exp(lam_j s),        Re lam_j <= 0,

with complex ``a_j`` and ``lam_j``: the contact-point gap in free flight (each
mode a damped oscillator, ``lam = -zeta omega + i omega_d``, plus the harmonic
forcing, ``lam = i Omega``), the Kelvin-Voigt contact force during contact
(eigenvalues of the coupled linear system) and the contact force while the
plate sticks to the striker.  This module finds the earliest ``s`` where such
a sum reaches zero, to rounding, with a guarantee that no touch is missed.

Why no touch is missed
    On ``[s_a, s_b]`` every derivative is bounded:
    ``|h^(k)(s)| <= M_k = sum_j |a_j| |lam_j|**k exp(Re(lam_j) s_a)``
    (each term decays, ``Re lam <= 0``).  ``h`` then lies below both parabolas
    ``h(s_a) + h'(s_a) u + M_2 u**2 / 2`` and ``h(s_b) - h'(s_b) w + M_2 w**2 / 2``;
    the maximum of their lower envelope is found in closed form (the two differ
    by a linear function).  If it is below ``-tol`` the interval is clear.
    Otherwise ``M_3`` bounds the curvature: where ``h`` is provably concave there
    is at most one maximum, found as the bracketed root of ``h'``; where it is
    provably convex the maximum is at an end.  Otherwise the interval is halved,
    leftmost first, so the first touch is the earliest.  A maximum within
    ``tol`` below zero is a grazing touch (the distinction is below the rounding
    of ``h``).  A crossing is located by a bracketed, safeguarded Newton
    iteration down to adjacent floats.  Sign sampling is never relied on.
"""

from __future__ import annotations

import math

import numba
import numpy as np

EPS = 2.220446049250313e-16
#: Halving depth below which an undecided interval is settled by its end values.
MAX_DEPTH = 80

# Result kinds of :func:`first_touch`.
NONE = 0
CROSSING = 1
GRAZE = 2


@numba.njit(cache=True, nogil=True)
def value(a, lam, c0, s, k):
    """``h^(k)(s)`` (``c0`` counts for k = 0 only)."""
    acc = c0 if k == 0 else 0.0
    for j in range(a.size):
        z = lam[j]
        e = math.exp(z.real * s)
        ph = z.imag * s
        w = a[j] * complex(e * math.cos(ph), e * math.sin(ph))
        for _ in range(k):
            w = w * z
        acc += w.real
    return acc


@numba.njit(cache=True, nogil=True)
def bound(a, lam, s, k):
    """``M_k >= |h^(k)(u)|`` for every ``u >= s``."""
    acc = 0.0
    for j in range(a.size):
        z = lam[j]
        acc += abs(a[j]) * abs(z) ** k * math.exp(min(z.real, 0.0) * s)
    return acc * (1.0 + 1e-12)


@numba.njit(cache=True, nogil=True)
def _solve(a, lam, c0, k, lo, hi, sign):
    """Root of ``sign * h^(k)`` in ``[lo, hi]`` with ``sign * h^(k)(lo) < 0 <= sign * h^(k)(hi)``.

    Safeguarded Newton (bisection whenever Newton leaves the bracket or stalls),
    down to adjacent floats; returns the right end of the final bracket, the
    first float where the sign has changed.
    """
    flo = sign * value(a, lam, c0, lo, k)
    fhi = sign * value(a, lam, c0, hi, k)
    x = hi if -flo > fhi else lo
    fx = fhi if x == hi else flo
    for _ in range(400):
        if hi - lo <= 2.0 * EPS * max(abs(lo), abs(hi), 1e-300):
            break
        d = sign * value(a, lam, c0, x, k + 1)
        newton_ok = False
        if d != 0.0:
            xn = x - fx / d
            if lo < xn < hi:
                newton_ok = True
        if not newton_ok:
            xn = 0.5 * (lo + hi)
        width = hi - lo
        fn = sign * value(a, lam, c0, xn, k)
        if fn >= 0.0:
            hi, fhi = xn, fn
        else:
            lo, flo = xn, fn
        x, fx = xn, fn
        if hi - lo > 0.5 * width and newton_ok:
            # Newton did not halve the bracket: bisect once.
            xm = 0.5 * (lo + hi)
            fm = sign * value(a, lam, c0, xm, k)
            if fm >= 0.0:
                hi, fhi = xm, fm
            else:
                lo, flo = xm, fm
            x, fx = xm, fm
        if fhi == 0.0:
            break
    return hi


@numba.njit(cache=True, nogil=True)
def _envelope_max(ha, da, hb, db, m2, length):
    """Max over [0, L] of min(ha + da u + m2 u^2/2, hb - db (L-u) + m2 (L-u)^2/2)."""
    def pa(u):
        return ha + da * u + 0.5 * m2 * u * u

    def pb(u):
        w = length - u
        return hb - db * w + 0.5 * m2 * w * w

    best = max(min(ha, pb(0.0)), min(pa(length), hb))
    # pa - pb is linear in u: slope da - db + m2 L ... solve pa(u) = pb(u)
    slope = da - db + m2 * length
    c = ha - (hb - db * length + 0.5 * m2 * length * length)
    if slope != 0.0:
        u = -c / slope
        if 0.0 < u < length:
            best = max(best, min(pa(u), pb(u)))
    return best


@numba.njit(cache=True, nogil=True)
def start_exclusion(a, lam, c0, s0, s_max):
    """First ``s > s0`` from which the search may start when ``h(s0)`` is ~0 on the stop.

    Uses the leading derivative ``d_k`` (k = 1, 2, 3) that is negative and not
    rounding-small: ``h(s0 + u) <= h(s0) + d_k u**k / k! + M_(k+1) u**(k+1) / (k+1)! < 0``
    for ``u < (k+1) |d_k| / M_(k+1) / 2`` (h(s0) treated as zero).  Returns
    ``s0`` when no derivative is usable (the caller then treats the start as a
    touch).
    """
    fact = 1.0
    for k in range(1, 4):
        fact *= k
        dk = value(a, lam, c0, s0, k)
        mk = bound(a, lam, s0, k)
        if abs(dk) <= 1e3 * EPS * mk:
            continue
        if dk > 0.0:
            return s0
        mk1 = bound(a, lam, s0, k + 1)
        if mk1 <= 0.0:
            return s_max
        u = 0.5 * (k + 1) * abs(dk) / mk1
        return min(s0 + u, s_max)
    return s0


@numba.njit(cache=True, nogil=True)
def first_touch(a, lam, c0, s_lo, s_hi, tol):
    """Earliest ``s`` in ``[s_lo, s_hi]`` where ``h(s) >= 0`` or ``h`` has a maximum >= -tol.

    Requires ``h(s_lo) < 0``.  Returns ``(kind, s, n_intervals)``: kind 0 (none),
    1 (crossing at the first float where ``h >= 0``), 2 (graze: a local maximum
    in ``[-tol, 0)`` at ``s``).
    """
    stack_a = np.empty(MAX_DEPTH + 2)
    stack_b = np.empty(MAX_DEPTH + 2)
    stack_d = np.empty(MAX_DEPTH + 2, dtype=np.int64)
    n = 0
    stack_a[0] = s_lo
    stack_b[0] = s_hi
    stack_d[0] = 0
    n = 1
    work = 0
    while n > 0:
        n -= 1
        sa = stack_a[n]
        sb = stack_b[n]
        depth = stack_d[n]
        work += 1
        length = sb - sa
        ha = value(a, lam, c0, sa, 0)
        if ha >= 0.0:
            return CROSSING, sa, work
        hb = value(a, lam, c0, sb, 0)
        da = value(a, lam, c0, sa, 1)
        db = value(a, lam, c0, sb, 1)
        m2 = bound(a, lam, sa, 2)
        if _envelope_max(ha, da, hb, db, m2, length) < -tol:
            continue
        m3 = bound(a, lam, sa, 3)
        ca = value(a, lam, c0, sa, 2)
        cb = value(a, lam, c0, sb, 2)
        # h''(sa + u) lies between max(ca - m3 u, cb - m3 (L - u)) and min(ca + m3 u, cb + m3 (L - u)).
        if m3 > 0.0:
            u = min(max((cb - ca + m3 * length) / (2.0 * m3), 0.0), length)
            curv_max = min(ca + m3 * u, cb + m3 * (length - u))
            u = min(max((ca - cb + m3 * length) / (2.0 * m3), 0.0), length)
            curv_min = max(ca - m3 * u, cb - m3 * (length - u))
        else:
            curv_max = max(ca, cb)
            curv_min = min(ca, cb)
        if curv_max < 0.0:  # concave: at most one maximum
            if hb >= 0.0:
                return CROSSING, _solve(a, lam, c0, 0, sa, sb, 1.0), work
            if da <= 0.0 or db >= 0.0:
                continue  # maximum at an end, below zero; the next interval goes on
            sm = _solve(a, lam, c0, 1, sa, sb, -1.0)
            hm = value(a, lam, c0, sm, 0)
            if hm >= 0.0:
                return CROSSING, _solve(a, lam, c0, 0, sa, sm, 1.0), work
            if hm >= -tol:
                return GRAZE, sm, work
            continue
        if curv_min > 0.0:  # convex: the maximum is at an end
            if hb >= 0.0:
                return CROSSING, _solve(a, lam, c0, 0, sa, sb, 1.0), work
            continue
        if depth >= MAX_DEPTH or length <= 4.0 * EPS * max(abs(sa), abs(sb)):
            if hb >= 0.0:
                return CROSSING, sb, work
            if hb >= -tol and db >= 0.0:
                return GRAZE, sb, work
            continue
        mid = 0.5 * (sa + sb)
        stack_a[n] = mid
        stack_b[n] = sb
        stack_d[n] = depth + 1
        stack_a[n + 1] = sa
        stack_b[n + 1] = mid
        stack_d[n + 1] = depth + 1
        n += 2
    return NONE, s_hi, work
