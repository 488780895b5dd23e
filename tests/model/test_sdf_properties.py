"""Property tests of the simulator over the parameter box (hypothesis, derandomized)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rattle_lab.model.sdf import SDFParams, SDFState, flow, simulate

PROFILE = settings(max_examples=120, deadline=None, derandomize=True,
                   suppress_health_check=[HealthCheck.too_slow])

def _mag(lo: float, hi: float) -> st.SearchStrategy[float]:
    """Floats in [lo, hi]: exact zero or magnitudes >= 1e-150 (SDFParams rejects smaller)."""
    return st.floats(lo, hi).filter(lambda q: q == 0.0 or abs(q) >= 1e-150)


params_box = st.builds(
    SDFParams,
    F=_mag(0.0, 5.0),
    omega=st.floats(0.05, 5.0),
    zeta=st.one_of(st.just(0.0), st.floats(0.0, 2.5)),
    e=st.floats(0.0, 1.0),
)
states = st.builds(
    SDFState,
    x=_mag(-3.0, 1.0),
    v=_mag(-3.0, 3.0),
    theta=st.floats(0.0, 2 * math.pi, exclude_max=True),
)


@PROFILE
@given(p=params_box, s0=states)
def test_invariants_hold_everywhere(p, s0):
    res = simulate(p, cycles=4, state=s0, crossings=True)
    imp = res.impacts
    assert np.all(np.isfinite(imp.t)) and np.all(np.isfinite(imp.v_in))
    assert np.all(np.diff(imp.t) >= 0)
    assert np.all((imp.t >= s0.t) & (imp.t <= res.state.t))
    assert np.all(imp.v_in >= 0)
    np.testing.assert_array_equal(imp.v_out, p.e * imp.v_in)
    assert res.state.x <= 1.0
    assert math.isfinite(res.state.v)
    assert res.state.t == math.fsum([s0.t, 4 * p.period]) or abs(
        res.state.t - (s0.t + 4 * p.period)) <= 1e-12 * max(1.0, res.state.t)
    assert np.all(res.crossings.v >= 0)


@PROFILE
@given(F=_mag(0.0, 0.99), omega=st.floats(0.2, 3.0), zeta=st.floats(0.0, 1.5),
       e=st.floats(0.05, 1.0), s0=states)
def test_no_impact_is_missed_between_logged_impacts(F, omega, zeta, e, s0):
    """F < 1 cannot stick, so the motion is free flights joined by the logged impacts.

    Re-evaluate every flight independently with the vectorised closed form on a
    fine grid: it must stay below the stop (a missed impact would show as x > 1)
    and reach it at the next logged impact.
    """
    p = SDFParams(F, omega, zeta, e)
    res = simulate(p, cycles=3, state=s0)
    # no sticking of any duration (a start on the stop moving outward, F = 0, may log an
    # empty one at its start: found by Hypothesis, not yet explained in the kernel)
    assert all(b <= a for a, b in res.sticking)
    starts = [(s0.t, s0.x, s0.v, s0.theta)]
    for t, ph, v_out in zip(res.impacts.t, res.impacts.phase, res.impacts.v_out):
        starts.append((t, 1.0, -v_out, ph))
    ends = list(res.impacts.t) + [res.state.t]
    for (t0, x0, v0, th0), t1 in zip(starts, ends):
        if t1 <= t0:
            continue
        s = np.linspace(0.0, t1 - t0, 400)[1:-1]
        x, _ = flow(F, omega, zeta, x0, v0, th0, s)
        # rounding of the closed form near the stop: a few ulp of the motion's size
        assert np.max(x, initial=-np.inf) <= 1.0 + 1e-9
    # each impact is on the stop: the flight that ends there reaches x = 1
    for (t0, x0, v0, th0), t1 in zip(starts[:-1], res.impacts.t):
        x1, _ = flow(F, omega, zeta, x0, v0, th0, t1 - t0)
        assert abs(x1 - 1.0) <= 1e-9


@settings(max_examples=40, deadline=None, derandomize=True)
@given(p=params_box, s0=states)
def test_compiled_matches_python_on_short_runs(p, s0):
    a = simulate(p, cycles=1, state=s0, method="exact")
    b = simulate(p, cycles=1, state=s0, method="exact-python")
    # same algorithm and the same decisions, except where numba's floating point
    # contraction moves a near-graze across the 4-ulp threshold: then counts may differ
    if len(a.impacts) == len(b.impacts):
        np.testing.assert_allclose(a.impacts.t, b.impacts.t, rtol=0, atol=1e-9)
    else:
        assert min(np.min(a.impacts.v_in, initial=1), np.min(b.impacts.v_in, initial=1)) < 1e-6
    assert abs(a.state.t - b.state.t) <= 1e-12 * max(1.0, abs(a.state.t))
