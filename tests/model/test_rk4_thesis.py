"""Tests of the thesis's RK4 integrator (Appendix A.1 ``evolve``), against independent references.

References: the closed-form linear solution evaluated in mpmath
(:func:`sdf_reference.closed_form_xv`, itself checked against
``mpmath.odefun`` in ``test_reference.py``), ``solve_ivp`` DOP853 at rtol 1e-12
(checked against the mpmath reference there to 1e-9), and the analytic release
time from the stop.
"""

from __future__ import annotations

import math
from itertools import pairwise
from typing import Any

import numpy as np
import pytest
from scipy.optimize import brentq

from rattle_lab.exceptions import ParameterError
from sdf_reference import closed_form_xv, scipy_impacts
from rattle_lab.model.sdf._rk4_thesis import run_rk4_thesis

# A run that never reaches the stop: |x| < 0.5 throughout.
FREE: dict[str, Any] = dict(F=0.15, omega=0.7, zeta=0.05, e=0.6, t0=0.0, x0=0.3, v0=-0.2, theta0=0.4)


def _free_end_error(steps_per_period: int, duration: float) -> float:
    p = FREE
    out = run_rk4_thesis(**p, duration=duration, steps_per_period=steps_per_period)
    assert out[0].size == 0  # no impact
    x_ref, v_ref = closed_form_xv(p["F"], p["omega"], p["zeta"], p["x0"], p["v0"], p["theta0"], duration)
    return max(abs(out[7] - float(x_ref)), abs(out[8] - float(v_ref)))


def test_fourth_order_convergence_without_impacts() -> None:
    # Classical RK4: global error O(h^4), so halving h divides the error by 2^4 = 16.
    # Observed ratios are 16.1-16.3; the tolerance [15, 17.5] allows the O(h^5)
    # next term (relative size ~ h, 2-6 % at these steps) and nothing more.  The
    # duration is not a multiple of h, so the shortened last step is covered too.
    duration = 3 * 2 * math.pi / FREE["omega"] + 0.37
    errs = [_free_end_error(n, duration) for n in (50, 100, 200, 400)]
    ratios = [a / b for a, b in pairwise(errs)]
    assert all(15.0 < r < 17.5 for r in ratios), ratios
    # Absolute level at the thesis's h = T/200: about 3e-8.
    assert errs[2] < 1e-7


def test_run_covers_exactly_the_duration() -> None:
    p = FREE
    duration = 2.0 * math.pi / p["omega"] * 1.2345
    out = run_rk4_thesis(**p, duration=duration)
    assert out[6] == p["t0"] + duration
    theta_end = (p["theta0"] + p["omega"] * duration) % (2 * math.pi)
    assert np.isclose(out[9], theta_end, rtol=0, atol=1e-12)
    assert not out[10]


def test_zero_duration_returns_the_start() -> None:
    out = run_rk4_thesis(0.2, 1.0, 0.05, 0.6, 5.0, 0.1, 0.2, 1.0, 0.0)
    assert out[6:] == (5.0, 0.1, 0.2, 1.0, False)
    assert all(a.size == 0 for a in out[:6])


def test_crossing_velocity_is_the_thesis_interpolation() -> None:
    # getx0v: v_cross = v - a dt x/(x - x_old), an interpolation back from the
    # step's end.  Its error is bounded by |x'''| h^2/2 (the acceleration used
    # is the one at the step's end) plus the O(h^2) error of the interpolated
    # time times |a|; here |x'''| <= F omega + 2 zeta |a| + |v| <= F omega + 1.
    p = FREE
    duration = 3 * 2 * math.pi / p["omega"]
    worst = {}
    for n in (200, 800):
        h = 2 * math.pi / p["omega"] / n
        out = run_rk4_thesis(**p, duration=duration, steps_per_period=n, want_crossings=True)
        assert out[4].size == 3
        errs = []
        for tc, vc in zip(out[4], out[5]):
            t_ref = brentq(lambda s: float(closed_form_xv(p["F"], p["omega"], p["zeta"], p["x0"], p["v0"],
                                                           p["theta0"], s)[0]), tc - h, tc + h, xtol=1e-15)  # fmt: skip
            _, v_ref = closed_form_xv(p["F"], p["omega"], p["zeta"], p["x0"], p["v0"], p["theta0"], t_ref)
            assert vc > 0
            assert abs(tc - t_ref) < h * h  # time: linear interpolation, O(h^2)
            errs.append(abs(vc - float(v_ref)))
        assert max(errs) < 0.5 * h * h * (p["F"] * p["omega"] + 1.0)
        worst[n] = max(errs)
    # Second order: 4x smaller h, errors at least 8x smaller (16x expected).
    assert worst[800] < worst[200] / 8


def test_impact_velocity_converges_to_scipy_reference() -> None:
    # First impact of case (i) from rest (transversal, v_in ~ 0.16).  The thesis
    # predicts the impact time linearly, h1 = (1 - x)/(v + (l1+l2+l3)/12); with
    # x = x_n + v tau + a tau^2/2 + ..., its error is h^2 a rho (rho/2 - 1/4)/v,
    # rho = tau/h in [0, 1], so |dt| <= |a| h^2/(4 v_in) (to leading order), and
    # |dv_in| ~ |a| |dt|.  The reference: solve_ivp DOP853 at rtol 1e-12, good
    # to ~1e-10 here (test_reference.py), far below the errors tested.
    F, omega, zeta, e = 0.2, 1.0, 0.05, 0.6
    duration = 3 * 2 * math.pi
    ref = scipy_impacts(F, omega, zeta, e, 0.0, 0.0, 0.0, duration, dense_check=False)
    assert ref.t.size == 1
    t_ref, v_ref = ref.t[0], ref.v_in[0]
    a_ref = F * math.cos(omega * t_ref) - 2 * zeta * v_ref - 1.0  # x'' just before the impact
    errs_v = {}
    for n in (200, 400, 800, 1600, 3200):
        h = 2 * math.pi / omega / n
        out = run_rk4_thesis(F, omega, zeta, e, 0.0, 0.0, 0.0, 0.0, duration, steps_per_period=n)
        assert out[0].size == 1
        bound_t = 1.2 * abs(a_ref) * h * h / (4 * v_ref)  # 1.2: higher-order terms
        assert abs(out[0][0] - t_ref) < bound_t
        assert abs(out[2][0] - v_ref) < 1.2 * abs(a_ref) * bound_t
        assert np.isclose(out[3][0], e * out[2][0], rtol=1e-15, atol=0)
        phase = (omega * out[0][0]) % (2 * math.pi)
        assert np.isclose(out[1][0], phase, rtol=0, atol=1e-12)
        errs_v[n] = abs(out[2][0] - v_ref)
    # Converges: 16x smaller h gives well over 16x smaller error (h^2: 256x, but
    # rho varies with h, so only 50x is asked).
    assert errs_v[3200] < errs_v[200] / 50
    assert errs_v[3200] < 1e-5


def test_sticking_until_the_analytic_release() -> None:
    # On the stop (x = 1, v = 0) with F cos(theta) > 1 the thesis keeps the mass
    # stuck; it is released at the first step whose RK4 prediction from (1, 0)
    # falls below 1, i.e. within about one step of F cos(theta) = 1.
    F, omega, zeta, e = 3.0, 0.5, 0.1, 0.5
    theta0 = 0.2
    t_release = (math.acos(1.0 / F) - theta0) / omega
    h = 2 * math.pi / omega / 200
    stuck = run_rk4_thesis(F, omega, zeta, e, 0.0, 1.0, 0.0, theta0, t_release - 2 * h)
    assert stuck[7:9] == (1.0, 0.0) and stuck[10]
    assert stuck[0].size == 0
    free = run_rk4_thesis(F, omega, zeta, e, 0.0, 1.0, 0.0, theta0, t_release + 2 * h)
    assert free[7] < 1.0 and free[8] < 0.0 and not free[10]


@pytest.mark.parametrize(
    "F, omega, zeta, e",
    [(0.2, 1.0, 0.05, 0.6), (0.2, 0.93, 0.05, 0.6), (2.0, 0.5, 0.1, 0.5), (3.0, 0.5, 0.1, 0.5), (2.0, 1.5, 0.0, 1.0)],
)
@pytest.mark.parametrize("n", [50, 200])
def test_no_nan_and_impacts_in_time_order(F: float, omega: float, zeta: float, e: float, n: int) -> None:
    duration = 20 * 2 * math.pi / omega
    out = run_rk4_thesis(F, omega, zeta, e, 0.0, 0.0, 0.0, 0.0, duration, steps_per_period=n, want_crossings=True)
    for a in out[:6]:
        assert np.all(np.isfinite(a))
    assert all(math.isfinite(v) for v in out[6:10])
    assert out[0].size > 0
    assert np.all(np.diff(out[0]) > 0)
    assert np.all((out[1] >= 0) & (out[1] < 2 * math.pi))
    assert out[7] <= 1.0 + 1e-2  # only the post-impact overshoot of the linear prediction


def test_sticking_case_reaches_the_stuck_branch() -> None:
    # Case (v) of the benchmark: complete chatter, then sticking (mpmath reference:
    # stuck on [13.6706, 15.0283]).  The thesis ends the chatter within a few
    # steps and then holds x = 1, v = 0.
    F, omega, zeta, e = 3.0, 0.5, 0.1, 0.5
    out = run_rk4_thesis(F, omega, zeta, e, 0.0, 0.0, 0.0, 0.0, 14.5)
    assert out[7:9] == (1.0, 0.0) and out[10]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(omega=0.0), r"`omega` must be > 0, was 0.0"),
        (dict(duration=-1.0), r"`duration` must be >= 0, was -1.0"),
        (dict(steps_per_period=0), r"`steps_per_period` must be an integer >= 1, was 0"),
        (dict(steps_per_period=2.5), r"`steps_per_period` must be an integer >= 1, was 2.5"),
        (dict(x0=float("nan")), r"`x0` must be finite, was nan"),
    ],
)
def test_invalid_arguments(kwargs: dict[str, float], match: str) -> None:
    args = dict(F=0.2, omega=1.0, zeta=0.05, e=0.6, t0=0.0, x0=0.0, v0=0.0, theta0=0.0, duration=1.0)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=match):
        run_rk4_thesis(**args)  # type: ignore[arg-type]
