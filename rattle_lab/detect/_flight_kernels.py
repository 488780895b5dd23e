"""Compiled inner loops of the flight model (:mod:`rattle_lab.detect._flights`).

The variable-projection searches evaluate the run model thousands of times for new
``(f_s, sigma)`` or ringing poles; each evaluation touches every sample of the flights
used.  These loops do it in one pass with no temporaries.  The run-wide columns come in
two parts: the forced response's, hat functions in time that are zero on all but a few
columns of each row (stored by rows: ``indptr``, ``indices``, ``values``), and a few dense
columns ``r`` (the ringing).  :func:`free_sums` forms the per-flight sums of the free
response's normal equations, :func:`residual_ss` the residual's sum of squares
(:func:`solve_flights` both and the elimination between them in one call),
:func:`sparse_cross` the products of the two parts, :func:`added_sums` what new dense
columns (given, or the ringing carried on over later flights, generated as it goes) add to
a model whose other parts are fixed, and :func:`tail_columns` that ringing's columns.
numba compiles them on first use and caches them on disk.
(No function here calls a compiled function of another module: numba's cache does not notice
when a callee in another file changes, and a stale copy of it fails at run time.)
"""

from __future__ import annotations

import math

import numba
import numpy as np


#: Rows between exact evaluations in the rotations of :func:`free_response` and
#: :func:`tail_columns` (each rotation adds a rounding error of ~1e-16 relative).
REANCHOR = 64


@numba.njit(cache=True, nogil=True)
def free_response(tau: np.ndarray, next_: np.ndarray, f_hz: float, sigma: float, dt: float
                  ) -> np.ndarray:  # pragma: no cover - compiled
    """``exp((-sigma + 2 pi i f) tau)`` per row.  Where a row is its predecessor's next
    sample (``next_``, ``tau`` larger by ``dt``) it is the predecessor's times
    ``exp((-sigma + 2 pi i f) dt)`` (one complex product instead of exp, cos and sin),
    evaluated exactly again every :data:`REANCHOR` rows."""
    pole = complex(-sigma, 2.0 * math.pi * f_hz)
    step = np.exp(pole * dt)
    out = np.empty(tau.size, dtype=np.complex128)
    run = 0
    for i in range(tau.size):
        if next_[i] and run < REANCHOR:
            out[i] = out[i - 1] * step
            run += 1
        else:
            out[i] = np.exp(pole * tau[i])
            run = 0
    return out


@numba.njit(cache=True, nogil=True)
def _sums_z(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
            p: int, r: np.ndarray, z: np.ndarray, seg: np.ndarray, n_seg: int
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """:func:`free_sums` with the free response ``z`` given."""
    n, m = r.shape
    zz = np.zeros((n_seg, 2, 2))
    zx = np.zeros((n_seg, 2, p + m))
    zy = np.zeros((n_seg, 2))
    for i in range(n):
        z0 = z[i].real
        z1 = z[i].imag
        s = seg[i]
        zz[s, 0, 0] += z0 * z0
        zz[s, 0, 1] += z0 * z1
        zz[s, 1, 1] += z1 * z1
        zy[s, 0] += z0 * y[i]
        zy[s, 1] += z1 * y[i]
        for k in range(indptr[i], indptr[i + 1]):
            q = indices[k]
            zx[s, 0, q] += z0 * values[k]
            zx[s, 1, q] += z1 * values[k]
        for q in range(m):
            zx[s, 0, p + q] += z0 * r[i, q]
            zx[s, 1, p + q] += z1 * r[i, q]
    for s in range(n_seg):
        zz[s, 1, 0] = zz[s, 0, 1]
    return zz, zx, zy


@numba.njit(cache=True, nogil=True)
def free_sums(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
              p: int, r: np.ndarray, tau: np.ndarray, seg: np.ndarray, next_: np.ndarray,
              n_seg: int, f_hz: float, sigma: float, dt: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """Per flight ``s``: ``Z_s'Z_s`` (2x2), ``Z_s'[X_s R_s]`` (2 x (p + m)) and ``Z_s'y_s``,
    where ``Z`` is the fundamental's free response ``exp(-sigma tau) [cos, sin](2 pi f tau)``
    (see :func:`free_response`)."""
    z = free_response(tau, next_, f_hz, sigma, dt)
    return _sums_z(y, indptr, indices, values, p, r, z, seg, n_seg)


@numba.njit(cache=True, nogil=True)
def _residual_z(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
                p: int, r: np.ndarray, beta: np.ndarray, z: np.ndarray, seg: np.ndarray,
                gamma: np.ndarray) -> float:  # pragma: no cover - compiled
    """:func:`residual_ss` with the free response ``z`` given."""
    n, m = r.shape
    total = 0.0
    for i in range(n):
        res = y[i]
        for k in range(indptr[i], indptr[i + 1]):
            res -= values[k] * beta[indices[k]]
        for q in range(m):
            res -= r[i, q] * beta[p + q]
        s = seg[i]
        res -= z[i].real * gamma[s, 0] + z[i].imag * gamma[s, 1]
        total += res * res
    return total


@numba.njit(cache=True, nogil=True)
def residual_ss(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
                p: int, r: np.ndarray, beta: np.ndarray, tau: np.ndarray, seg: np.ndarray,
                next_: np.ndarray, gamma: np.ndarray, f_hz: float, sigma: float, dt: float
                ) -> float:  # pragma: no cover - compiled
    """``sum (y - [X R] beta - Z gamma_seg)^2``, ``Z`` as in :func:`free_sums`."""
    z = free_response(tau, next_, f_hz, sigma, dt)
    return _residual_z(y, indptr, indices, values, p, r, beta, z, seg, gamma)


@numba.njit(cache=True, nogil=True)
def _solve2(a: np.ndarray, b: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """``a^-1 b`` for a 2x2 ``a`` and 2 x k ``b``: LU with partial pivoting (LAPACK
    ``gesv``'s steps for a 2x2)."""
    a00, a01, a10, a11 = a[0, 0], a[0, 1], a[1, 0], a[1, 1]
    swap = abs(a10) > abs(a00)
    if swap:
        a00, a01, a10, a11 = a10, a11, a00, a01
    if a00 == 0.0:
        raise np.linalg.LinAlgError("Singular matrix")   # numpy's error and message
    lo = a10 / a00
    u11 = a11 - lo * a01
    if u11 == 0.0:
        raise np.linalg.LinAlgError("Singular matrix")
    out = np.empty(b.shape)
    for j in range(b.shape[1]):
        b0, b1 = (b[1, j], b[0, j]) if swap else (b[0, j], b[1, j])
        x1 = (b1 - lo * b0) / u11
        out[1, j] = x1
        out[0, j] = (b0 - a01 * x1) / a00
    return out


@numba.njit(cache=True, nogil=True)
def solve_flights(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
                  p: int, r: np.ndarray, tau: np.ndarray, seg: np.ndarray, next_: np.ndarray,
                  n_seg: int, f_hz: float, sigma: float, dt: float, xtx: np.ndarray,
                  xty: np.ndarray, scale: np.ndarray
                  ) -> tuple[float, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """``(rss, beta, gamma)`` of the run model at ``(f_s, sigma)`` in one call
    (:meth:`rattle_lab.detect._flights._Model.solve`'s steps: each flight's free response
    eliminated from the normal equations ``xtx``, ``xty`` of the run-wide columns, which are
    solved scaled by ``scale`` with LAPACK ``gelsd`` at ``rcond = 1e-12``, then the
    residual); the free response is formed once for both passes."""
    z = free_response(tau, next_, f_hz, sigma, dt)
    zz, zx, zy = _sums_z(y, indptr, indices, values, p, r, z, seg, n_seg)
    q = zx.shape[2]
    a = xtx.copy()
    b = xty.copy()
    g_zx = np.empty((n_seg, 2, q))
    g_zy = np.empty((n_seg, 2))
    rhs = np.empty((2, q + 1))
    for s in range(n_seg):
        m = zz[s].copy()
        ridge = 1e-12 * (m[0, 0] + m[1, 1])
        m[0, 0] += ridge
        m[1, 1] += ridge
        rhs[:, :q] = zx[s]
        rhs[:, q] = zy[s]
        g = _solve2(m, rhs)
        g_zx[s] = g[:, :q]
        g_zy[s] = g[:, q]
        for i in range(q):
            zi0, zi1 = zx[s, 0, i], zx[s, 1, i]
            for j in range(q):
                a[i, j] -= zi0 * g[0, j] + zi1 * g[1, j]
            b[i] -= zi0 * g[0, q] + zi1 * g[1, q]
    for i in range(q):
        for j in range(q):
            a[i, j] /= scale[i] * scale[j]
        b[i] /= scale[i]
    beta = np.linalg.lstsq(a, b, 1e-12)[0] / scale
    gamma = np.empty((n_seg, 2))
    for s in range(n_seg):
        for k in range(2):
            acc = g_zy[s, k]
            for j in range(q):
                acc -= g_zx[s, k, j] * beta[j]
            gamma[s, k] = acc
    rss = _residual_z(y, indptr, indices, values, p, r, beta, z, seg, gamma)
    return rss, beta, gamma


#: Most samples in one block of :func:`added_sums` (a flight, or part of a long one).
BLOCK = 512


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def added_sums(y: np.ndarray, z: np.ndarray, seg: np.ndarray, n_seg: int, bounds: np.ndarray,
               xptr: np.ndarray, xcols: np.ndarray, xoff: np.ndarray, xvals: np.ndarray,
               n_x: int, r: np.ndarray, last: np.ndarray, dt: np.ndarray, next_: np.ndarray,
               dt_step: float, d: np.ndarray, gaps: np.ndarray, f_hz: np.ndarray, s: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """What new dense columns ``R`` add to a model whose other parts are fixed, in one pass
    over the samples: ``(R'R, R'X, R'y, Z_s'R_s)``.

    ``R`` is the columns ``r`` given followed by two columns (real, imaginary) per ringing
    mode ``(f_hz[j], s[j])``, :func:`tail_columns`'s, generated here and never stored whole:
    the same recursion over the impacts and the same rows evaluated exactly (where a sample
    is not its predecessor's next after the same impact, and every :data:`REANCHOR`
    rotations); a row ``k`` rotations after one is that row's value times ``step^k``, from
    a table of the powers formed by the same repeated products (rows independent of each
    other, at the same rounding error).  The samples go in blocks within one flight
    (:data:`BLOCK`).  ``X`` (the model's run-wide columns) comes block by block, only its
    columns that are nonzero in the block, each as a contiguous row of the block's values;
    a block's new columns are formed into rows alike, and every sum is a dot product of two
    rows, two new columns at a time (compiled with reassociation: vectorised, each sum
    rounded in another order than sample after sample, ~1e-16 relative).

    Parameters
    ----------
    y : ndarray
        The samples (``n``).
    z : ndarray
        The fundamental's free response (:func:`free_response`), per sample.
    seg : ndarray
        Each sample's flight (a block lies in one).
    n_seg : int
        The number of flights.
    bounds : ndarray
        Block ``b`` is samples ``bounds[b]`` to ``bounds[b + 1] - 1``.
    xptr, xcols, xoff, xvals : ndarray
        ``X`` by blocks: block ``b``'s nonzero columns are ``xcols[xptr[b]:xptr[b + 1]]``,
        the ``t``-th of them its values ``xvals[xoff[b] + t L_b + u]``, ``u < L_b`` (the
        block's length).
    n_x : int
        The number of columns of ``X``.
    r : ndarray
        The new columns given (``n x m_r``, may be ``n x 0``).
    last, dt, next_, dt_step, d, gaps : ndarray, ndarray, ndarray, float, ndarray, ndarray
        Where the samples lie after the impacts, and the impacts' amplitudes, as
        :func:`tail_columns` takes them (unused without modes).
    f_hz, s : ndarray
        The ringing modes' frequencies and decay rates (may be empty).

    Returns
    -------
    rr : ndarray
        ``R'R`` (``m x m``, ``m = m_r + 2 n_modes``).
    rx : ndarray
        ``R'X`` (``m x n_x``).
    ry : ndarray
        ``R'y`` (``m``).
    zr : ndarray
        Per flight ``Z_s'R_s`` (``n_seg x 2 x m``).
    """
    m_r = r.shape[1]
    n_modes = f_hz.size
    m = m_r + 2 * n_modes
    # each mode's C_k = C_{k-1} exp(p gap_k) + d_k over the impacts (as tail_columns)
    c = np.empty((n_modes, d.size), dtype=np.complex128)
    poles = np.empty(n_modes, dtype=np.complex128)
    steps = np.empty(n_modes, dtype=np.complex128)
    for j in range(n_modes):
        pole = complex(-s[j], 2.0 * math.pi * f_hz[j])
        poles[j] = pole
        steps[j] = np.exp(pole * dt_step)
        acc = 0j
        for k in range(d.size):
            if k:
                acc = acc * np.exp(pole * gaps[k - 1]) + d[k]
            else:
                acc = complex(d[0], 0.0)
            c[j, k] = acc
    e = np.zeros(n_modes, dtype=np.complex128)
    pw = np.empty((n_modes, REANCHOR + 1), dtype=np.complex128)
    for j in range(n_modes):
        pw[j, 0] = 1.0
        for k in range(1, REANCHOR + 1):
            pw[j, k] = pw[j, k - 1] * steps[j]
    rr = np.zeros((m, m))
    rx = np.zeros((m, n_x))
    ry = np.zeros(m)
    zr = np.zeros((n_seg, 2, m))
    longest = 0
    for b in range(bounds.size - 1):
        longest = max(longest, bounds[b + 1] - bounds[b])
    buf = np.empty((m, longest))       # the block's new columns, one a row
    z0 = np.empty(longest)
    z1 = np.empty(longest)
    k_run = np.empty(longest, dtype=np.int64)
    run = REANCHOR
    for b in range(bounds.size - 1):
        lo, hi = bounds[b], bounds[b + 1]
        size = hi - lo
        for u in range(size):
            i = lo + u
            z0[u] = z[i].real
            z1[u] = z[i].imag
            for a in range(m_r):
                buf[a, u] = r[i, a]
        if n_modes:
            # the rotations' count since the last exact evaluation (-1: before any impact)
            for u in range(size):
                i = lo + u
                li = last[i]
                if li < 0:
                    run = REANCHOR
                    k_run[u] = -1
                elif next_[i] and li == last[i - 1] and run < REANCHOR:
                    run += 1
                    k_run[u] = run
                else:
                    run = 0
                    k_run[u] = 0
            for j in range(n_modes):
                ea = e[j]
                for u in range(size):
                    k = k_run[u]
                    if k < 0:
                        buf[m_r + 2 * j, u] = 0.0
                        buf[m_r + 2 * j + 1, u] = 0.0
                        continue
                    i = lo + u
                    if k == 0:
                        ea = np.exp(poles[j] * dt[i])
                    t = c[j, last[i]] * (ea * pw[j, k])
                    buf[m_r + 2 * j, u] = t.real
                    buf[m_r + 2 * j + 1, u] = t.imag
                e[j] = ea
        sg = seg[lo]
        yb = y[lo:hi]
        a = 0
        while a < m:
            ba = buf[a, :size]
            two = a + 1 < m
            bb = buf[a + 1 if two else a, :size]
            sy = 0.0
            s0 = 0.0
            s1 = 0.0
            ty = 0.0
            t0 = 0.0
            t1 = 0.0
            for u in range(size):
                sy += ba[u] * yb[u]
                s0 += ba[u] * z0[u]
                s1 += ba[u] * z1[u]
                ty += bb[u] * yb[u]
                t0 += bb[u] * z0[u]
                t1 += bb[u] * z1[u]
            ry[a] += sy
            zr[sg, 0, a] += s0
            zr[sg, 1, a] += s1
            if two:
                ry[a + 1] += ty
                zr[sg, 0, a + 1] += t0
                zr[sg, 1, a + 1] += t1
            for a2 in range(a, m):
                bc = buf[a2, :size]
                acc1 = 0.0
                acc2 = 0.0
                for u in range(size):
                    acc1 += ba[u] * bc[u]
                    acc2 += bb[u] * bc[u]
                rr[a, a2] += acc1
                if two and a2 > a:
                    rr[a + 1, a2] += acc2
            for t in range(xptr[b], xptr[b + 1]):
                start = xoff[b] + (t - xptr[b]) * size
                xt = xvals[start:start + size]
                acc1 = 0.0
                acc2 = 0.0
                for u in range(size):
                    acc1 += ba[u] * xt[u]
                    acc2 += bb[u] * xt[u]
                rx[a, xcols[t]] += acc1
                if two:
                    rx[a + 1, xcols[t]] += acc2
            a += 2
    for a in range(m):
        for a2 in range(a):
            rr[a, a2] = rr[a2, a]
    return rr, rx, ry, zr


@numba.njit(cache=True, nogil=True)
def eliminate_free(rr: np.ndarray, rx: np.ndarray, ry: np.ndarray, zr: np.ndarray,
                   h: np.ndarray, gx: np.ndarray, gy: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """The sums of :func:`added_sums` with each flight's free response eliminated:
    ``R'R - sum_s zr_s' H_s zr_s``, ``R'X - sum_s zr_s' G_s`` and ``R'y - sum_s zr_s' g_s``
    (``H_s = (Z_s'Z_s)^-1``, ``G_s = H_s Z_s'X_s``, ``g_s = H_s Z_s'y_s``)."""
    n_seg, _, m = zr.shape
    p = gx.shape[2]
    a_rr, a_rx, b_r = rr.copy(), rx.copy(), ry.copy()
    for s in range(n_seg):
        for a in range(m):
            z0, z1 = zr[s, 0, a], zr[s, 1, a]
            for b in range(m):
                hz0 = h[s, 0, 0] * zr[s, 0, b] + h[s, 0, 1] * zr[s, 1, b]
                hz1 = h[s, 1, 0] * zr[s, 0, b] + h[s, 1, 1] * zr[s, 1, b]
                a_rr[a, b] -= z0 * hz0 + z1 * hz1
            for q in range(p):
                a_rx[a, q] -= z0 * gx[s, 0, q] + z1 * gx[s, 1, q]
            b_r[a] -= z0 * gy[s, 0] + z1 * gy[s, 1]
    return a_rr, a_rx, b_r


@numba.njit(cache=True, nogil=True)
def sparse_cross(indptr: np.ndarray, indices: np.ndarray, values: np.ndarray, p: int,
                 r: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """``X' r`` for ``X`` stored by rows (``p`` columns) and dense ``r``."""
    n, m = r.shape
    out = np.zeros((p, m))
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            q = indices[k]
            for j in range(m):
                out[q, j] += values[k] * r[i, j]
    return out


@numba.njit(cache=True, nogil=True)
def tail_columns(last: np.ndarray, dt: np.ndarray, next_: np.ndarray, dt_step: float,
                 d: np.ndarray, gaps: np.ndarray, f_hz: float, s: float
                 ) -> np.ndarray:  # pragma: no cover - compiled
    """``sum_{i <= last} d_i exp(p (t - t_i))``, ``p = -s + 2 pi i f``, as (real, imaginary)
    columns: ``C_k = C_{k-1} exp(p gap_k) + d_k`` over the impacts, then each sample
    ``C_last exp(p dt)`` (rotated from its predecessor where it is the next sample after
    the same impact, as in :func:`free_response`); zero before the first impact."""
    pole = complex(-s, 2.0 * math.pi * f_hz)
    c = np.empty(d.size, dtype=np.complex128)
    acc = 0j
    for k in range(d.size):
        if k:
            acc = acc * np.exp(pole * gaps[k - 1]) + d[k]
        else:
            acc = complex(d[0], 0.0)
        c[k] = acc
    out = np.zeros((last.size, 2))
    step = np.exp(pole * dt_step)
    run = REANCHOR
    e = 0j
    for i in range(last.size):
        if last[i] < 0:
            run = REANCHOR
            continue
        if next_[i] and last[i] == last[i - 1] and run < REANCHOR:
            e = e * step
            run += 1
        else:
            e = np.exp(pole * dt[i])
            run = 0
        z = c[last[i]] * e
        out[i, 0] = z.real
        out[i, 1] = z.imag
    return out


@numba.njit(cache=True, nogil=True)
def sparse_gram(indptr: np.ndarray, indices: np.ndarray, values: np.ndarray, p: int,
                y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """``(X'X, X'y)`` for ``X`` stored by rows (``p`` columns): each row's few nonzero
    entries, in pairs."""
    xtx = np.zeros((p, p))
    xty = np.zeros(p)
    for i in range(indptr.size - 1):
        for a in range(indptr[i], indptr[i + 1]):
            qa, va = indices[a], values[a]
            xty[qa] += va * y[i]
            for b in range(indptr[i], indptr[i + 1]):
                xtx[qa, indices[b]] += va * values[b]
    return xtx, xty

