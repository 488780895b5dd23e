"""The thesis's CFCF plate: band-averaged centre mobility from an independent Ritz solution.

The multi-mode model (``plate_system``: the project's Ritz modes and the omitted modes'
element) gives the thesis plate (0.254 x 0.2286 m, 1 mm aluminium, the sides of length a
clamped, the sides of length b free) a band-averaged driving-point mobility at its centre of
0.81/Z in the 1 kHz octave, Z = 8 sqrt(D m'') the infinite plate's point impedance.  These
tests check that number against a reference that shares no code with the project's plate
solver, to tell a model defect from a property of the plate.

Reference
    A Rayleigh-Ritz solution of the thin (Kirchhoff) plate written here: normalised Legendre
    polynomials ``sqrt((2k + 1)/2) P_k(u)`` along the free direction x and the
    clamped-clamped beam eigenfunctions (Warburton's and Leissa's choice) along the clamped
    direction y, both in centred coordinates ``u = 2x/a - 1``, ``v = 2y/b - 1``.  (The
    project uses ``s^p (1 - s)^q P_k(2 s - 1)`` orthonormalised by Cholesky in both
    directions.)  Both families are orthonormal on [-1, 1] as they stand (Gram matrices the
    identity to 3e-12), so the mass matrix is diagonal and nothing is orthogonalised.  The
    energy integrals, with the ``nu`` and ``2 (1 - nu)`` twisting terms, use 400-point
    Gauss-Legendre quadrature; ``scipy.linalg.eigh`` solves the generalized problem, split by
    symmetry about the plate's mid-lines.  Only modes symmetric in both x and y move the
    centre: the mobility uses that class alone, 30 x 24 terms (720 modes).

Frequencies
    The search of stored public pages found Leissa's paper (J. Sound Vib. 31, 257, 1973) but
    not the text of its tables, so the published check is against Leissa's square C-F-C-F
    values (nu = 0.3) as the thesis quotes them (its Table 2.1, three significant figures;
    transcribed in rattle_lab/model/plate/_tables.py): 22.2, 26.4, 43.6, 61.2, 67.2, 79.8.
    The Ritz values, 22.166, 26.404, 43.592, 61.172, 67.169, 79.814 (24 terms per symmetry
    class and direction), round to each.  Two further checks that need no table: the
    clamped-clamped beam limits, (beta L)**2 = 4.7300**2 (a long clamped span in cylindrical
    bending; a narrow strip, with E I = D (1 - nu**2) a), and the convergence in the basis
    size, N to 2N (the thesis plate, modes symmetric in x and y, frequencies in Hz):

    ========== ======== ======== ======== ======== ======== ========== ============
    terms      mode 1   mode 2   mode 3   mode 4   mode 5   mode 20    mode 60
    ========== ======== ======== ======== ======== ======== ========== ============
    15 x 12    105.101  186.042  541.447  569.692  680.640  3835.288   11941.597
    30 x 24    105.092  186.022  541.434  569.641  680.561  3835.013   11791.684
    60 x 48    105.089  186.013  541.429  569.620  680.533  3834.924   11791.474
    ========== ======== ======== ======== ======== ======== ========== ============

    Convergence is algebraic (the clamped-free corners are singular) but 30 x 24 is within
    5e-5 of 60 x 48 for the first 60 of these modes (to 12 kHz).  The model's 64 and 128
    excited modes agree with the reference to 5.4e-5 and 1.4e-4.

Mobility (band means of Re(Y) * Z over the octaves 1-8 kHz, the damping ratio of the model,
zeta = 0.05; 2001 frequencies per band for the reference, as ``_ssss_centre_series`` of
test_modal_convergence.py, 20001 for the model, as ``band_means`` of tests/plate_mobility.py)

    ================================ ======= ======= ======= =======
    octave                           1 kHz   2 kHz   4 kHz   8 kHz
    ================================ ======= ======= ======= =======
    reference 30 x 24, all modes     0.8116  1.0325  0.9465  0.9594
    reference 60 x 48, all modes     0.8116  1.0325  0.9466  0.9598
    reference, modes below 40 kHz    0.8116  1.0324  0.9462  0.9583
    model N = 64                     0.8140  1.0426  0.9849  1.0769
    model N = 64, element removed    0.8112  1.0316  0.9425  0.9285
    model N = 128                    0.8121  1.0351  0.9567  0.9983
    ================================ ======= ======= ======= =======

So the 1 kHz octave's 0.81/Z is the plate's: the reference has it (18.8 % below 1/Z) and the
model agrees with it to 0.3 % (N = 64).  The "within 10 % of 1/Z" target holds for this plate
at its centre in the octaves 2-8 kHz, not at 1 kHz (three modes that move the centre fall in
that octave, 0.71-1.41 kHz: 1.047, 1.215 and 1.410 kHz).

Where the model departs from the reference: the omitted modes' element adds a real mobility
``omega**2 Z G**2`` below its cut ``omega_c = 2 / (pi Z G)`` (13.0 kHz at N = 64), about
``(4/pi**2) (omega/omega_c)**2 / Z``; the modes it stands for add far less there (their real
part is proportional to zeta).  Measured at N = 64: +0.3, +1.0, +4.1 and +12.2 % over the
reference in the octaves 1, 2, 4, 8 kHz, of which the element accounts for +0.3, +1.1, +4.5 and
+15.5 %; the plain modal sum is within 0.5 % of the reference up to 4 kHz.  At N = 128 (cut
26 kHz): +0.06, +0.25, +1.1, +4.1 %.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.polynomial import legendre
from scipy.linalg import eigh
from scipy.optimize import brentq

from rattle_lab.model.modal import ModalSystem, plate_system
from rattle_lab.model.plate import Plate
from plate_mobility import band_means, z_inf

# eigensolvers through BLAS (tests/conftest.py marks the files of NUMERICS_MODULES so)
pytestmark = pytest.mark.numerics

A_M, B_M, H_M, E_PA, NU, RHO = 0.254, 0.2286, 1e-3, 7e10, 0.34, 2710.0
THESIS = Plate(a_m=A_M, b_m=B_M, h_p_m=H_M, E_pa=E_PA, nu=NU, rho_kg_m3=RHO, edges="CFCF")
OCTAVES_HZ = (1000.0, 2000.0, 4000.0, 8000.0)
#: Legendre polynomials (x, free) and beam functions (y, clamped) per symmetry class.
N_X, N_Y = 30, 24

_U, _WQ = legendre.leggauss(400)


def _d_and_mass(plate: Plate) -> tuple[float, float]:
    return plate.E_pa * plate.h_p_m**3 / (12.0 * (1.0 - plate.nu**2)), plate.rho_kg_m3 * plate.h_p_m


# ---------------------------------------------------------------- the independent Ritz solution
def _legendre(parity: int, n: int, u: np.ndarray) -> list[np.ndarray]:
    """``sqrt((2k + 1)/2) P_k(u)`` and its first two u-derivatives, k = parity, parity + 2, ...;
    each of shape (n, len(u)).  Orthonormal on [-1, 1]; no condition at the ends (free)."""
    rows: list[list[np.ndarray]] = [[], [], []]
    for k in range(parity, parity + 2 * n, 2):
        c = np.zeros(k + 1)
        c[k] = math.sqrt((2 * k + 1) / 2.0)
        for order in range(3):
            rows[order].append(legendre.legval(u, legendre.legder(c, m=order) if order else c))
    return [np.array(r).reshape(n, -1) for r in rows]


def _cc_kappas(parity: int, n: int) -> np.ndarray:
    """Half-wavenumbers ``kappa`` of the clamped-clamped beam on [-1, 1]: tan k + tanh k = 0
    (symmetric modes, 2.3650, 5.4978, ...) or tan k - tanh k = 0 (antisymmetric, 3.9266, ...);
    one root in each bracket below."""
    out = []
    for m in range(1, n + 1):
        if parity == 0:
            f, lo = (lambda k: math.sin(k) + math.cos(k) * math.tanh(k)), m * math.pi - math.pi / 2
        else:
            f, lo = (lambda k: math.sin(k) - math.cos(k) * math.tanh(k)), m * math.pi
        out.append(brentq(f, lo, lo + math.pi / 2, xtol=1e-14, rtol=1e-15))
    return np.array(out)


def _cc_raw(parity: int, kap: np.ndarray, v: np.ndarray) -> list[np.ndarray]:
    """``cos(k v)/cos k - cosh(k v)/cosh k`` (or sin, sinh) and two v-derivatives; the
    hyperbolic parts written with decaying exponentials (no overflow for large k)."""
    k = kap[:, None]
    v = np.atleast_1d(v)[None, :]
    ep, em, e2 = np.exp(k * (v - 1.0)), np.exp(-k * (v + 1.0)), np.exp(-2.0 * k)
    kv = k * v
    if parity == 0:
        trig = [np.cos(kv), -k * np.sin(kv), -k**2 * np.cos(kv)]
        hyp = [(ep + em) / (1 + e2), k * (ep - em) / (1 + e2), k**2 * (ep + em) / (1 + e2)]
        den = np.cos(k)
    else:
        trig = [np.sin(kv), k * np.cos(kv), -k**2 * np.sin(kv)]
        hyp = [(ep - em) / (1 - e2), k * (ep + em) / (1 - e2), k**2 * (ep - em) / (1 - e2)]
        den = np.sin(k)
    return [t / den - hh for t, hh in zip(trig, hyp)]


def _cc_beam(parity: int, n: int, v: np.ndarray) -> list[np.ndarray]:
    """The first n clamped-clamped beam functions of one parity, normalised on [-1, 1]."""
    kap = _cc_kappas(parity, n)
    norm = np.sqrt(np.sum(_cc_raw(parity, kap, _U)[0] ** 2 * _WQ, axis=1))[:, None]
    return [f / norm for f in _cc_raw(parity, kap, v)]


def _ritz(a: float, b: float, D: float, m2: float, nu: float, nx: int, ny: int,
          px: int = 0, py: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Angular frequencies [rad/s] and mass-normalised centre deflections [kg^-1/2] of the
    modes of parity ``px`` in x and ``py`` in y (0 symmetric, 1 antisymmetric) of the plate
    ``0 <= x <= a`` (edges x = 0, a free), ``0 <= y <= b`` (edges y = 0, b clamped).

    With ``w = sum c_ij X_i(u) Y_j(v)``, dx dy = (ab/4) du dv, d/dx = (2/a) d/du:
    ``U = (D/2) int [w_xx^2 + w_yy^2 + 2 nu w_xx w_yy + 2 (1 - nu) w_xy^2]`` and
    ``T = (omega^2/2) m'' int w^2`` give ``K c = omega^2 M c``; ``eigh`` normalises
    ``c^T M c = 1``, so ``m'' int W^2 dA = 1``.
    """
    X, Y = _legendre(px, nx, _U), _cc_beam(py, ny, _U)

    def gram(p: np.ndarray, q: np.ndarray) -> np.ndarray:
        return (p * _WQ) @ q.T

    A0, A1, A2, CA = gram(X[0], X[0]), gram(X[1], X[1]), gram(X[2], X[2]), gram(X[2], X[0])
    B0, B1, B2, CB = gram(Y[0], Y[0]), gram(Y[1], Y[1]), gram(Y[2], Y[2]), gram(Y[2], Y[0])
    s = a * b / 4.0
    K = 16.0 * D * s * (np.kron(A2, B0) / a**4 + np.kron(A0, B2) / b**4
                        + nu * (np.kron(CA, CB.T) + np.kron(CA.T, CB)) / (a * b) ** 2
                        + 2.0 * (1.0 - nu) * np.kron(A1, B1) / (a * b) ** 2)
    M = m2 * s * np.kron(A0, B0)
    w2, c = eigh(0.5 * (K + K.T), 0.5 * (M + M.T))
    centre = np.kron(_legendre(px, nx, np.zeros(1))[0][:, 0], _cc_beam(py, ny, np.zeros(1))[0][:, 0])
    return np.sqrt(np.clip(w2, 0.0, None)), centre @ c


def _lambdas(b_over_a: float, nu: float, n: int, count: int = 6) -> np.ndarray:
    """``lambda = omega a^2 sqrt(m''/D)`` (a: the side along the free direction) of the first
    ``count`` modes of every symmetry class."""
    lam = [_ritz(1.0, b_over_a, 1.0, 1.0, nu, n, n, px, py)[0][:count] for px in (0, 1) for py in (0, 1)]
    return np.sort(np.concatenate(lam))[:count]


def _series(omega: np.ndarray, beta2: np.ndarray, zeta: float, z: float,
            centres_hz: tuple[float, ...] = OCTAVES_HZ, n_freq: int = 2001) -> np.ndarray:
    """Band means of Re(Y) * Z from modes ``omega`` with ``beta2 = W(centre)^2`` (mass-normalised),
    as ``_ssss_centre_series`` of test_modal_convergence.py."""
    out = []
    for fc in centres_hz:
        w = 2.0 * math.pi * np.linspace(fc / math.sqrt(2.0), fc * math.sqrt(2.0), n_freq)
        den = omega[:, None] ** 2 - w[None, :] ** 2 + 2j * zeta * omega[:, None] * w[None, :]
        out.append(float(np.mean(np.sum(beta2[:, None] * 1j * w[None, :] / den, axis=0).real)))
    return np.array(out) * z


def _thesis_reference(nx: int = N_X, ny: int = N_Y) -> tuple[np.ndarray, np.ndarray]:
    D, m2 = _d_and_mass(THESIS)
    return _ritz(A_M, B_M, D, m2, NU, nx, ny, 0, 0)


@pytest.fixture(scope="module")
def reference() -> tuple[np.ndarray, np.ndarray]:
    return _thesis_reference()


@pytest.fixture(scope="module")
def model64() -> ModalSystem:
    return plate_system(THESIS, n_modes=64, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0)


@pytest.fixture(scope="module")
def model128() -> ModalSystem:
    return plate_system(THESIS, n_modes=128, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0)


# ------------------------------------------------------------------------------------ the tests
def test_bases_are_orthonormal_and_the_beam_functions_clamped():
    # Both families orthonormal as they stand (measured 3e-12 for the Legendre polynomials to
    # degree 59, 7e-15 for the beam functions): M is diagonal, no orthogonalisation needed.
    for parity in (0, 1):
        X, Y = _legendre(parity, N_X, _U)[0], _cc_beam(parity, N_Y, _U)[0]
        np.testing.assert_allclose((X * _WQ) @ X.T, np.eye(N_X), rtol=0, atol=1e-10)
        np.testing.assert_allclose((Y * _WQ) @ Y.T, np.eye(N_Y), rtol=0, atol=1e-10)
        # w = w' = 0 at both clamped ends (w' relative to its scale kappa), to rounding
        ends = _cc_beam(parity, N_Y, np.array([-1.0, 1.0]))
        kap = _cc_kappas(parity, N_Y)[:, None]
        assert np.max(np.abs(ends[0])) < 1e-12
        assert np.max(np.abs(ends[1] / kap)) < 1e-12


def test_square_plate_frequencies_round_to_leissas():
    # Leissa's square C-F-C-F plate (nu = 0.3) as the thesis quotes it (Table 2.1, three
    # significant figures): every Ritz value (24 terms per class and direction) within half a
    # unit of the last printed digit.  Measured 22.166, 26.404, 43.592, 61.172, 67.169,
    # 79.814; they fall by at most 0.0016 from 24 to 32 terms (Ritz values fall as terms are
    # added).
    leissa = np.array([22.2, 26.4, 43.6, 61.2, 67.2, 79.8])
    lam = _lambdas(1.0, 0.3, 24)
    assert np.all(np.abs(lam - leissa) <= 0.05), lam


def test_beam_limits():
    beam = 4.730040744862704**2  # clamped-clamped beam, (beta L)^2
    # Long clamped edges (a = 10 b): cylindrical bending across the span b, lambda_b = omega
    # b^2 sqrt(m''/D) -> beam, from below (the free edges soften it): measured -0.144 % at
    # a/b = 10 and -0.108 % at a/b = 20 (unchanged from 16 to 48 terms along x).
    w, _ = _ritz(10.0, 1.0, 1.0, 1.0, 0.3, 24, 8)
    assert -2e-3 < w[0] / beam - 1.0 < 0.0
    # A narrow strip (b = 20 a) is a clamped-clamped beam of stiffness E I = D (1 - nu^2) a:
    # lambda_b -> beam sqrt(1 - nu^2), from above (plane strain at the clamped ends, over a
    # length ~ a): measured +1.26, +0.70, +0.31 % at b/a = 10, 20, 50 (48, 48, 64 terms along
    # y; the end zones need many beam functions, and fewer terms only raise it).
    w, _ = _ritz(1.0, 20.0, 1.0, 1.0, 0.3, 4, 48)
    assert 0.0 < (w[0] * 400.0) / (beam * math.sqrt(1.0 - 0.09)) - 1.0 < 0.01


def test_reference_has_converged(reference):
    # 30 x 24 against 40 x 32 terms (60 x 48 in the module docstring): frequencies of the
    # modes to 12 kHz within 1e-4 (measured 2.3e-5), band means within 2e-3 (measured 1e-5,
    # 2e-5, 7e-5, 3e-4 in the octaves 1-8 kHz).
    omega, wc = reference
    omega2, wc2 = _thesis_reference(40, 32)
    assert np.sum(omega < 2.0 * math.pi * 12e3) == 60
    np.testing.assert_allclose(omega2[:60], omega[:60], rtol=1e-4)
    Z = z_inf(THESIS)
    np.testing.assert_allclose(_series(omega2, wc2**2, 0.05, Z), _series(omega, wc**2, 0.05, Z), rtol=2e-3)
    # All 720 modes of the basis are summed; those above 40 kHz (its 194th on) add 0.0012/Z to
    # the 8 kHz octave and < 4e-4/Z below: their frequencies need no accuracy.
    high = omega > 2.0 * math.pi * 40e3
    part = _series(omega[high], wc[high] ** 2, 0.05, Z)
    assert np.all(np.abs(part) < 3e-3), part


def test_one_khz_octave_is_the_plates_own(reference, model64):
    # The independent modes give the 1 kHz octave 0.812/Z: 19 % below 1/Z, so "within 10 %
    # of 1/Z" is not a property of this plate at its centre there; the octaves 2-8 kHz are
    # within it (1.032, 0.946, 0.959).
    zeta = float(np.atleast_1d(model64.zeta)[0])
    assert zeta == 0.05
    omega, wc = reference
    ref = _series(omega, wc**2, zeta, z_inf(THESIS))
    assert ref[0] < 0.9, ref
    assert np.all(np.abs(ref[1:] - 1.0) < 0.10), ref
    # Few modes: three that move the centre in the octave 0.71-1.41 kHz (1.047, 1.215 and
    # 1.410 kHz; the asymptotic density of the doubly symmetric quarter, S sqrt(m''/D) / 8
    # per Hz, gives 3.3).
    f = omega / (2.0 * math.pi)
    assert np.sum((f > 1000.0 / math.sqrt(2.0)) & (f < 1000.0 * math.sqrt(2.0))) == 3


def test_model_modes_and_band_mobility_match_the_reference(reference, model64, model128):
    omega, wc = reference
    Z = z_inf(THESIS)
    zeta = float(np.atleast_1d(model64.zeta)[0])
    ref = _series(omega, wc**2, zeta, Z)
    # The model's excited modes are the reference's doubly symmetric ones: frequencies within
    # 2e-4 (measured 5.4e-5 for N = 64, 1.4e-4 for N = 128, the latter the project's basis at
    # its 48-term cap, converging from above).  Single centre amplitudes are not compared:
    # close pairs (e.g. 11685.0 and 11686.6 Hz) share theirs differently in each basis.
    np.testing.assert_allclose(model64.omega_rad_s, omega[:64], rtol=2e-4)
    np.testing.assert_allclose(model128.omega_rad_s, omega[:128], rtol=2e-4)
    # The model's modal sum alone (element removed), N = 64 (last mode 12.9 kHz): within 1 %
    # of the reference in the octaves 1-4 kHz (measured -0.05, -0.08, -0.42 %: the modes
    # above 12.9 kHz that it lacks).
    plain = model64.replace(local_impedance_n_s_m=0.0, residual_compliance_m_n=0.0)
    np.testing.assert_allclose(band_means(plain, OCTAVES_HZ[:3]) * Z, ref[:3], rtol=0.01)
    # The whole model, in the octaves well below the element's cut (omega_c / 2 pi = 13.0 kHz
    # at N = 64, 26.1 kHz at N = 128): within 2 %.  Measured +0.29, +0.98 % (N = 64, 1-2 kHz)
    # and +0.06, +0.25, +1.07 % (N = 128, 1-4 kHz): the element's real part there,
    # ~ (4/pi^2) (omega/omega_c)^2 / Z (1.1 % in the 2 kHz octave at N = 64), and the 2 %
    # leaves the 1 kHz octave's 19 % from 1/Z far outside.
    np.testing.assert_allclose(band_means(model64, OCTAVES_HZ[:2]) * Z, ref[:2], rtol=0.02)
    np.testing.assert_allclose(band_means(model128, OCTAVES_HZ[:3]) * Z, ref[:3], rtol=0.02)
    # Not asserted (module docstring): nearer the cut the element's real part exceeds the
    # omitted modes' (+4.1 and +12.2 % over the reference at 4 and 8 kHz for N = 64).
