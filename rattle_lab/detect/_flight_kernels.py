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
columns add to a model whose other parts are fixed, and :func:`tail_columns` the ringing
carried on over later flights.  numba compiles them on first use and caches them on disk.
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


@numba.njit(cache=True, nogil=True)
def added_sums(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
               p: int, r: np.ndarray, z: np.ndarray, seg: np.ndarray, n_seg: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover
    """What dense columns ``r`` add to a model whose other parts are fixed, in one pass:
    ``(R'R, R'X, R'y, Z_s'R_s)`` (``X`` stored by rows, ``p`` columns; ``z`` the free
    response of :func:`free_response`, per flight ``s``)."""
    n, m = r.shape
    rr = np.zeros((m, m))
    rx = np.zeros((m, p))
    ry = np.zeros(m)
    zr = np.zeros((n_seg, 2, m))
    for i in range(n):
        s = seg[i]
        z0 = z[i].real
        z1 = z[i].imag
        for a in range(m):
            ra = r[i, a]
            ry[a] += ra * y[i]
            zr[s, 0, a] += z0 * ra
            zr[s, 1, a] += z1 * ra
            for b in range(a, m):
                rr[a, b] += ra * r[i, b]
            for k in range(indptr[i], indptr[i + 1]):
                rx[a, indices[k]] += ra * values[k]
    for a in range(m):
        for b in range(a):
            rr[a, b] = rr[b, a]
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

