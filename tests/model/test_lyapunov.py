"""Tests of rattle_lab.model.analysis.lyapunov: the largest Lyapunov exponent from the impact log.

References: the Floquet multipliers of the closed-form 1/1 orbits
(rattle_lab.model.analysis.one_over_n_orbits), an explicit numpy product of the
saltation and transition matrices (rattle_lab.model.analysis._saltation), and
central finite differences of the simulator itself.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from rattle_lab.model.analysis import OneOverNOrbit, one_over_n_orbits
from rattle_lab.model.analysis._saltation import impact_saltation, transition_matrix
from rattle_lab.model.analysis.lyapunov import (
    _tangent,
    lyapunov_exponent,
    lyapunov_from_result,
    tangent_log_growth,
)
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams, SDFState, simulate

BASE = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)


def _on_orbit(p: SDFParams) -> tuple[SDFState, OneOverNOrbit]:
    """A state on the stable 1/1 orbit half a period after its impact, and the orbit.

    Starting mid-flight puts both ends of every whole-period window at the same
    section of the orbit, away from the impact.
    """
    orbit = [o for o in one_over_n_orbits(p, 1) if o.exists and o.stable][0]
    after = SDFState(x=1.0, v=-p.e * orbit.v_im, theta=orbit.phase)
    return simulate(p, duration=0.5 * p.period, state=after).state, orbit


@pytest.mark.parametrize("omega", [0.99, 1.225])
def test_stable_1_1_orbit_with_real_multipliers_matches_floquet(omega: float) -> None:
    # Real, distinct multipliers: after the warm-up the tangent vector lies along the
    # leading eigenvector and every period contributes exactly log|mu_1|.  The
    # simulated orbit equals the closed form to rounding, so the tolerance 1e-9
    # (relative) is limited only by impact times located to ~1e-14.
    p = BASE.replace(omega=omega)
    state, orbit = _on_orbit(p)
    assert abs(orbit.multipliers[0].imag) == 0.0
    res = lyapunov_exponent(p, cycles=400, warmup_cycles=100, state=state)
    expected = math.log(abs(orbit.multipliers[0])) / orbit.period
    assert res.status == "ok" and res.n_impacts == 300
    assert res.exponent == pytest.approx(expected, rel=1e-9)
    assert res.per_period == pytest.approx(expected * p.period, rel=1e-9)


def test_stable_1_1_orbit_with_complex_multipliers() -> None:
    # Complex pair: |M^k w| / |mu|^k stays within [1/c, c], c = cond(eigenvectors),
    # so the estimate over a window L is within 2 log(c) / L of log|mu| / T.
    p = BASE.replace(omega=1.1)
    state, orbit = _on_orbit(p)
    assert abs(orbit.multipliers[0].imag) > 0.1
    M = impact_saltation(p.F, p.zeta, p.e, orbit.phase, orbit.v_im) @ transition_matrix(
        p.zeta, orbit.period)
    cond = np.linalg.cond(np.linalg.eig(M)[1])
    res = lyapunov_exponent(p, cycles=2000, warmup_cycles=100, state=state)
    length = res.t_stop - res.t_start
    expected = math.log(abs(orbit.multipliers[0])) / orbit.period
    assert abs(res.exponent - expected) <= 2.0 * math.log(cond) / length
    # both exponents equal: the tangent product agrees with the determinants' sum
    assert res.n_impacts == 1900
    assert abs(res.exponent - res.exponent_sum / 2.0) <= 2.0 * math.log(cond) / length


def test_tangent_product_equals_explicit_matrix_product() -> None:
    # A hand-built impact log (any times, phases, velocities) against the numpy
    # saltation and transition matrices of the orbits developer: 1e-12 relative.
    rng = np.random.default_rng(7)
    p = BASE
    t = np.cumsum(rng.uniform(0.2, 9.0, 40))
    phase = rng.uniform(0.0, 2.0 * math.pi, 40)
    v_in = rng.uniform(0.05, 1.0, 40)
    checkpoints = np.array([t[9], t[25] + 0.5, t[-1] + 20.0])
    growth, dirs, status = _tangent(t, phase, v_in, np.empty((0, 2)), p.F, p.zeta, p.e, 0.0,
                                    0.0, checkpoints, 1.0, 0.0, 2.0 * math.pi)
    assert status == 0
    w = np.array([1.0, 0.0])
    t_now = 0.0
    for i in range(40):
        w = transition_matrix(p.zeta, t[i] - t_now) @ w
        w = impact_saltation(p.F, p.zeta, p.e, phase[i], v_in[i]) @ w
        t_now = t[i]
        if i == 9:
            assert growth[0] == pytest.approx(math.log(np.linalg.norm(w)), rel=1e-12)
            np.testing.assert_allclose(dirs[0], w / np.linalg.norm(w), rtol=1e-12, atol=1e-14)
        if i == 25:
            w25 = transition_matrix(p.zeta, 0.5) @ w
            assert growth[1] == pytest.approx(math.log(np.linalg.norm(w25)), rel=1e-12)
    w = transition_matrix(p.zeta, 20.0) @ w
    assert growth[2] == pytest.approx(math.log(np.linalg.norm(w)), rel=1e-12)


def test_chaotic_case_matches_central_finite_differences() -> None:
    # Benettin's method with the simulator itself: two runs from the reference
    # state +- delta * d over each forcing period, the difference renormalised.
    # Central differences cancel the restart's rounding and leave O(delta^2)
    # truncation; at delta = 1e-6 the measured error is ~5e-7 in the cumulative
    # log growth over 150 periods, so 1e-5 is a 20-fold margin.
    p = BASE.replace(omega=0.94)
    st = simulate(p, cycles=500).state
    T, n = p.period, 150
    tc = st.t + T * np.arange(1, n + 1)
    ref = simulate(p, duration=n * T, state=st, dense_t=tc, dense_fields=("x", "v"))
    assert ref.dense is not None and ref.dense.x is not None and ref.dense.v is not None
    delta = 1e-6
    d = np.array([1.0, 1.0]) / math.sqrt(2.0)
    fd, total = [], 0.0
    x, v, t_prev = st.x, st.v, st.t
    for j in range(n):
        theta = st.theta + p.omega * (t_prev - st.t)
        runs = [simulate(p, duration=tc[j] - t_prev,
                         state=SDFState(t=t_prev, x=x + s * delta * d[0], v=v + s * delta * d[1],
                                        theta=theta)).state for s in (1.0, -1.0)]
        sep = 0.5 * np.array([runs[0].x - runs[1].x, runs[0].v - runs[1].v])
        norm = float(np.hypot(*sep))
        total += math.log(norm / delta)
        fd.append(total)
        d = sep / norm
        x, v, t_prev = ref.dense.x[j], ref.dense.v[j], tc[j]
    growth, _ = tangent_log_growth(p, ref, tc, t_start=st.t, w0=(1.0, 1.0))
    np.testing.assert_allclose(growth, fd, rtol=0, atol=1e-5)
    assert growth[-1] / (n * T) > 0.01  # and it grows: chaos


def test_chaotic_case_has_positive_exponent_and_periodic_window_negative() -> None:
    # Thesis Fig. 4-3: chaos after the 1/4 orbit's secondary grazing (0.9284);
    # inside the 1/4 window (stable between its period doubling 0.91183 and 0.9284,
    # rattle_lab.model.analysis.branch_events) the exponent is negative.
    chaos = lyapunov_exponent(BASE.replace(omega=0.94), cycles=2000, warmup_cycles=500)
    assert chaos.status == "ok" and chaos.exponent > 0.01
    p4 = BASE.replace(omega=0.92)
    st = simulate(p4, cycles=400, state=SDFState(x=0.5)).state
    periodic = lyapunov_exponent(p4, cycles=600, warmup_cycles=100, state=st)
    assert periodic.exponent < -0.005


def test_no_impact_motion_decays_at_the_damping_rate() -> None:
    # Free damped flight: both exponents are -zeta; the transition matrix's
    # non-normality bounds the finite-window error by log(1 / sqrt(1 - zeta^2)) / L
    # (a few 1e-6 here); 1e-4 leaves room.
    res = lyapunov_exponent(BASE.replace(F=0.05), cycles=300, warmup_cycles=50)
    assert res.n_impacts == 0
    assert res.exponent == pytest.approx(-0.05, abs=1e-4)
    assert res.exponent_sum == -0.1


def test_sticking_collapses_the_tangent_and_trajectories() -> None:
    # F > 1: complete chatter, then the mass sticks and is released at the phase
    # arccos(1/F) whatever came before: -inf, and two different starts coincide
    # after their first stick (independent check on the simulator).
    p = SDFParams(F=1.5, omega=0.3, zeta=0.05, e=0.6)
    res = lyapunov_exponent(p, cycles=20, warmup_cycles=5)
    assert res.status == "sticking" and res.exponent == -math.inf and res.n_sticking > 0
    a = simulate(p, cycles=20)
    b = simulate(p, cycles=20, state=SDFState(x=-0.3, v=0.2))
    ra, rb = a.sticking[2, 1], b.sticking[2, 1]
    assert ra == pytest.approx(rb, rel=1e-12)
    ta, tb = a.impacts.t[a.impacts.t > ra][:5], b.impacts.t[b.impacts.t > rb][:5]
    np.testing.assert_allclose(ta, tb, rtol=1e-12)


def test_sticking_during_warmup_restarts_the_vector() -> None:
    # Hand-built: no impacts, a stuck interval [1, 2] before the warm-up end 3:
    # the growth from 3 to 10 is that of Phi(7) applied to Phi(1) w0 (restart at 2).
    p = BASE
    stick = np.array([[1.0, 2.0]])
    growth, _, status = _tangent(np.empty(0), np.empty(0), np.empty(0), stick, p.F, p.zeta,
                                 p.e, 0.0, 3.0, np.array([3.0, 10.0]), 1.0, 0.0, 1.0)
    assert status == 0
    w3 = transition_matrix(p.zeta, 1.0) @ np.array([1.0, 0.0])
    w10 = transition_matrix(p.zeta, 7.0) @ w3
    assert growth[1] - growth[0] == pytest.approx(
        math.log(np.linalg.norm(w10) / np.linalg.norm(w3)), rel=1e-12)
    # the same interval after the warm-up end: collapse
    _, _, status = _tangent(np.empty(0), np.empty(0), np.empty(0), stick, p.F, p.zeta, p.e,
                            0.0, 0.5, np.array([0.5, 10.0]), 1.0, 0.0, 1.0)
    assert status == 1


def test_grazing_impact_and_micro_bounce_are_reported_not_computed() -> None:
    res = simulate(BASE, cycles=30)
    v = np.array(res.impacts.v_in)
    v[10] = 0.0
    graze = dataclasses.replace(res, impacts=dataclasses.replace(res.impacts, v_in=v))
    out = lyapunov_from_result(graze, t_start=0.0, warmup=5 * BASE.period)
    assert out.status == "grazing-impact" and math.isnan(out.exponent)
    bounce = dataclasses.replace(res, micro_bounce=np.array([[1.0, 2.0, 10.0]]))
    out = lyapunov_from_result(bounce, t_start=0.0)
    assert out.status == "micro-bounce" and math.isnan(out.exponent)
    assert out.to_dict()["exponent"] is None


def test_invalid_arguments() -> None:
    with pytest.raises(ParameterError, match="`cycles` must be > warmup_cycles"):
        lyapunov_exponent(BASE, cycles=10, warmup_cycles=10)
    with pytest.raises(ParameterError, match="`warmup_cycles` must be >= 0"):
        lyapunov_exponent(BASE, cycles=10, warmup_cycles=-1)
    with pytest.raises(ParameterError, match="`params` must be an SDFParams"):
        lyapunov_exponent("p", cycles=10)  # type: ignore[arg-type]
    res = simulate(BASE, cycles=5)
    with pytest.raises(ParameterError, match="`warmup` must be in"):
        lyapunov_from_result(res, t_start=0.0, warmup=10 * BASE.period)
    with pytest.raises(ParameterError, match="`times` must be sorted"):
        tangent_log_growth(BASE, res, np.array([2.0, 1.0]), t_start=0.0)
    with pytest.raises(ParameterError, match="`w0` must be a finite nonzero vector"):
        tangent_log_growth(BASE, res, np.array([1.0]), t_start=0.0, w0=(0.0, 0.0))


def test_to_dict_is_json_ready() -> None:
    import json

    p = SDFParams(F=1.5, omega=0.3, zeta=0.05, e=0.6)
    d = lyapunov_exponent(p, cycles=20, warmup_cycles=5).to_dict()
    assert d["exponent"] == "-inf" and d["status"] == "sticking"
    json.dumps(d)
