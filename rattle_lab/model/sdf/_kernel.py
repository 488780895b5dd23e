"""Event-driven exact kernel of the SDF impact oscillator (scalar code).

This module is written once and loaded twice: as plain Python (the readable
reference path, ``method="exact-python"``) and compiled with numba
(``method="exact"``).  :mod:`rattle_lab.model.sdf._compiled` does the second load
with the module global ``__rattle_jit__`` set; nothing else differs.

Model (nondimensional, thesis eq. 2.33)::

    x'' + 2 zeta x' + x = F cos(theta),  theta = theta0 + omega s,   x < 1
    v -> -e v                                                       at x = 1

Free flight
    Closed form (see :mod:`rattle_lab.model.sdf._flow`): particular part plus the
    homogeneous part, for zeta < 1, = 1, > 1, and the undamped resonance.  No
    time step is taken.  Each flight is restarted ("rebased") at least once per
    window ``W = min(2 pi, 2 pi / omega)`` so that local times stay small and
    phases stay accurate to rounding.

Why no impact can be missed
    The impact is the earliest ``s`` in the window where ``g(s) = x(s) - 1 >= 0``.
    The window is cut into chunks and each chunk ``[s_a, s_b]`` is examined with
    rigorous bounds ``M_k >= |x^(k)|`` over the chunk (:func:`deriv_bound`), the
    smaller of two valid ones:

    * modal: the particular part has ``|x_p^(k)| <= R omega^k`` (R its
      amplitude); the homogeneous part ``y`` obeys
      ``d/ds (y^2 + y'^2) = -4 zeta y'^2 <= 0``, so ``rho = |(y, y')|`` never
      grows and ``|y^(k)| <= n_k rho(s_a)`` (``n_k`` the norm of the first row of
      the k-th power of the companion matrix; for zeta > 1 the two decaying
      modes are bounded separately);
    * energy: ``d/ds |(x, v)| <= F`` bounds ``|x|, |v|`` on the chunk, and the
      equation of motion bounds the higher derivatives; this one stays sharp
      near resonance, where the modal parts are large and cancel.

    With ``M2`` on the chunk, ``g`` lies below both parabolas
    ``g_a + g'_a u + M2 u^2 / 2`` and ``g_b - g'_b w + M2 w^2 / 2``; if the
    maximum of their lower envelope is below ``-GRAZE_TOL`` the chunk holds no
    impact.  If not, ``M3`` bounds ``x''``: if ``x''`` is provably negative the
    chunk holds at most one local maximum of ``x``, found as a bracketed root of
    ``v`` and compared with the stop; if ``x''`` is provably positive the
    maximum is at an end.  Otherwise the chunk is halved.  Near a tangency the
    curvature is bounded away from zero, so the concavity test settles it after
    a few halvings.  A maximum within ``GRAZE_TOL`` (4 ulp) of the stop is a
    grazing impact (``v_in`` is then the rounding-level velocity there): below
    that the distinction is lost in the rounding of ``x`` itself.  Sampling sign
    changes is never relied on.  Each chunk examines at most ``MAX_WORK``
    sub-intervals (a guard that has not been reached in any test); if it is,
    the caller is warned.

Impacts on and from the stop
    A flight that starts on the stop (after an impact, or on release from
    sticking) is evaluated near its start by its Taylor series about the start,
    ``x - 1 = sum_k d_k s^k / k!`` with ``d_k`` from the equation of motion, so
    that tiny chatter flights are resolved to relative rounding instead of being
    lost in the cancellation ``x_p + y - 1``.  The first instants are excluded by
    the leading nonzero derivative: ``g(u) <= d_k u^k / k! + M_{k+1} u^{k+1} /
    (k+1)! < 0`` for small ``u`` when ``d_k < 0``.  When the leading derivative
    pushes into the stop (v = 0 and F cos(theta) > 1), the mass sticks.

Chatter and sticking
    When the force pushes into the stop (``a_stop = F cos(theta) - 1 > 0`` at
    x = 1, v = 0) and flights shrink geometrically (complete chatter, Budd &
    Dux 1994; Nordmark & Piiroinen 2009), the remaining flight times form a
    geometric series.  Each micro-flight is solved from the Taylor series about
    the stop (:func:`micro_flight`, a proven single root), and after each
    micro-impact the tail ``tau_k q / (1 - q)`` (``q`` the measured ratio of the
    last two flight times, which tends to ``e``) is computed.  Once the tail,
    or its error estimate ``tail |q_k - q_(k-1)| / (1 - q)^2`` (q drifts by
    O(w) per flight), is below the time resolution ``16 ulp(t)``, or after
    ``N_CHATTER_MAX`` micro-impacts, the solver jumps to the accumulation point
    and sticks.  With e = 1 there is no accumulation point; elastic
    micro-bouncing is averaged (:func:`micro_bounce`) and reported.  While stuck (x = 1, v = 0) the net force
    ``F cos(theta) - 1`` pushes into the stop; the mass is released at the
    analytic phase ``theta = arccos(1 / F)`` where the force reverses.

Time
    Phases are kept reduced to [0, 2 pi); time is kept as a compensated sum
    ``t + t_lo`` (error-free two-sum of every flight time, :func:`_time_add`),
    so impact times stay within a few ulp of the exact time however many
    flights are summed (plain ``t += s`` drifted by 1e-8 after 1e4 forcing
    periods and 8e-7 after 1e5: the rounding of ``t + s`` with nearly equal
    ``s`` is biased).

The kernel never lets x exceed 1 (impacts set x = 1 exactly), and every loop is
bounded (``max_events``).
"""

import math

import numpy as np

try:  # set by rattle_lab.model.sdf._compiled before executing this source
    _JIT = bool(__rattle_jit__)  # type: ignore[name-defined]  # noqa: F821
except NameError:
    _JIT = False

if _JIT:
    import numba

    def jit(func):
        return numba.njit(cache=True, nogil=True)(func)
else:

    def jit(func):
        return func


TWO_PI = 2.0 * math.pi
EPS = 2.220446049250313e-16
#: Terms of the Taylor series used near a start on the stop.
N_TAYLOR = 20
#: Taylor series used while s * LAMBDA <= TAYLOR_REACH (remainder < 1e-25 relative).
TAYLOR_REACH = 0.5
#: Micro-impacts of one chatter sequence before jumping to its accumulation point.
N_CHATTER_MAX = 20000
#: Maximum halvings of a search chunk.
MAX_LEVEL = 60
#: Consecutive short elastic (e = 1) bounces before micro-bounce averaging.
N_MICRO = 1000
#: Elastic bounces shorter than TAU_MICRO (relative to the fastest time scale)
#: are averaged; averaging ends when the flight time grows to TAU_EXIT.
TAU_MICRO = 1e-4
TAU_EXIT = 1e-2
#: A local maximum of x within GRAZE_TOL of the stop is a grazing impact: the
#: distinction is below the rounding of x (4 ulp of 1.0).
GRAZE_TOL = 4.0 * EPS
#: Maximum sub-intervals examined in one search chunk.
MAX_WORK = 20000
#: A flight's window is searched in chunks of at most W / CHUNKS_PER_WINDOW.  The search
#: is rigorous (derivative bounds) whatever the chunk, so this only moves work: 2 (half a
#: period) costs 0.7-1.3 us per impact on the 1/1 orbit where 8 cost 2.4 us (fewer chunks
#: and bounds per flight; chatter, chaos and 1/3 motion also as fast or faster), with every
#: mpmath, thesis and grazing test unchanged (benchmarks/speed_goals.py).
CHUNKS_PER_WINDOW = 2.0

# Layout of the parameter vector P.
I_F, I_W, I_Z, I_E, I_AC, I_AS, I_R, I_RES, I_REG, I_WD, I_R1, I_R2, I_LAM = range(13)
I_NK = 13  # n_0 .. n_7 follow
N_P = I_NK + 8

# Layout of the segment vector S.
J_TH, J_Y, J_YD, J_ONSTOP = range(4)
J_TAY = 4  # Taylor coefficients t_0 .. t_N_TAYLOR (t_k = d_k / k!)
N_S = J_TAY + N_TAYLOR + 1


@jit
def make_params(F, omega, zeta, e):
    """Pack the parameters and the derived constants into one float vector."""
    P = np.zeros(N_P)
    P[I_F] = F
    P[I_W] = omega
    P[I_Z] = zeta
    P[I_E] = e
    one_m_w2 = (1.0 - omega) * (1.0 + omega)
    two_zw = 2.0 * zeta * omega
    D = one_m_w2 * one_m_w2 + two_zw * two_zw
    if D == 0.0:  # undamped resonance: secular particular solution
        P[I_RES] = 1.0
    else:
        P[I_AC] = F * one_m_w2 / D
        P[I_AS] = F * two_zw / D
        P[I_R] = math.sqrt(P[I_AC] * P[I_AC] + P[I_AS] * P[I_AS])
    if zeta < 1.0:
        P[I_REG] = 0.0
        P[I_WD] = math.sqrt((1.0 - zeta) * (1.0 + zeta))
        lam_h = 1.0
    elif zeta == 1.0:
        P[I_REG] = 1.0
        lam_h = 1.0
    else:
        P[I_REG] = 2.0
        mu = math.sqrt((zeta - 1.0) * (zeta + 1.0))
        P[I_WD] = mu
        P[I_R1] = -1.0 / (zeta + mu)
        P[I_R2] = -zeta - mu
        lam_h = zeta + mu
    P[I_LAM] = max(omega, lam_h, 1.0)
    # n_k = |first row of A^k|, A = [[0, 1], [-1, -2 zeta]] (companion matrix)
    a00, a01 = 1.0, 0.0
    a10, a11 = 0.0, 1.0
    for k in range(8):
        P[I_NK + k] = math.sqrt(a00 * a00 + a01 * a01) * (1.0 + 1e-12)
        # (row0, row1) <- A @ (row0, row1)
        n00 = a10
        n01 = a11
        n10 = -a00 - 2.0 * zeta * a10
        n11 = -a01 - 2.0 * zeta * a11
        a00, a01, a10, a11 = n00, n01, n10, n11
    return P


@jit
def transition(P, s):
    """(Ec, Es) of the homogeneous flow over time s."""
    z = P[I_Z]
    reg = P[I_REG]
    if reg == 0.0:
        wd = P[I_WD]
        d = math.exp(-z * s)
        return d * math.cos(wd * s), d * math.sin(wd * s) / wd
    if reg == 1.0:
        d = math.exp(-s)
        return d, d * s
    mu = P[I_WD]
    e1 = math.exp(P[I_R1] * s)
    e2 = math.exp(P[I_R2] * s)
    return 0.5 * (e1 + e2), e1 * (-math.expm1(-2.0 * mu * s)) / (2.0 * mu)


@jit
def particular(P, th, s):
    """(x_p, v_p) at phase th, s after the flight started (s matters at resonance only)."""
    c = math.cos(th)
    sn = math.sin(th)
    if P[I_RES] != 0.0:
        h = 0.5 * P[I_F]
        return h * s * sn, h * (sn + s * c)
    Ac = P[I_AC]
    As = P[I_AS]
    return Ac * c + As * sn, P[I_W] * (As * c - Ac * sn)


@jit
def reduce_phase(th):
    """Reduce a phase to [0, 2 pi)."""
    r = th - TWO_PI * math.floor(th / TWO_PI)
    if r < 0.0:
        r += TWO_PI
    if r >= TWO_PI:
        r = 0.0
    return r


@jit
def start_segment(P, S, th, x, v, on_stop):
    """Fill the segment vector S for a free flight starting at (x, v, th)."""
    cth = math.cos(th)  # one cos and one sin for the particular part and the Taylor terms
    sth = math.sin(th)
    if P[I_RES] != 0.0:  # particular(P, th, 0.0), with the cos and sin above
        h = 0.5 * P[I_F]
        xp = h * 0.0 * sth
        vp = h * (sth + 0.0 * cth)
    else:
        xp = P[I_AC] * cth + P[I_AS] * sth
        vp = P[I_W] * (P[I_AS] * cth - P[I_AC] * sth)
    S[J_TH] = th
    S[J_Y] = x - xp
    S[J_YD] = v - vp
    S[J_ONSTOP] = 1.0 if on_stop else 0.0
    if on_stop:
        F = P[I_F]
        w = P[I_W]
        z = P[I_Z]
        # d_0 = x (=1), d_1 = v, d_{k+2} = F w^k cos(th + k pi/2) - 2 z d_{k+1} - d_k
        dkm1 = 1.0
        dk = v
        S[J_TAY] = 1.0
        S[J_TAY + 1] = v
        fact = 1.0
        wk = 1.0
        for k in range(N_TAYLOR - 1):
            q = k % 4
            if q == 0:
                trig = cth
            elif q == 1:
                trig = -sth
            elif q == 2:
                trig = -cth
            else:
                trig = sth
            dnew = F * wk * trig - 2.0 * z * dk - dkm1
            if k <= 2 and abs(dnew) <= 8.0 * EPS * (F * wk + 2.0 * z * abs(dk) + abs(dkm1)):
                # rounding noise of an exact zero (release from sticking, contact at
                # the crest of the force): keep the leading order of the motion exact
                dnew = 0.0
            wk *= w
            fact *= (k + 2)
            S[J_TAY + k + 2] = dnew / fact
            dkm1 = dk
            dk = dnew


@jit
def evaluate(P, S, s):
    """(x - 1 if on-stop Taylor else x, v, a, y, yd, x) at local time s.

    Returns a tuple (x, v, a, y, yd, zstop) where zstop = x - 1 computed without
    cancellation near a start on the stop (Taylor), else x - 1.  Within the Taylor
    reach of a start on the stop, x and v come from the series and the homogeneous
    state from them, ``(y, yd) = (x - x_p, v - v_p)`` (equal to the closed form's to
    rounding; it only enters the derivative bounds), so the closed-form transition
    (an exp, a cos and a sin) is not evaluated there.
    """
    th = S[J_TH] + P[I_W] * s
    z = P[I_Z]
    c = math.cos(th)  # shared by the particular part and the force
    sn = math.sin(th)
    if P[I_RES] != 0.0:
        h = 0.5 * P[I_F]
        xp = h * s * sn
        vp = h * (sn + s * c)
    else:
        xp = P[I_AC] * c + P[I_AS] * sn
        vp = P[I_W] * (P[I_AS] * c - P[I_AC] * sn)
    if S[J_ONSTOP] != 0.0 and s * P[I_LAM] <= TAYLOR_REACH:
        zs = 0.0
        vs = 0.0
        for k in range(N_TAYLOR, 0, -1):
            zs = zs * s + S[J_TAY + k]
            vs = vs * s + k * S[J_TAY + k]
        zstop = zs * s
        v = vs
        x = 1.0 + zstop
        y = x - xp
        yd = v - vp
    else:
        Ec, Es = transition(P, s)
        y0 = S[J_Y]
        yd0 = S[J_YD]
        y = (Ec + z * Es) * y0 + Es * yd0
        yd = -Es * y0 + (Ec - z * Es) * yd0
        x = xp + y
        v = vp + yd
        zstop = x - 1.0
    a = P[I_F] * c - 2.0 * z * v - x
    return x, v, a, y, yd, zstop


@jit
def deriv_bound(P, k, y, yd, s_end, x, v, L):
    """Bound of |x^(k)| (k = 2..5) over an interval [s_a, s_a + L], s_a + L = s_end.

    (y, yd) is the homogeneous state and (x, v) the full state at s_a.  Two
    valid bounds are computed and the smaller is returned:

    * modal: ``R omega^k`` for the particular part plus ``n_k |(y, y')|`` (or the
      two decaying modes for zeta > 1) for the homogeneous part, which never
      grows;
    * energy: ``d/ds sqrt(x^2 + v^2) <= F`` gives ``|x|, |v| <= r = |(x, v)| + F L``
      on the interval, and the equation of motion gives
      ``|x^(j+2)| <= F omega^j + 2 zeta |x^(j+1)| + |x^(j)|``.  This one stays
      sharp near resonance, where the particular and homogeneous parts are
      both large and cancel.
    """
    if P[I_RES] != 0.0:
        bp = 0.5 * P[I_F] * (s_end + k)
    else:
        bp = P[I_R] * P[I_W] ** k
    if P[I_REG] == 2.0:
        r1 = P[I_R1]
        r2 = P[I_R2]
        c1 = (yd - r2 * y) / (r1 - r2)
        c2 = (r1 * y - yd) / (r1 - r2)
        bh = (abs(c1) * abs(r1) ** k + abs(c2) * abs(r2) ** k) * (1.0 + 1e-10)
    else:
        bh = P[I_NK + k] * math.sqrt(y * y + yd * yd)
    modal = bp + bh
    F = P[I_F]
    w = P[I_W]
    tz = 2.0 * P[I_Z]
    r = math.sqrt(x * x + v * v) + F * L
    m0 = r
    m1 = r
    wj = 1.0
    for j in range(k - 1):
        m2 = F * wj + tz * m1 + m0
        m0 = m1
        m1 = m2
        wj *= w
    return min(modal, m1) * (1.0 + 1e-12) + 1e-300


@jit
def level_values(P, S, s, c, sig):
    """g = sig (x - c), g' and g'' at s, plus the homogeneous state (y, yd)."""
    x, v, a, y, yd, zstop = evaluate(P, S, s)
    if c == 1.0:
        g = sig * zstop
    else:
        g = sig * (x - c)
    return g, sig * v, sig * a, y, yd


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


@jit
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


@jit
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
                gc, gvc, gac, yc, ydc = level_values(P, S, sc, c, sig)
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
                gc, gvc, gac, yc, ydc = level_values(P, S, sc, c, sig)
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


@jit
def first_reach(P, S, c, sig, s_lo, s_hi, hmax, diag, work):
    """Earliest s in (s_lo, s_hi] where sig (x(s) - c) >= 0, or -1.

    Requires sig (x(s_lo) - c) < 0.  ``work`` is scratch of shape
    ``(MAX_LEVEL + 6, 12)`` (see :func:`new_work`), allocated once per run: no
    allocation per search.
    """
    va = work[MAX_LEVEL + 4]
    vb = work[MAX_LEVEL + 5]
    g, gv, ga, y, yd = level_values(P, S, s_lo, c, sig)
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
    g, gv, ga, y, yd = level_values(P, S, s0, c, sig)
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


@jit
def _two_sum(a, b):
    """Error-free sum: (s, err) with s = fl(a + b) and s + err = a + b exactly (Knuth)."""
    s = a + b
    bb = s - a
    err = (a - (s - bb)) + (b - bb)
    return s, err


@jit
def _time_add(t_hi, t_lo, s):
    """Advance the compensated time ``t_hi + t_lo`` by ``s``.

    Time is kept as an unevaluated sum of two floats (``|t_lo| <= ulp(t_hi) / 2``),
    so that summing ~1e6 flight times loses nothing: ``t_hi`` stays the correctly
    rounded time, where ``t += s`` drifts by the bias of repeated rounding (1e-8
    after 1e4 forcing periods, 1e-6 after 1e5).
    """
    hi, err = _two_sum(t_hi, s)
    lo = t_lo + err
    hi2 = hi + lo
    return hi2, lo - (hi2 - hi)


@jit
def _time_at(t_hi, t_lo, s):
    """The float nearest ``t_hi + t_lo + s`` (a time s after the compensated time)."""
    hi, err = _two_sum(t_hi, s)
    return hi + (err + t_lo)


@jit
def _time_left(e_hi, e_lo, t_hi, t_lo):
    """``(e_hi + e_lo) - (t_hi + t_lo)`` to rounding of the difference."""
    d, err = _two_sum(e_hi, -t_hi)
    return d + (err + (e_lo - t_lo))


@jit
def _grow(arr, n):
    if n < arr.shape[0]:
        return arr
    new = np.empty((2 * arr.shape[0] + 16, arr.shape[1]))
    new[: arr.shape[0]] = arr
    return new


@jit
def run(F, omega, zeta, e, t0, x0, v0, th0, stuck0, duration, want_cross, want_segs,
        max_events):
    """Simulate for `duration` from the given state.

    Returns (imp, n_imp, acc, n_acc, stk, n_stk, crs, n_crs, seg, n_seg,
    t, x, v, th, stuck, n_events, status, n_unresolved, avg, n_avg) where imp rows are
    (t, phase, v_in, v_out), stk rows (t_start, t_end), crs rows (t, v), seg rows
    (t_start, th0, y0, yd0, kind) with kind 0 = free flight, 1 = stuck, and
    avg rows (t_start, t_end, n_bounces) mark elastic micro-bounce intervals
    that were averaged (see :func:`micro_bounce`);
    status 0 = done, 1 = event budget exhausted; n_unresolved counts search
    chunks settled at the MAX_WORK cap (zero in all tested cases).
    """
    P = make_params(F, omega, zeta, e)
    S = np.zeros(N_S)
    diag = np.zeros(2)
    work = new_work()
    imp = np.empty((64, 4))
    acc = np.empty((4, 1))
    stk = np.empty((4, 2))
    crs = np.empty((16 if want_cross else 1, 2))
    seg = np.empty((64 if want_segs else 1, 5))
    avg = np.empty((2, 3))
    n_avg = 0
    n_imp = 0
    n_acc = 0
    n_stk = 0
    n_crs = 0
    n_seg = 0
    W = min(TWO_PI, TWO_PI / omega)
    hmax = W / CHUNKS_PER_WINDOW
    t = t0
    t_lo = 0.0  # compensated time: t + t_lo (see _time_add)
    x = x0
    v = v0
    th = reduce_phase(th0)
    stuck = stuck0
    t_end, t_end_lo = _two_sum(t0, duration)
    rem = duration
    n_events = 0
    status = 0
    tau_prev = -1.0  # previous chatter flight time (-1: not in a chatter sequence)
    q_prev = 0.0
    n_chat = 0
    last_was_impact = False
    released_now = False
    while rem > 0.0:
        # recomputed, so that t ends at t0 + duration to rounding
        rem = _time_left(t_end, t_end_lo, t, t_lo)
        if rem <= 0.0:
            break
        if n_events >= max_events:
            status = 1
            break
        if stuck:
            if want_segs:
                seg = _grow(seg, n_seg)
                seg[n_seg, 0] = t
                seg[n_seg, 1] = th
                seg[n_seg, 2] = 0.0
                seg[n_seg, 3] = 0.0
                seg[n_seg, 4] = 1.0
                n_seg += 1
            if F > 1.0:
                psi = math.acos(1.0 / F)
            else:
                psi = 0.0
            phi = th if th <= math.pi else th - TWO_PI
            if -psi <= phi < psi and not released_now:
                s_rel = (psi - phi) / omega
                th_rel = psi
            else:
                s_rel = 0.0
                th_rel = th
            stk = _grow(stk, n_stk)
            stk[n_stk, 0] = t
            if s_rel >= rem:
                t = t_end
                t_lo = t_end_lo
                th = reduce_phase(th + omega * rem)
                rem = 0.0
                stk[n_stk, 1] = t
                n_stk += 1
                break
            t, t_lo = _time_add(t, t_lo, s_rel)
            th = th_rel
            stk[n_stk, 1] = t
            n_stk += 1
            stuck = False
            released_now = True
            x = 1.0
            v = 0.0
            n_events += 1
            last_was_impact = False
            continue
        on_stop = x == 1.0
        start_segment(P, S, th, x, v, on_stop)
        if want_segs:
            seg = _grow(seg, n_seg)
            seg[n_seg, 0] = t
            seg[n_seg, 1] = th
            seg[n_seg, 2] = S[J_Y]
            seg[n_seg, 3] = S[J_YD]
            seg[n_seg, 4] = 0.0
            n_seg += 1
        Wn = min(W, rem)
        s_lo = 0.0
        sgn = 1.0
        k_lead = 0
        if on_stop:
            sgn, k_lead = stop_sign(P, S)
            if sgn > 0.0 and not released_now:
                stuck = True
                x = 1.0
                v = 0.0
                n_seg -= 1 if want_segs else 0
                continue
        released_now = False
        s_imp = -1.0
        micro = False
        if on_stop:
            s_imp = micro_flight(P, S, Wn)
            micro = s_imp >= 0.0
            if not micro and sgn < 0.0:
                # the first instants, proven clear of the stop (a micro-flight needs none)
                s_lo = min(stop_clear(P, S, hmax, k_lead), Wn)
        if not micro and s_lo < Wn:
            s_imp = first_reach(P, S, 1.0, 1.0, s_lo, Wn, hmax, diag, work)
        s_end = s_imp if s_imp >= 0.0 else Wn
        # a micro flight stays within |v0| s_imp of the stop: it cannot reach x = 0
        if want_cross and not (micro and -S[J_TAY + 1] * s_imp < 0.5):
            # upward crossings of x = 0 inside (0, s_end]
            xs, vs, a_s, ys, yds, zs = evaluate(P, S, 0.0)
            if xs < 0.0 or (xs == 0.0 and vs < 0.0):
                sig = 1.0
            else:
                sig = -1.0
            s_from = 0.0
            if xs == 0.0:
                s_from = min(level_exit(P, S, 0.0, 0.0, sig, hmax), s_end)
            while s_from < s_end:
                sc = first_reach(P, S, 0.0, sig, s_from, s_end, hmax, diag, work)
                if sc < 0.0:
                    break
                xc, vc, ac, yc, ydc, zc = evaluate(P, S, sc)
                if sig > 0.0 and vc > 0.0:  # v = 0 is a tangency, not a crossing
                    crs = _grow(crs, n_crs)
                    crs[n_crs, 0] = _time_at(t, t_lo, sc)
                    crs[n_crs, 1] = vc
                    n_crs += 1
                sig = -sig
                # step past the crossing by a proven margin, clear of rounding noise
                s_from = sc + level_exit(P, S, sc, 0.0, sig, hmax)
        if s_imp < 0.0:
            xn, vn, an, yn, ydn, zn = evaluate(P, S, Wn)
            x = min(xn, 1.0)
            if x == 1.0:
                x = 1.0 - EPS  # a window end within rounding of the stop (no impact found)
            v = vn
            t, t_lo = _time_add(t, t_lo, Wn)
            th = reduce_phase(th + omega * Wn)
            tau_prev = -1.0
            n_chat = 0
            last_was_impact = False
            continue
        # impact
        if micro:  # evaluate() would take the Taylor branch; only its velocity is needed
            v_in = taylor_velocity(S, s_imp)
        else:
            xi, v_in, ai, yi, ydi, zi = evaluate(P, S, s_imp)
        if v_in < 0.0:
            v_in = 0.0  # grazing: the crossing velocity is zero to rounding
        t_imp = _time_at(t, t_lo, s_imp)
        th = reduce_phase(th + omega * s_imp)
        imp = _grow(imp, n_imp)
        imp[n_imp, 0] = t_imp
        imp[n_imp, 1] = th
        imp[n_imp, 2] = v_in
        imp[n_imp, 3] = e * v_in
        n_imp += 1
        n_events += 1
        x = 1.0
        v = -e * v_in
        tau = s_imp if last_was_impact else -1.0
        t, t_lo = _time_add(t, t_lo, s_imp)
        rem = _time_left(t_end, t_end_lo, t, t_lo)
        last_was_impact = True
        # complete chatter: jump to the accumulation point
        a_stop = F * math.cos(th) - 1.0
        if a_stop > 0.0 and tau > 0.0:
            if tau_prev > 0.0:
                q = tau / tau_prev
                n_chat += 1
            else:
                q = e
                n_chat = 1
            dq = abs(q - q_prev) if n_chat >= 3 else 1.0
            q_prev = q
            tau_prev = tau
            if e < 1.0 and q < 1.0:
                tail = tau * q / (1.0 - q)
                res = 16.0 * EPS * max(1.0, abs(t))
                # error of the geometric tail from the drift of q (O(w) per flight)
                tail_err = tail * dq / ((1.0 - q) * (1.0 - q))
                if (tail <= res or tail_err <= res or n_chat >= N_CHATTER_MAX) and tail < rem:
                    if F * math.cos(th + omega * tail) - 1.0 > 0.0:
                        t, t_lo = _time_add(t, t_lo, tail)
                        th = reduce_phase(th + omega * tail)
                        acc = _grow(acc, n_acc)
                        acc[n_acc, 0] = t
                        n_acc += 1
                        n_events += 1
                        stuck = True
                        v = 0.0
                        tau_prev = -1.0
                        n_chat = 0
                        last_was_impact = False
                        continue
            if (e == 1.0 and n_chat >= N_MICRO and tau * max(1.0, omega, 2.0 * zeta) < TAU_MICRO):
                # elastic micro-bouncing: no accumulation exists; average it
                dt_avg, w_end, n_b, now_stuck = micro_bounce(F, omega, zeta, th, e * v_in, rem)
                avg = _grow(avg, n_avg)
                avg[n_avg, 0] = t
                avg[n_avg, 1] = _time_at(t, t_lo, dt_avg)
                avg[n_avg, 2] = n_b
                n_avg += 1
                n_events += 1
                t, t_lo = _time_add(t, t_lo, dt_avg)
                th = reduce_phase(th + omega * dt_avg)
                v = -w_end
                if now_stuck:
                    v = 0.0
                    stuck = True
                tau_prev = -1.0
                n_chat = 0
                last_was_impact = False
                continue
            # a flight shorter than the time resolution cannot be resolved: stick
            if tau < 4.0 * EPS * max(1.0, abs(t)) and e * v_in < 1e-8:
                stuck = True
                v = 0.0
                tau_prev = -1.0
                n_chat = 0
                last_was_impact = False
                continue
        else:
            tau_prev = -1.0
            n_chat = 0
    return (imp, n_imp, acc, n_acc, stk, n_stk, crs, n_crs, seg, n_seg,
            t, x, v, th, stuck, n_events, status, diag[0], avg, n_avg)


@jit
def _append_rows(dst, n, src, m):
    """Append rows ``src[:m]`` to ``dst`` (``n`` rows used); returns (dst, n + m)."""
    while n + m > dst.shape[0]:
        dst = _grow(dst, dst.shape[0])
    for i in range(m):
        for j in range(src.shape[1]):
            dst[n + i, j] = src[i, j]
    return dst, n + m


@jit
def run_sweep(F_arr, w_arr, e_arr, zeta, t0, x0, v0, th0, stuck0, discard_cycles, kept_cycles):
    """A whole sweep direction in one call: at each value, ``discard_cycles`` forcing
    periods, then ``kept_cycles`` with crossings, the state carried over.

    Exactly the calls :func:`rattle_lab.model.analysis._sweep.sweep` made through
    ``simulate`` (same durations ``cycles * 2 pi / omega`` and event budgets), so
    the motion is the same to the last bit.  Returns (imp, crs, off, ends, info):
    imp rows (t, phase, v_in) and crs rows (t, v) of every kept window, value i's
    rows ``off[i, 0]:off[i + 1, 0]`` and ``off[i, 1]:off[i + 1, 1]``; ends rows
    (t at the kept window's start, t, x, v, theta, stuck) at its end; info rows
    (sticking or accumulation in the kept window, status, searches settled at the
    work cap), status as for :func:`run` (the sweep stops at the first nonzero).
    """
    n = F_arr.shape[0]
    imp = np.empty((64, 3))
    crs = np.empty((64, 2))
    n_imp = 0
    n_crs = 0
    off = np.zeros((n + 1, 2), dtype=np.int64)
    ends = np.zeros((n, 6))
    info = np.zeros((n, 3))
    t = t0
    x = x0
    v = v0
    th = th0
    stuck = stuck0
    for i in range(n):
        period = TWO_PI / w_arr[i]
        if discard_cycles > 0.0:
            d = discard_cycles * period
            me = 10**6 + int(1000.0 * (d / period + 1.0))
            out = run(F_arr[i], w_arr[i], zeta, e_arr[i], t, x, v, th, stuck, d, False, False, me)
            t, x, v, th, stuck = out[10], out[11], out[12], out[13], out[14]
            info[i, 1] = out[16]
            info[i, 2] += out[17]
            if out[16] != 0:
                off[i + 1:, 0] = n_imp
                off[i + 1:, 1] = n_crs
                return imp[:n_imp], crs[:n_crs], off, ends, info
        ends[i, 0] = t
        d = kept_cycles * period
        me = 10**6 + int(1000.0 * (d / period + 1.0))
        out = run(F_arr[i], w_arr[i], zeta, e_arr[i], t, x, v, th, stuck, d, True, False, me)
        t, x, v, th, stuck = out[10], out[11], out[12], out[13], out[14]
        imp, n_imp = _append_rows(imp, n_imp, out[0][:, :3], out[1])
        crs, n_crs = _append_rows(crs, n_crs, out[6], out[7])
        off[i + 1, 0] = n_imp
        off[i + 1, 1] = n_crs
        ends[i, 1] = t
        ends[i, 2] = x
        ends[i, 3] = v
        ends[i, 4] = th
        ends[i, 5] = 1.0 if stuck else 0.0
        info[i, 0] = 1.0 if (out[5] > 0 or out[3] > 0) else 0.0
        info[i, 1] = out[16]
        info[i, 2] += out[17]
        if out[16] != 0:
            off[i + 2:, 0] = n_imp
            off[i + 2:, 1] = n_crs
            return imp[:n_imp], crs[:n_crs], off, ends, info
    return imp[:n_imp], crs[:n_crs], off, ends, info


@jit
def run_pieces(F_arr, omega, zeta, e, t0, x0, v0, th0, stuck0, t_stop, group_gap, group_size,
               quiet_time, quiet_ok, last_imp):
    """Consecutive pieces at forcing amplitudes ``F_arr``, piece ``j`` running until
    ``t_stop[j]``, the state carried over: one call for a whole amplitude ramp.

    Exactly the calls ``simulate(SDFParams(F_arr[j], omega, zeta, e),
    duration=max(0, t_stop[j] - state.t), state=state)`` a Python loop makes (same
    durations and event budgets), so the motion is the same to the last bit.
    Early stop, after the piece where it first holds (0 or negative: never):
    ``group_gap > 0``: ``group_size`` consecutive impacts, each less than
    ``group_gap`` after the previous; ``quiet_time > 0``: a piece without impacts
    with ``quiet_ok[j]``, ending more than ``quiet_time`` after the last impact
    (``last_imp``: the last one before this call, NaN if none).
    Returns (imp, off, ends, info): imp rows (t, phase, v_in) of every piece, piece
    j's rows ``off[j]:off[j + 1]``; ends rows (t, x, v, theta, stuck) at each piece's
    end; info rows (status, searches settled at the work cap) as for :func:`run`;
    the pieces stop at the first nonzero status or early stop (later ``info`` rows
    -1, their ``off`` equal to the last).
    """
    n = F_arr.shape[0]
    imp = np.empty((64, 3))
    n_imp = 0
    off = np.zeros(n + 1, dtype=np.int64)
    ends = np.zeros((n, 5))
    info = np.full((n, 2), -1.0)
    t = t0
    x = x0
    v = v0
    th = th0
    stuck = stuck0
    period = TWO_PI / omega
    streak = 1
    for j in range(n):
        d = max(0.0, t_stop[j] - t)
        me = 10**6 + int(1000.0 * (d / period + 1.0))
        out = run(F_arr[j], omega, zeta, e, t, x, v, th, stuck, d, False, False, me)
        t, x, v, th, stuck = out[10], out[11], out[12], out[13], out[14]
        m = out[1]
        imp, n_imp = _append_rows(imp, n_imp, out[0][:, :3], m)
        off[j + 1] = n_imp
        ends[j, 0] = t
        ends[j, 1] = x
        ends[j, 2] = v
        ends[j, 3] = th
        ends[j, 4] = 1.0 if stuck else 0.0
        info[j, 0] = out[16]
        info[j, 1] = out[17]
        stop = out[16] != 0
        if group_gap > 0.0:
            for i in range(m):
                ti = out[0][i, 0]
                if last_imp == last_imp and ti - last_imp < group_gap:
                    streak += 1
                else:
                    streak = 1
                last_imp = ti
                if streak >= group_size:
                    stop = True
        elif m > 0:
            last_imp = out[0][m - 1, 0]
        if (quiet_time > 0.0 and m == 0 and quiet_ok[j] and last_imp == last_imp
                and t_stop[j] - last_imp > quiet_time):
            stop = True
        if stop:
            off[j + 2:] = n_imp
            return imp[:n_imp], off, ends, info
    return imp[:n_imp], off, ends, info


#: Length of the header of :func:`run_packed`'s buffer.
N_HEAD = 14


@jit
def run_packed(F, omega, zeta, e, t0, x0, v0, th0, stuck0, duration, want_cross, want_segs,
               max_events):
    """:func:`run` with everything in one flat buffer (one array to hand back, not six).

    Layout: a header of ``N_HEAD`` values (n_imp, n_acc, n_stk, n_crs, n_seg, n_avg,
    t, x, v, th, stuck, n_events, status, n_unresolved), then the impact columns
    t, phase, v_in, v_out (n_imp each), the accumulation times (n_acc), the sticking
    rows (n_stk x 2, row-major), the crossing columns t, v (n_crs each), the
    segment rows (n_seg x 5, row-major) and the micro-bounce rows (n_avg x 3).
    """
    (imp, n_imp, acc, n_acc, stk, n_stk, crs, n_crs, seg, n_seg,
     t, x, v, th, stuck, n_events, status, n_unres, avg, n_avg) = run(
        F, omega, zeta, e, t0, x0, v0, th0, stuck0, duration, want_cross, want_segs,
        max_events)
    size = N_HEAD + 4 * n_imp + n_acc + 2 * n_stk + 2 * n_crs + 5 * n_seg + 3 * n_avg
    buf = np.empty(size)
    buf[0] = n_imp
    buf[1] = n_acc
    buf[2] = n_stk
    buf[3] = n_crs
    buf[4] = n_seg
    buf[5] = n_avg
    buf[6] = t
    buf[7] = x
    buf[8] = v
    buf[9] = th
    buf[10] = 1.0 if stuck else 0.0
    buf[11] = n_events
    buf[12] = status
    buf[13] = n_unres
    k = N_HEAD
    for j in range(4):
        for i in range(n_imp):
            buf[k] = imp[i, j]
            k += 1
    for i in range(n_acc):
        buf[k] = acc[i, 0]
        k += 1
    for i in range(n_stk):
        for j in range(2):
            buf[k] = stk[i, j]
            k += 1
    for j in range(2):
        for i in range(n_crs):
            buf[k] = crs[i, j]
            k += 1
    for i in range(n_seg):
        for j in range(5):
            buf[k] = seg[i, j]
            k += 1
    for i in range(n_avg):
        for j in range(3):
            buf[k] = avg[i, j]
            k += 1
    return buf
