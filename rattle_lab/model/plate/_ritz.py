"""Rayleigh-Ritz modes of a rectangular plate with products of beam functions.

The deflection is ``W(xi, eta) = sum_ij c_ij X_i(xi) Y_j(eta)`` with ``xi = x/a``,
``eta = y/b`` and ``X_i``, ``Y_j`` the eigenfunctions of beams with the plate's
edge conditions (:mod:`rattle_lab.model.plate._beam`).  With ``rho_a = a/b`` the strain
and kinetic energies of the thin plate give ``K c = lambda**2 M c`` with

    K = E2x (x) E0y + rho_a**4 E0x (x) E2y
        + nu rho_a**2 (Cx (x) Cy^T + Cx^T (x) Cy) + 2 (1 - nu) rho_a**2 E1x (x) E1y,
    M = E0x (x) E0y,

where ``Ek = int phi_p^(k) phi_q^(k)``, ``C = int phi_p'' phi_q`` and ``(x)`` is the
Kronecker product; ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25).  The
generalized symmetric eigenproblem is solved with :func:`scipy.linalg.eigh`, split
into the symmetry classes of the terms where opposite edges are alike.

Free edges
    Products of beam functions converge very slowly where an edge is free: every
    free-free beam function has zero second and third derivatives at the free end,
    whereas the plate's free edge has ``W_xx = -nu W_yy != 0``; with 12 x 12 terms
    ``lambda`` was 0.4-0.45 % high (SFSF, CFCF, CFFF) and 15 x 15 terms gained only
    7.7e-4.  For a plate with a free edge the basis is therefore polynomial in both
    directions:
    ``s^a (1 - s)^b P_k(2 s - 1)`` (``a, b`` = 2, 1, 0 for a clamped, simply
    supported, free end: only the geometric conditions are imposed), made
    orthonormal on [0, 1]; it spans every smooth admissible function and
    converges exponentially (beam functions along a clamped direction would need
    ~40 terms for 1e-6).  Plates without a free edge keep beam functions (exact
    sines for S-S).  ``lambda`` converges from above either way.

Basis size
    By default (``n_terms=None``) the number of terms is chosen by a convergence
    check: it grows by :data:`N_TERMS_STEP` per direction from
    :data:`DEFAULT_N_TERMS` until the estimated error of the requested
    ``lambda`` is at most :data:`CONVERGED_RTOL` (relative), so that every edge
    set is within 1e-4 of its converged value (the tests compare with Leissa's values and a
    high-order solution).
"""

from __future__ import annotations

import math

import numpy as np

from rattle_lab.exceptions import ConvergenceError, ParameterError
from ._bases import PolyBasis, plate_bases
from ._beam import BeamBasis, beam_basis, gauss_points
from ._checks import check_aspect_ratio, check_count
from ._edges import check_edges
from ._modes import PlateModes

#: First size (terms per side) of the convergence check, and the size of every check
#: step's smallest problem.  Fixed at 12 x 12 beam functions, free-edge plates were
#: 0.4-0.45 % high; see the module docstring.
DEFAULT_N_TERMS = 12

#: Terms added per direction between two sizes of the convergence check.
N_TERMS_STEP = 4
#: The basis has converged when the estimated error of the requested lambda
#: (relative to max(lambda, 1)) is at most this (see :func:`_converged_size`).
CONVERGED_RTOL = 1e-5
#: Most terms per direction the convergence check tries.
MAX_N_TERMS = 40

#: A mode's centre is a node when |W(centre)| <= NODE_RTOL * max |W|.  Symmetry makes
#: such centres vanish to rounding (~1e-14); 1e-6 leaves room for that.
NODE_RTOL = 1e-6

#: Relative gap of lambda**2 below which eigenvalues count as degenerate (relative to the
#: pair's own lambda**2; the eigensolver's rounding, relative to the largest eigenvalue of
#: the basis, is added: :func:`_rotate_degenerate`).
DEGENERATE_RTOL = 1e-8

_GRID_SEARCH = 101


def _to_beam_terms(basis: BeamBasis | PolyBasis) -> np.ndarray:
    """Matrix mapping coefficients on ``basis`` to those on as many beam functions.

    Beam functions are orthonormal on [0, 1], so the projection is ``int phi_beam phi``.
    It names a mode's dominant term (``m, n``) in beam-function indices whatever the
    basis.
    """
    if isinstance(basis, BeamBasis):
        return np.eye(len(basis))
    s, w = gauss_points()
    beams = beam_basis(basis.left, basis.right, len(basis)).evaluate(s)
    return (beams * w) @ basis.evaluate(s).T


def _gram(basis: BeamBasis | PolyBasis) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    s, w = gauss_points()
    p0 = basis.evaluate(s, 0)
    p1 = basis.evaluate(s, 1)
    p2 = basis.evaluate(s, 2)
    e0 = (p0 * w) @ p0.T
    e1 = (p1 * w) @ p1.T
    e2 = (p2 * w) @ p2.T
    c = (p2 * w) @ p0.T  # c[p, q] = int phi_p'' phi_q
    mean = p0 @ w  # int phi_p
    return e0, e1, e2, c, mean


def _parities(basis: BeamBasis | PolyBasis) -> np.ndarray:
    """+1 / -1 for functions symmetric / antisymmetric about s = 1/2; 0 when the ends differ.

    Beam functions with equal end conditions are exactly (anti)symmetric, so the sign
    of ``sum phi(s) phi(1 - s)`` at a few points identifies the parity.
    """
    if basis.left != basis.right:
        return np.zeros(len(basis))
    s = np.array([0.05, 0.17, 0.31, 0.43])
    return np.sign(np.sum(basis.evaluate(s) * basis.evaluate(1.0 - s), axis=1))


def _solve_by_parity(K: np.ndarray, M: np.ndarray, px: np.ndarray,
                     py: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Solve ``K c = Lambda M c`` block by block in the symmetry classes of the terms.

    Terms of different parity in x (or y) do not couple when the plate is symmetric in
    that direction, so K and M are block diagonal in the classes (px_i, py_j).  Solving
    the blocks separately (``scipy.linalg.eigh`` each) is exact, gives modes of pure
    symmetry (centre nodes exactly zero) and keeps the dense problems small.
    """
    import scipy.linalg

    from threadpoolctl import threadpool_limits

    labels = [(a, b) for a in px for b in py]  # row-major order of the terms (i, j)
    n = K.shape[0]
    all_vals, all_vecs = [], []
    # One BLAS thread: these blocks (a few hundred unknowns) gain nothing from threads,
    # and on a busy machine oversubscribed threads made them 100x slower.
    with threadpool_limits(limits=1, user_api="blas"):
        for label in sorted(set(labels)):
            idx = np.array([k for k, lab in enumerate(labels) if lab == label])
            vals, vecs = scipy.linalg.eigh(K[np.ix_(idx, idx)], M[np.ix_(idx, idx)])
            full = np.zeros((n, vals.size))
            full[idx, :] = vecs
            all_vals.append(vals)
            all_vecs.append(full)
    vals = np.concatenate(all_vals)
    vecs = np.concatenate(all_vecs, axis=1)
    order = np.argsort(vals, kind="stable")
    return vals[order], vecs[:, order]


def _n_terms_pair(n_terms: int | tuple[int, int]) -> tuple[int, int]:
    if isinstance(n_terms, tuple):
        if len(n_terms) != 2:
            raise ParameterError(f"`n_terms` must be an int or a pair of ints, was {n_terms!r}")
        return check_count("n_terms", n_terms[0]), check_count("n_terms", n_terms[1])
    k = check_count("n_terms", n_terms)
    return k, k


def _rotate_degenerate(vals: np.ndarray, vecs: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Make eigenvectors of (numerically) equal eigenvalues deterministic.

    Within a degenerate cluster the eigensolver may return any orthonormal mix (e.g.
    the (2,1) and (1,2) modes of a square clamped plate).  Rotate the cluster so that it
    diagonalises ``diag(weight)`` (weight = position of each term (i, j) in the
    row-major order of the coefficients): the modes then separate into the purest
    combinations, ordered by their dominant term, e.g. (1, 2) before (2, 1).
    """
    vecs = vecs.copy()
    # the eigensolver's rounding is relative to the largest eigenvalue of the basis (it
    # grows like the basis size to the 8th power); a gap relative to that largest one, as
    # this once was, made modes of a 36-term basis 1e3 apart in lambda**2 one "cluster" and
    # rotated them into each other (mode 3 of the CFCF thesis plate lost its excitation)
    noise = 1e3 * np.finfo(float).eps * max(float(np.max(np.abs(vals))), 1.0)
    start = 0
    n = vals.size
    while start < n:
        stop = start + 1
        while stop < n and vals[stop] - vals[stop - 1] <= (
                DEGENERATE_RTOL * max(abs(float(vals[stop])), 1.0) + noise):
            stop += 1
        if stop - start > 1:
            block = vecs[:, start:stop]
            s = block.T @ (weight[:, None] * block)
            _, rot = np.linalg.eigh(0.5 * (s + s.T))
            vecs[:, start:stop] = block @ rot
        start = stop
    return vecs


def _refine_max(c: np.ndarray, bx: BeamBasis | PolyBasis, by: BeamBasis | PolyBasis, xi0: float, eta0: float,
                sign: float) -> tuple[float, float, float]:
    """Local maximum of ``sign * W`` near (xi0, eta0); returns (xi, eta, W)."""
    from scipy.optimize import minimize

    def neg(p: np.ndarray) -> tuple[float, np.ndarray]:
        xv = np.array([p[0]])
        yv = np.array([p[1]])
        X0, X1 = bx.evaluate(xv, 0)[:, 0], bx.evaluate(xv, 1)[:, 0]
        Y0, Y1 = by.evaluate(yv, 0)[:, 0], by.evaluate(yv, 1)[:, 0]
        val = X0 @ c @ Y0
        grad = np.array([X1 @ c @ Y0, X0 @ c @ Y1])
        return -sign * float(val), -sign * grad

    res = minimize(neg, np.array([xi0, eta0]), jac=True, method="L-BFGS-B",
                   bounds=[(0.0, 1.0), (0.0, 1.0)], options={"ftol": 1e-15, "gtol": 1e-12})
    return float(res.x[0]), float(res.x[1]), -sign * float(res.fun)


def _solve(r: float, edges: str, nu: float, nx: int, ny: int) -> tuple[
        BeamBasis | PolyBasis, BeamBasis | PolyBasis, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Assemble and solve the Ritz eigenproblem with ``nx`` x ``ny`` terms."""
    bx, by = plate_bases(edges, nx, ny)
    e0x, e1x, e2x, cx, mx = _gram(bx)
    e0y, e1y, e2y, cy, my = _gram(by)
    ra2 = (1.0 / r) ** 2
    K = (np.kron(e2x, e0y) + ra2**2 * np.kron(e0x, e2y)
         + nu * ra2 * (np.kron(cx, cy.T) + np.kron(cx.T, cy))
         + 2.0 * (1.0 - nu) * ra2 * np.kron(e1x, e1y))
    K = 0.5 * (K + K.T)
    M = np.kron(e0x, e0y)
    M = 0.5 * (M + M.T)
    vals, vecs = _solve_by_parity(K, M, _parities(bx), _parities(by))
    scale = max(float(np.max(np.abs(vals))), 1.0)
    if vals[0] < -1e-9 * scale:
        raise ConvergenceError(f"Ritz stiffness matrix is not positive semi-definite: eigenvalue {vals[0]:.3e}")
    return bx, by, vals, vecs, mx, my, e0x, e0y


def _converged_size(r: float, edges: str, nu: float, n_modes: int) -> tuple[int, int]:
    """Smallest size (from DEFAULT_N_TERMS in steps of N_TERMS_STEP per direction) at which
    the estimated error of the first ``n_modes`` lambda is at most CONVERGED_RTOL.

    Ritz values decrease monotonically with the size.  From the last two changes
    ``d_k``, ``d_(k+1)`` (relative to ``max(lambda, 1)``) with ratio ``q < 1`` the
    remaining error is estimated as the geometric tail ``d_(k+1) q / (1 - q)``.
    Exponential convergence (smooth edges) makes that an over-estimate; clamped-free
    corners make the solution singular and the convergence algebraic (CFCF:
    changes fall like N^-5), where the geometric tail under-estimates by a factor
    of about two, well inside the factor ten between CONVERGED_RTOL and the 1e-4
    target.
    """
    n = DEFAULT_N_TERMS

    def lam(k: int) -> np.ndarray:
        return np.sqrt(np.clip(_solve(r, edges, nu, k, k)[2][:n_modes], 0.0, None))

    prev = lam(n)
    d_prev: np.ndarray | None = None
    while n + N_TERMS_STEP <= MAX_N_TERMS:
        n += N_TERMS_STEP
        cur = lam(n)
        d = np.abs(cur - prev) / np.maximum(prev, 1.0)
        if d_prev is not None:
            q = d / np.maximum(d_prev, 1e-300)
            # a change at the rounding level of the eigensolver (~1e-9 relative for
            # these Gram matrices) is converged whatever its ratio
            done = (d <= 1e-9) | ((q < 0.9) & (d * q / (1.0 - q) <= CONVERGED_RTOL))
            if np.all(done):
                return n, n
        prev, d_prev = cur, d
    raise ConvergenceError(
        f"Ritz modes of {edges} (b/a = {r}) did not converge to {CONVERGED_RTOL:g} "
        f"with {MAX_N_TERMS} terms per side; pass `n_terms` to choose the size")


def ritz_modes(aspect_ratio: float, edges: str, *, nu: float = 0.3, n_modes: int = 6,
               n_terms: int | tuple[int, int] | None = None, n_grid: int = 41) -> PlateModes:
    """First modes of a thin rectangular plate by Rayleigh-Ritz with beam functions.

    Parameters
    ----------
    aspect_ratio : float
        ``b/a``, > 0.  ``lambda`` is scaled with ``a`` (eq. 2.25).
    edges : str
        Four letters C (clamped), S (simply supported), F (free) for the edges
        y=0, x=a, y=b, x=0 in that order; ``"CFCF"`` clamps the two sides of length
        ``a`` (Table 2.1), ``"CCCC"`` is Table 2.2.
    nu : float
        Poisson's ratio, -1 < nu < 0.5 (enters only through free edges; Leissa's
        free-edge values are for 0.3).
    n_modes : int
        Number of modes returned, 1 <= n_modes <= number of terms.
    n_terms : int or (int, int) or None
        Basis functions along x and along y (rigid-body modes of free ends
        included): beam functions, or orthonormal polynomials along a direction
        with a free end (module docstring).  None (default): chosen by the
        convergence check (:data:`CONVERGED_RTOL`); the size used is
        ``PlateModes.n_terms``.
    n_grid : int
        Points per side of the grid of :attr:`PlateModes.shapes`, >= 2.

    Returns
    -------
    PlateModes
        ``lam`` (eq. 2.25), ``Q1``, ``Q2`` (eq. 2.18, 2.19) with ``W = 1`` at the
        plate centre, or at max ``|W|`` when the centre is a node (as the thesis's
        tables), and the normalised shapes on the grid.

    Raises
    ------
    ParameterError
        If an argument is out of range.
    ConvergenceError
        If the stiffness matrix is not positive semi-definite to rounding.

    Examples
    --------
    >>> import numpy as np
    >>> modes = ritz_modes(1.0, "CCCC", n_modes=1)
    >>> bool(np.isclose(modes.lam[0], 35.99, rtol=1e-3))
    True
    """
    r = check_aspect_ratio(aspect_ratio)
    edges = check_edges(edges)
    nu_f = float(nu)
    if not (-1.0 < nu_f < 0.5):
        raise ParameterError(f"`nu` must satisfy -1 < nu < 0.5, was {nu}")
    nx, ny = _n_terms_pair(DEFAULT_N_TERMS if n_terms is None else n_terms)
    n_modes = check_count("n_modes", n_modes)
    if n_modes > nx * ny:
        raise ParameterError(f"`n_modes` must be <= n_terms_x * n_terms_y = {nx * ny}, was {n_modes}")
    n_grid = check_count("n_grid", n_grid, minimum=2)

    if n_terms is None:
        nx, ny = _converged_size(r, edges, nu_f, n_modes)
    bx, by, vals, vecs, mx, my, e0x, e0y = _solve(r, edges, nu_f, nx, ny)
    weight = np.arange(nx * ny, dtype=float)
    vecs = _rotate_degenerate(vals, vecs, weight)

    # Rigid-body modes give lambda**2 = 0 to rounding (checked above); clip that rounding.
    lam = np.sqrt(np.clip(vals[:n_modes], 0.0, None))

    to_bx, to_by = _to_beam_terms(bx), _to_beam_terms(by)
    xi = np.linspace(0.0, 1.0, n_grid)
    eta = np.linspace(0.0, 1.0, n_grid)
    gx = np.linspace(0.0, 1.0, _GRID_SEARCH)
    Xs, Ys = bx.evaluate(gx), by.evaluate(gx)
    Xg, Yg = bx.evaluate(xi), by.evaluate(eta)
    Xc, Yc = bx.evaluate(np.array([0.5]))[:, 0], by.evaluate(np.array([0.5]))[:, 0]

    out_q1, out_q2, out_at_max = [], [], []
    out_ref, out_dom, out_shapes, out_coef = [], [], [], []
    for k in range(n_modes):
        c = vecs[:, k].reshape(nx, ny)
        w_search = Xs.T @ c @ Ys  # (xi, eta)
        i_max = np.unravel_index(int(np.argmax(np.abs(w_search))), w_search.shape)
        w_grid_max = float(w_search[i_max])
        xi_m, eta_m, w_max = _refine_max(c, bx, by, float(gx[i_max[0]]), float(gx[i_max[1]]),
                                         math.copysign(1.0, w_grid_max))
        if abs(w_max) < abs(w_grid_max):  # the optimiser must not lose the grid maximum
            xi_m, eta_m, w_max = float(gx[i_max[0]]), float(gx[i_max[1]]), w_grid_max
        w_centre = float(Xc @ c @ Yc)
        at_max = abs(w_centre) <= NODE_RTOL * abs(w_max)
        ref_xi, ref_eta, w_ref = (xi_m, eta_m, w_max) if at_max else (0.5, 0.5, w_centre)
        c = c / w_ref
        # Eq. (2.18), (2.19): integrals over x/a in [0, 1] and y/a in [0, b/a] = r * (xi, eta) integrals
        out_q1.append(r * float(mx @ c @ my))
        out_q2.append(r * float(np.sum(c * (e0x @ c @ e0y))))
        out_at_max.append(at_max)
        out_ref.append((ref_xi, ref_eta))
        c_beam = to_bx @ c @ to_by.T
        i_dom = np.unravel_index(int(np.argmax(np.abs(c_beam))), c_beam.shape)
        out_dom.append((int(i_dom[0]) + 1, int(i_dom[1]) + 1))
        out_shapes.append(Yg.T @ c.T @ Xg)  # (eta, xi)
        out_coef.append(c)

    def ro(a: np.ndarray) -> np.ndarray:
        a.setflags(write=False)
        return a

    ref = np.array(out_ref)
    return PlateModes(
        aspect_ratio=r, edges=edges, nu=nu_f, n_terms=(nx, ny),
        lam=ro(lam.copy()), Q1=ro(np.array(out_q1)), Q2=ro(np.array(out_q2)),
        at_max=ro(np.array(out_at_max, dtype=bool)), ref_xi=ro(ref[:, 0].copy()), ref_eta=ro(ref[:, 1].copy()),
        dominant=ro(np.array(out_dom, dtype=int)), xi=ro(xi), eta=ro(eta),
        shapes=ro(np.array(out_shapes)), coefficients=ro(np.array(out_coef)),
    )
