"""Plate modal data: beam functions, closed form, thesis tables, Rayleigh-Ritz."""

from __future__ import annotations

import functools
import math

import mpmath
import numpy as np
import pytest
import scipy.linalg
from scipy import integrate

from rattle_lab.exceptions import ConvergenceError, ParameterError
from rattle_lab.model.plate import (
    DEFAULT_N_TERMS,
    EDGE_ORDER,
    TABLE_ASPECT_RATIOS,
    Plate,
    PlateMode,
    PlateModes,
    TableMode,
    ritz_modes,
    simply_supported_mode,
    simply_supported_modes,
    table_modes,
)
from rattle_lab.model.plate import _beam
from rattle_lab.model.plate import _ritz as ritz_module
from rattle_lab.model.plate._edges import check_edges

#: Leissa's free-edge values are for nu = 0.3.
NU_LEISSA = 0.3
#: The thesis's FEM plate is aluminium, nu = 0.34 (section 5.1.1); Q1/Q2 of free-edge
#: plates depend on nu through the anticlastic curvature of the free edges.
NU_THESIS = 0.34


def _ritz(aspect_ratio: float, edges: str, nu: float, n_terms: int = DEFAULT_N_TERMS) -> PlateModes:
    # nu drops out of a plate without free edges (the nu terms of the energy integrate to
    # boundary terms that vanish), so such plates share one cached solve.
    return _ritz_cached(aspect_ratio, edges, nu if "F" in edges else NU_LEISSA, n_terms)


@functools.cache
def _ritz_cached(aspect_ratio: float, edges: str, nu: float, n_terms: int) -> PlateModes:
    return ritz_modes(aspect_ratio, edges, nu=nu, n_modes=6, n_terms=n_terms)


# --------------------------------------------------------------------------- beam functions
class TestBeamBasis:
    # First elastic roots of beam frequency equations, to 12 digits (cosh b cos b = 1,
    # cosh b cos b = -1, tan b = tanh b); reference values computed with mpmath.findroot.
    @pytest.mark.parametrize(
        ("left", "right", "n_rigid", "equation", "guess"),
        [
            ("C", "C", 0, lambda b: mpmath.cosh(b) * mpmath.cos(b) - 1, 4.73),
            ("F", "F", 2, lambda b: mpmath.cosh(b) * mpmath.cos(b) - 1, 4.73),
            ("C", "F", 0, lambda b: mpmath.cosh(b) * mpmath.cos(b) + 1, 1.875),
            ("F", "C", 0, lambda b: mpmath.cosh(b) * mpmath.cos(b) + 1, 1.875),
            ("C", "S", 0, lambda b: mpmath.tan(b) - mpmath.tanh(b), 3.927),
            ("S", "C", 0, lambda b: mpmath.tan(b) - mpmath.tanh(b), 3.927),
            ("S", "F", 1, lambda b: mpmath.tan(b) - mpmath.tanh(b), 3.927),
            ("F", "S", 1, lambda b: mpmath.tan(b) - mpmath.tanh(b), 3.927),
            ("S", "S", 0, lambda b: mpmath.sin(b), 3.14),
        ],
    )
    def test_first_elastic_root_matches_mpmath(self, left, right, n_rigid, equation, guess):
        basis = _beam.beam_basis(left, right, 6)
        assert np.all(basis.beta[:n_rigid] == 0.0)
        with mpmath.workdps(30):
            ref = float(mpmath.findroot(equation, guess))
        # brentq polished to a few ulp of beta
        assert basis.beta[n_rigid] == pytest.approx(ref, rel=1e-12)

    def test_high_roots_against_mpmath(self):
        # All 12 clamped-clamped roots (up to beta ~ 39, where cosh/sinh forms fail in
        # double precision) against cosh(b) cos(b) = 1 solved at 40 digits.
        basis = _beam.beam_basis("C", "C", 12)
        with mpmath.workdps(40):
            ref = [float(mpmath.findroot(lambda b: mpmath.cos(b) - 1 / mpmath.cosh(b), (k + 0.5) * mpmath.pi))
                   for k in range(1, 13)]
        np.testing.assert_allclose(basis.beta, ref, rtol=1e-13)

    @pytest.mark.parametrize("ends", ["CC", "CF", "FC", "SS", "CS", "SC", "FF", "SF", "FS"])
    def test_orthonormal_and_boundary_conditions(self, ends):
        left, right = ends
        basis = _beam.beam_basis(left, right, 12)
        s, w = _beam.gauss_points()
        p = basis.evaluate(s)
        # Orthonormality by quadrature: rounding only (sums of 200 terms).
        np.testing.assert_allclose((p * w) @ p.T, np.eye(12), atol=1e-12)
        orders = {"C": (0, 1), "S": (0, 2), "F": (2, 3)}
        scale = np.maximum(basis.beta, 1.0)
        for end, x in ((left, 0.0), (right, 1.0)):
            for k in orders[end]:
                val = basis.evaluate(np.array([x]), k)[:, 0] / scale**k
                np.testing.assert_allclose(val, 0.0, atol=1e-9)

    def test_integrals_match_adaptive_quadrature(self):
        # An independent check of the 200-point Gauss-Legendre rule on the hardest
        # integrands (highest functions, second derivatives, boundary layers).
        basis = _beam.beam_basis("F", "F", 12)

        def f(x: float, i: int, k: int, oi: int, ok: int) -> float:
            xs = np.array([x])
            return float(basis.evaluate(xs, oi)[i, 0] * basis.evaluate(xs, ok)[k, 0])

        e0, e1, e2, c, mean = ritz_module._gram(basis)
        for i, k in [(11, 11), (10, 11), (3, 11), (2, 9)]:
            scale = basis.beta[max(i, k)] ** 4
            ref2 = integrate.quad(f, 0, 1, args=(i, k, 2, 2), limit=400, epsabs=1e-13 * scale, epsrel=1e-12)[0]
            ref1 = integrate.quad(f, 0, 1, args=(i, k, 1, 1), limit=400, epsabs=1e-13 * scale, epsrel=1e-12)[0]
            refc = integrate.quad(f, 0, 1, args=(i, k, 2, 0), limit=400, epsabs=1e-13 * scale, epsrel=1e-12)[0]
            assert e2[i, k] == pytest.approx(ref2, abs=1e-11 * scale)
            assert e1[i, k] == pytest.approx(ref1, abs=1e-11 * scale)
            assert c[i, k] == pytest.approx(refc, abs=1e-11 * scale)
        ref_mean = integrate.quad(lambda x: float(basis.evaluate(np.array([x]))[4, 0]), 0, 1, epsabs=1e-14)[0]
        assert mean[4] == pytest.approx(ref_mean, abs=1e-12)

    def test_no_roots_raises(self, monkeypatch):
        _beam.beam_basis.cache_clear()
        monkeypatch.setattr(_beam, "_det", lambda beta, left, right: 1.0)
        with pytest.raises(ConvergenceError, match=r"beam basis C-C: found 0 of 3 eigenvalues"):
            _beam.beam_basis("C", "C", 3)
        _beam.beam_basis.cache_clear()


# --------------------------------------------------------------------------- edges
class TestEdges:
    def test_order_is_documented(self):
        assert EDGE_ORDER == ("y=0", "x=a", "y=b", "x=0")
        assert check_edges("cfcf") == "CFCF"

    @pytest.mark.parametrize("bad", ["CFC", "CFCFC", "CFXF", ""])
    def test_bad_strings(self, bad):
        with pytest.raises(ParameterError, match=r"`edges` must be 4 letters from C .* was '"):
            check_edges(bad)

    def test_not_a_string(self):
        with pytest.raises(ParameterError, match=r"`edges` must be a string of 4 letters .* was 4"):
            check_edges(4)  # type: ignore[arg-type]


# --------------------------------------------------------------------------- closed form
class TestSimplySupported:
    def test_lambda_and_integrals(self):
        r = 0.7
        mode = simply_supported_mode(3, 1, r)
        assert mode.lam == pytest.approx(math.pi**2 * (9 + 1 / r**2), rel=1e-15)
        # Eq. (2.23) literally, and the sign of W(centre) = sin(3 pi/2) sin(pi/2) = -1.
        eq_2_23 = r / (3 * math.pi**2) * 2 * 2
        assert mode.Q1 == pytest.approx(-eq_2_23, rel=1e-14)
        assert mode.Q2 == pytest.approx(r / 4, rel=1e-15)
        assert not mode.at_max and (mode.ref_xi, mode.ref_eta) == (0.5, 0.5)

    def test_integrals_against_mpmath(self):
        # Eq. (2.18), (2.19) integrated at 30 digits for W normalised to 1 at the centre.
        r, m, n = 0.7, 3, 5
        mode = simply_supported_mode(m, n, r)
        with mpmath.workdps(30):
            centre = mpmath.sin(m * mpmath.pi / 2) * mpmath.sin(n * mpmath.pi / 2)
            # W separates, so the double integrals are products of 1-D quadratures.
            ix = mpmath.quad(lambda x: mpmath.sin(m * mpmath.pi * x), [0, 1])
            iy = mpmath.quad(lambda y: mpmath.sin(n * mpmath.pi * y / r), [0, r])
            ix2 = mpmath.quad(lambda x: mpmath.sin(m * mpmath.pi * x) ** 2, [0, 1])
            iy2 = mpmath.quad(lambda y: mpmath.sin(n * mpmath.pi * y / r) ** 2, [0, r])
            q1 = ix * iy / centre
            q2 = ix2 * iy2 / centre**2
        assert mode.Q1 == pytest.approx(float(q1), rel=1e-13)
        assert mode.Q2 == pytest.approx(float(q2), rel=1e-13)

    def test_node_at_centre_uses_max(self):
        mode = simply_supported_mode(2, 1, 1.0)
        assert mode.at_max and mode.Q1 == 0.0
        assert (mode.ref_xi, mode.ref_eta) == (0.25, 0.5)

    def test_sorted_modes(self):
        modes = simply_supported_modes(2.0, 5)
        assert [(m.m, m.n) for m in modes] == [(1, 1), (1, 2), (1, 3), (2, 1), (1, 4)]
        assert all(isinstance(m, PlateMode) for m in modes)

    @pytest.mark.parametrize(
        ("args", "match"),
        [
            ((0, 1, 1.0), r"`m` must be an integer >= 1, was 0"),
            ((1, 1.5, 1.0), r"`n` must be an integer >= 1, was 1.5"),
            ((1, 1, -2.0), r"`aspect_ratio` \(b/a\) must be finite and > 0, was -2.0"),
            ((1, 1, float("nan")), r"`aspect_ratio` \(b/a\) must be finite and > 0, was nan"),
        ],
    )
    def test_errors(self, args, match):
        with pytest.raises(ParameterError, match=match):
            simply_supported_mode(*args)

    def test_modes_errors(self):
        with pytest.raises(ParameterError, match=r"`n_modes` must be an integer >= 1, was 0"):
            simply_supported_modes(1.0, 0)

    @pytest.mark.parametrize("r", [0.5, 0.9, 1.0, 1.7, 2.0])
    def test_ritz_with_sine_functions_is_exact(self, r):
        # S-S beam functions are the exact plate modes (sines), so the Ritz solution
        # reproduces eq. 2.20-2.24 to rounding: 1e-10 leaves 1000x margin.
        ritz = ritz_modes(r, "SSSS", n_modes=8, n_terms=8)
        closed = simply_supported_modes(r, 8)
        np.testing.assert_allclose(ritz.lam, [m.lam for m in closed], rtol=1e-10)
        np.testing.assert_allclose(ritz.Q1, [m.Q1 for m in closed], rtol=0, atol=1e-10)
        np.testing.assert_allclose(ritz.Q2, [m.Q2 for m in closed], rtol=1e-10)
        assert ritz.at_max.tolist() == [m.at_max for m in closed]
        assert ritz.dominant.tolist() == [[m.m, m.n] for m in closed]


# --------------------------------------------------------------------------- thesis tables
_LEISSA_CASES = [
    pytest.param(edges, r, t.mode, t.lam_leissa, id=f"{edges}-{r}-mode{t.mode}")
    for edges in ("CFCF", "CCCC")
    for r in TABLE_ASPECT_RATIOS[edges]
    for t in table_modes(edges, r)
    if t.lam_leissa is not None
]

_UNSTARRED_CASES = [
    pytest.param(edges, r, t, id=f"{edges}-{r}-mode{t.mode}")
    for edges in ("CFCF", "CCCC")
    for r in TABLE_ASPECT_RATIOS[edges]
    for t in table_modes(edges, r)
    if not t.starred
]


class TestTables:
    def test_accessor(self):
        modes = table_modes("CFCF", 0.9)
        assert len(modes) == 6 and all(isinstance(m, TableMode) for m in modes)
        assert modes[0] == TableMode(1, 27.7, 27.4, 0.500, 0.402, False)
        assert [m.starred for m in modes] == [False, True, False, True, True, True]
        assert all(m.lam_leissa is None for m in table_modes("CCCC", 0.9))
        assert TABLE_ASPECT_RATIOS == {"CFCF": (0.5, 0.9, 1.0, 2.0), "CCCC": (0.5, 0.9, 1.0)}

    def test_starred_means_zero_Q1(self):
        for edges, ratios in TABLE_ASPECT_RATIOS.items():
            for r in ratios:
                assert all(m.Q1 == 0.0 for m in table_modes(edges, r) if m.starred)

    def test_counts(self):
        # Every Leissa value of both tables is tested below: 4 x 6 + 2 x 6 (b/a = 0.9 of
        # Table 2.2 is "no").
        assert len(_LEISSA_CASES) == 36
        assert len(_UNSTARRED_CASES) == 17

    def test_errors(self):
        with pytest.raises(ParameterError, match=r"`edges` must be one of \['CCCC', 'CFCF'\] .* was 'SSSS'"):
            table_modes("SSSS", 1.0)
        with pytest.raises(ParameterError, match=r"`aspect_ratio` must be one of \[0.5, 0.9, 1.0\] .* was 2.0"):
            table_modes("CCCC", 2.0)


class TestRitzAgainstThesis:
    @pytest.mark.parametrize(("edges", "r", "mode", "lam_leissa"), _LEISSA_CASES)
    def test_lambda_within_1p5_percent_of_leissa(self, edges, r, mode, lam_leissa):
        # The requirement.  The largest deviation, 1.04 %, is CCCC b/a = 0.5 mode 1,
        # where the thesis quotes 97.3 but Leissa's value is 98.31 (the Ritz value is 98.31).
        lam = _ritz(r, edges, NU_LEISSA).lam[mode - 1]
        assert abs(lam / lam_leissa - 1.0) <= 0.015

    @pytest.mark.parametrize(("edges", "r", "t"), _UNSTARRED_CASES)
    def test_Q1_Q2_against_fem(self, edges, r, t):
        # The FEM values have 3 digits (rounding <= 0.0005), but their error is dominated
        # by the thesis's 16x16 shell mesh: its lambda is up to 6.5 % above the converged
        # Ritz value for the higher modes.  Tolerance: 5 % where the FEM lambda is within
        # 1.5 % of Ritz (shape resolved), 12 % otherwise, plus 0.005 absolute on Q1 (small
        # Q1 such as 0.005, 0.016 are differences of large lobes).  The thesis tabulates
        # |Q1|: W normalised to +1 at the centre gives Q1 < 0 for e.g. CFCF b/a=2 mode 6.
        ritz = _ritz(r, edges, NU_THESIS)
        k = t.mode - 1
        fem_error = abs(t.lam_fem / ritz.lam[k] - 1.0)
        rtol = 0.05 if fem_error <= 0.015 else 0.12
        assert not ritz.at_max[k]
        assert abs(ritz.Q1[k]) == pytest.approx(t.Q1, rel=rtol, abs=0.005)
        assert ritz.Q2[k] == pytest.approx(t.Q2, rel=rtol)

    @pytest.mark.parametrize("edges", ["CFCF", "CCCC"])
    def test_fundamental_Q1_Q2_within_3_percent(self, edges):
        # Mode 1 is the one the SDF model uses; its FEM lambda is within 1.2 % of Ritz.
        for r in TABLE_ASPECT_RATIOS[edges]:
            ritz, t = _ritz(r, edges, NU_THESIS), table_modes(edges, r)[0]
            assert ritz.Q1[0] == pytest.approx(t.Q1, rel=0.03)
            assert ritz.Q2[0] == pytest.approx(t.Q2, rel=0.03)

    @pytest.mark.parametrize("edges", ["CFCF", "CCCC"])
    def test_star_flags_match(self, edges):
        for r in TABLE_ASPECT_RATIOS[edges]:
            ritz = _ritz(r, edges, NU_THESIS)
            assert ritz.at_max.tolist() == [t.starred for t in table_modes(edges, r)]
            np.testing.assert_allclose(ritz.Q1[ritz.at_max], 0.0, atol=1e-10)


class TestRitz:
    @pytest.mark.parametrize(("edges", "limit"), [("CFCF", 1e-3), ("CCCC", 1e-4)])
    def test_converged(self, edges, limit):
        # 12 -> 15 terms per side changes lambda_1 by 7.7e-4 (free edges converge slowly:
        # beam functions do not satisfy the natural conditions) and 1e-5 (CCCC).
        a = _ritz(0.9, edges, NU_THESIS).lam[0]
        b = _ritz(0.9, edges, NU_THESIS, 15).lam[0]
        assert b <= a  # Ritz converges from above
        assert abs(b / a - 1.0) < limit

    @pytest.mark.parametrize(
        ("edges", "lam_ref", "rtol"),
        [
            # Levy-type exact solution, SS on x = 0, a and C on y = 0, b, square: 28.95.
            ("CSCS", 28.951, 1e-4),
            # Completely free square plate, nu = 0.3 (Leissa): 13.468 after 3 rigid modes.
            ("FFFF", 13.468, 3e-3),
            # Three edges SS, y = b free, nu = 0.3, exact Levy solution: 11.68.
            ("SSSF", 11.685, 5e-3),
        ],
    )
    def test_other_edges_against_leissa(self, edges, lam_ref, rtol):
        modes = ritz_modes(1.0, edges, nu=0.3)
        elastic = modes.lam[modes.lam > 1e-3]
        assert elastic[0] == pytest.approx(lam_ref, rel=rtol)

    def test_nu_drops_out_without_free_edges(self):
        a = ritz_modes(0.9, "CCCC", nu=0.0, n_terms=6).lam
        b = ritz_modes(0.9, "CCCC", nu=0.45, n_terms=6).lam
        np.testing.assert_allclose(a, b, rtol=1e-12)

    def test_free_plate_rigid_modes(self):
        modes = ritz_modes(1.0, "FFFF", nu=0.3)
        np.testing.assert_allclose(modes.lam[:3], 0.0, atol=1e-4)
        # Translation first (the degenerate cluster is ordered by term index): W = 1, Q1 = Q2 = b/a.
        assert modes.Q1[0] == pytest.approx(1.0, rel=1e-12)
        assert modes.Q2[0] == pytest.approx(1.0, rel=1e-12)
        assert modes.at_max[1:3].tolist() == [True, True]  # the two rotations

    def test_degenerate_square_modes_are_deterministic(self):
        modes = _ritz(1.0, "CCCC", NU_LEISSA)
        assert modes.lam[1] == pytest.approx(modes.lam[2], rel=1e-10)
        assert modes.dominant[1:3].tolist() == [[1, 2], [2, 1]]
        coefs = np.abs(modes.coefficients[1])
        assert coefs[0, 1] > 0.99 * coefs.max() and coefs[1, 0] < 1e-8 * coefs.max()


    @pytest.mark.parametrize("n_terms", [28, 36])
    def test_large_bases_keep_each_shape_with_its_eigenvalue(self, n_terms):
        # Issue 24: a tie-break between "equal" eigenvalues judged equal relative to the
        # basis' largest eigenvalue (1e11-1e12 from 28 terms) swapped the shapes of modes of
        # different symmetry 1e3 apart in lambda**2: at 36 terms the thesis plate's mode 3
        # (an excited (3, 1) mode, lambda 48.3) carried the shape of mode 5 (antisymmetric,
        # no net force).  Each shape must stay with its eigenvalue whatever the basis: the
        # pattern of modes with zero net force (Q1) and the Q1 of the others agree with a
        # 20-term basis (lambda agree to 2e-4; Q1, an integral over the plate, to 2e-3 or to
        # 1e-4 of the largest Q1 where it is small: the basis' error in a shape is relative
        # to the whole shape, not to its small net force).
        ref = ritz_modes(0.9, "CFCF", nu=NU_THESIS, n_modes=40, n_terms=20)
        big = ritz_modes(0.9, "CFCF", nu=NU_THESIS, n_modes=40, n_terms=n_terms)
        np.testing.assert_allclose(big.lam, ref.lam, rtol=2e-4)
        excited = np.abs(ref.Q1) > 1e-9
        assert (np.abs(big.Q1) > 1e-9).tolist() == excited.tolist()
        np.testing.assert_allclose(big.Q1[excited], ref.Q1[excited], rtol=2e-3,
                                   atol=1e-4 * np.abs(ref.Q1).max())
    def test_shapes_normalised(self):
        modes = _ritz(0.9, "CFCF", NU_THESIS)
        w_ref = modes.evaluate(modes.ref_xi[:, None], modes.ref_eta[:, None])
        np.testing.assert_allclose(np.diagonal(w_ref[:, :, 0]), 1.0, rtol=1e-12)
        assert modes.shapes.shape == (6, 41, 41)
        for k in np.flatnonzero(modes.at_max):
            assert np.abs(modes.shapes[k]).max() <= 1.0 + 1e-9
        np.testing.assert_allclose(modes.shapes[:, 0, :], 0.0, atol=1e-12)  # clamped y = 0
        np.testing.assert_allclose(modes.shapes[0], modes.evaluate(modes.xi[None, :], modes.eta[:, None])[0],
                                   atol=1e-13)
        assert not modes.lam.flags.writeable

    def test_Q_integrals_against_adaptive_quadrature(self):
        # Eq. (2.18)/(2.19) integrated adaptively over the evaluated shape: checks the
        # tensor-product integration and the normalisation, independently.
        modes = _ritz(0.9, "CFCF", NU_THESIS)
        r = modes.aspect_ratio

        def w(eta: float, xi: float) -> float:
            return float(modes.evaluate(xi, eta)[0])

        # Adaptive tolerance 1e-8 keeps this under a second; compare at 1e-7.
        q1 = integrate.dblquad(w, 0, 1, 0, 1, epsabs=1e-9, epsrel=1e-8)[0] * r
        q2 = integrate.dblquad(lambda e, x: w(e, x) ** 2, 0, 1, 0, 1, epsabs=1e-9, epsrel=1e-8)[0] * r
        assert modes.Q1[0] == pytest.approx(q1, rel=1e-7)
        assert modes.Q2[0] == pytest.approx(q2, rel=1e-7)

    def test_mode_accessor(self):
        modes = _ritz(0.9, "CFCF", NU_THESIS)
        m0 = modes[0]
        assert isinstance(m0, PlateMode) and m0.lam == modes.lam[0] and (m0.m, m0.n) == (1, 1)
        assert m0.participation == pytest.approx(modes.participation[0])
        assert len(modes) == 6

    @pytest.mark.parametrize(
        ("kwargs", "match"),
        [
            ({"aspect_ratio": 0.0}, r"`aspect_ratio` \(b/a\) must be finite and > 0, was 0.0"),
            ({"edges": "CFCQ"}, r"`edges` must be 4 letters .* was 'CFCQ'"),
            ({"nu": 0.5}, r"`nu` must satisfy -1 < nu < 0.5, was 0.5"),
            ({"n_modes": 0}, r"`n_modes` must be an integer >= 1, was 0"),
            ({"n_modes": 10, "n_terms": 3}, r"`n_modes` must be <= n_terms_x \* n_terms_y = 9, was 10"),
            ({"n_terms": (3,)}, r"`n_terms` must be an int or a pair of ints, was \(3,\)"),
            ({"n_terms": 2.5}, r"`n_terms` must be an integer >= 1, was 2.5"),
            ({"n_grid": 1}, r"`n_grid` must be an integer >= 2, was 1"),
        ],
    )
    def test_errors(self, kwargs, match):
        args = {"aspect_ratio": 1.0, "edges": "CCCC"} | kwargs
        with pytest.raises(ParameterError, match=match):
            ritz_modes(**args)

    def test_evaluate_outside_plate(self):
        modes = _ritz(0.9, "CFCF", NU_THESIS)
        with pytest.raises(ParameterError, match=r"`xi` must lie in \[0, 1\], was 1.5"):
            modes.evaluate(1.5, 0.5)
        with pytest.raises(ParameterError, match=r"`eta` must lie in \[0, 1\], was nan"):
            modes.evaluate(0.5, float("nan"))

    def test_indefinite_stiffness_raises(self, monkeypatch):
        def fake_eigh(K, M):
            n = K.shape[0]
            return np.r_[-1.0, np.arange(1.0, n)], np.eye(n)

        monkeypatch.setattr(scipy.linalg, "eigh", fake_eigh)
        with pytest.raises(ConvergenceError, match=r"not positive semi-definite: eigenvalue -1.000e\+00"):
            ritz_modes(1.0, "CCCC", n_terms=3)


# --------------------------------------------------------------------------- Plate
THESIS_PLATE = {"a_m": 0.254, "b_m": 0.2286, "h_p_m": 1e-3, "E_pa": 7e10, "nu": 0.34, "rho_kg_m3": 2710.0}


class TestPlate:
    def test_thesis_plate(self):
        plate = Plate(**THESIS_PLATE, edges="cfcf")
        assert plate.edges == "CFCF"
        assert plate.aspect_ratio == pytest.approx(0.9, rel=1e-12)
        assert plate.mass_per_area_kg_m2 == pytest.approx(2.71, rel=1e-12)
        assert plate.flexural_rigidity_nm == pytest.approx(7e10 * 1e-9 / (12 * (1 - 0.34**2)), rel=1e-14)
        assert plate.omega_rad_s(27.4) == pytest.approx(2 * np.pi * plate.frequency_hz(27.4), rel=1e-14)

    def test_ritz_f1_of_thesis_plate(self):
        # Section 5.1.1: f1 = 105 Hz; the Ritz lambda must give it within 1.5 %.
        plate = Plate(**THESIS_PLATE, edges="CFCF")
        lam = plate.modes(n_modes=2).lam[0]
        # Plate.modes is ritz_modes with the solver's default (converged) basis size
        assert lam == pytest.approx(
            ritz_modes(plate.aspect_ratio, plate.edges, nu=plate.nu, n_modes=2).lam[0], rel=1e-12)
        assert plate.frequency_hz(lam) == pytest.approx(105.0, rel=0.015)

    @pytest.mark.parametrize(
        ("field", "value", "match"),
        [
            ("a_m", 0.0, r"`a_m` must be finite and > 0, was 0.0"),
            ("b_m", -1.0, r"`b_m` must be finite and > 0, was -1.0"),
            ("h_p_m", -1e-3, r"`h_p_m` must be finite and > 0, was -0.001"),
            ("E_pa", float("inf"), r"`E_pa` must be finite and > 0, was inf"),
            ("rho_kg_m3", float("nan"), r"`rho_kg_m3` must be finite and > 0, was nan"),
            ("nu", 0.5, r"`nu` must satisfy -1 < nu < 0.5, was 0.5"),
            ("edges", "CFC", r"`edges` must be 4 letters .* was 'CFC'"),
        ],
    )
    def test_errors(self, field, value, match):
        kwargs = THESIS_PLATE | {"edges": "CFCF", field: value}
        with pytest.raises(ParameterError, match=match):
            Plate(**kwargs)


# --------------------------------------------------------------------------- converged basis size
class TestConvergedSize:
    def test_sfsf_matches_leissa_exact_levy_value(self):
        # Leissa (1973) SFSF square, nu = 0.3: 9.6314 (exact Levy-type solution).
        # Products of beam functions gave 0.4 % high with 12 x 12 terms; the
        # polynomial basis chosen by the convergence check must give 1e-4.
        modes = ritz_modes(1.0, "SFSF", nu=0.3, n_modes=1)
        assert modes.lam[0] == pytest.approx(9.6314, rel=1e-4)

    @pytest.mark.parametrize(("edges", "r"), [("SFSF", 0.5), ("CFCF", 1.0), ("CFFF", 1.0),
                                              ("CCCC", 0.5), ("SSSF", 2.0)])
    def test_default_within_1e4_of_high_order(self, edges, r):
        # Reference: the same Ritz problem with 36 terms per side (1296 unknowns), past the
        # default's size.  It must be more accurate than the 1e-4 it judges: its own change
        # from 32 to 36 terms (an over-estimate of its remaining error for these exponentially
        # or N^-5 converging sequences) is held below 1e-5, a margin of ten.  CFCF and CFFF
        # converge algebraically (clamped-free corners are singular): 36 terms are within
        # ~3e-6 of the limit there.
        modes = ritz_modes(r, edges, nu=0.3, n_modes=4)
        ref = ritz_modes(r, edges, nu=0.3, n_modes=4, n_terms=36)
        ref34 = ritz_modes(r, edges, nu=0.3, n_modes=4, n_terms=34)
        ref32 = ritz_modes(r, edges, nu=0.3, n_modes=4, n_terms=32)
        assert modes.n_terms[0] < 36
        assert np.all(np.abs(ref32.lam / ref.lam - 1.0) < 1e-5)
        np.testing.assert_allclose(modes.lam, ref.lam, rtol=1e-4)
        # Ritz values converge from above in exact arithmetic.  In floating point a
        # converged value carries the eigensolver's rounding, which for these Gram matrices
        # (stiffness terms growing like n^8) is far above machine epsilon and depends on the
        # BLAS kernel: 3e-8 relative for SSSF on OpenBLAS Haswell, below 1e-9 on others.
        # Its size is measured here, not assumed: once the sequence has converged, the
        # 32-, 34- and 36-term values differ by rounding alone, so their largest difference
        # bounds the reference's rounding (for the algebraic cases it also holds the last
        # truncation steps, a larger and still conservative value).  Three times it covers
        # the scatter of an estimate from three draws.  Where the default is converged to
        # below that floor, "from above" cannot be resolved and the check is that the
        # default lies within the floor.
        floor = 3.0 * np.maximum(np.abs(ref32.lam - ref.lam), np.abs(ref34.lam - ref.lam))
        assert np.all(modes.lam >= ref.lam - floor)

    def test_ritz_decreases_with_size_where_truncation_dominates(self):
        # CFCF's algebraic convergence keeps each step's change (>= 3e-7 relative up to 36
        # terms) two orders above the eigensolver's rounding (<= 3e-8 on every BLAS kernel
        # tried), so the monotone decrease of the Ritz upper bounds is resolved there.
        lams = [ritz_modes(1.0, "CFCF", nu=0.3, n_modes=4, n_terms=n).lam for n in (20, 24, 28)]
        steps = np.diff(np.array(lams), axis=0) / lams[0]
        assert np.all(steps < -1e-7), steps

    def test_cccc_half_table_entry_is_flagged_as_misprint(self):
        # Leissa's clamped 2:1 plate, 24.58 in units of the long side = 98.32 in units of a;
        # the thesis prints 97.3 (flagged), the converged Ritz value is 98.31.
        lam = ritz_modes(0.5, "CCCC", nu=0.3, n_modes=1).lam[0]
        assert lam == pytest.approx(24.58 * 4, rel=2e-4)
        row = table_modes("CCCC", 0.5)[0]
        assert row.lam_leissa == 97.3 and "misprint" in row.note
        assert all(m.note == "" for m in table_modes("CFCF", 0.9))
