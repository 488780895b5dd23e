"""The kernel's event loop :func:`run`, and the compensated time it keeps.

See "Time" in the package docstring for the compensated sum ``t + t_lo``.
"""

import math

import numpy as np

from ._constants import (CHUNKS_PER_WINDOW, EPS, J_TAY, J_Y, J_YD, N_CHATTER_MAX, N_MICRO, N_S,
                         TAU_MICRO, TWO_PI)
from ._flight import evaluate, make_params, reduce_phase, start_segment
from ._jit import jit
from ._search import first_reach, new_work
from ._stop import (level_exit, micro_bounce, micro_flight, stop_clear, stop_sign,
                    taylor_velocity)


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

