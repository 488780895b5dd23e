"""One compiled call per ramp replay (issue 13): the same answer as one simulate() per piece.

The reference is the per-piece loop the ramp model used before
(``rattle_lab.fit._ramp_model._replay_per_piece``, one ``simulate`` call per forcing
period, kept for this comparison) and the plain ``simulate`` loop for
``rattle_lab.model.sdf._simulate.simulate_pieces``.  Tolerance: zero (bit for bit), since both run the
same compiled kernel on the same durations and event budgets; only the number of Python
calls differs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.exceptions import ParameterError
from rattle_lab.fit import RampSpec, fit_restitution_down, model_threshold
from rattle_lab.fit import _ramp_model
from rattle_lab.model.sdf import SDFParams, SDFState, simulate
from rattle_lab.model.sdf._simulate import simulate_pieces
from rattle_lab.detect.thresholds import Threshold

MODAL = dict(gap_m=1.3e-3, f_s_hz=96.0, zeta=0.0085, participation=1.2442)


def _loop(F, omega, zeta, e, t_stop, state):
    times, ends = [], []
    for Fj, tj in zip(F, t_stop):
        res = simulate(SDFParams(F=Fj, omega=omega, zeta=zeta, e=e),
                       duration=max(0.0, tj - state.t), state=state)
        state = res.state
        times.append(res.impacts.t)
        ends.append(state)
    return times, ends


def test_pieces_equal_the_simulate_loop_bit_for_bit():
    """A ramp through grazing and chatter-free impacting motion, and a stretch that sticks
    (F > 1 at omega = 0.3: sticking and releases), pieces of one forcing period."""
    for omega, zeta, e, F0, F1 in ((1.05, 0.01, 0.6, 0.05, 0.4), (0.3, 0.05, 0.5, 1.5, 2.5)):
        n = 60
        F = np.linspace(F0, F1, n)
        t_stop = 0.7 + np.arange(1, n + 1) * 2 * math.pi / omega
        start = SDFState(t=0.7, x=0.2, v=0.0, theta=0.3)
        run = simulate_pieces(F, omega=omega, zeta=zeta, e=e, t_stop=t_stop, state=start)
        times, ends = _loop(F, omega, zeta, e, t_stop, start)
        assert run.offsets.size == n + 1 and run.impact_t.size > 20
        for j in range(n):
            np.testing.assert_array_equal(run.impact_t[run.offsets[j]:run.offsets[j + 1]],
                                          times[j])
            assert run.state(j) == ends[j]


def test_pieces_stop_rules_only_truncate():
    """The early stops return a prefix of the full run, ending at the first piece where the
    rule holds (checked here in plain Python on the full run's impacts)."""
    omega, zeta, e = 1.05, 0.01, 0.6
    n = 80
    F = np.linspace(0.05, 0.4, n)
    t_stop = np.arange(1, n + 1) * 2 * math.pi / omega
    full = simulate_pieces(F, omega=omega, zeta=zeta, e=e, t_stop=t_stop, state=SDFState())
    gap = 1.5 * 2 * math.pi / omega
    grouped = simulate_pieces(F, omega=omega, zeta=zeta, e=e, t_stop=t_stop, state=SDFState(),
                              group_gap=gap, group_size=4)
    t = full.impact_t
    complete = next(i for i in range(3, t.size) if np.all(np.diff(t[i - 3:i + 1]) < gap))
    k = int(np.searchsorted(full.offsets[1:], complete, side="right"))
    assert grouped.offsets.size == k + 2
    np.testing.assert_array_equal(grouped.impact_t, t[:full.offsets[k + 1]])
    # downward, more damped: impacts stop; quiet after 20 time units without impacts
    F_down = np.linspace(0.4, 0.01, n)
    down = simulate_pieces(F_down, omega=omega, zeta=0.05, e=e, t_stop=t_stop,
                           state=SDFState(), quiet_time=20.0)
    ref = simulate_pieces(F_down, omega=omega, zeta=0.05, e=e, t_stop=t_stop,
                          state=SDFState())
    last, k_quiet = math.nan, None
    for j in range(n):
        a, b = ref.offsets[j], ref.offsets[j + 1]
        if b > a:
            last = ref.impact_t[b - 1]
        elif last == last and t_stop[j] - last > 20.0:
            k_quiet = j
            break
    assert k_quiet is not None and down.offsets.size == k_quiet + 2
    np.testing.assert_array_equal(down.impact_t, ref.impact_t[:ref.offsets[k_quiet + 1]])


def test_pieces_bad_input():
    with pytest.raises(ParameterError, match="one length"):
        simulate_pieces([0.1, 0.2], omega=1.0, zeta=0.05, e=0.6, t_stop=[1.0], state=SDFState())
    with pytest.raises(ParameterError, match=">= 0"):
        simulate_pieces([-0.1], omega=1.0, zeta=0.05, e=0.6, t_stop=[1.0], state=SDFState())
    with pytest.raises(ParameterError, match="`omega`"):
        simulate_pieces([0.1], omega=0.0, zeta=0.05, e=0.6, t_stop=[1.0], state=SDFState())


@pytest.mark.parametrize("ramp, anchor", [
    (RampSpec(100.0, "down", 50.0, 3.0, 6.0), 7.0),      # windowed, from the 1/1 orbit
    (RampSpec(100.0, "down", 50.0, 3.0, 6.0), None),     # whole record, settled start
    (RampSpec(100.0, "down", 50.0, 3.0, 6.0), 4.0),      # wrong anchor: redone from start
    (RampSpec(96.0, "up", 3.0, 10.0, 3.0), None),
    (RampSpec(96.0, "up", 3.0, 10.0, 3.0), 6.9),
    (RampSpec(98.0, "down", 26.0, 2.0, 3.0), 6.5),
])
@pytest.mark.parametrize("hold", [1, 3])
def test_one_call_replays_equal_per_piece_replays(monkeypatch, ramp, anchor, hold):
    new = model_threshold(ramp, e=0.6, anchor_ms2=anchor, level_hold_periods=hold, **MODAL)
    monkeypatch.setattr(_ramp_model, "_replay", _ramp_model._replay_per_piece)
    old = model_threshold(ramp, e=0.6, anchor_ms2=anchor, level_hold_periods=hold, **MODAL)
    assert np.any(np.isfinite(old.t_s))
    np.testing.assert_array_equal(new.t_s, old.t_s)
    np.testing.assert_array_equal(new.values_ms2, old.values_ms2)


def test_fitted_e_equals_the_per_piece_fit(monkeypatch):
    """The fit of e by the ramp model (its profile over e and the refinement) on two
    measured-like downward ramps: the same e, chi2 profile and residuals, exactly."""
    ths = [Threshold("down_98", 98.0, "down", 6.6, 2.4, ramp_start_ms2=26.0, ramp_end_ms2=2.0,
                     ramp_duration_s=3.0, ramp_rms_ms2=0.0),
           Threshold("down_100", 100.0, "down", 6.9, 5.5, ramp_start_ms2=50.0,
                     ramp_end_ms2=3.0, ramp_duration_s=6.0, ramp_rms_ms2=0.0)]
    kw = dict(zeta=MODAL["zeta"], gap_m=MODAL["gap_m"], f_s_hz=MODAL["f_s_hz"],
              participation=MODAL["participation"], e_bounds=(0.3, 0.9), e_step=0.1)
    new = fit_restitution_down(ths, **kw)
    monkeypatch.setattr(_ramp_model, "_replay", _ramp_model._replay_per_piece)
    old = fit_restitution_down(ths, **kw)
    assert old.value is not None and math.isfinite(old.value)
    assert new.value == old.value
    np.testing.assert_array_equal(new.chi2, old.chi2)
    np.testing.assert_array_equal(new.model_ms2, old.model_ms2)
