"""Closed-form free flight against mpmath at 50 digits.

References: (1) the same closed form evaluated in mpmath at 50 digits, itself
checked against (2) ``mpmath.odefun``, an independent Taylor-series ODE solver.
Tolerance: the double-precision closed form is evaluated with a handful of
roundings on quantities of size ~max(|x_p|, |y|), so the absolute error is a few
ulp of that size; we allow 64 eps * scale (scale = 1 + |x_p| + |y| + ...).
"""

from __future__ import annotations

import math

import mpmath as mp
import numpy as np
import pytest

from rattle_lab.model.sdf import flow, homogeneous_transition, particular_coeffs
from rattle_lab.model.sdf._compiled import jit_kernel, python_kernel

mp.mp.dps = 50
EPS = np.finfo(float).eps


def mp_flow(F, w, z, x0, v0, th0, s):
    """Closed form at 50 digits (independent derivation in mpmath)."""
    F, w, z, x0, v0, th0, s = (mp.mpf(q) for q in (F, w, z, x0, v0, th0, s))
    if z == 0 and w == 1:
        xp = lambda t: F / 2 * t * mp.sin(th0 + t)  # noqa: E731
        vp = lambda t: F / 2 * (mp.sin(th0 + t) + t * mp.cos(th0 + t))  # noqa: E731
    else:
        D = (1 - w**2) ** 2 + (2 * z * w) ** 2
        Ac, As = F * (1 - w**2) / D, F * 2 * z * w / D
        xp = lambda t: Ac * mp.cos(th0 + w * t) + As * mp.sin(th0 + w * t)  # noqa: E731
        vp = lambda t: w * (As * mp.cos(th0 + w * t) - Ac * mp.sin(th0 + w * t))  # noqa: E731
    y0, yd0 = x0 - xp(0), v0 - vp(0)
    # roots of r^2 + 2 z r + 1 = 0
    if z == 1:
        y = (y0 + (yd0 + y0) * s) * mp.exp(-s)
        yd = (yd0 - (yd0 + y0) * s) * mp.exp(-s)
    else:
        disc = mp.sqrt(mp.mpc(z**2 - 1))
        r1, r2 = -z + disc, -z - disc
        c1 = (yd0 - r2 * y0) / (r1 - r2)
        c2 = (r1 * y0 - yd0) / (r1 - r2)
        y = mp.re(c1 * mp.exp(r1 * s) + c2 * mp.exp(r2 * s))
        yd = mp.re(c1 * r1 * mp.exp(r1 * s) + c2 * r2 * mp.exp(r2 * s))
    return xp(s) + y, vp(s) + yd


CASES = [
    # F, omega, zeta, x0, v0, theta0, s
    (0.2, 1.0, 0.05, 0.3, -0.4, 0.7, 3.1),
    (0.2, 0.93, 0.05, 1.0, -0.2, 2.0, 6.5),
    (1.3, 0.8, 0.0, 0.1, 0.2, 0.3, 5.0),
    (0.5, 1.0, 0.0, -0.5, 0.1, 1.1, 4.0),      # undamped resonance (secular)
    (2.0, 0.5, 1.0, 0.9, -1.0, 0.4, 2.5),      # critical damping
    (3.0, 2.0, 1.5, -0.2, 0.7, 5.0, 1.7),      # over-damped
    (1e3, 0.01, 20.0, 0.5, 0.0, 0.1, 30.0),    # heavy over-damping
    (0.1, 100.0, 1e-9, 0.2, 0.3, 0.0, 0.05),   # fast forcing
    (0.7, 1.3, 1.0 - 1e-9, 0.4, -0.3, 0.2, 2.0),  # just under-critical
    (0.7, 1.3, 1.0 + 1e-9, 0.4, -0.3, 0.2, 2.0),  # just over-critical
]


@pytest.mark.parametrize("case", CASES)
def test_flow_matches_mpmath(case):
    F, w, z, x0, v0, th0, s = case
    xr, vr = mp_flow(*case)
    x, v = flow(F, w, z, x0, v0, th0, s)
    scale = 1 + abs(float(xr)) + abs(float(vr)) + F / max(abs(1 - w * w) + 2 * z * w, 1e-3)
    assert abs(x - float(xr)) <= 64 * EPS * scale
    assert abs(v - float(vr)) <= 64 * EPS * scale


@pytest.mark.parametrize("kernel", [python_kernel, jit_kernel], ids=["python", "numba"])
@pytest.mark.parametrize("case", CASES)
def test_kernel_evaluate_matches_mpmath(kernel, case):
    F, w, z, x0, v0, th0, s = case
    P = kernel.make_params(F, w, z, 0.5)
    S = np.zeros(kernel.N_S)
    kernel.start_segment(P, S, th0, x0, v0, x0 == 1.0)
    x, v, a, y, yd, zstop = kernel.evaluate(P, S, s)
    xr, vr = mp_flow(*case)
    scale = 1 + abs(float(xr)) + abs(float(vr)) + F / max(abs(1 - w * w) + 2 * z * w, 1e-3)
    assert abs(x - float(xr)) <= 64 * EPS * scale
    assert abs(v - float(vr)) <= 64 * EPS * scale
    # the acceleration is the equation of motion itself
    assert a == pytest.approx(F * math.cos(th0 + w * s) - 2 * z * v - x, abs=64 * EPS * scale)


@pytest.mark.parametrize("case", [CASES[0], CASES[4], CASES[5]])
def test_mpmath_closed_form_matches_odefun(case):
    """The 50-digit reference itself, against mpmath's Taylor ODE solver."""
    F, w, z, x0, v0, th0, s = case
    mp.mp.dps = 30
    try:
        sol = mp.odefun(lambda t, u: [u[1], F * mp.cos(th0 + w * t) - 2 * z * u[1] - u[0]],
                        0, [mp.mpf(x0), mp.mpf(v0)])
        xo, vo = sol(mp.mpf(s))
        xr, vr = mp_flow(*case)
        assert abs(xo - xr) < mp.mpf(10) ** -25
        assert abs(vo - vr) < mp.mpf(10) ** -25
    finally:
        mp.mp.dps = 50


def test_taylor_near_stop_matches_closed_form():
    """Near a start on the stop, x - 1 comes from the Taylor series: relative accuracy."""
    F, w, z = 3.0, 0.2, 0.05
    P = python_kernel.make_params(F, w, z, 0.5)
    S = np.zeros(python_kernel.N_S)
    vstart = -1e-6
    python_kernel.start_segment(P, S, 0.0, 1.0, vstart, True)
    for s in (1e-8, 1e-7, 5e-7):
        _, v, _, _, _, zstop = python_kernel.evaluate(P, S, s)
        xr, vr = mp_flow(F, w, z, 1.0, vstart, 0.0, s)
        assert zstop == pytest.approx(float(xr - 1), rel=1e-12)
        assert v == pytest.approx(float(vr), rel=1e-12)


def test_particular_and_transition_limits():
    A_c, A_s = particular_coeffs(0.2, 1.0, 0.05)
    assert A_c == pytest.approx(0.0, abs=1e-16) and A_s == pytest.approx(2.0, rel=1e-15)
    Ec, Es = homogeneous_transition(np.array([0.5, 1.0, 2.0]), 0.0)
    np.testing.assert_array_equal(Ec, 1.0)
    np.testing.assert_array_equal(Es, 0.0)
    # no overflow or NaN for heavy damping over long times
    Ec, Es = homogeneous_transition(20.0, 1e4)
    assert np.isfinite(Ec) and np.isfinite(Es) and Ec >= 0


def test_particular_coeffs_with_a_damping_whose_square_underflows() -> None:
    """At resonance with zeta ~ 1e-193, (2 zeta omega)^2 underflows to 0: no 0/0.

    Found by Hypothesis (test_sdf_properties drew F = 0, omega = 1, zeta = 1.6e-193 and
    the flow came out NaN).  Reference: the closed form A_c = 0, A_s = F / (2 zeta omega)
    at omega = 1, exact in binary here (a power-of-two damping).
    """
    zeta = 2.0 ** -640                       # 2 zeta squared is far below the smallest double
    A_c, A_s = particular_coeffs(0.0, 1.0, zeta)
    assert float(A_c) == 0.0 and float(A_s) == 0.0
    A_c, A_s = particular_coeffs(2.0 ** -600, 1.0, zeta)
    assert float(A_c) == 0.0 and float(A_s) == 2.0 ** -600 / (2.0 * zeta)
    # unforced: the flow is the free oscillation cos/sin (damping below rounding)
    x, v = flow(0.0, 1.0, 1.6e-193, 0.3, 0.1, 0.0, 2.0)
    assert x == pytest.approx(0.3 * np.cos(2.0) + 0.1 * np.sin(2.0), rel=1e-15, abs=1e-16)
    assert v == pytest.approx(-0.3 * np.sin(2.0) + 0.1 * np.cos(2.0), rel=1e-15, abs=1e-16)
