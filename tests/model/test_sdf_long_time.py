"""Impact times stay exact in long runs (issue 13).

The kernel keeps time as a compensated sum (``t + t_lo``, error-free two-sum of
every flight time), so that summing a million flight times adds no drift; the
plain ``t += s`` it replaces was off by 1.2e-8 after 1e4 forcing periods and
7.8e-7 after 1e5 (repeated rounding of ``t + s`` with nearly the same ``s``
is biased).

Reference: a run started on the impact of a stable 1/n orbit (closed form,
:func:`rattle_lab.model.analysis.one_over_n_orbits`) impacts at ``t0 + k n T`` with
``T = 2 pi / omega`` exactly; the reference times are computed in mpmath at 40
digits, independently of the kernel.  The orbit's phase from the closed form
is accurate to ~1e-15 and any offset it makes decays (both multipliers inside
the unit circle), so the simulated times must equal the rounded reference to a
few ulp of ``t``.  Tolerance: 4 ulp of the reference time (measured: <= 1.3 ulp
on both orbits over 1e6 forcing periods; the time of an impact itself is the
rounding of ``t + s_imp``, half an ulp, plus the phase noise of the orbit).
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from rattle_lab.model.analysis import one_over_n_orbits
from rattle_lab.model.sdf import SDFParams, SDFState, simulate


@pytest.mark.parametrize("n, omega", [(1, 1.1), (3, 0.952)])
def test_impact_times_exact_after_a_million_periods(n: int, omega: float) -> None:
    params = SDFParams(F=0.2, omega=omega, zeta=0.05, e=0.6)
    orbit = one_over_n_orbits(params, n)[1]
    assert orbit.exists and orbit.stable
    t0 = 0.25
    start = SDFState(t=t0, x=1.0, v=-params.e * orbit.v_im, theta=orbit.phase)
    res = simulate(params, state=start, cycles=1e6 + 0.5)
    t = res.impacts.t
    assert t.size == 10**6 // n
    mp.mp.dps = 40
    period = 2 * mp.pi / mp.mpf(omega)
    rows = np.unique(np.r_[np.arange(0, t.size, 997), np.arange(t.size - 50, t.size)])
    worst = 0.0
    for i in rows:
        ref = mp.mpf(t0) + int(i + 1) * n * period
        ulp = float(np.spacing(float(ref)))
        worst = max(worst, abs(float(mp.mpf(float(t[i])) - ref)) / ulp)
    assert worst <= 4.0, f"impact time off by {worst:.2f} ulp"
    # and the phases stay on the orbit
    np.testing.assert_allclose(res.impacts.phase[-10:], orbit.phase, atol=1e-12)


def test_end_time_is_exactly_start_plus_duration() -> None:
    # t ends at the correctly rounded t0 + duration, however many flights were summed
    params = SDFParams(F=0.2, omega=1.1, zeta=0.05, e=0.6)
    start = SDFState(t=0.1, x=0.0, v=0.0, theta=0.0)
    res = simulate(params, state=start, duration=2.0e4 * params.period)
    assert res.state.t == 0.1 + 2.0e4 * params.period
