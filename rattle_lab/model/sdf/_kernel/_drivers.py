"""Drivers of the kernel: many runs, or one run's result packed, per compiled call.

:func:`run_sweep` (a sweep direction), :func:`run_pieces` (a ramp of the forcing
amplitude) and :func:`run_packed` (:func:`._run.run` in one flat buffer, what
``simulate`` calls) each make the calls to :func:`._run.run` a Python loop would, so
their motion is the same to the last bit, without the fixed cost per call.
"""

import numpy as np

from ._constants import TWO_PI
from ._jit import jit
from ._run import _grow, run


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
