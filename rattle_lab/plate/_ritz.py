"""Rayleigh-Ritz modes of a rectangular plate with products of beam functions.

The deflection is ``W(xi, eta) = sum_ij c_ij X_i(xi) Y_j(eta)`` with ``xi = x/a``,
``eta = y/b`` and ``X_i``, ``Y_j`` the eigenfunctions of beams with the plate's
edge conditions (:mod:`rattle_lab.plate._beam`).  With ``rho_a = a/b`` the strain
and kinetic energies of the thin plate give ``K c = lambda**2 M c`` with

    K = E2x (x) E0y + rho_a**4 E0x (x) E2y
        + nu rho_a**2 (Cx (x) Cy^T + Cx^T (x) Cy) + 2 (1 - nu) rho_a**2 E1x (x) E1y,
    M = E0x (x) E0y,

where ``Ek = int phi_p^(k) phi_q^(k)``, ``C = int phi_p'' phi_q`` and ``(x)`` is the
Kronecker product; ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25).  The
generalized symmetric eigenproblem is solved with :func:`scipy.linalg.eigh`, split
into the symmetry classes of the terms where opposite edges are alike.  Beam
functions are not admissible for the natural boundary conditions of a free edge
but span them in the limit, so ``lambda`` converges from above.
"""

from __future__ import annotations

import math

import numpy as np

from ..exceptions import ConvergenceError, ParameterError
from ._beam import BeamBasis, beam_basis, gauss_points
from ._edges import check_edges, x_ends, y_ends
from ._simply_supported import _check_aspect_ratio, _check_count
from ._types import PlateModes

#: Default number of beam functions along each side: 12 x 12 = 144 unknowns.  It
#: reproduces every Leissa value of Tables 2.1 and 2.2 to 1.5 % (1.04 % at worst, see
#: the tests); raising it to 15 changes lambda_1 by 7.7e-4 relative for CFCF (free edges
#: converge slowly) and 1e-5 for CCCC.
DEFAULT_N_TERMS = 12

#: A mode's centre is a node when |W(centre)| <= NODE_RTOL * max |W|.  Symmetry makes
#: such centres vanish to rounding (~1e-14); 1e-6 leaves room for that.
NODE_RTOL = 1e-6

#: Relative gap of lambda**2 below which eigenvalues count as degenerate.
DEGENERATE_RTOL = 1e-8

_GRID_SEARCH = 101


def _gram(basis: BeamBasis) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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


def _parities(basis: BeamBasis) -> np.ndarray:
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

    labels = [(a, b) for a in px for b in py]  # row-major order of the terms (i, j)
    n = K.shape[0]
    all_vals, all_vecs = [], []
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
        return _check_count("n_terms", n_terms[0]), _check_count("n_terms", n_terms[1])
    k = _check_count("n_terms", n_terms)
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
    scale = max(float(np.max(np.abs(vals))), 1.0)
    start = 0
    n = vals.size
    while start < n:
        stop = start + 1
        while stop < n and vals[stop] - vals[stop - 1] <= DEGENERATE_RTOL * scale:
            stop += 1
        if stop - start > 1:
            block = vecs[:, start:stop]
            s = block.T @ (weight[:, None] * block)
            _, rot = np.linalg.eigh(0.5 * (s + s.T))
            vecs[:, start:stop] = block @ rot
        start = stop
    return vecs


def _refine_max(c: np.ndarray, bx: BeamBasis, by: BeamBasis, xi0: float, eta0: float,
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


def ritz_modes(aspect_ratio: float, edges: str, *, nu: float = 0.3, n_modes: int = 6,
               n_terms: int | tuple[int, int] = DEFAULT_N_TERMS, n_grid: int = 41) -> PlateModes:
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
    n_terms : int or (int, int)
        Beam functions along x and along y (rigid-body modes of free ends included).
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
    r = _check_aspect_ratio(aspect_ratio)
    edges = check_edges(edges)
    nu_f = float(nu)
    if not (-1.0 < nu_f < 0.5):
        raise ParameterError(f"`nu` must satisfy -1 < nu < 0.5, was {nu}")
    nx, ny = _n_terms_pair(n_terms)
    n_modes = _check_count("n_modes", n_modes)
    if n_modes > nx * ny:
        raise ParameterError(f"`n_modes` must be <= n_terms_x * n_terms_y = {nx * ny}, was {n_modes}")
    n_grid = _check_count("n_grid", n_grid, minimum=2)

    bx = beam_basis(*x_ends(edges), nx)
    by = beam_basis(*y_ends(edges), ny)
    e0x, e1x, e2x, cx, mx = _gram(bx)
    e0y, e1y, e2y, cy, my = _gram(by)
    ra2 = (1.0 / r) ** 2
    K = (np.kron(e2x, e0y) + ra2**2 * np.kron(e0x, e2y)
         + nu_f * ra2 * (np.kron(cx, cy.T) + np.kron(cx.T, cy))
         + 2.0 * (1.0 - nu_f) * ra2 * np.kron(e1x, e1y))
    K = 0.5 * (K + K.T)
    M = np.kron(e0x, e0y)
    M = 0.5 * (M + M.T)
    vals, vecs = _solve_by_parity(K, M, _parities(bx), _parities(by))
    scale = max(float(np.max(np.abs(vals))), 1.0)
    if vals[0] < -1e-9 * scale:
        raise ConvergenceError(f"Ritz stiffness matrix is not positive semi-definite: eigenvalue {vals[0]:.3e}")
    weight = np.arange(nx * ny, dtype=float)
    vecs = _rotate_degenerate(vals, vecs, weight)

    # Rigid-body modes give lambda**2 = 0 to rounding (checked above); clip that rounding.
    lam = np.sqrt(np.clip(vals[:n_modes], 0.0, None))

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
        i_dom = np.unravel_index(int(np.argmax(np.abs(c))), c.shape)
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
