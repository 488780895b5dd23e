"""The kernel's rigorous search for the first reach of a level, and its root finder.

A flight's window is cut into chunks (:func:`first_reach`); each chunk is settled
by derivative bounds or halved (:func:`_search_chunk`), and a bracketed root is
found by safeguarded Newton/Halley steps (:func:`_root`).  See "Why no impact can
be missed" in the package docstring.
"""

import math

import numpy as np

from ._constants import (EPS, GRAZE_TOL, I_R, I_RES, I_Z, J_ONSTOP, J_Y, J_YD, MAX_LEVEL,
                         MAX_WORK, TWO_PI)
from ._flight import deriv_bound, level_values, level_values_called
from ._jit import jit, jit_inline


@jit
def _max_min_parabolas(ga, gva, gb, gvb, M, L):
    """max over [0, L] of min(ga + gva u + M u^2/2, gb - gvb (L-u) + M (L-u)^2/2)."""
    best = max(ga, gb)
    coef = gva - gvb + M * L
    const = ga - gb + gvb * L - 0.5 * M * L * L
    if coef != 0.0:
        u = -const / coef
        if 0.0 < u < L:
            p1 = ga + gva * u + 0.5 * M * u * u
            if p1 > best:
                best = p1
    return best


@jit
def _lower_line_bound(fa, fb, M, L):
    """min over [0, L] of max(fa - M u, fb - M (L - u)): a lower bound of f."""
    u = (fa - fb + M * L) / (2.0 * M)
    if u <= 0.0:
        return fb - M * L
    if u >= L:
        return fa - M * L
    return fa - M * u


@jit
def _upper_line_bound(fa, fb, M, L):
    """max over [0, L] of min(fa + M u, fb + M (L - u)): an upper bound of f."""
    return -_lower_line_bound(-fa, -fb, M, L)


@jit
def _shrink_bracket(s, f, lo, hi):
    """Narrow the sign bracket (lo, hi) of f, f(lo) < 0 <= f(hi), to the side of s that keeps it.

    Parameters
    ----------
    s : float
        A point inside the bracket, nondimensional time.
    f : float
        The function value there.
    lo, hi : float
        The bracket.

    Returns
    -------
    lo, hi : float
        The narrower bracket: ``hi = s`` where ``f >= 0``, else ``lo = s``.
    """
    if f >= 0.0:
        return lo, s
    return s, hi


@jit
def _safeguard_newton(s, sn, lo, hi):
    """Keep a Newton iterate inside the bracket (lo, hi), falling back to bisection.

    Parameters
    ----------
    s : float
        The current iterate, nondimensional time.
    sn : float
        The proposed next iterate.
    lo, hi : float
        The current bracket.

    Returns
    -------
    s_next : float
        ``sn`` if it lies strictly inside the bracket and moves, else the midpoint.
    converged : bool
        True when Newton has stalled and the midpoint is an end of the bracket
        (the bracket is two neighbouring floats): the caller stops iterating.
    """
    if not (lo < sn < hi):
        sn = 0.5 * (lo + hi)
    if sn == s:
        # Newton has converged: finish with the neighbouring float towards the bracket.
        sn = 0.5 * (lo + hi)
        if sn == lo or sn == hi:
            return sn, True
    return sn, False


@jit
def _halley_step(s, f, fp, fpp):
    """Halley's step from s (Newton's where Halley's denominator is small); -1 if fp <= 0."""
    if not fp > 0.0:
        return -1.0
    den = 2.0 * fp * fp - f * fpp
    if den > 0.5 * fp * fp:
        return s - 2.0 * f * fp / den
    return s - f / fp


@jit
def _root(P, S, c, sig, which, lo, hi, flo, fhi, dlo, dhi, d2lo, d2hi):
    """Bracketed root of f on [lo, hi] with f(lo) < 0 <= f(hi); f', f'' there.

    which = 0: f = g (returns the smallest point found with g >= 0);
    which = 1: f = -g' (critical point of g, a maximum).
    Safeguarded Newton with bisection fallback; converges to rounding.  The first
    iterate is the Newton step from the end where |f| is smaller, if it falls inside
    the bracket, else the secant.
    """
    if fhi == 0.0:
        return hi
    s = -1.0
    if -flo < fhi:
        s = _halley_step(lo, flo, dlo, d2lo)
    else:
        s = _halley_step(hi, fhi, dhi, d2hi)
    if not (lo < s < hi):
        den = fhi - flo
        s = hi - fhi * ((hi - lo) / den) if den > 0.0 else 0.5 * (lo + hi)
    if not (lo < s < hi):
        s = 0.5 * (lo + hi)
    width_old = hi - lo
    f_old = math.inf
    probe = 0.0  # length of the last probe from an end of the bracket (0: none)
    for it in range(200):
        g, gv, ga, y, yd = level_values(P, S, s, c, sig)
        if which == 0:
            f = g
            fp = gv
        else:
            f = -gv
            fp = -ga
        if f == 0.0:
            return s
        lo, hi = _shrink_bracket(s, f, lo, hi)
        tol = 2.0 * EPS * max(abs(lo), abs(hi), 1e-300)
        if hi - lo <= tol:
            break
        if which == 0 and fp != 0.0:
            # Halley's step (g'' comes with g and g' at no cost): cubic convergence
            den2 = 2.0 * fp * fp - f * ga
            sn = s - 2.0 * f * fp / den2 if den2 > 0.5 * fp * fp else s - f / fp
        else:
            sn = s - f / fp if fp != 0.0 else 0.5 * (lo + hi)
        # Newton has converged onto one end of the bracket (a step within rounding, to
        # that end or past it): the root is within rounding of that end, so probe just
        # inside it, doubling the probe while the sign stays, instead of halving the
        # whole bracket from the far side (which took ~25 evaluations where one Newton
        # sequence had converged from one side).
        if abs(sn - s) <= 4.0 * tol and (sn <= lo + tol or sn >= hi - tol):
            probe = tol if probe == 0.0 else 2.0 * probe
            sn = lo + probe if f < 0.0 else hi - probe
        else:
            probe = 0.0
            # every third step: bisect if neither the bracket halved nor |f| fell 4-fold
            # (a Newton sequence converging from one side shrinks |f|, not the bracket)
            if it % 3 == 2 and hi - lo > 0.5 * width_old and not abs(f) < 0.25 * f_old:
                sn = 0.5 * (lo + hi)
        if it % 3 == 2:
            width_old = hi - lo
            f_old = abs(f)
        s, converged = _safeguard_newton(s, sn, lo, hi)
        if converged:
            break
    return hi


@jit_inline
def _push_chunk(stk, n, sa, sb, ga, gva, gaa, ya, yda, gb, gvb, gab, level):
    """Write the sub-interval [sa, sb] of a search chunk into row n of the stack.

    Parameters
    ----------
    stk : ndarray, shape (MAX_LEVEL + 4, 12)
        The work stack of :func:`_search_chunk`.
    n : int
        The row to write.
    sa, sb : float
        Ends of the sub-interval, nondimensional local time.
    ga, gva, gaa, ya, yda : float
        ``g, g', g''`` and the homogeneous state ``(y, y')`` at ``sa``.
    gb, gvb, gab : float
        ``g, g', g''`` at ``sb``.
    level : float
        Number of halvings that made the sub-interval.
    """
    stk[n, 0] = sa
    stk[n, 1] = sb
    stk[n, 2] = ga
    stk[n, 3] = gva
    stk[n, 4] = gaa
    stk[n, 5] = ya
    stk[n, 6] = yda
    stk[n, 7] = gb
    stk[n, 8] = gvb
    stk[n, 9] = gab
    stk[n, 10] = level


@jit_inline
def _search_chunk(P, S, c, sig, sa, sb, va, out_b, diag, stk):
    """Earliest s in (sa, sb] with g(s) >= 0, or -1.  va = values at sa (g < 0).

    out_b receives the values at sb (g, g', g'', y, yd) for the next chunk.
    At most MAX_WORK sub-intervals are examined; past that the chunk is
    settled at the current resolution and diag[0] counts it (reported to the
    caller as a NumericalWarning).  ``stk`` is the work stack (at least
    ``MAX_LEVEL + 4`` rows of 12), allocated once per run by the caller.
    """
    work = 0
    graze = c == 1.0
    gtol = GRAZE_TOL if graze else 0.0
    gb, gvb, gab, yb, ydb = level_values(P, S, sb, c, sig)
    out_b[0] = gb
    out_b[1] = gvb
    out_b[2] = gab
    out_b[3] = yb
    out_b[4] = ydb
    _push_chunk(stk, 0, sa, sb, va[0], va[1], va[2], va[3], va[4], gb, gvb, gab, 0.0)
    n = 1
    while n > 0:
        n -= 1
        a0 = stk[n, 0]
        b0 = stk[n, 1]
        ga = stk[n, 2]
        gva = stk[n, 3]
        gaa = stk[n, 4]
        ya = stk[n, 5]
        yda = stk[n, 6]
        gbb = stk[n, 7]
        gvbb = stk[n, 8]
        gabb = stk[n, 9]
        level = stk[n, 10]
        L = b0 - a0
        xa = c + sig * ga
        vxa = sig * gva
        M2 = deriv_bound(P, 2, ya, yda, b0, xa, vxa, L)
        tiny = L <= 4.0 * EPS * max(abs(b0), 1e-300) or level >= MAX_LEVEL
        work += 1
        if work > MAX_WORK:
            if work == MAX_WORK + 1:
                diag[0] += 1.0
            tiny = True
        if gbb >= 0.0:
            # a root lies in (a0, b0]; find the earliest one
            if _lower_line_bound(gva, gvbb, M2, L) > 0.0 or tiny:
                return _root(P, S, c, sig, 0, a0, b0, ga, gbb, gva, gvbb, gaa, gabb)
            M3 = deriv_bound(P, 3, ya, yda, b0, xa, vxa, L)  # only where M2 did not settle it
            uba = _upper_line_bound(gaa, gabb, M3, L)
            lba = _lower_line_bound(gaa, gabb, M3, L)
            if lba > 0.0:  # convex: a single crossing
                return _root(P, S, c, sig, 0, a0, b0, ga, gbb, gva, gvbb, gaa, gabb)
            if uba < 0.0:  # concave: rises to one maximum then falls
                if gvbb >= 0.0 or gva <= 0.0:
                    return _root(P, S, c, sig, 0, a0, b0, ga, gbb, gva, gvbb, gaa, gabb)
                sc = _root(P, S, c, sig, 1, a0, b0, -gva, -gvbb, -gaa, -gabb, 0.0, 0.0)
                gc, gvc, gac, yc, ydc = level_values_called(P, S, sc, c, sig)
                if gc >= 0.0:
                    return _root(P, S, c, sig, 0, a0, sc, ga, gc, gva, gvc, gaa, gac)
                return _root(P, S, c, sig, 0, a0, b0, ga, gbb, gva, gvbb, gaa, gabb)
        else:
            if graze and gbb >= -GRAZE_TOL and gvbb >= 0.0:
                return b0  # touches the stop (within rounding) at the chunk end
            if _max_min_parabolas(ga, gva, gbb, gvbb, M2, L) < -gtol:
                continue
            M3 = deriv_bound(P, 3, ya, yda, b0, xa, vxa, L)
            uba = _upper_line_bound(gaa, gabb, M3, L)
            lba = _lower_line_bound(gaa, gabb, M3, L)
            if lba > 0.0:
                continue  # convex: the maximum is at an end, both ends < 0
            if uba < 0.0:
                if gva <= 0.0 or gvbb >= 0.0:
                    continue  # monotone: the maximum is at an end
                sc = _root(P, S, c, sig, 1, a0, b0, -gva, -gvbb, -gaa, -gabb, 0.0, 0.0)
                gc, gvc, gac, yc, ydc = level_values_called(P, S, sc, c, sig)
                if gc >= 0.0:
                    return _root(P, S, c, sig, 0, a0, sc, ga, gc, gva, gvc, gaa, gac)
                if gc >= -gtol:
                    return sc  # grazing contact: the maximum touches the stop
                continue
            if tiny:
                continue  # degenerate (g, g', g'' all ~0): below resolution
        # split
        m = 0.5 * (a0 + b0)
        gm, gvm, gam, ym, ydm = level_values(P, S, m, c, sig)
        # right half first (processed last)
        _push_chunk(stk, n, m, b0, gm, gvm, gam, ym, ydm, gbb, gvbb, gabb, level + 1.0)
        if gm >= 0.0:
            n -= 1  # the root is in the left half; the right half is never needed
        n += 1
        _push_chunk(stk, n, a0, m, ga, gva, gaa, ya, yda, gm, gvm, gam, level + 1.0)
        n += 1
    return -1.0


@jit
def new_work():
    """Scratch for :func:`first_reach`: the search stack and two rows of values."""
    return np.empty((MAX_LEVEL + 6, 12))


@jit_inline
def below_stop_for_ever(P, S, y, yd):
    """Whether the flight of ``S`` provably stays below the stop from a point where its
    homogeneous state is ``(y, yd)``, by more than the grazing tolerance.

    ``x = x_p + y`` with ``|x_p| <= R`` (the particular part's amplitude) and
    ``d/ds (y^2 + y'^2) = -4 zeta y'^2 <= 0``: ``x <= R + |(y, yd)|`` from there on.
    The evaluations the search would make are the exact flight to rounding: with
    ``|Ec| <= 1`` and ``|Es| <= s <= 2 pi`` (a window), their error is a few ulp of
    ``1 + 2 R + (2 + 2 pi (1 + 2 zeta)) (|y0| + |yd0| + |(y, yd)|)``; 64 ulp of it are
    kept as margin.  So where this holds the search finds nothing, not even a grazing
    contact (``g >= -GRAZE_TOL``), and need not look.  Not for the undamped resonance
    (secular particular part) or a flight from the stop (``x`` starts at 1).
    """
    if P[I_RES] != 0.0 or S[J_ONSTOP] != 0.0:
        return False
    R = P[I_R]
    rho = math.sqrt(y * y + yd * yd)
    scale = 1.0 + 2.0 * R + (2.0 + TWO_PI * (1.0 + 2.0 * P[I_Z])) * (
        abs(S[J_Y]) + abs(S[J_YD]) + rho)
    return R + rho + 64.0 * EPS * scale < 1.0 - GRAZE_TOL


@jit
def first_reach(P, S, c, sig, s_lo, s_hi, hmax, diag, work):
    """Earliest s in (s_lo, s_hi] where sig (x(s) - c) >= 0, or -1.

    Requires sig (x(s_lo) - c) < 0, and ``s_hi - s_lo <= 2 pi`` (a window).  ``work``
    is scratch of shape ``(MAX_LEVEL + 6, 12)`` (see :func:`new_work`), allocated once
    per run: no allocation per search.  The stop (``c = 1, sig = 1``) is not searched
    for where the flight provably stays below it (:func:`below_stop_for_ever`; the
    steady motion of a sweep's values without impact): the search would find nothing.
    """
    va = work[MAX_LEVEL + 4]
    vb = work[MAX_LEVEL + 5]
    g, gv, ga, y, yd = level_values(P, S, s_lo, c, sig)
    if c == 1.0 and sig == 1.0 and below_stop_for_ever(P, S, y, yd):
        return -1.0
    va[0] = g
    va[1] = gv
    va[2] = ga
    va[3] = y
    va[4] = yd
    sa = s_lo
    while sa < s_hi:
        sb = min(sa + hmax, s_hi)
        if s_hi - sb < 0.25 * hmax:
            sb = s_hi
        r = _search_chunk(P, S, c, sig, sa, sb, va, vb, diag, work)
        if r >= 0.0:
            return r
        for i in range(5):
            va[i] = vb[i]
        sa = sb
    return -1.0

