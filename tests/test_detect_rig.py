"""Detectors on the synthetic rig's default scene (``rattle_lab.rig``, session fixture).

The rig simulates the exact SDF impact oscillator with a finite contact
(``truth.extra['contact_s']``) and writes the true impacts and thresholds.
"""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.fit import analyse_run
from rattle_lab.records import read


@pytest.fixture(scope="module")
def analysed(synthetic_campaign_record):
    rec = read(synthetic_campaign_record)
    results = {run.run_id: analyse_run("rig", run, detect={}, fit={},
                                       mic_distance_m=rec.rig.mic_distance_m) for run in rec.runs}
    return rec, results


def test_rig_every_impact_found(analysed):
    rec, results = analysed
    contact_s = rec.truth.extra["contact_s"]
    for run_id, r in results.items():
        true = rec.truth.impacts[run_id]
        assert r.impacts.n_impacts == true.t_s.size, run_id
        if true.t_s.size:
            k = np.abs(r.impacts.t_s[:, None] - true.t_s[None, :]).argmin(axis=0)
            # the detector times the velocity jump; the rig's contact lasts contact_s
            assert np.max(np.abs(r.impacts.t_s[k] - true.t_s)) < contact_s + 1.0 / 20000, run_id


@pytest.mark.parametrize("run_id, kind", [("up_096", "onset_level"), ("up_097", "onset_level"),
                                          ("up_098", "onset_level"), ("down_097", "disappearance_level"),
                                          ("down_098", "disappearance_level")])
def test_rig_thresholds_near_resonance(analysed, run_id, kind):
    rec, results = analysed
    thr = rec.truth.thresholds
    f = results[run_id].freq_hz
    truth = float(getattr(thr, kind)[np.flatnonzero(thr.freq_hz == f)[0]])
    # a ramp threshold is known to one forcing cycle of the ramp, and the lock-in low-pass
    # averages over ~5 cycles: 3 %
    assert results[run_id].threshold.accel_ms2 == pytest.approx(truth, rel=0.03)
