"""Tests of rattle_lab.model.analysis.maps: regime maps, basins and the disturbance study.

References: the closed-form 1/n orbits and their stability (rattle_lab.model.analysis),
the grazing forcing (eq. 3.4), and the unstable 1/1 orbit, which the
trajectory at the disturbance threshold must visit (it lies on the boundary
of the impact-free response's basin).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.analysis import one_over_n_orbits
from rattle_lab.model.analysis._disturbance import (
    _impact_free_start,
    disturbance_map,
    disturbance_threshold,
)
from rattle_lab.model.analysis.maps import basin_map, regime_map
from rattle_lab.model.sdf import SDFParams, SDFState, simulate
from rattle_lab.plot import plot_attractor_map, plot_disturbance_map

P_HYST = SDFParams(F=0.2, omega=1.15, zeta=0.05, e=0.6)


@pytest.fixture(scope="module")
def rmap():  # type: ignore[no-untyped-def]
    return regime_map([0.05, 0.2], [0.92, 0.96, 0.98, 1.1])


def test_regime_map_matches_closed_form_orbits(rmap) -> None:  # type: ignore[no-untyped-def]
    # F = 0.05 is below the grazing forcing everywhere here (min 0.1 at omega = 1),
    # so no impact.  At F = 0.2 the stable 1/n orbit of Fig. 4-3 at each omega:
    # 1/4 (0.9118 < omega < 0.9284), 1/2 (0.9717 < omega < 0.9847), 1/1; and chaos
    # at 0.96.  After the 100 discarded periods the transient has decayed like
    # |mu_1|^(100/n) (3e-5 for 1/2 at 0.98, 9e-6 for 1/4 at 0.92, 3e-35 for 1/1), times
    # the initial distance (< 1): the impact velocities equal the closed form to that.
    assert rmap.labels().tolist() == [["no impact"] * 4, ["1/4", "aperiodic", "1/2", "1/1"]]
    assert rmap.code.tolist() == [[0, 0, 0, 0], [1, 2, 1, 1]]
    for j, n in ((0, 4), (2, 2), (3, 1)):
        p = SDFParams(F=0.2, omega=float(rmap.x[j]), zeta=0.05, e=0.6)
        orbit = one_over_n_orbits(p, n)[1]
        assert orbit.stable
        decay = abs(orbit.multipliers[0]) ** (100 / n)
        assert rmap.max_impact_velocity[1, j] == pytest.approx(orbit.v_im,
                                                               rel=max(decay, 1e-10))
        # mean per cycle = v_im / n, to one impact at the window edge (50 kept periods)
        assert rmap.mean_impact_velocity[1, j] == pytest.approx(orbit.v_im / n,
                                                                rel=n / 50 + 1e-9)
    assert rmap.lyapunov[1, 1] > 0.01
    assert np.isnan(rmap.lyapunov[1, [0, 2, 3]]).all()
    assert not rmap.sticking.any()
    assert rmap.counts() == {"no impact": 4, "1/1": 1, "1/2": 1, "1/4": 1, "aperiodic": 1}


def test_regime_map_is_the_same_as_single_runs(rmap) -> None:  # type: ignore[no-untyped-def]
    # each point is an independent run from rest: compare one with simulate
    p = SDFParams(F=0.2, omega=0.96, zeta=0.05, e=0.6)
    res = simulate(p, cycles=150, state=SDFState())
    kept = res.impacts.v_in[res.impacts.t >= 100 * p.period]
    assert rmap.max_impact_velocity[1, 1] == kept.max()
    assert rmap.mean_impact_velocity[1, 1] == kept.sum() / 50


def test_basin_map_hysteresis_region() -> None:
    # Above resonance and below grazing the impact-free response and the 1/1
    # orbit coexist: rest stays impact-free, a large velocity reaches 1/1.
    bm = basin_map(P_HYST, [0.0], [0.0, 1.5], cycles=100, discard=70)
    assert bm.labels()[:, 0].tolist() == ["no impact", "1/1"]
    hi = one_over_n_orbits(P_HYST, 1)[1]
    assert bm.max_impact_velocity[1, 0] == pytest.approx(hi.v_im, rel=1e-8)
    assert bm.x_name == "x0" and bm.y_name == "v0" and bm.kind == "basin"


def test_disturbance_threshold_sits_on_the_unstable_orbit() -> None:
    # The boundary of the impact-free basin is the stable manifold of the unstable
    # (lower-velocity) 1/1 orbit.  Bisected to 1e-10, the trajectory with the
    # threshold kick must pass close to that orbit: several impacts with v_in within
    # 1e-3 of its closed-form velocity (measured: closest approach ~1e-7), then
    # settle on the stable 1/1; a kick 1e-10 smaller ends impact-free.
    kick = disturbance_threshold(P_HYST, kick_tol=1e-10)
    lo, hi = one_over_n_orbits(P_HYST, 1)
    assert lo.exists and not lo.stable and hi.stable
    above = simulate(P_HYST, cycles=200, state=_impact_free_start(P_HYST, kick))
    rel = np.abs(above.impacts.v_in / lo.v_im - 1.0)
    assert np.sum(rel < 1e-3) >= 3 and rel.min() < 1e-4
    assert above.impacts.v_in[-1] == pytest.approx(hi.v_im, rel=1e-8)
    below = simulate(P_HYST, cycles=200, state=_impact_free_start(P_HYST, kick - 1e-10))
    assert below.impacts.t[-1] < 100 * P_HYST.period


def test_impact_free_start_is_on_the_linear_response() -> None:
    # x = 0 rising with v = omega F / sqrt(D) (eq. 4.7-4.9): without a kick, no
    # impact and the crossings repeat the start.
    st = _impact_free_start(P_HYST, 0.0)
    D = (1 - 1.15 ** 2) ** 2 + (2 * 0.05 * 1.15) ** 2
    assert st.v == pytest.approx(1.15 * 0.2 / math.sqrt(D), rel=1e-14)
    res = simulate(P_HYST, cycles=20, state=st, crossings=True)
    assert len(res.impacts) == 0
    assert res.crossings is not None
    np.testing.assert_allclose(res.crossings.v, st.v, rtol=1e-12)


def test_disturbance_map_fig47_structure(tmp_path: Path) -> None:
    # NaN at or above grazing (no impact-free response), inf where no kick up to
    # kick_max sustains impact (here below the 1/1 saddle-node, where no impacting
    # orbit exists), and inside the hysteresis region a threshold that falls as F
    # grows (the demarcation curves of Fig. 4-7 rise with omega).
    F = np.array([0.09, 0.15, 0.2, 0.25])
    w = np.array([1.08, 1.15])
    dm = disturbance_map(F, w, kick_tol=1e-2)
    grazing = np.hypot(1 - w ** 2, 0.1 * w)
    assert np.array_equal(np.isnan(dm.threshold), F[:, None] >= grazing[None, :])
    assert np.isinf(dm.threshold[0]).all() and not dm.hysteresis[0].any()
    col = dm.threshold[1:, 1]
    assert dm.hysteresis[1:, 1].all() and np.all(np.isfinite(col)) and np.all(np.diff(col) < 0)
    assert dm.threshold[1, 0] < dm.threshold[1, 1]
    json.dumps(dm.to_dict())
    png = plot_disturbance_map(dm, tmp_path / "d.png", levels=(0.2, 0.5))
    assert png.read_bytes()[:4] == b"\x89PNG"


def test_map_plots_and_json(rmap, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    doc = json.loads(json.dumps(rmap.to_dict()))
    assert doc["labels"][1] == ["1/4", "aperiodic", "1/2", "1/1"]
    assert doc["lyapunov"][0][0] is None
    out = plot_attractor_map(rmap, tmp_path / "r.svg")
    assert b"<svg" in out.read_bytes()[:500]
    bm = basin_map(P_HYST, [-0.5, 0.0, 0.5], [0.0, 1.5], cycles=60, discard=30)
    assert plot_attractor_map(bm, tmp_path / "b.png").stat().st_size > 1000


def test_invalid_arguments(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="`F` must not be empty"):
        regime_map([], [1.0])
    with pytest.raises(ParameterError, match="`omega` must be finite"):
        regime_map([0.1], [math.nan])
    with pytest.raises(ParameterError, match="`omega` must be > 0"):
        regime_map([0.1], [0.0])
    with pytest.raises(ParameterError, match="`discard` must be < cycles"):
        regime_map([0.1], [1.0], cycles=10, discard=10)
    with pytest.raises(ParameterError, match="`n_max` must be <="):
        regime_map([0.1], [1.0], cycles=20, discard=10, n_max=6)
    with pytest.raises(ParameterError, match="`workers` must be an integer >= 1, was 0"):
        regime_map([0.1], [1.0], workers=0)
    with pytest.raises(ParameterError, match="`scheduler` must be an address"):
        regime_map([0.1], [1.0], scheduler="")
    with pytest.raises(ParameterError, match="`chunk_size` must be an integer >= 1"):
        regime_map([0.1], [1.0], chunk_size=0)
    with pytest.raises(ParameterError, match="`state` must be an SDFState at t = 0"):
        regime_map([0.1], [1.0], state=SDFState(t=5.0))
    with pytest.raises(ParameterError, match="`x0` must be <= 1"):
        basin_map(P_HYST, [1.5], [0.0])
    with pytest.raises(ParameterError, match="`params` must be an SDFParams"):
        basin_map("p", [0.0], [0.0])  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="`kick_tol` must be in"):
        disturbance_threshold(P_HYST, kick_tol=5.0)
    with pytest.raises(ParameterError, match="`kick_max` must be finite and > 0"):
        disturbance_threshold(P_HYST, kick_max=-1.0)
    with pytest.raises(ParameterError, match="`check_cycles` must be < cycles"):
        disturbance_threshold(P_HYST, cycles=20, check_cycles=20)
    with pytest.raises(ParameterError, match="must end in .png, .pdf or .svg"):
        plot_attractor_map(basin_map(P_HYST, [0.0], [0.0], cycles=30, discard=0, n_max=1),
                           tmp_path / "x.gif")
