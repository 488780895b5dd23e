"""The closed-form free flight of the kernel: parameters, start, evaluation, bounds.

Between impacts the motion is the particular part plus the homogeneous part
(:mod:`rattle_lab.model.sdf._flow` writes the same closed form for readers);
:func:`deriv_bound` gives the rigorous derivative bounds the search in
:mod:`._search` relies on.  See the package docstring for the algorithm.
"""

import math

import numpy as np

from ._constants import (EPS, I_AC, I_AS, I_E, I_F, I_LAM, I_NK, I_R, I_R1, I_R2, I_REG,
                         I_RES, I_W, I_WD, I_WK, I_Z, J_MEMO, J_MEMO_NEXT, J_ONSTOP, J_TAY,
                         J_TH, J_Y, J_YD, MEMO_WIDTH, N_MEMO, N_P, N_TAYLOR, TAYLOR_REACH,
                         TWO_PI)
from ._jit import jit, jit_inline


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
    for k in range(8):
        P[I_WK + k] = omega ** k  # as deriv_bound computed it (k an integer), once
    return P


@jit_inline
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


@jit_inline
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
    for i in range(N_MEMO):  # a new flight: forget the last one's evaluations
        S[J_MEMO + MEMO_WIDTH * i] = math.nan
    S[J_MEMO_NEXT] = 0.0
    if not on_stop:
        # evaluate(P, S, 0.0), from the cos and sin above: at s = 0 the transition is
        # (Ec, Es) = (1, 0) exactly (exp, cos of +-0 are 1, sin and expm1 of +-0 are
        # +-0, C99 Annex F), and th + omega * 0 = th (th >= +0, reduced), so this is
        # the same arithmetic on the same numbers as evaluate's
        Ec = 1.0
        Es = 0.0
        z = P[I_Z]
        y0 = S[J_Y]
        yd0 = S[J_YD]
        y = (Ec + z * Es) * y0 + Es * yd0
        yd = -Es * y0 + (Ec - z * Es) * yd0
        x0 = xp + y
        v0 = vp + yd
        a0 = P[I_F] * cth - 2.0 * z * v0 - x0
        _memo_put(S, 0.0, x0, v0, a0, y, yd, x0 - 1.0)
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


@jit_inline
def _memo_put(S, s, x, v, a, y, yd, zstop):
    """Write an evaluation at s into the flight's memo (over its oldest row)."""
    i = int(S[J_MEMO_NEXT])
    j = J_MEMO + MEMO_WIDTH * i
    S[j] = s
    S[j + 1] = x
    S[j + 2] = v
    S[j + 3] = a
    S[j + 4] = y
    S[j + 5] = yd
    S[j + 6] = zstop
    S[J_MEMO_NEXT] = float((i + 1) % N_MEMO)


@jit_inline
def _evaluate(P, S, s):
    """(x - 1 if on-stop Taylor else x, v, a, y, yd, x) at local time s.

    Returns a tuple (x, v, a, y, yd, zstop) where zstop = x - 1 computed without
    cancellation near a start on the stop (Taylor), else x - 1.  Within the Taylor
    reach of a start on the stop, x and v come from the series and the homogeneous
    state from them, ``(y, yd) = (x - x_p, v - v_p)`` (equal to the closed form's to
    rounding; it only enters the derivative bounds), so the closed-form transition
    (an exp, a cos and a sin) is not evaluated there.

    The last ``N_MEMO`` evaluations of the flight are kept in ``S`` (reset by
    :func:`start_segment`, which also puts s = 0 there for a flight off the stop): a
    point evaluated again is returned from there, the same numbers.
    """
    for i in range(N_MEMO):
        j = J_MEMO + MEMO_WIDTH * i
        if S[j] == s:
            return S[j + 1], S[j + 2], S[j + 3], S[j + 4], S[j + 5], S[j + 6]
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
    _memo_put(S, s, x, v, a, y, yd, zstop)
    return x, v, a, y, yd, zstop


@jit
def evaluate(P, S, s):
    """:func:`_evaluate`, called (not inlined): for the event loop's few evaluations,
    which would otherwise each inline the whole evaluation (compile time)."""
    return _evaluate(P, S, s)


@jit_inline
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
        bp = P[I_R] * P[I_WK + k]
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


@jit_inline
def level_values(P, S, s, c, sig):
    """g = sig (x - c), g' and g'' at s, plus the homogeneous state (y, yd)."""
    x, v, a, y, yd, zstop = _evaluate(P, S, s)
    if c == 1.0:
        g = sig * zstop
    else:
        g = sig * (x - c)
    return g, sig * v, sig * a, y, yd


@jit
def level_values_called(P, S, s, c, sig):
    """:func:`level_values`, called (not inlined): for the searches' rare evaluations
    (at a critical point, on leaving a level), to keep compile time down."""
    return level_values(P, S, s, c, sig)
