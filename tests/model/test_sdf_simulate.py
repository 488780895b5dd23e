"""The exact event-driven simulator: references, grazing, chatter, sticking, invariants.

Reference for impacts: :func:`sdf_reference.mpmath_impacts`, an
independent event-driven solver that evaluates the closed form at 30 digits and
locates impacts with its own root scan.  Tolerance for impact times and
velocities: 1e-11.  The double-precision closed form has an absolute error of a
few ulp of the motion's size per evaluation; along a stable orbit over ~10
impacts the errors stay within ~1e-13 (the benchmark measures this), and 1e-11
leaves room for the conditioning of impact times (error / v_in).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from rattle_lab.exceptions import ParameterError, SimulationError
from rattle_lab.model.sdf import SDFParams, SDFState, particular_state, simulate
from sdf_reference import mpmath_impacts

REF_CASES = {
    "1/1 orbit": (0.2, 1.0, 0.05, 0.6, 0.0, 0.0, 0.0, 40.0),
    "below resonance": (0.2, 0.93, 0.05, 0.6, 0.0, 0.0, 0.0, 40.0),
    "undamped, F>1": (1.3, 0.8, 0.0, 0.5, 0.0, 0.0, 0.0, 30.0),
    "critical damping": (2.5, 0.9, 1.0, 0.7, 0.5, 0.5, 1.0, 20.0),
    "over-damped": (4.0, 0.7, 1.5, 0.4, 0.0, 0.0, 0.0, 20.0),
    "start on stop": (0.5, 1.2, 0.1, 0.8, 1.0, -0.3, 2.0, 30.0),
}


@pytest.mark.parametrize("name", list(REF_CASES))
def test_impacts_match_mpmath_reference(name):
    F, w, z, e, x0, v0, th0, T = REF_CASES[name]
    ref = mpmath_impacts(F, w, z, e, x0, v0, th0, T, dps=30)
    res = simulate(SDFParams(F, w, z, e), duration=T, state=SDFState(x=x0, v=v0, theta=th0))
    assert len(ref.t) > 0, "case must contain impacts"
    # Chatter sequences are followed impact by impact down to different speeds
    # (the reference to 1e-10, ours until the geometric tail is below rounding),
    # so impacts are compared above 1e-6 and the accumulation points directly.
    ref_t = np.array([float(q) for q in ref.t])
    ref_v = np.array([float(q) for q in ref.v_in])
    keep_ref = ref_v > 1e-6
    keep = res.impacts.v_in > 1e-6
    assert keep.sum() == keep_ref.sum()
    np.testing.assert_allclose(res.impacts.t[keep], ref_t[keep_ref], rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.impacts.v_in[keep], ref_v[keep_ref], rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.impacts.v_out, e * res.impacts.v_in, rtol=1e-15)
    np.testing.assert_allclose(res.accumulations, [float(q) for q in ref.accumulations],
                               rtol=0, atol=1e-11)
    np.testing.assert_allclose(res.sticking, np.array(ref.sticking, dtype=float).reshape(-1, 2),
                               rtol=0, atol=1e-11)
    assert res.state.t == pytest.approx(T, rel=1e-14)


@pytest.mark.parametrize("method", ["exact", "exact-python"])
def test_compiled_and_python_paths_agree(method):
    p = SDFParams(0.2, 0.95, 0.05, 0.6)
    a = simulate(p, cycles=30, crossings=True, method="exact")
    b = simulate(p, cycles=30, crossings=True, method=method)
    assert len(a.impacts) == len(b.impacts) > 10
    # same algorithm; numba may contract or reorder floating point operations
    np.testing.assert_allclose(a.impacts.t, b.impacts.t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.impacts.v_in, b.impacts.v_in, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a.crossings.v, b.crossings.v, rtol=0, atol=1e-12)


def test_tangency_free_oscillator_reports_the_touch():
    # x(t) = cos(t - 1): touches x = 1 at t = 1 exactly, nowhere else in [0, 3]
    res = simulate(SDFParams(0.0, 1.0, 0.0, 0.5), duration=3.0,
                   state=SDFState(x=math.cos(1.0), v=math.sin(1.0)))
    assert len(res.impacts) == 1
    assert res.impacts.t[0] == pytest.approx(1.0, abs=1e-7)  # a graze is located to sqrt(eps)
    assert res.impacts.v_in[0] == pytest.approx(0.0, abs=1e-7)


@pytest.mark.parametrize("theta0", [0.0, 0.3, 1.234, 4.0])
def test_tangency_forced_steady_state_touches_each_period(theta0):
    # the linear steady state with F on the grazing curve (eq. 3.4) has amplitude 1
    w, z = 0.9, 0.05
    F = math.sqrt((1 - w * w) ** 2 + (2 * z * w) ** 2)
    xp, vp = particular_state(F, w, z, theta0)
    p = SDFParams(F, w, z, 0.6)
    res = simulate(p, cycles=3, state=SDFState(x=float(xp), v=float(vp), theta=theta0))
    # one touch per forcing period, where x_p peaks: phase = atan2(A_s, A_c) (mod 2 pi)
    peak = math.atan2(2 * z * w, 1 - w * w) % (2 * math.pi)
    expected = [(peak - theta0) % (2 * math.pi) / w + k * p.period for k in range(3)]
    expected = [t for t in expected if t <= 3 * p.period]
    assert len(res.impacts) >= len(expected) - 1 >= 1
    for t_imp, t_exp in zip(res.impacts.t, expected):
        assert t_imp == pytest.approx(t_exp, abs=1e-6)
    assert np.all(res.impacts.v_in < 1e-6)
    # 1e-9 below the grazing amplitude: no impact at all
    scaled = simulate(SDFParams(F * (1 - 1e-9), w, z, 0.6), cycles=3,
                      state=SDFState(x=float(xp) * (1 - 1e-9), v=float(vp) * (1 - 1e-9),
                                     theta=theta0))
    assert len(scaled.impacts) == 0


@pytest.mark.parametrize("method", ["exact", "exact-python"])
@pytest.mark.parametrize("w0", [1e-2, 1e-3, 1e-4])
def test_chatter_accumulation_matches_geometric_series(method, w0):
    # leave the stop slowly while F cos(theta) - 1 = 2 pushes back: complete chatter
    F, w, z, e = 3.0, 0.2, 0.05, 0.5
    res = simulate(SDFParams(F, w, z, e), duration=20.0,
                   state=SDFState(x=1.0, v=-w0, theta=0.0), method=method)
    a_stop = F - 1.0
    t_geo = 2 * w0 / (a_stop * (1 - e))  # sum of 2 w e^k / a
    assert len(res.accumulations) >= 1
    # the geometric series is the leading term; its relative error is O(w0)
    # (damping and the drift of the force over the sequence), here ~0.034 w0
    assert abs(res.accumulations[0] - t_geo) <= 0.1 * w0 * t_geo
    # then stuck until the force reverses: F cos(omega t) = 1
    t_release = math.acos(1 / F) / w
    assert res.sticking[0, 0] == pytest.approx(res.accumulations[0], abs=0)
    assert res.sticking[0, 1] == pytest.approx(t_release, rel=1e-14)
    # micro-impacts were followed until the geometric tail fell below rounding
    assert len(res.impacts) < 60
    v_in = res.impacts.v_in[: len(res.impacts)]
    early = v_in[(res.impacts.t < res.accumulations[0])]
    assert np.all(np.diff(early) < 0)


def test_inelastic_impact_sticks_and_releases_analytically():
    F, w, z = 3.0, 0.5, 0.1
    res = simulate(SDFParams(F, w, z, 0.0), cycles=3)
    assert len(res.sticking) >= 2
    psi = math.acos(1 / F)
    for start, end in res.sticking[:-1]:
        # stuck only while the force pushes into the stop; release exactly where it reverses
        theta_end = (w * end) % (2 * math.pi)
        assert theta_end == pytest.approx(psi, abs=1e-12)
        mid = 0.5 * (start + end)
        assert F * math.cos(w * mid) - 1 > 0
    assert np.all(res.impacts.v_out == 0.0)


def test_sticking_state_round_trip():
    p = SDFParams(3.0, 0.5, 0.1, 0.0)
    a = simulate(p, cycles=1.1)
    b = simulate(p, duration=1.0, state=a.state)
    assert b.state.t == pytest.approx(a.state.t + 1.0)
    full = simulate(p, duration=a.state.t + 1.0)
    assert full.state.x == pytest.approx(b.state.x, abs=1e-12)
    assert full.state.v == pytest.approx(b.state.v, abs=1e-12)


def test_continuation_equals_one_run():
    p = SDFParams(0.2, 1.0, 0.05, 0.6)
    one = simulate(p, cycles=20)
    first = simulate(p, cycles=10)
    second = simulate(p, cycles=10, state=first.state)
    both_t = np.concatenate([first.impacts.t, second.impacts.t])
    both_v = np.concatenate([first.impacts.v_in, second.impacts.v_in])
    np.testing.assert_allclose(both_t, one.impacts.t, rtol=0, atol=1e-11)
    np.testing.assert_allclose(both_v, one.impacts.v_in, rtol=0, atol=1e-11)


def test_forcing_phase_continuity_when_omega_changes():
    p1 = SDFParams(0.2, 1.0, 0.05, 0.6)
    first = simulate(p1, duration=7.3)
    theta = first.state.theta
    assert theta == pytest.approx((1.0 * 7.3) % (2 * math.pi), abs=1e-12)
    p2 = p1.replace(omega=1.2)
    second = simulate(p2, duration=0.0, state=first.state, dense_t=[first.state.t],
                      dense_fields=("excitation",))
    # the excitation is continuous across the change of omega
    assert second.dense.excitation[0] == pytest.approx(0.2 * math.cos(theta), abs=1e-15)


def test_dense_output_is_consistent():
    p = SDFParams(0.2, 1.0, 0.05, 0.6)
    T = 10 * p.period
    t = np.linspace(0.0, T, 20001)
    res = simulate(p, duration=T, dense_t=t,
                   dense_fields=("x", "v", "a", "forced", "transient", "excitation"))
    d = res.dense
    assert np.all(d.x <= 1.0)
    np.testing.assert_allclose(d.forced + d.transient, d.x, atol=1e-14)
    np.testing.assert_allclose(d.a, d.excitation - 2 * 0.05 * d.v - d.x, atol=1e-14)
    np.testing.assert_allclose(d.excitation, 0.2 * np.cos(t), atol=1e-12)
    # v is the derivative of x away from impacts (central differences, O(h^2))
    h = t[1] - t[0]
    dxdt = (d.x[2:] - d.x[:-2]) / (2 * h)
    near = np.zeros(t.size, bool)
    for ti in res.impacts.t:
        near |= np.abs(t - ti) < 3 * h
    ok = ~near[1:-1]
    np.testing.assert_allclose(dxdt[ok], d.v[1:-1][ok], atol=1e-5)
    # x = 1 at the impacts
    at = simulate(p, duration=T, dense_t=res.impacts.t, dense_fields=("x",)).dense.x
    np.testing.assert_allclose(at, 1.0, atol=1e-14)


def test_only_requested_outputs_are_computed():
    p = SDFParams(0.2, 1.0, 0.05, 0.6)
    res = simulate(p, cycles=5)
    assert res.crossings is None and res.dense is None
    res = simulate(p, cycles=5, dense_t=[0.0, 1.0], dense_fields=("v",))
    assert res.dense.v is not None and res.dense.x is None and res.dense.a is None


def test_upward_crossings_of_zero():
    p = SDFParams(0.2, 1.0, 0.05, 0.6)
    res = simulate(p, cycles=50, crossings=True)
    c = res.crossings
    assert len(c) >= 49 and np.all(c.v > 0)
    # on the 1/1 orbit the crossing velocity settles to one value
    assert np.ptp(c.v[-10:]) < 1e-9
    xs = simulate(p, cycles=50, dense_t=c.t, dense_fields=("x",)).dense.x
    np.testing.assert_allclose(xs, 0.0, atol=1e-12)


# --- stress corpus: bounded time and invariants ------------------------------------

ZETAS = [0.0, 1e-9, 0.5, 1.0, 1.5, 20.0]
ES = [0.0, 1e-6, 0.5, 1.0]
FS = [1e-6, 0.5, 3.0, 1e3]
OMEGAS = [0.01, 1.0, 100.0]


def _check_invariants(res):
    imp = res.impacts
    assert np.all(np.isfinite(imp.t)) and np.all(np.isfinite(imp.v_in))
    assert np.all(np.diff(imp.t) >= 0), "time must be monotone"
    # v_in > 0 for transversal impacts; a graze (within 4 ulp of the stop) has v_in ~ 0
    assert np.all(imp.v_in >= 0)
    assert np.all((imp.phase >= 0) & (imp.phase < 2 * math.pi))
    assert res.state.x <= 1.0 and math.isfinite(res.state.v)
    if res.crossings is not None:
        assert np.all(res.crossings.v >= 0)


@pytest.mark.parametrize("zeta,e,F,omega", list(itertools.product(ZETAS, ES, FS, OMEGAS)))
def test_stress_corpus(zeta, e, F, omega):
    p = SDFParams(F, omega, zeta, e)
    cycles = 2 if omega == 0.01 else 20
    T = cycles * p.period
    res = simulate(p, cycles=cycles, crossings=True, dense_t=np.linspace(0, T, 257))
    _check_invariants(res)
    assert np.all(res.dense.x <= 1.0) and np.all(np.isfinite(res.dense.a))
    if F > 1 and e < 1 and zeta < 20 and omega < 100:
        # F > 1 pushes through the stop: contact, chatter or sticking must occur
        assert len(res.impacts) + len(res.sticking) > 0


@pytest.mark.parametrize("params", [(0.2, 1.0, 0.05, 0.6), (0.2, 0.93, 0.05, 0.6),
                                    (3.0, 0.5, 0.1, 0.5)])
def test_long_runs(params):
    res = simulate(SDFParams(*params), cycles=1e5)
    _check_invariants(res)
    assert res.state.t == pytest.approx(1e5 * 2 * math.pi / params[1], rel=1e-12)
    assert len(res.impacts) > 1e4


def test_elastic_micro_bouncing_is_averaged_and_bounded():
    # e = 1 with damping and a push into the stop has no accumulation point;
    # the bounces are averaged once they are shorter than TAU_MICRO
    p = SDFParams(3.0, 0.01, 0.5, 1.0)
    res = simulate(p, cycles=1)
    _check_invariants(res)
    assert len(res.micro_bounce) >= 1
    start, end, n_bounces = res.micro_bounce[0]
    assert end > start and n_bounces > 100
    inside = (res.impacts.t > start) & (res.impacts.t < end)
    assert not np.any(inside)


# --- errors ------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs,match", [
    ({"F": -1.0, "omega": 1.0, "zeta": 0.1, "e": 0.5}, r"`F` must be >= 0, was -1.0"),
    ({"F": 0.1, "omega": 0.0, "zeta": 0.1, "e": 0.5}, r"`omega` must be > 0, was 0.0"),
    ({"F": 0.1, "omega": 1.0, "zeta": -0.1, "e": 0.5}, r"`zeta` must be >= 0, was -0.1"),
    ({"F": 0.1, "omega": 1.0, "zeta": 0.1, "e": 1.5}, r"`e` must be in \[0, 1\], was 1.5"),
    ({"F": math.nan, "omega": 1.0, "zeta": 0.1, "e": 0.5}, r"`F` must be finite, was nan"),
    ({"F": 1e-300, "omega": 1.0, "zeta": 0.1, "e": 0.5},
     r"`F` must be 0 or of magnitude >= 1e-150, was 1e-300"),
])
def test_invalid_parameters(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        SDFParams(**kwargs)


def test_invalid_state_and_arguments():
    p = SDFParams(0.2, 1.0, 0.05, 0.6)
    with pytest.raises(ParameterError, match=r"`x` must be <= 1 \(the stop is at x = 1\), was 1.5"):
        SDFState(x=1.5)
    with pytest.raises(ParameterError, match="a stuck state must have x = 1 and v = 0"):
        SDFState(x=0.5, stuck=True)
    with pytest.raises(ParameterError, match="give exactly one of `duration` and `cycles`"):
        simulate(p)
    with pytest.raises(ParameterError, match="give exactly one of `duration` and `cycles`"):
        simulate(p, duration=1.0, cycles=1.0)
    with pytest.raises(ParameterError, match=r"`cycles` must be finite and >= 0, was -1.0"):
        simulate(p, cycles=-1)
    with pytest.raises(ParameterError, match=r"`duration` must be finite and >= 0, was inf"):
        simulate(p, duration=math.inf)
    with pytest.raises(ParameterError, match="`method` must be one of"):
        simulate(p, cycles=1, method="euler")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="`dense_t` must be non-decreasing"):
        simulate(p, cycles=1, dense_t=[1.0, 0.5])
    with pytest.raises(ParameterError, match=r"`dense_t` must lie within \[0.0, "):
        simulate(p, duration=1.0, dense_t=[0.0, 2.0])
    with pytest.raises(ParameterError, match="`dense_fields` entries must be in"):
        simulate(p, cycles=1, dense_t=[0.0], dense_fields=("jerk",))  # type: ignore[list-item]
    with pytest.raises(ParameterError, match="`params` must be an SDFParams, was dict"):
        simulate({"F": 1}, cycles=1)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"`max_events` must be > 0, was 0"):
        simulate(p, cycles=1, max_events=0)
    with pytest.raises(ParameterError, match=r"`max_events` must be an integer, was 2.5"):
        simulate(p, cycles=1, max_events=2.5)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"`cycles` must be a number, was 'x'"):
        simulate(p, cycles="x")  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match=r"`duration` must be a number, was \[1.0\]"):
        simulate(p, duration=[1.0])  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="`dense_t` is available for the exact methods only"):
        simulate(p, cycles=1, dense_t=[0.0], method="rk4-thesis")


def test_event_budget_raises_simulation_error():
    with pytest.raises(SimulationError, match=r"event budget of 5 events exhausted at t = "):
        simulate(SDFParams(0.2, 1.0, 0.05, 0.6), cycles=100, max_events=5)


def test_packed_result_unpacks_to_the_kernels_arrays():
    """simulate() reads the kernel's one-buffer result (``run_packed``): the same impacts,
    crossings, sticking, accumulations, dense motion and end state as ``run``'s six arrays,
    exactly (same kernel); a run with chatter, sticking and crossings."""
    from rattle_lab.model.sdf import _kernel
    import importlib

    simulate_module = importlib.import_module("rattle_lab.model.sdf._simulate")
    from rattle_lab.model.sdf._compiled import jit_kernel

    assert simulate_module._N_HEAD == _kernel.N_HEAD
    p = SDFParams(F=2.0, omega=0.3, zeta=0.05, e=0.5)
    start = SDFState(t=0.25, x=0.1, v=0.2, theta=1.0)
    res = simulate(p, state=start, cycles=6, crossings=True, dense_t=np.linspace(0.25, 100, 50))
    (imp, n_imp, acc, n_acc, stk, n_stk, crs, n_crs, seg, n_seg, t, x, v, th, stuck, n_ev,
     status, n_unres, avg, n_avg) = jit_kernel.run(p.F, p.omega, p.zeta, p.e, start.t, start.x,
                                                   start.v, start.theta, False,
                                                   6 * p.period, True, True, 10**7)
    assert n_imp > 10 and n_stk > 0 and n_acc > 0 and n_crs > 0 and status == 0
    for j, name in enumerate(("t", "phase", "v_in", "v_out")):
        np.testing.assert_array_equal(getattr(res.impacts, name), imp[:n_imp, j])
        assert not getattr(res.impacts, name).flags.writeable
    np.testing.assert_array_equal(res.accumulations, acc[:n_acc, 0])
    np.testing.assert_array_equal(res.sticking, stk[:n_stk])
    np.testing.assert_array_equal(res.crossings.t, crs[:n_crs, 0])
    np.testing.assert_array_equal(res.crossings.v, crs[:n_crs, 1])
    np.testing.assert_array_equal(res.micro_bounce, avg[:n_avg])
    assert res.state == SDFState(t=t, x=x, v=v, theta=th, stuck=stuck)
    assert res.n_events == n_ev
    dense = simulate_module.dense_from_segments(p, seg[:n_seg], np.linspace(0.25, 100, 50),
                                                ("x", "v", "a"))
    np.testing.assert_array_equal(res.dense.x, dense.x)
    empty = simulate(p, state=start, cycles=0.001)
    assert len(empty.impacts) == 0 and empty.sticking.shape == (0, 2)
    assert empty.micro_bounce.shape == (0, 3) and empty.accumulations.shape == (0,)
