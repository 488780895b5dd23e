"""Tests of the independent references in ``tests/sdf_reference.py``.

The closed form is checked against ``mpmath.odefun`` (Taylor series at the
working precision), the impact search against an analytic grazing impact, the
reference against itself at two precisions, and ``solve_ivp`` against the
mpmath reference.
"""

from __future__ import annotations

import math
from itertools import pairwise

import mpmath
import numpy as np
import pytest

from rattle_lab.exceptions import ParameterError
from sdf_reference import (
    check_closed_form_against_odefun,
    closed_form_xv,
    mpmath_impacts,
    scipy_impacts,
)


@pytest.mark.parametrize("zeta", [0.05, 1.0, 1.7])  # under-, critically and over-damped branches
def test_closed_form_matches_odefun(zeta: float) -> None:
    # Both at 30 digits; odefun's own tolerance is about the working epsilon, so
    # 1e-25 leaves 5 digits for rounding in both and is still 1e9 times tighter
    # than anything the double-precision methods are judged at.
    worst = check_closed_form_against_odefun(0.2, 0.93, zeta, 0.1, -0.3, 0.4, [0.7, 2.5, 4.0], dps=30)
    assert worst < 1e-25


def test_closed_form_initial_state_and_static_solution() -> None:
    x, v = closed_form_xv(0.2, 0.93, 0.05, 0.1, -0.3, 0.4, 0.0)
    assert x == mpmath.mpf(0.1) and abs(v - mpmath.mpf(-0.3)) < mpmath.mpf(10) ** -38
    # F = 0: the free damped oscillation x = exp(-zeta t)(cos(wd t) + zeta/wd sin(wd t)).
    zeta, t = 0.25, 3.0
    wd = math.sqrt(1 - zeta**2)
    x, _ = closed_form_xv(0.0, 1.0, zeta, 1.0, 0.0, 0.0, t)
    assert np.isclose(float(x), math.exp(-zeta * t) * (math.cos(wd * t) + zeta / wd * math.sin(wd * t)),
                      rtol=1e-15, atol=0)  # fmt: skip


def _steady_start(F: float, omega: float, zeta: float) -> tuple[float, float, float, mpmath.mpf]:
    """A start on the linear steady state, at its minimum; and the amplitude R (mpf)."""
    with mpmath.workdps(40):
        D = (1 - mpmath.mpf(omega) ** 2) ** 2 + (2 * mpmath.mpf(zeta) * omega) ** 2
        Ac = mpmath.mpf(F) * (1 - mpmath.mpf(omega) ** 2) / D
        As = 2 * mpmath.mpf(F) * zeta * omega / D
        R = mpmath.sqrt(Ac**2 + As**2)
        delta = mpmath.atan2(As, Ac)
        theta0 = float(delta + mpmath.pi)
        x0 = float(Ac * mpmath.cos(theta0) + As * mpmath.sin(theta0))
        v0 = float(omega * (-Ac * mpmath.sin(theta0) + As * mpmath.cos(theta0)))
        return x0, v0, theta0, R


@pytest.mark.parametrize("excess", [1e-12, 1e-6])
def test_grazing_impact_is_found(excess: float) -> None:
    # On the steady orbit x = R cos(psi), psi = theta - delta, R = 1 + excess, the
    # first impact is at psi = -acos(1/R) with v_in = omega sqrt(R^2 - 1).  For
    # excess 1e-12 the orbit stays beyond the stop for only ~3e-6 time units, so
    # any sampling coarser than that would miss it.  Tolerance: the float start
    # lies off the exact orbit by ~1e-16 in x and v (a decaying transient),
    # which moves the impact by ~1e-16 (1 + |a|)/v_in ~ 1e-10 in t and v_in at
    # excess 1e-12; 1e-8 is asked.
    omega, zeta = 0.9, 0.05
    F_graze = math.sqrt((1 - omega**2) ** 2 + (2 * zeta * omega) ** 2)  # thesis eq. (3.4)
    F = F_graze * (1 + excess)
    x0, v0, theta0, R = _steady_start(F, omega, zeta)
    ref = mpmath_impacts(F, omega, zeta, 0.6, x0, v0, theta0, 2 * math.pi / omega, dps=40)
    with mpmath.workdps(40):
        t_pred = (mpmath.pi - mpmath.acos(1 / R)) / omega
        v_pred = omega * mpmath.sqrt(R**2 - 1)
        assert len(ref.t) >= 1
        assert abs(ref.t[0] - t_pred) < 1e-8
        assert abs(ref.v_in[0] - v_pred) < 1e-8
        assert ref.v_in[0] > 0


def test_orbit_just_below_the_stop_has_no_impact() -> None:
    omega, zeta = 0.9, 0.05
    F = math.sqrt((1 - omega**2) ** 2 + (2 * zeta * omega) ** 2) * (1 - 1e-12)
    x0, v0, theta0, _ = _steady_start(F, omega, zeta)
    ref = mpmath_impacts(F, omega, zeta, 0.6, x0, v0, theta0, 5 * 2 * math.pi / omega, dps=40)
    assert len(ref.t) == 0
    assert ref.x_end < 1


def test_reference_agrees_with_itself_at_two_precisions() -> None:
    # Case (ii) of the benchmark (irregular), 20 forcing cycles: dps 30 and 40
    # must agree to ~1e-25 times the error amplification along the orbit; 1e-18
    # leaves a factor 1e7 for that amplification.
    args = (0.2, 0.93, 0.05, 0.6, 0.0, 0.0, 0.0, 20 * 2 * math.pi / 0.93)
    r30 = mpmath_impacts(*args, dps=30)
    r40 = mpmath_impacts(*args, dps=40)
    assert len(r30.t) == len(r40.t) >= 5
    assert max(abs(a - b) for a, b in zip(r30.t, r40.t)) < 1e-18
    assert max(abs(a - b) for a, b in zip(r30.v_in, r40.v_in)) < 1e-18


def test_sticking_reference_release_is_analytic() -> None:
    # Complete chatter, then sticking: the release is at F cos(theta) = 1.
    F, omega = 3.0, 0.5
    ref = mpmath_impacts(F, omega, 0.1, 0.5, 0.0, 0.0, 0.0, 16.0, dps=40)
    assert len(ref.accumulations) == 1 and len(ref.sticking) == 1
    start, end = ref.sticking[0]
    assert start == ref.accumulations[0]
    with mpmath.workdps(40):
        assert abs(F * mpmath.cos(omega * end) - 1) < mpmath.mpf(10) ** -35
        assert F * mpmath.cos(omega * start) > 1
    # The chatter's velocities fall geometrically by e before the accumulation.
    chatter = [v for t, v in zip(ref.t, ref.v_in) if 13.0 < t < start]
    ratios = [float(b / a) for a, b in pairwise(chatter) if a < 1e-6]
    assert ratios and np.allclose(ratios, 0.5, rtol=1e-3)


@pytest.mark.parametrize(
    "F, omega, zeta, e, n_cycles",
    [(0.2, 1.0, 0.05, 0.6, 20), (0.2, 0.93, 0.05, 0.6, 20), (3.0, 0.5, 0.1, 0.5, 3)],
)
def test_scipy_dop853_matches_mpmath(F: float, omega: float, zeta: float, e: float, n_cycles: int) -> None:
    # DOP853 at rtol = atol = 1e-12 has a local error ~1e-12 per step; over the
    # ~10^3 steps of these runs, and through the impact map (which amplifies
    # state errors by O(1-10) per impact in these non-chaotic windows), the
    # impact times and velocities come out within ~5e-11 of the 40-digit
    # reference (observed 2e-11 - 4e-11).  1e-9 is asked: a factor 20 for
    # platform differences, and still 1e6 finer than a missed or spurious impact.
    # Impacts are compared above v_in = 1e-4: the scipy run ends chatter at
    # e v_in < 1e-6, the reference at ~1e-15.
    duration = n_cycles * 2 * math.pi / omega
    ref = mpmath_impacts(F, omega, zeta, e, 0.0, 0.0, 0.0, duration, dps=40)
    sp = scipy_impacts(F, omega, zeta, e, 0.0, 0.0, 0.0, duration, method="DOP853", rtol=1e-12)
    keep_r = ref.v_in_float > 1e-4
    keep_s = sp.v_in > 1e-4
    assert keep_r.sum() == keep_s.sum() >= 7
    assert np.max(np.abs(ref.t_float[keep_r] - sp.t[keep_s])) < 1e-9
    assert np.max(np.abs(ref.v_in_float[keep_r] - sp.v_in[keep_s])) < 1e-9
    assert sp.dense_ok and sp.n_missed_dense == 0
    assert np.all(np.diff(sp.t) > 0)  # no event at a restart point
    assert sp.n_rhs > 0 and not sp.truncated


def test_scipy_coarse_tolerance_is_worse_but_consistent() -> None:
    # RK45 at rtol 1e-6 on case (i): same impacts, errors between 1e-9 and 1e-3.
    args = (0.2, 1.0, 0.05, 0.6, 0.0, 0.0, 0.0, 10 * 2 * math.pi)
    ref = mpmath_impacts(*args, dps=40)
    sp = scipy_impacts(*args, method="RK45", rtol=1e-6)
    assert sp.t.size == len(ref.t)
    err = np.max(np.abs(sp.t - ref.t_float))
    assert 1e-9 < err < 1e-3


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(omega=-1.0), r"`omega` must be > 0, was -1.0"),
        (dict(e=1.5), r"`e` must be in \[0, 1\], was 1.5"),
        (dict(zeta=-0.1), r"`zeta` must be >= 0, was -0.1"),
        (dict(duration=-2.0), r"`duration` must be >= 0, was -2.0"),
        (dict(x0=1.5), r"the start must not lie beyond the stop: x0=1.5, v0=0.0"),
        (dict(F=float("inf")), r"`F` must be finite, was inf"),
    ],
)
@pytest.mark.parametrize("fn", [mpmath_impacts, scipy_impacts])
def test_invalid_arguments(fn, kwargs: dict[str, float], match: str) -> None:  # type: ignore[no-untyped-def]
    args = dict(F=0.2, omega=1.0, zeta=0.05, e=0.6, x0=0.0, v0=0.0, theta0=0.0, duration=1.0)
    args.update(kwargs)
    with pytest.raises(ParameterError, match=match):
        fn(**args)
