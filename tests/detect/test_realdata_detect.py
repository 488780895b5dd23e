"""Detectors on real measured records from ../shared/realdata (not ours; see its README).

Sources:
- droptable/Test_001.lvm: High-Rate-SHM-Working-Group/Dataset-5-Extended-Impact-Testing,
  data/dataset-2/data-1/Test_001.lvm (Downey et al. 2022), CC BY-SA 4.0.
- hammer/measurements_1.npy: ladisk/pyFRF at commit 55431fd, data/measurements_1.npy
  (LGPL-3.0 then, MIT now).
- clap/rir_clap.wav: spatialaudio/selected-topics-in-audio-signal-processing-exercises,
  data/rir_clap.wav, CC0 1.0.

Transient records hold one event: the trigger uses a high ``on`` level (100 noise
units; the shocks are at 10^4) and a separation longer than the ringing.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import realdata

from rattle_lab.detect import (ImpactParams, cross_correlation_delay, detect_impacts,
                               sound_peaks)
from rattle_lab.records import read

ROOT = Path(__file__).resolve().parents[2]
MAPPINGS = ROOT / "data_schema" / "mappings"
SHOCK = ImpactParams(on=100.0, off=10.0, min_separation_s=0.5)



def _read(rel: str, mapping: str):
    path = realdata(rel)
    with warnings.catch_warnings():   # uncalibrated / assumed units are flagged by the reader
        warnings.simplefilter("ignore")
        return read(path, mapping=MAPPINGS / mapping)


def test_droptable_one_shock_on_both_channels():
    """Downey et al. 2022, Test_001.lvm: one shock near 0.092 s on table and board."""
    rec = _read("droptable/Test_001.lvm", "droptable_lvm.toml")
    run = rec.runs[0]
    onsets = {}
    for name in ("table", "board"):
        ch = run.channel(name)
        log = detect_impacts(ch.sample_rate_hz, accel_ms2=ch.read(), params=SHOCK,
                             start_time_s=ch.start_time_s or 0.0)
        assert log.n_impacts == 1, name                    # no event in the quiet part
        assert log.onset_s[0] == pytest.approx(0.092, abs=0.002)
        onsets[name] = log.onset_s[0]
    # table-to-board delay: board after table, by less than a millisecond
    delay = cross_correlation_delay(run.channel("table").read(), run.channel("board").read(),
                                    run.channel("table").sample_rate_hz, max_lag_s=0.01)
    assert 0.0 < delay < 1e-3
    assert 0.0 <= onsets["board"] - onsets["table"] < 1e-3


def test_hammer_force_paired_with_delayed_response():
    """ladisk/pyFRF measurements_1.npy: the force pulse near 0.85 ms, the response peak after it."""
    rec = _read("hammer/measurements_1.npy", "hammer_npy.toml")
    run = rec.runs[0]
    force, resp = run.channel("force"), run.channel("response")
    t = run.timestamps["t"].read(0, force.n_samples)
    fs_hz = 1.0 / float(np.median(np.diff(t)))
    log = detect_impacts(fs_hz, accel_ms2=force.read(), params=SHOCK, start_time_s=float(t[0]))
    assert log.n_impacts == 1
    assert log.t_s[0] == pytest.approx(0.85e-3, abs=0.1e-3)
    pk = sound_peaks(resp.read(), fs_hz, log.t_s, window_s=0.05, start_time_s=float(t[0]))
    assert 0.0 < pk.delay_first_s[0] <= pk.delay_max_s[0] < 0.05
    assert pk.p_max_pa[0] >= pk.p_first_pa[0] > 0


def test_clap_one_sound_event_first_and_max_peaks():
    """spatialaudio rir_clap.wav: one clap near t = 0; first peak, then the largest, in 5 ms."""
    rec = _read("clap/rir_clap.wav", "clap_wav.toml")
    ch = rec.runs[0].channels[0]
    assert ch.si_units == "1"                              # uncalibrated, declared as such
    p = ch.read()
    log = detect_impacts(ch.sample_rate_hz, accel_ms2=p, params=SHOCK)
    assert log.n_impacts == 1 and log.onset_s[0] < 0.005
    pk = sound_peaks(p, ch.sample_rate_hz, log.onset_s, window_s=0.05)
    assert log.onset_s[0] < pk.t_first_s[0] <= pk.t_max_s[0] < 0.005
    # the parabolic peak height of a sharp click may exceed the largest sample by a few %
    assert np.max(np.abs(p)) <= pk.p_max_pa[0] <= 1.03 * np.max(np.abs(p))


def test_droptable_in_segments_finds_what_the_whole_record_finds():
    """Downey et al. 2022, Test_001.lvm read as a steady run (not a transient) and cut into
    three segments of 16384 samples (issue 29): the same events at the same times as the
    whole record (within 0.01 sample), with the default trigger and with the shock trigger."""
    from dataclasses import replace

    from rattle_lab.detect import analyse_run, run_segments

    rec = _read("droptable/Test_001.lvm", "droptable_lvm.toml")
    run = replace(rec.runs[0], protocol="unspecified")
    cut = {"segment_samples": 16384}
    assert len(run_segments("k", run, cut) or ()) == 3
    fs = run.channel("board").sample_rate_hz
    for trigger in ({}, {"on": 100.0, "off": 10.0, "min_separation_s": 0.5}):
        whole = analyse_run("k", run, detect=trigger, fit={})
        parts = analyse_run("k", run, detect={**trigger, **cut}, fit={})
        assert whole.impacts.n_impacts >= 1
        assert parts.impacts.n_impacts == whole.impacts.n_impacts, trigger
        np.testing.assert_allclose(parts.impacts.t_s, whole.impacts.t_s, rtol=0, atol=0.01 / fs)
        assert parts.impacts.t_s[0] == pytest.approx(0.093, abs=0.002)
