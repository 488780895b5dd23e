"""The ramp fit of e evaluates only the part of its coarse grid it needs (issue 13).

Reference: the same fit on the whole coarse grid (``_restitution._FULL_GRID = True``, the
behaviour before the coarse search).  Tolerance: zero.  The search leaves out only grid
points whose chi2 lies above the 2-sigma cut, and the estimate, its standard error, its
interval, the damping part and the model at the estimate are computed from the points
below the cut and the first point beyond it on each side, which both runs evaluate with
the same code: so they must agree bit for bit.  The test also checks the search's claim
itself on the whole profile: every point it left out is above the cut.

Thresholds 'measured' on the synthetic rig's simulation of continuous ramps (its own
piecing, start and threshold reading), at several true e, one with the estimate near
the end of the grid, one with a flat profile (e not identified) and one with the damping
uncertainty propagated.
"""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.detect.thresholds import Threshold, sustained_impact_time
from rattle_lab.fit import _restitution, fit_restitution_down
from rattle_lab.rig._motion import Modal, simulate_run
from rattle_lab.rig._scene import RunSpec

PLATE = dict(gap_m=1.3e-3, f_s_hz=96.0, participation=1.2442)
ZETA = 0.0085


def _rig_threshold(e: float, freq_hz: float, start: float, end: float,
                   duration_s: float) -> Threshold:
    modal = Modal(f_s_hz=96.0, zeta=ZETA, participation=1.2442, gap_m=1.3e-3, e=e)
    run = RunSpec(f"down_{freq_hz:g}", "amplitude_ramp_down", freq_hz, start, duration_s,
                  level_end_m_s2=end)
    motion = simulate_run(modal, run, piece_periods=1, settle_time_constants=8.0,
                          sample_rate_hz=None)
    t = sustained_impact_time(motion.impact_t_s, freq_hz, "down")
    return Threshold(run.run_id, freq_hz, "down", start + (end - start) * t / duration_s, t,
                     ramp_start_ms2=start, ramp_end_ms2=end, ramp_duration_s=duration_s,
                     ramp_rms_ms2=0.0)


def _fits(monkeypatch, ths, **kw):
    fast = fit_restitution_down(ths, zeta=ZETA, **PLATE, **kw)
    monkeypatch.setattr(_restitution, "_FULL_GRID", True)
    full = fit_restitution_down(ths, zeta=ZETA, **PLATE, **kw)
    monkeypatch.setattr(_restitution, "_FULL_GRID", False)
    return fast, full


def _assert_same(fast, full):
    for name in ("value", "stderr", "ci_low", "ci_high"):
        a, b = getattr(fast, name), getattr(full, name)
        assert a == b, name                       # (None: not available)
    assert fast.stderr_from_zeta == full.stderr_from_zeta
    assert fast.chi2_scale == full.chi2_scale
    assert fast.notes == full.notes
    np.testing.assert_array_equal(fast.model_ms2, full.model_ms2)
    # the points evaluated are points of the whole profile, with the same chi2
    common = np.isin(full.e_grid, fast.e_grid)
    assert np.isin(fast.e_grid, full.e_grid).all()
    np.testing.assert_array_equal(fast.chi2, full.chi2[common])
    # the search's claim: what it left out lies above the 2-sigma cut
    cut = full.chi2.min() + 4 * full.chi2_scale
    assert np.all(full.chi2[~common] > cut)


@pytest.mark.parametrize("e_true, e_step", [(0.6, 0.05), (0.35, 0.025), (0.85, 0.05)])
def test_coarse_search_equals_the_whole_grid(monkeypatch, e_true, e_step):
    ths = [_rig_threshold(e_true, 98.0, 26.0, 2.0, 6.0),
           _rig_threshold(e_true, 100.0, 50.0, 3.0, 6.0)]
    fast, full = _fits(monkeypatch, ths, e_bounds=(0.2, 0.95), e_step=e_step)
    _assert_same(fast, full)
    assert abs(fast.value - e_true) < 0.05          # the fit itself (see test_fit.py)
    assert fast.e_grid.size < full.e_grid.size        # and it did leave points out


def test_coarse_search_near_the_end_of_the_grid(monkeypatch):
    ths = [_rig_threshold(0.9, 100.0, 50.0, 3.0, 6.0)]
    fast, full = _fits(monkeypatch, ths, e_bounds=(0.3, 0.95), e_step=0.05)
    _assert_same(fast, full)


def test_coarse_search_with_the_damping_uncertainty(monkeypatch):
    ths = [_rig_threshold(0.6, 100.0, 50.0, 3.0, 6.0)]
    fast, full = _fits(monkeypatch, ths, e_bounds=(0.2, 0.95), e_step=0.05,
                       zeta_stderr=0.03 * ZETA)
    assert full.stderr_from_zeta > 0
    _assert_same(fast, full)


def test_coarse_search_on_a_flat_profile(monkeypatch):
    """97 Hz on a 3 s ramp: the threshold does not depend on e (test_fit.py)."""
    ths = [_rig_threshold(0.6, 97.0, 16.0, 2.0, 3.0)]
    fast, full = _fits(monkeypatch, ths, e_step=0.1)
    assert any(note.startswith("e not identified") for note in full.notes)
    _assert_same(fast, full)
