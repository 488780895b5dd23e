"""Compiled inner loops of the flight model (:mod:`rattle_lab.detect._flights`) and of the
local fits either side of an impact (:mod:`rattle_lab.detect._local_fits`).

The variable-projection searches evaluate the run model thousands of times for new
``(f_s, sigma)`` or ringing poles; each evaluation touches every sample of the flights
used.  These loops do it in one pass with no temporaries.  The run-wide columns come in
two parts: the forced response's, hat functions in time that are zero on all but a few
columns of each row (stored by rows: ``indptr``, ``indices``, ``values``), and a few dense
columns ``r`` (the ringing).  :func:`free_sums` forms the per-flight sums of the free
response's normal equations, :func:`residual_ss` the residual's sum of squares,
:func:`sparse_cross` the products of the two parts, :func:`added_sums` what new dense
columns add to a model whose other parts are fixed, and :func:`tail_columns` the ringing
carried on over later flights.  numba compiles them on first use and caches them on disk.
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
def free_sums(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
              p: int, r: np.ndarray, tau: np.ndarray, seg: np.ndarray, next_: np.ndarray,
              n_seg: int, f_hz: float, sigma: float, dt: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # pragma: no cover - compiled
    """Per flight ``s``: ``Z_s'Z_s`` (2x2), ``Z_s'[X_s R_s]`` (2 x (p + m)) and ``Z_s'y_s``,
    where ``Z`` is the fundamental's free response ``exp(-sigma tau) [cos, sin](2 pi f tau)``
    (see :func:`free_response`)."""
    n, m = r.shape
    zz = np.zeros((n_seg, 2, 2))
    zx = np.zeros((n_seg, 2, p + m))
    zy = np.zeros((n_seg, 2))
    z = free_response(tau, next_, f_hz, sigma, dt)
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
def residual_ss(y: np.ndarray, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
                p: int, r: np.ndarray, beta: np.ndarray, tau: np.ndarray, seg: np.ndarray,
                next_: np.ndarray, gamma: np.ndarray, f_hz: float, sigma: float, dt: float
                ) -> float:  # pragma: no cover - compiled
    """``sum (y - [X R] beta - Z gamma_seg)^2``, ``Z`` as in :func:`free_sums`."""
    n, m = r.shape
    z = free_response(tau, next_, f_hz, sigma, dt)
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


# --- compiled local fits (detect/_local_fits): the design and its least squares -----------

@numba.njit(cache=True, nogil=True)
def local_design(k: np.ndarray, k0: float, scale: float, degree: int, w: float,
                 periodic: bool) -> np.ndarray:  # pragma: no cover - compiled
    """The design matrix of :class:`rattle_lab.detect._local_fits._LocalFit` at samples ``k``:
    ``[u^degree .. u^0]`` (polynomial), or ``[1, u^j cos(w tau), u^j sin(w tau)]_j``
    (``periodic``), ``tau = k - k0``, ``u = tau / scale``."""
    n = k.size
    if not periodic:
        out = np.empty((n, degree + 1))
        for i in range(n):
            u = (k[i] - k0) / scale
            x = 1.0
            for j in range(degree, -1, -1):
                out[i, j] = x
                x *= u
        return out
    out = np.empty((n, 1 + 2 * (degree + 1)))
    for i in range(n):
        tau = k[i] - k0
        u = tau / scale
        c, s_ = math.cos(w * tau), math.sin(w * tau)
        out[i, 0] = 1.0
        x = 1.0
        for j in range(degree + 1):
            out[i, 1 + 2 * j] = x * c
            out[i, 2 + 2 * j] = x * s_
            x *= u
    return out


@numba.njit(cache=True, nogil=True)
def local_lstsq(k: np.ndarray, v: np.ndarray, k0: float, scale: float, degree: int, w: float,
                periodic: bool) -> np.ndarray:  # pragma: no cover - compiled
    """Least-squares coefficients of :func:`local_design` for ``v`` (LAPACK ``gelsd``, as
    :func:`numpy.linalg.lstsq`)."""
    a = local_design(k, k0, scale, degree, w, periodic)
    rcond = np.finfo(np.float64).eps * max(a.shape[0], a.shape[1])   # numpy's rcond=None
    return np.linalg.lstsq(a, v, rcond)[0]


@numba.njit(cache=True, nogil=True)
def local_eval(k: np.ndarray, k0: float, scale: float, degree: int, w: float, periodic: bool,
               coef: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The fit with coefficients ``coef`` at samples ``k``."""
    return local_design(k, k0, scale, degree, w, periodic) @ coef
