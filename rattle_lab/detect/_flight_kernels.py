"""Compiled inner loops of the flight model (:mod:`rattle_lab.detect._flights`).

The variable-projection searches evaluate the run model thousands of times for new
``(f_s, sigma)`` or ringing poles; each evaluation touches every sample of the flights
used.  These loops do it in one pass with no temporaries.  The run-wide columns come in
two parts: the forced response's, hat functions in time that are zero on all but a few
columns of each row (stored by rows: ``indptr``, ``indices``, ``values``), and a few dense
columns ``r`` (the ringing).  :func:`free_sums` forms the per-flight sums of the free
response's normal equations, :func:`residual_ss` the residual's sum of squares, sample by
sample; :func:`solve_flights` both and the elimination between them in one call, over
blocks of a flight with the forced columns gathered by blocks (what the searches for
``(f_s, sigma)`` evaluate); :func:`sparse_cross` the products of the two parts,
:func:`added_sums` what new dense columns (given, or the ringing carried on over later
flights, generated as it goes) add to a model whose other parts are fixed, and
:func:`tail_columns` that ringing's columns.
numba compiles them on first use and caches them on disk.
(No function here calls a compiled function of another module: numba's cache does not notice
when a callee in another file changes, and a stale copy of it fails at run time.)
"""

from __future__ import annotations

import math

import numba
import numpy as np


#: Rows between exact evaluations in the rotations of :func:`free_response` and of the
#: carried ringing's tails (:func:`tail_runs`; each rotation adds a rounding error of
#: ~1e-16 relative).
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
def _beta_gamma(a: np.ndarray, b: np.ndarray, scale: np.ndarray, g_zx: np.ndarray,
                g_zy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
    """The run-wide coefficients from the eliminated normal equations ``a beta = b`` (scaled
    by ``scale``, LAPACK ``gelsd`` at ``rcond = 1e-12``; ``a`` and ``b`` are overwritten) and
    each flight's free amplitudes ``gamma_s = g_zy_s - g_zx_s beta``."""
    q = b.size
    for i in range(q):
        for j in range(q):
            a[i, j] /= scale[i] * scale[j]
        b[i] /= scale[i]
    beta = np.linalg.lstsq(a, b, 1e-12)[0] / scale
    n_seg = g_zy.shape[0]
    gamma = np.empty((n_seg, 2))
    for s in range(n_seg):
        for k in range(2):
            acc = g_zy[s, k]
            for j in range(q):
                acc -= g_zx[s, k, j] * beta[j]
            gamma[s, k] = acc
    return beta, gamma


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def solve_flights(y: np.ndarray, tau: np.ndarray, anchor: np.ndarray, seg: np.ndarray,
                  n_seg: int, bounds: np.ndarray, xptr: np.ndarray, xcols: np.ndarray,
                  xoff: np.ndarray, xvals: np.ndarray, r_t: np.ndarray, f_hz: float,
                  sigma: float, dt: float, xtx: np.ndarray, xty: np.ndarray, scale: np.ndarray
                  ) -> tuple[float, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """``(rss, beta, gamma)`` of the run model at ``(f_s, sigma)`` in one call.

    :meth:`rattle_lab.detect._flights._Model.solve`'s steps: each flight's free response
    eliminated from the normal equations ``xtx``, ``xty`` of the run-wide columns (``X``,
    sparse, and ``R``, dense), which are solved scaled by ``scale`` with LAPACK ``gelsd``
    at ``rcond = 1e-12``, then the residual.

    The free response is :func:`free_response`'s: exact at the rows ``anchor`` (where a row
    is not its predecessor's next sample, and every :data:`REANCHOR` rotations), each row
    after one that row's value times ``step^k`` from a table of the powers formed by
    repeated products (as :func:`added_sums`: the rows independent of each other, at the
    same rounding error as one product after another).  The samples go in blocks within
    one flight (as in :func:`added_sums`), ``X`` block by block, only its columns that are
    nonzero in the block, each a contiguous row of the block's values, and ``R`` as rows
    of ``R'``: the flights' sums and the residual are dot products and sums of rows, two
    columns at a time (compiled with reassociation: vectorised, each sum rounded in
    another order than sample after sample, ~1e-16 relative).

    Parameters
    ----------
    y : ndarray
        The samples (``n``).
    tau : ndarray
        Each sample's time in its flight's free response, s.
    anchor : ndarray
        The rows where the free response is evaluated exactly, increasing, then ``n``: rows
        ``anchor[a] + k``, ``k < anchor[a + 1] - anchor[a] <= REANCHOR + 1``, are each its
        predecessor's next sample (``tau`` larger by ``dt``).
    seg : ndarray
        Each sample's flight (a block lies in one).
    n_seg : int
        The number of flights.
    bounds, xptr, xcols, xoff, xvals : ndarray
        The blocks, and ``X`` by blocks, as :func:`added_sums` takes them (``p`` columns).
    r_t : ndarray
        ``R'`` (``m x n``, C-contiguous, may be ``0 x n``): columns ``p`` to ``q - 1``.
    f_hz, sigma, dt : float
        The free response's frequency, Hz, and decay rate, 1/s; the sampling interval, s.
    xtx, xty : ndarray
        ``W'W`` and ``W'y`` of the run-wide columns ``W = [X R]`` (``q x q``, ``q``).
    scale : ndarray
        The columns' scales for the solution (``q``).

    Returns
    -------
    rss : float
        The residual sum of squares.
    beta : ndarray
        The run-wide coefficients (``q``).
    gamma : ndarray
        Each flight's free amplitudes (``n_seg x 2``).
    """
    n = y.size
    q = xty.size
    m = r_t.shape[0]
    p = q - m
    # the free response, real and imaginary parts: each row its chain's exact value times
    # a power of the step
    pole = complex(-sigma, 2.0 * math.pi * f_hz)
    step = np.exp(pole * dt)
    pw0 = np.empty(REANCHOR + 1)
    pw1 = np.empty(REANCHOR + 1)
    w = 1.0 + 0j
    for k in range(REANCHOR + 1):
        pw0[k] = w.real
        pw1[k] = w.imag
        w = w * step
    z0 = np.empty(n)
    z1 = np.empty(n)
    for j in range(anchor.size - 1):
        i = anchor[j]
        size = anchor[j + 1] - i
        e = np.exp(pole * tau[i])
        e0, e1 = e.real, e.imag
        o0 = z0[i:i + size]
        o1 = z1[i:i + size]
        for k in range(size):
            o0[k] = e0 * pw0[k] - e1 * pw1[k]
            o1[k] = e0 * pw1[k] + e1 * pw0[k]
    # per flight Z'Z (00, 01, 11), Z'W and Z'y, block by block: dot products of rows, two
    # columns at a time (y with the block's first column, Z'Z alongside)
    zz = np.zeros((n_seg, 3))
    zx = np.zeros((n_seg, 2, q))
    zy = np.zeros((n_seg, 2))
    longest = 0
    for b in range(bounds.size - 1):
        lo, hi = bounds[b], bounds[b + 1]
        size = hi - lo
        longest = max(longest, size)
        s = seg[lo]
        a0 = z0[lo:hi]
        a1 = z1[lo:hi]
        yb = y[lo:hi]
        nx = xptr[b + 1] - xptr[b]
        tot = nx + m          # the block's columns: X's nonzero ones, then R's
        t = -1
        while t < tot:
            # columns t and t + 1 (-1: y; the last one paired with itself)
            t2 = t + 1 if t + 1 < tot else t
            if t < 0:
                xa, ca = yb, -1
            elif t < nx:
                st = xoff[b] + t * size
                xa, ca = xvals[st:st + size], xcols[xptr[b] + t]
            else:
                xa, ca = r_t[t - nx, lo:hi], p + t - nx
            if t2 < 0:
                xb, cb = yb, -1
            elif t2 < nx:
                st = xoff[b] + t2 * size
                xb, cb = xvals[st:st + size], xcols[xptr[b] + t2]
            else:
                xb, cb = r_t[t2 - nx, lo:hi], p + t2 - nx
            c00 = 0.0
            c01 = 0.0
            c10 = 0.0
            c11 = 0.0
            if t < 0:
                s00 = 0.0
                s01 = 0.0
                s11 = 0.0
                for u in range(size):
                    s00 += a0[u] * a0[u]
                    s01 += a0[u] * a1[u]
                    s11 += a1[u] * a1[u]
                    c00 += a0[u] * xa[u]
                    c01 += a1[u] * xa[u]
                    c10 += a0[u] * xb[u]
                    c11 += a1[u] * xb[u]
                zz[s, 0] += s00
                zz[s, 1] += s01
                zz[s, 2] += s11
                zy[s, 0] += c00
                zy[s, 1] += c01
            else:
                for u in range(size):
                    c00 += a0[u] * xa[u]
                    c01 += a1[u] * xa[u]
                    c10 += a0[u] * xb[u]
                    c11 += a1[u] * xb[u]
                zx[s, 0, ca] += c00
                zx[s, 1, ca] += c01
            if t2 > t:
                zx[s, 0, cb] += c10
                zx[s, 1, cb] += c11
            t += 2
    # each flight's 2x2 system (ridged) solved as _solve2 does, without its allocations,
    # and eliminated from W'W, W'y
    a = xtx.copy()
    rhs = xty.copy()
    g_zx = np.empty((n_seg, 2, q))
    g_zy = np.empty((n_seg, 2))
    for s in range(n_seg):
        ridge = 1e-12 * (zz[s, 0] + zz[s, 2])
        a00, a01, a10, a11 = zz[s, 0] + ridge, zz[s, 1], zz[s, 1], zz[s, 2] + ridge
        swap = abs(a10) > abs(a00)
        if swap:
            a00, a01, a10, a11 = a10, a11, a00, a01
        if a00 == 0.0:
            raise np.linalg.LinAlgError("Singular matrix")   # numpy's error and message
        lo_ = a10 / a00
        u11 = a11 - lo_ * a01
        if u11 == 0.0:
            raise np.linalg.LinAlgError("Singular matrix")
        for j in range(q + 1):
            r0 = zx[s, 0, j] if j < q else zy[s, 0]
            r1 = zx[s, 1, j] if j < q else zy[s, 1]
            b0, b1 = (r1, r0) if swap else (r0, r1)
            x1 = (b1 - lo_ * b0) / u11
            x0 = (b0 - a01 * x1) / a00
            if j < q:
                g_zx[s, 0, j] = x0
                g_zx[s, 1, j] = x1
            else:
                g_zy[s, 0] = x0
                g_zy[s, 1] = x1
        for i in range(q):
            zi0, zi1 = zx[s, 0, i], zx[s, 1, i]
            for j in range(q):
                a[i, j] -= zi0 * g_zx[s, 0, j] + zi1 * g_zx[s, 1, j]
            rhs[i] -= zi0 * g_zy[s, 0] + zi1 * g_zy[s, 1]
    beta, gamma = _beta_gamma(a, rhs, scale, g_zx, g_zy)
    # the residual, block by block: the free response's fit and the columns' taken off y two
    # at a time, the squares summed with the last two
    res = np.empty(longest)
    rss = 0.0
    for b in range(bounds.size - 1):
        lo, hi = bounds[b], bounds[b + 1]
        size = hi - lo
        s = seg[lo]
        yb = y[lo:hi]
        rb = res[:size]
        nx = xptr[b + 1] - xptr[b]
        tot = nx + m
        acc = 0.0
        t = -2              # -2, -1: the free response's two columns
        while t < tot:
            t2 = t + 1
            if t < 0:
                xa, ba = z0[lo:hi], gamma[s, 0]
            elif t < nx:
                st = xoff[b] + t * size
                xa, ba = xvals[st:st + size], beta[xcols[xptr[b] + t]]
            else:
                xa, ba = r_t[t - nx, lo:hi], beta[p + t - nx]
            if t2 < 0:
                xb, bb = z1[lo:hi], gamma[s, 1]
            elif t2 >= tot:
                xb, bb = xa, 0.0
            elif t2 < nx:
                st = xoff[b] + t2 * size
                xb, bb = xvals[st:st + size], beta[xcols[xptr[b] + t2]]
            else:
                xb, bb = r_t[t2 - nx, lo:hi], beta[p + t2 - nx]
            # (separate loops for y and rb, so that each vectorises)
            if t + 2 < tot:
                if t < 0:
                    for u in range(size):
                        rb[u] = yb[u] - (ba * xa[u] + bb * xb[u])
                else:
                    for u in range(size):
                        rb[u] -= ba * xa[u] + bb * xb[u]
            elif t < 0:
                for u in range(size):
                    r = yb[u] - (ba * xa[u] + bb * xb[u])
                    acc += r * r
            else:
                for u in range(size):
                    r = rb[u] - (ba * xa[u] + bb * xb[u])
                    acc += r * r
            t += 2
        rss += acc
    return rss, beta, gamma


@numba.njit(cache=True, nogil=True)
def solve_flights_rows(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray,
                       values: np.ndarray, p: int, r: np.ndarray, tau: np.ndarray,
                       seg: np.ndarray, next_: np.ndarray, n_seg: int, f_hz: float,
                       sigma: float, dt: float, xtx: np.ndarray, xty: np.ndarray,
                       scale: np.ndarray
                       ) -> tuple[float, np.ndarray, np.ndarray]:  # pragma: no cover
    """:func:`solve_flights` sample by sample, the run-wide columns ``X`` stored by rows
    (``indptr``, ``indices``, ``values``; ``p`` columns) and ``r`` dense: no block layout,
    whose dense rows per block take several times the rows' memory (a whole run's model,
    solved once or twice).  ``(rss, beta, gamma)`` of the run model at ``(f_s, sigma)`` in
    one call (:meth:`rattle_lab.detect._flights._Model.solve`'s steps: each flight's free response
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
    beta, gamma = _beta_gamma(a, b, scale, g_zx, g_zy)
    rss = _residual_z(y, indptr, indices, values, p, r, beta, z, seg, gamma)
    return rss, beta, gamma


#: Most samples in one block of :func:`added_sums` (a flight, or part of a long one).
BLOCK = 512


@numba.njit(cache=True, nogil=True, fastmath={"reassoc", "contract"})
def added_sums(y: np.ndarray, z: np.ndarray, seg: np.ndarray, n_seg: int, bounds: np.ndarray,
               xptr: np.ndarray, xcols: np.ndarray, xoff: np.ndarray, xvals: np.ndarray,
               n_x: int, r: np.ndarray, last: np.ndarray, dt: np.ndarray, k_run: np.ndarray,
               dt_step: float, d: np.ndarray, gaps: np.ndarray, f_hz: np.ndarray, s: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """What new dense columns ``R`` add to a model whose other parts are fixed, in one pass
    over the samples: ``(R'R, R'X, R'y, Z_s'R_s)``.

    ``R`` is the columns ``r`` given followed by two columns (real, imaginary) per ringing
    mode ``(f_hz[j], s[j])``, :func:`tail_columns`'s, generated here and never stored whole:
    the same recursion over the impacts and the same rows evaluated exactly (``k_run``,
    :func:`tail_runs`); a row ``k`` rotations after one is that row's value times
    ``step^k``, from a table of the powers formed by the same repeated products (rows
    independent of each other, at the same rounding error; a run of them is one vectorised
    loop).  The samples go in blocks within one flight
    (:data:`BLOCK`).  ``X`` (the model's run-wide columns) comes block by block, only its
    columns that are nonzero in the block, each as a contiguous row of the block's values;
    a block's new columns are formed into rows alike, and every sum is a dot product of two
    rows, two new columns at a time (compiled with reassociation: vectorised, each sum
    rounded in another order than sample after sample, ~1e-16 relative); the dense columns
    come as rows of ``R'``.

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
    last, dt, k_run, dt_step, d, gaps : ndarray, ndarray, ndarray, float, ndarray, ndarray
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
    # the powers' table, real and imaginary parts apart (the rows' products in real
    # arithmetic, (a + ib)(c + id) = (ac - bd) + i(ad + bc) as numba's complex product)
    pw_re = np.empty((n_modes, REANCHOR + 1))
    pw_im = np.empty((n_modes, REANCHOR + 1))
    for j in range(n_modes):
        acc = 1.0 + 0j
        pw_re[j, 0] = 1.0
        pw_im[j, 0] = 0.0
        for k in range(1, REANCHOR + 1):
            acc = acc * steps[j]
            pw_re[j, k] = acc.real
            pw_im[j, k] = acc.imag
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
    for b in range(bounds.size - 1):
        lo, hi = bounds[b], bounds[b + 1]
        size = hi - lo
        for u in range(size):
            i = lo + u
            z0[u] = z[i].real
            z1[u] = z[i].imag
            for a in range(m_r):
                buf[a, u] = r[i, a]
        for j in range(n_modes):
            # runs of rotations after one exact evaluation: each row the run's start
            # times a power from the table (rows independent of each other: vectorised)
            row_re = buf[m_r + 2 * j]
            row_im = buf[m_r + 2 * j + 1]
            ea = e[j]
            u = 0
            while u < size:
                k = k_run[lo + u]
                if k < 0:
                    row_re[u] = 0.0
                    row_im[u] = 0.0
                    u += 1
                    continue
                i = lo + u
                if k == 0:
                    ea = np.exp(poles[j] * dt[i])
                v = u + 1
                while v < size and k_run[lo + v] == k + (v - u):
                    v += 1
                cc = c[j, last[i]]
                c_re = cc.real
                c_im = cc.imag
                e_re = ea.real
                e_im = ea.imag
                n_run = v - u
                p_re = pw_re[j, k:k + n_run]
                p_im = pw_im[j, k:k + n_run]
                o_re = row_re[u:v]
                o_im = row_im[u:v]
                for q in range(n_run):
                    a_re = p_re[q]
                    a_im = p_im[q]
                    t_re = e_re * a_re - e_im * a_im
                    t_im = e_re * a_im + e_im * a_re
                    o_re[q] = c_re * t_re - c_im * t_im
                    o_im[q] = c_re * t_im + c_im * t_re
                u = v
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
def carried_gains(y: np.ndarray, z: np.ndarray, seg: np.ndarray, n_seg: int,
                  bounds: np.ndarray, xptr: np.ndarray, xcols: np.ndarray, xoff: np.ndarray,
                  xvals: np.ndarray, n_x: int, r: np.ndarray, last: np.ndarray, dt: np.ndarray,
                  k_run: np.ndarray, dt_step: float, d: np.ndarray, gaps: np.ndarray,
                  f_hz: np.ndarray, s: np.ndarray, h: np.ndarray, gx: np.ndarray,
                  gy: np.ndarray, beta: np.ndarray, a_inv: np.ndarray
                  ) -> np.ndarray:  # pragma: no cover - compiled
    """How much each of several sets of new columns lowers a fixed model's residual, in one
    call: per row ``c`` of ``f_hz`` and ``s``, :func:`added_sums` (the columns ``r`` and the
    ringing modes ``(f_hz[c, j], s[c, j])`` carried on), :func:`eliminate_free`, and the
    gain ``c' S^-1 c`` of the Schur complement (``c = b_R - A_RX beta``,
    ``S = A_RR - A_RX A^-1 A_XR``, solved by least squares, ``rcond = 1e-12``).

    The campaign's mode search evaluates many candidate modes at one ``(f_s, sigma)``:
    one compiled call per run and batch of candidates rather than one from Python each.

    Parameters
    ----------
    y, z, seg, n_seg, bounds, xptr, xcols, xoff, xvals, n_x, r, last, dt, k_run, dt_step, d, gaps
        As :func:`added_sums` takes them.
    f_hz, s : ndarray
        The candidates' modes, one candidate a row (``n_cand x n_modes``, C order).
    h, gx, gy : ndarray
        The flights' factors, as :func:`eliminate_free` takes them.
    beta : ndarray
        The model's run-wide coefficients without the new columns.
    a_inv : ndarray
        The inverse of its normal matrix with the free responses eliminated.

    Returns
    -------
    ndarray
        Each candidate's gain (the residual sum of squares without the new columns minus
        that with them).
    """
    n_cand = f_hz.shape[0]
    out = np.empty(n_cand)
    for c in range(n_cand):
        rr, rx, ry, zr = added_sums(y, z, seg, n_seg, bounds, xptr, xcols, xoff, xvals, n_x,
                                    r, last, dt, k_run, dt_step, d, gaps,
                                    np.ascontiguousarray(f_hz[c]), np.ascontiguousarray(s[c]))
        a_rr, a_rx, b_r = eliminate_free(rr, rx, ry, zr, h, gx, gy)
        cc = b_r - np.dot(a_rx, beta)
        schur = a_rr - np.dot(np.dot(a_rx, a_inv), np.ascontiguousarray(a_rx.T))
        sol = np.linalg.lstsq(schur, cc, rcond=1e-12)[0]
        out[c] = np.dot(cc, sol)
    return out


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
def tail_runs(last: np.ndarray, next_: np.ndarray) -> np.ndarray:  # pragma: no cover
    """Per sample, how many rotations the carried tails take from their last exact
    evaluation: 0 where a sample is evaluated exactly (it is not its predecessor's next
    sample after the same impact, or :data:`REANCHOR` rotations have passed), -1
    before any impact.  It depends on the samples and the impacts only, not on the modes:
    formed once per model, it is what :func:`tail_columns` and :func:`added_sums` follow."""
    k_run = np.empty(last.size, dtype=np.int64)
    run = REANCHOR
    for i in range(last.size):
        li = last[i]
        if li < 0:
            run = REANCHOR
            k_run[i] = -1
        elif i > 0 and next_[i] and li == last[i - 1] and run < REANCHOR:
            run += 1
            k_run[i] = run
        else:
            run = 0
            k_run[i] = 0
    return k_run


@numba.njit(cache=True, nogil=True)
def tail_columns(last: np.ndarray, dt: np.ndarray, k_run: np.ndarray, dt_step: float,
                 d: np.ndarray, gaps: np.ndarray, f_hz: float, s: float
                 ) -> np.ndarray:  # pragma: no cover - compiled
    """``sum_{i <= last} d_i exp(p (t - t_i))``, ``p = -s + 2 pi i f``, as (real, imaginary)
    columns: ``C_k = C_{k-1} exp(p gap_k) + d_k`` over the impacts, then each sample
    ``C_last exp(p dt)`` (rotated from its predecessor where :func:`tail_runs` says so, as
    in :func:`free_response`); zero before the first impact."""
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
    e = 0j
    for i in range(last.size):
        k = k_run[i]
        if k < 0:
            continue
        if k > 0:
            e = e * step
        else:
            e = np.exp(pole * dt[i])
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



@numba.njit(cache=True, nogil=True)
def forced_rows(t_s: np.ndarray, c: np.ndarray, s: np.ndarray, knots: np.ndarray,
                j: np.ndarray, new_index: np.ndarray, keep: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """The forced columns' nonzero entries by rows (CSR ``indptr``, ``indices``, ``values``).

    Sample ``i`` lies in knot interval ``j[i]``: its columns are ``1`` (column 0) and the
    hats ``h_left``, ``h_right`` of knots ``j`` and ``j + 1`` times ``cos wt`` and ``sin wt``
    (columns ``1 + 2 j`` .. ``4 + 2 j``), each hat computed as :func:`numpy.interp` computes
    it; ``c``, ``s`` the cosine and sine (computed by the caller, as the dense path computes
    them).  Kept columns only (``keep``), renumbered by ``new_index``; exact zeros left out.
    Two passes (count, then fill): nothing larger than the result.
    """
    n = t_s.size
    indptr = np.empty(n + 1, np.int64)
    indptr[0] = 0
    for fill in range(2):
        if fill:
            indices = np.empty(indptr[n], np.int64)
            values = np.empty(indptr[n])
        m = 0
        for i in range(n):
            k = j[i]
            t = t_s[i]
            if t >= knots[knots.size - 1]:
                h_left, h_right = 0.0, 1.0
            elif t == knots[k]:
                h_left, h_right = 1.0, 0.0
            else:
                width = knots[k + 1] - knots[k]
                off = t - knots[k]
                h_left = ((0.0 - 1.0) / width) * off + 1.0
                h_right = ((1.0 - 0.0) / width) * off + 0.0
            for q in range(5):
                if q == 0:
                    col, v = 0, 1.0
                elif q == 1:
                    col, v = 1 + 2 * k, h_left * c[i]
                elif q == 2:
                    col, v = 2 + 2 * k, h_left * s[i]
                elif q == 3:
                    col, v = 3 + 2 * k, h_right * c[i]
                else:
                    col, v = 4 + 2 * k, h_right * s[i]
                if v != 0.0 and keep[col]:
                    if fill:
                        indices[m] = new_index[col]
                        values[m] = v
                    m += 1
            if not fill:
                indptr[i + 1] = m
    return indptr, indices, values
