"""The kernel on and near the stop: leaving it, micro-flights, elastic micro-bouncing.

See "Impacts on and from the stop" and "Chatter and sticking" in the package
docstring.
"""

import math

from ._constants import EPS, I_F, I_LAM, J_TAY, J_Y, J_YD, N_TAYLOR, TAU_EXIT, TAYLOR_REACH, TWO_PI
from ._flight import deriv_bound, level_values_called
from ._jit import jit
from ._search import _safeguard_newton, _shrink_bracket


@jit
def micro_flight(P, S, s_hi):
    """Next impact of a short flight from the stop, from its Taylor series; -1 if
    the fast path does not apply.

    On the stop, ``x - 1 = s p(s)`` with ``p(s) = sum_k t_k s^(k-1)``.  When the
    mass leaves (``t_1 = v < 0``) against a push (``t_2 = a / 2 > 0``), the flight
    is short and ``p`` is provably increasing on ``[0, s_max]`` if
    ``t_2 - sum_{k>=3} (k-1) |t_k| s_max^(k-2) > 0``; then ``p`` has exactly one
    root in ``(0, s_max)`` when ``p(s_max) > 0``, ``x < 1`` before it, and it is
    the next impact.  This resolves chatter flights to relative rounding at a
    fraction of the cost of the general search.
    """
    t1 = S[J_TAY + 1]
    t2 = S[J_TAY + 2]
    if not (t1 < 0.0 and t2 > 0.0):
        return -1.0
    s_max = -2.0 * t1 / t2
    if s_max * P[I_LAM] > TAYLOR_REACH or s_max >= s_hi:
        return -1.0
    lb = t2
    sk = 1.0
    # The Newton iteration below sums the series only up to the last term that can
    # still reach the rounding of p: |t_k| s^(k-1) > 2^-80 |t_1| on [0, s_max]
    # (a term below that is 2^-27 of an ulp of t_1, the size of p's terms at the root).
    thr = 2.0 ** -80 * abs(t1)
    n_use = 2
    for k in range(3, N_TAYLOR + 1):
        sk *= s_max
        term = abs(S[J_TAY + k]) * sk
        lb -= (k - 1) * term
        if term * s_max > thr:
            n_use = k
    if lb <= 0.25 * t2:
        return -1.0
    ph = 0.0
    for k in range(N_TAYLOR, 0, -1):
        ph = ph * s_max + S[J_TAY + k]
    if ph <= 0.0:
        return -1.0
    lo = 0.0
    hi = s_max
    s = -t1 / t2
    for it in range(100):
        f = 0.0
        fp = 0.0
        for k in range(n_use, 0, -1):
            f = f * s + S[J_TAY + k]
        for k in range(n_use, 1, -1):
            fp = fp * s + (k - 1) * S[J_TAY + k]
        if f == 0.0:
            return s
        lo, hi = _shrink_bracket(s, f, lo, hi)
        if hi - lo <= 2.0 * EPS * hi:
            break
        s, converged = _safeguard_newton(s, s - f / fp, lo, hi)
        if converged:
            break
    return hi


@jit
def stop_sign(P, S):
    """Leaving the stop or pushed into it, from the leading nonzero Taylor term.

    Returns (+1, 0) if the motion pushes into the stop (stick), else (-1, k) with
    ``k`` the order of the leading nonzero term ``t_k < 0`` (0: all of t_1..t_4
    vanish, degenerate).
    """
    for k in range(1, 5):
        tk = S[J_TAY + k]
        if tk > 0.0:
            return 1.0, 0
        if tk < 0.0:
            return -1.0, k
    return -1.0, 0


@jit
def stop_clear(P, S, hmax, k):
    """Advance u with g < 0 proven on (0, u], leaving the stop with leading term t_k < 0."""
    if k == 0:
        # all leading terms vanish (degenerate): leave with a tiny advance
        return 64.0 * EPS
    y = S[J_Y]
    yd = S[J_YD]
    tk = S[J_TAY + k]
    u = hmax
    # g(u) <= t_k u^k + M_{k+1} u^{k+1} / (k+1)!  < 0  for u < |t_k| (k+1)! / M
    for it in range(60):
        M = deriv_bound(P, k + 1, y, yd, u, 1.0, S[J_TAY + 1], u)
        fact = 1.0
        for j in range(2, k + 2):
            fact *= j
        u_ok = abs(tk) * fact / M
        if u_ok > u:
            break
        u = 0.5 * u_ok
    return u


@jit
def stop_exit(P, S, hmax):
    """Leave the stop: (+1, 0) if the motion pushes into the stop (stick), else
    (-1, u1) with g < 0 proven on (0, u1].  Uses the leading nonzero Taylor term.

    (:func:`run` calls the two halves, :func:`stop_sign` and :func:`stop_clear`, and the
    second only when the flight is not a micro-flight, which needs no ``u1``.)
    """
    sgn, k = stop_sign(P, S)
    if sgn > 0.0:
        return 1.0, 0.0
    return -1.0, stop_clear(P, S, hmax, k)


@jit
def taylor_velocity(S, s):
    """x'(s) of a flight from the stop, from its Taylor series (as :func:`evaluate`)."""
    vs = 0.0
    for k in range(N_TAYLOR, 0, -1):
        vs = vs * s + k * S[J_TAY + k]
    return vs


@jit
def level_exit(P, S, s0, c, sig, hmax):
    """Smallest advance u with sig (x - c) < 0 proven on (s0, s0 + u], starting at a
    point exactly on the level with sig v < 0 (first order)."""
    g, gv, ga, y, yd = level_values_called(P, S, s0, c, sig)
    if gv >= 0.0:
        # degenerate: on the level without a velocity away from it (a tangency,
        # or at rest on the level when F = 0); step on by a fraction of a chunk
        if P[I_F] == 0.0 and g == 0.0 and gv == 0.0 and ga == 0.0:
            return 1e300  # at rest on the level for ever: no further crossing
        return hmax / 64.0
    u = hmax
    for it in range(60):
        M = deriv_bound(P, 2, y, yd, s0 + u, c + sig * g, sig * gv, u)
        u_ok = 2.0 * (-gv) / M
        if u_ok > u:
            break
        u = 0.5 * u_ok
    return u


@jit
def micro_bounce(F, omega, zeta, th, w0, rem):
    """Average elastic (e = 1) micro-bouncing on the stop while the force pushes.

    With e = 1 there is no accumulation point: damping removes
    ``4 zeta w^3 / (3 a)`` of energy per bounce of rebound speed ``w`` under the
    net push ``a = F cos(theta) - 1``, so ``dw/dt = -(2 zeta / 3) w``, and the
    bounce action ``w^3 / a`` is an adiabatic invariant, so over a slowly
    varying push ``w(t) = w0 (a(t) / a0)^(1/3) exp(-2 zeta t / 3)``.  The
    number of bounces grows without bound as w shrinks, so following them one
    by one cannot finish; this asymptotic solution (relative error of order
    the flight time over the forcing and damping time scales, below
    TAU_MICRO) carries the state to the time where the flight time
    ``2 w / a`` reaches TAU_EXIT again (near the force reversal), from where
    the exact solver resumes.

    When the bounce height ``w^2 / (2 a)`` falls below the displacement
    resolution (half an ulp of 1.0) the mass is in contact to double precision
    and is reported stuck.

    Returns (duration, w at the end, estimated number of bounces skipped,
    stuck flag).
    """
    a0 = F * math.cos(th) - 1.0
    psi = math.acos(1.0 / F)
    phi = th if th <= math.pi else th - TWO_PI
    t_push = (psi - phi) / omega
    scale = max(1.0, omega, 2.0 * zeta)
    n_scan = 512
    t_prev = 0.0
    t_exit = min(t_push, rem)
    n_b = 0.0
    f_prev = a0 / (2.0 * w0)
    for k in range(1, n_scan + 1):
        tk = t_push * k / n_scan
        ak = F * math.cos(th + omega * tk) - 1.0
        if ak <= 0.0 or tk >= rem:
            t_exit = min(tk, rem)
            break
        wk = w0 * (ak / a0) ** (1.0 / 3.0) * math.exp(-2.0 * zeta * tk / 3.0)
        if wk * wk / (2.0 * ak) < 0.5 * EPS:
            return tk, 0.0, n_b, True
        if 2.0 * wk / ak * scale >= TAU_EXIT:
            lo = t_prev
            hi = tk
            for it in range(60):
                mid = 0.5 * (lo + hi)
                am = F * math.cos(th + omega * mid) - 1.0
                wm = w0 * (am / a0) ** (1.0 / 3.0) * math.exp(-2.0 * zeta * mid / 3.0)
                if am <= 0.0 or 2.0 * wm / am * scale >= TAU_EXIT:
                    hi = mid
                else:
                    lo = mid
            t_exit = hi
            break
        f_k = ak / (2.0 * wk)
        n_b += 0.5 * (f_prev + f_k) * (tk - t_prev)
        f_prev = f_k
        t_prev = tk
    t_exit = min(t_exit, rem)
    a_end = F * math.cos(th + omega * t_exit) - 1.0
    if a_end > 0.0:
        w_end = w0 * (a_end / a0) ** (1.0 / 3.0) * math.exp(-2.0 * zeta * t_exit / 3.0)
    else:
        w_end = 0.0
    return t_exit, w_end, n_b, False

