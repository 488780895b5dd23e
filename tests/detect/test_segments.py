"""Long runs analysed in segments (issue 29: bounded memory whatever the run's length).

The record comes from the independent generator (``tests/independent_campaign.py``: its own
physics and measurement chain, not ``rattle_lab.rig``).  The same run is analysed whole and
in segments (``segment_samples`` made small, so that a 20 s run has four); what each result
may differ by, and why, is stated at each assertion.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from independent_campaign import Chain, Plant, write_campaign
from rattle_lab.detect import DetectParams, ImpactLog, analyse_run
from rattle_lab.detect._segments import Span, merge_logs, segment_spans, segment_view
from rattle_lab.exceptions import ParameterError
from rattle_lab.records import read

SEG = 1 << 17   # 5.12 s at 25.6 kHz


def _grazing_ms2(plant: Plant, f_hz: float) -> float:
    w, r = 2 * math.pi * plant.f_s_hz, f_hz / plant.f_s_hz
    return plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) / plant.q


@pytest.fixture(scope="module")
def long_run(tmp_path_factory):
    """A 20 s dwell of the independent generator (rattling 1/1 at 95 Hz), read lazily."""
    plant = Plant()
    path = tmp_path_factory.mktemp("seg") / "c.h5"
    write_campaign(path, plant, Chain(fs_hz=25600.0), [
        {"run_id": "dwell_95", "protocol": "sine_dwell", "freq_hz": 95.0,
         "levels": np.full(20 * 95, 1.5 * _grazing_ms2(plant, 95.0))}], seed=5)
    with read(path) as record:
        yield record.run("dwell_95"), record.rig.mic_distance_m


def _both(run, mic_m, **detect):
    whole = analyse_run("k", run, detect={}, fit={}, mic_distance_m=mic_m)
    cut = analyse_run("k", run, detect={"segment_samples": SEG, **detect}, fit={},
                      mic_distance_m=mic_m)
    return whole, cut


def _se_median(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return 1.2533 * float(np.std(x)) / math.sqrt(x.size)


def test_segments_cover_the_run_once_and_short_runs_stay_whole(long_run):
    run, _ = long_run
    ch = next(c for c in run.channels if c.quantity == "plate_velocity")
    params = DetectParams(segment_samples=SEG)
    spans = segment_spans(run, params, ch)
    # with both plate channels: the stretch they share decides (here the same)
    acc = next(c for c in run.channels if c.quantity == "plate_acceleration")
    assert segment_spans(run, params, ch, acc) == spans
    assert spans is not None and len(spans) == round(ch.n_samples / SEG) == 4
    t0, t1 = ch.start_time_s or 0.0, (ch.start_time_s or 0.0) + ch.n_samples / ch.sample_rate_hz
    assert spans[0].core_lo_s <= t0 and spans[-1].core_hi_s >= t1
    for a, b in zip(spans, spans[1:]):
        assert a.core_hi_s == b.core_lo_s                       # contiguous, no overlap
        assert a.read_hi_s == pytest.approx(a.core_hi_s + 1.0)   # the margin
    assert spans[0].read_lo_s >= min(c.start_time_s or 0.0 for c in run.channels)
    # up to 1.5 segments: whole (the default 2**20 samples leaves this 0.5 M-sample run whole)
    assert segment_spans(run, DetectParams(), ch) is None
    assert segment_spans(run, DetectParams(segment_samples=ch.n_samples * 2 // 3 + 1), ch) is None
    assert segment_spans(replace(run, protocol="transient"), params, ch) is None
    view = segment_view(run, spans[1])
    vch = view.channel(ch.name)
    i0 = round(((vch.start_time_s or 0.0) - t0) * ch.sample_rate_hz)
    np.testing.assert_array_equal(vch.read(), ch.read(i0, i0 + vch.n_samples))   # a view


def test_segmented_run_equals_the_whole_run(long_run):
    """Every impact once, at the same time; e, levels and loudness as the whole run's.

    The impact times come from the same samples and fits: they may differ only through
    what each segment estimates from its own impacts (trigger noise, the vibrometer's
    offset and delay), far below a sample.  e per run may move by the per-segment estimates'
    sampling error: at most the standard error of the run's median e.  The levels are
    energy means of the segments (the same samples: within 0.01 dB; LAFmax and LCpeak the
    largest of the segments'); N5 joins the segments' N(t), each from rest (within 1 %)."""
    run, mic_m = long_run
    whole, cut = _both(run, mic_m)
    a, b = whole.impacts, cut.impacts
    assert a.n_impacts > 500 and b.n_impacts == a.n_impacts
    np.testing.assert_allclose(b.t_s, a.t_s, rtol=0, atol=0.01 / a.fs_hz)
    assert abs(np.nanmedian(b.e) - np.nanmedian(a.e)) <= _se_median(a.e)
    assert cut.pattern == whole.pattern
    assert cut.peaks.p_first_pa.size == b.n_impacts
    np.testing.assert_allclose(cut.peaks.t_first_s, whole.peaks.t_first_s, rtol=0, atol=1e-6)
    assert cut.spl_rms_db == pytest.approx(whole.spl_rms_db, abs=0.01)
    assert cut.spl_rms_a_db == pytest.approx(whole.spl_rms_a_db, abs=0.01)
    fs_mic = next(c for c in run.channels if c.quantity == "sound_pressure").sample_rate_hz
    assert abs(cut.acoustic_delay_s - whole.acoustic_delay_s) < 1.0 / fs_mic
    sa, sb = whole.acoustics.summary()["acoustics"], cut.acoustics.summary()["acoustics"]
    for key in ("laeq_db", "lafmax_db", "lcpeak_db"):
        assert sb[key] == pytest.approx(sa[key], abs=0.01), key
    for key in ("loudness_n5_sone", "loudness_max_sone", "sharpness_acum", "impacts_per_s",
                "rattle_loudness_n5_sone"):
        assert sb[key] == pytest.approx(sa[key], rel=0.01), key
    assert len(sb["episodes"]) == 4   # an episode is cut at each segment's edge
    assert cut.acoustics.loudness.curve is None   # no curves kept on a result


def test_an_impact_on_a_segment_edge_is_found_once(long_run):
    """The record is cut so that a segment edge falls on an impact (within a quarter sample):
    the segments on both sides see it, the run counts it once."""
    run, mic_m = long_run
    ch = next(c for c in run.channels if c.quantity == "plate_velocity")
    fs = ch.sample_rate_hz
    t = analyse_run("k", run, detect={}, fit={}, mic_distance_m=mic_m).impacts.t_s
    n = 3 * SEG     # three segments of SEG samples: the first edge at SEG / fs from the start
    best = None
    for s0 in range(0, ch.n_samples - n):
        edge = (ch.start_time_s or 0.0) + (s0 + SEG) / fs
        d = np.min(np.abs(t - edge)) * fs
        if best is None or d < best[0]:
            best = (d, s0)
        if d < 0.05:
            break
    assert best[0] < 0.25
    s0 = best[1]
    shifted = segment_view(run, Span(0, 1, 0, 0, (ch.start_time_s or 0.0) + s0 / fs,
                                     (ch.start_time_s or 0.0) + (s0 + n) / fs))
    whole, cut = _both(shifted, mic_m)
    assert cut.impacts.n_impacts == whole.impacts.n_impacts
    np.testing.assert_allclose(cut.impacts.t_s, whole.impacts.t_s, rtol=0, atol=0.01 / fs)
    assert np.all(np.diff(cut.impacts.t_s) > DetectParams().min_separation_s)


def _log(t):
    t = np.asarray(t, float)
    return ImpactLog(t_s=t, onset_s=t, v_in_m_s=-np.ones(t.size), v_out_m_s=0.5 * np.ones(t.size),
                     e=0.5 * np.ones(t.size), strength=np.ones(t.size), channels=("v",),
                     fs_hz=1000.0, velocity_delay_s=1e-5, velocity_delay_stderr_s=1e-6,
                     velocity_delay_n=t.size)


def test_merge_keeps_each_impact_once_at_the_edges():
    """Two segments meeting at 1.0 s, ``min_separation_s`` 2 ms: an impact both found is
    kept once; one only the later segment found just before the edge is kept; an impact
    beyond a segment's core and slack is the other segment's."""
    a = Span(0, 2, 0.0, 1.0, 0.0, 2.0)
    b = Span(1, 2, 1.0, 2.0, 0.0, 2.0)
    log_a = _log([0.5, 0.9995, 1.5])          # 1.5: beyond a's core and slack -> b's
    log_b = _log([0.5, 0.9985, 0.99951, 1.5])  # 0.5: a's; 0.9985: b found it alone, kept
    merged, keep = merge_logs([(a, log_a), (b, log_b)], 2e-3)
    # 0.9985 lies within 2 ms of a's 0.9995, so it is taken for a's (the detector keeps
    # impacts at least min_separation_s apart: they cannot be two)
    np.testing.assert_allclose(merged.t_s, [0.5, 0.9995, 1.5])
    assert keep[0].tolist() == [True, True, False] and keep[1].tolist() == [False, False, False,
                                                                             True]
    # an impact only the later segment found, within its slack before the edge: kept; one
    # further back is the earlier segment's to find (it read that stretch in the middle)
    merged, _ = merge_logs([(a, _log([0.5, 0.99])), (b, _log([0.99, 0.9985, 1.5]))], 2e-3)
    np.testing.assert_allclose(merged.t_s, [0.5, 0.99, 0.9985, 1.5])
    # both kept, either side of the edge, more than min_separation_s apart: in time order
    merged, _ = merge_logs([(a, _log([0.5, 1.0015])), (b, _log([0.9985, 1.5]))], 2e-3)
    np.testing.assert_allclose(merged.t_s, [0.5, 0.9985, 1.0015, 1.5])
    assert merged.velocity_delay_s == pytest.approx(1e-5)
    assert merged.velocity_delay_stderr_s == pytest.approx(1e-6 / math.sqrt(2))
    assert merged.velocity_delay_n == 4


def test_a_segment_with_bad_samples_fails_the_run_as_the_whole_run_does(long_run):
    """NaN across a segment edge: the run fails with the same error, whole or in segments
    (the detector refuses non-finite samples); clipping across an edge: the same impacts."""
    run, mic_m = long_run
    ch = next(c for c in run.channels if c.quantity == "plate_velocity")
    data = ch.read(si=False).copy()
    edge = ch.n_samples // 4   # the first segment edge
    bad = data.copy()
    bad[edge - 50:edge + 50] = np.nan
    nan_run = replace(run, channels=tuple(replace(c, data=bad) if c.name == ch.name else c
                                          for c in run.channels))
    with pytest.raises(ParameterError, match="finite"):
        analyse_run("k", nan_run, detect={}, fit={}, mic_distance_m=mic_m)
    with pytest.raises(ParameterError, match="finite"):
        analyse_run("k", nan_run, detect={"segment_samples": SEG}, fit={}, mic_distance_m=mic_m)
    top = np.quantile(data, 0.99)
    clipped = data.copy()
    clipped[edge - 2000:edge + 2000] = np.minimum(clipped[edge - 2000:edge + 2000], top)
    clip_run = replace(run, channels=tuple(replace(c, data=clipped) if c.name == ch.name else c
                                           for c in run.channels))
    whole, cut = _both(clip_run, mic_m)
    assert cut.impacts.n_impacts == whole.impacts.n_impacts
    np.testing.assert_allclose(cut.impacts.t_s, whole.impacts.t_s, rtol=0,
                               atol=0.01 / ch.sample_rate_hz)


@pytest.mark.parametrize("value", [1000, 2.0 ** 20, True, -1])
def test_segment_samples_is_checked(value):
    with pytest.raises(ParameterError, match="segment_samples"):
        DetectParams.from_mapping({"segment_samples": value})


def test_the_segments_notes_are_said_once_with_their_counts_summed():
    from rattle_lab.detect._segments import merged_notes

    a = "no velocities for 51 of 1733 impacts, left out: no flight long enough"
    b = "no velocities for 48 of 1826 impacts, left out: no flight long enough"
    other = "local fits kept: no ringing found after the impacts"
    assert merged_notes([a, "", b, other, other]) == (
        "no velocities for 99 of 3559 impacts, left out: no flight long enough; " + other)
    assert merged_notes(["jumps differ by +12 %", "jumps differ by +15 %"]) == (
        "jumps differ by +12 % (the first of 2 segments that said so)")
    assert merged_notes(["", ""]) == ""


def test_a_long_ramp_in_segments_has_the_whole_ramps_threshold(tmp_path):
    """An amplitude ramp (0.6 to 1.6 times grazing over 16 s, the independent generator at
    12.8 kHz) cut into four segments: the same onset impact, so the same threshold (its time
    within 0.01 sample, the level read there from the base accelerometer read whole, within
    the envelope's change over that time: 1e-6 relative)."""
    plant = Plant()
    g = _grazing_ms2(plant, 95.0)
    path = tmp_path / "ramp.h5"
    truth = write_campaign(path, plant, Chain(fs_hz=12800.0), [
        {"run_id": "up", "protocol": "amplitude_ramp_up", "freq_hz": 95.0,
         "levels": np.linspace(0.6 * g, 1.6 * g, 16 * 95)}], seed=8)
    with read(path) as record:
        run = record.run("up")
        mic_m = record.rig.mic_distance_m
        n = next(c for c in run.channels if c.quantity == "plate_velocity").n_samples
        seg = 1 << 16
        assert round(n / seg) == 3
        whole = analyse_run("k", run, detect={}, fit={}, mic_distance_m=mic_m)
        cut = analyse_run("k", run, detect={"segment_samples": seg}, fit={},
                          mic_distance_m=mic_m)
    a, b = whole.threshold, cut.threshold
    assert a is not None and b is not None and math.isfinite(a.accel_ms2)
    assert b.t_s == pytest.approx(a.t_s, abs=0.01 / 12800.0)
    assert b.accel_ms2 == pytest.approx(a.accel_ms2, rel=1e-6)
    assert 0.6 * g < a.accel_ms2 < 1.6 * g
    assert cut.channels_used == whole.channels_used
    # the impacts: every one found is a true one; each segment's own estimates (trigger
    # noise, offset, delay) may decide a marginal impact otherwise than the whole ramp's --
    # here the segments find one true impact (10 ms before another) the whole ramp misses
    t_true = truth.impacts["up"][0]
    for log in (whole.impacts, cut.impacts):
        d = np.abs(log.t_s[:, None] - t_true[None, :]).min(axis=1)
        assert np.all(d < 1e-3)                                  # precision 1
        assert log.n_impacts >= 0.99 * t_true.size               # recall >= 0.99
    assert abs(cut.impacts.n_impacts - whole.impacts.n_impacts) <= 1


def test_a_long_quiet_run_in_segments_is_a_valid_result_without_impacts(tmp_path):
    """Below grazing (0.5 times): no impact in any segment; the run is still analysed, its
    sound levels and loudness joined, no pattern of impacts."""
    plant = Plant()
    path = tmp_path / "quiet.h5"
    write_campaign(path, plant, Chain(fs_hz=12800.0), [
        {"run_id": "quiet", "protocol": "sine_dwell", "freq_hz": 95.0,
         "levels": np.full(12 * 95, 0.5 * _grazing_ms2(plant, 95.0))}], seed=4)
    with read(path) as record:
        run = record.run("quiet")
        res = analyse_run("k", run, detect={"segment_samples": 1 << 15}, fit={},
                          mic_distance_m=record.rig.mic_distance_m)
        whole = analyse_run("k", run, detect={}, fit={}, mic_distance_m=record.rig.mic_distance_m)
    assert res.status == "ok" and res.impacts.n_impacts == 0 == whole.impacts.n_impacts
    assert res.pattern == whole.pattern == "no impact"
    assert res.peaks.p_first_pa.size == 0
    assert res.acoustics.episodes == ()
    assert res.acoustics.levels.laeq_db == pytest.approx(whole.acoustics.levels.laeq_db, abs=0.01)


@pytest.mark.parametrize("cut", ["shorter", "later"])
def test_a_microphone_that_does_not_cover_the_run_in_segments(long_run, cut):
    """A microphone that stops at 40 % of the run, or starts at half of it: the segments it
    does not reach give their impacts no sound, as the whole run does beyond the microphone;
    the sound found and the levels equal the whole run's."""
    from rattle_lab.records import ArrayData

    run, mic_m = long_run
    mic = run.channel("mic")
    raw = mic.read(si=False)
    if cut == "shorter":
        new = replace(mic, data=ArrayData(raw[: int(0.4 * raw.size)]))
    else:
        half = raw.size // 2
        new = replace(mic, data=ArrayData(raw[half:]),
                      start_time_s=(mic.start_time_s or 0.0) + half / mic.sample_rate_hz)
    run = replace(run, channels=tuple(new if c.name == "mic" else c for c in run.channels))
    whole, parts = _both(run, mic_m)
    assert parts.impacts.n_impacts == whole.impacts.n_impacts
    heard = np.isfinite(whole.peaks.p_first_pa)
    assert 0 < heard.sum() < heard.size
    np.testing.assert_array_equal(np.isfinite(parts.peaks.p_first_pa), heard)
    assert parts.spl_rms_db == pytest.approx(whole.spl_rms_db, abs=0.01)
    assert parts.acoustics.levels.laeq_db == pytest.approx(whole.acoustics.levels.laeq_db,
                                                           abs=0.01)


@pytest.mark.parametrize("name", ["plate", "velocity"])
def test_a_plate_channel_shorter_than_the_other_in_segments(long_run, name):
    """The accelerometer (or the vibrometer) stops at 60 % of the run: the impacts come from
    the stretch both share, whole or in segments -- the same impacts, pattern and e."""
    from rattle_lab.records import ArrayData

    run, mic_m = long_run
    ch = run.channel(name)
    short = replace(ch, data=ArrayData(ch.read(si=False)[: int(0.6 * ch.n_samples)]))
    run = replace(run, channels=tuple(short if c.name == name else c for c in run.channels))
    whole, parts = _both(run, mic_m)
    assert parts.impacts.n_impacts == whole.impacts.n_impacts > 0
    np.testing.assert_allclose(parts.impacts.t_s, whole.impacts.t_s, rtol=0,
                               atol=0.01 / ch.sample_rate_hz)
    assert parts.pattern == whole.pattern
    assert abs(np.nanmedian(parts.impacts.e) - np.nanmedian(whole.impacts.e)) \
        <= _se_median(whole.impacts.e)
