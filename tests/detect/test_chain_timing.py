"""Issue 28: channel timing and the vibrometer's measurand identified from the record.

Records from the independent generator (``tests/independent_campaign.py``: plain numpy, its
own SDF physics; causal Butterworth and Bessel decoders built from their analog prototypes
by the bilinear transform, checked here against the closed-form group delay at DC).

Tolerances:
* delay: the centroid of any filter's impulse response is its DC group delay, so the
  median over a run's impacts of (velocity step centroid - contact pulse centroid) is the
  vibrometer's delay; the estimator truncates the step's tail to its window (a bias of
  up to 0.05 sample seen on the 10 kHz Butterworth at 25.6 kHz), so 0.1 sample is asserted.
* e (median of the matched impacts with ``|v_in| >= 0.1 m/s``): within 3 % (the issue's
  acceptance); v_in median within 1 %.
* measurand coefficient (0 relative, 1 absolute): within 4 standard errors of the truth.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from independent_campaign import Chain, Plant, iir_dc_delay_s, measure, write_campaign
from rattle_lab.detect import ImpactParams, detect_impacts
from rattle_lab.detect._timing import channel_delay, coarse_lag, measurand_share
from rattle_lab.store import ingest
from record_factory import run_command


def _grazing_ms2(plant: Plant, f_hz: float) -> float:
    w = 2 * math.pi * plant.f_s_hz
    r = f_hz / plant.f_s_hz
    return plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) / plant.q


def _run(chain: Chain, f_hz: float = 99.0, periods: int = 60, seed: int = 2):
    plant = Plant()
    levels = np.full(periods, 1.5 * _grazing_ms2(plant, f_hz))
    chans, imp = measure(plant, chain, 2 * math.pi * f_hz, levels, np.random.default_rng(seed))
    return plant, chans, imp


def _matched_e(log, imp, fs):
    t_true, v_in, v_out = imp
    es, vr = [], []
    for t, vi in zip(t_true, v_in):
        k = int(np.argmin(np.abs(log.t_s - t)))
        if abs(log.t_s[k] - t) < 0.5e-3 and abs(vi) >= 0.1 and np.isfinite(log.e[k]):
            es.append(log.e[k])
            vr.append(abs(log.v_in_m_s[k]) / abs(vi))
    assert len(es) >= 20
    return float(np.median(es)), float(np.median(vr))


def test_decoder_delay_matches_scipy_free_closed_form():
    # the generator's decoders: group delay at DC sum Re 1/(1 - z_k) - n/2 samples, against a
    # finite difference of the phase of their own frequency response (independent formula)
    from independent_campaign import iir_response

    for kind in ("butterworth", "bessel"):
        for order, fc, fs in ((4, 10000.0, 25600.0), (8, 2000.0, 51200.0), (2, 20000.0, 51200.0)):
            df = 1e-3
            h = iir_response(kind, order, fc, fs, np.array([-df, df]))
            tau = -(np.angle(h[1]) - np.angle(h[0])) / (2 * math.pi * 2 * df)
            assert iir_dc_delay_s(kind, order, fc, fs) == pytest.approx(tau, rel=1e-6)
            assert abs(iir_response(kind, order, fc, fs, np.array([fc]))[0]) == \
                pytest.approx(2 ** -0.5, rel=1e-9)
    # the decoder: 4th-order Butterworth at 10 kHz, 25.6 kHz sampling, ~18 us
    assert iir_dc_delay_s("butterworth", 4, 10000.0, 25600.0) == pytest.approx(18.26e-6, abs=0.01e-6)


def test_coarse_lag_and_delay_estimators():
    rng = np.random.default_rng(0)
    a = np.abs(rng.standard_normal(5000))
    a[rng.choice(5000, 30, replace=False)] += 60.0
    assert coarse_lag(np.roll(a, 17), a, 40, 4.0) == 17
    assert coarse_lag(np.roll(a, -5), a, 40, 4.0) == -5
    est = channel_delay(np.arange(50) + 0.3 + 0.01 * rng.standard_normal(50), np.arange(50.0))
    assert est.value == pytest.approx(0.3, abs=5 * est.stderr) and est.n == 50


@pytest.mark.parametrize("chain", [
    # the chain: 18.3 us, under half a sample
    Chain(decoder="butterworth", decoder_order=4, decoder_cutoff_hz=10000.0, decoder_delay_s=0.0,
          ring_in_velocity=False),
    # a slow decoder (0.4 ms, 21 samples) and 2.7 samples more, at 51.2 kHz
    pytest.param(Chain(fs_hz=51200.0, decoder="bessel", decoder_order=8,
                       decoder_cutoff_hz=2000.0, decoder_delay_s=2.7 / 51200.0,
                       ring_in_velocity=False), marks=pytest.mark.slow),
    # a ringing decoder: 8th-order Butterworth, 3 kHz, 25.6 kHz, +1.2 samples.  Its step
    # settles 1.1 ms after its delay: the step centroid was 0.47 sample early (the ringing
    # tail cut off) and e -10 %; now the decoder is identified and equalised
    # (rattle_lab.detect._decoder, tests/detect/test_decoder.py)
    pytest.param(Chain(decoder="butterworth", decoder_order=8, decoder_cutoff_hz=3000.0,
                       decoder_delay_s=1.2 / 25600.0, ring_in_velocity=False),
                 marks=pytest.mark.slow),
], ids=["butter4-10k", "bessel8-2k-51k", "butter8-3k"])
def test_undeclared_delay_is_measured_and_e_holds(chain):
    plant, ch, imp = _run(chain)
    fs = chain.fs_hz
    log = detect_impacts(fs, velocity_m_s=ch["velocity"], accel_ms2=ch["plate"],
                         excitation_freq_hz=99.0)
    assert log.velocity_delay_s == pytest.approx(chain.velocity_delay_s, abs=0.1 / fs)
    # applied: the measured delay (an identified decoder's, the steps' centroids after it
    # only checking it: they agree within the 0.1 sample)
    assert log.velocity_delay_applied_s == pytest.approx(log.velocity_delay_s, abs=0.1 / fs)
    # no ringing: the short-flank and long-fit estimators agree, the error stays small
    assert log.velocity_delay_stderr_s * fs < 0.1
    e, vin = _matched_e(log, imp, fs)
    assert e == pytest.approx(plant.e, rel=0.03)
    assert vin == pytest.approx(1.0, abs=0.01)


def _ringing_undeclared(order: int, cutoff_hz: float, extra_samples: float, seed: int,
                        identify: bool = True):
    """An undeclared Butterworth decoder at 25.6 kHz, the plate's higher modes ringing in the
    vibrometer (2 % damping), one 80-period dwell at 99 Hz: the chain and the detector's log,
    after checking that every impact is found once (within 0.5 ms) and nothing much else."""
    chain = Chain(decoder="butterworth", decoder_order=order, decoder_cutoff_hz=cutoff_hz,
                  decoder_delay_s=extra_samples / 25600.0, ring_in_velocity=True,
                  declare_delay=False, declare_measurand=False)
    _, ch, imp = _run(chain, periods=80, seed=seed)
    log = detect_impacts(chain.fs_hz, velocity_m_s=ch["velocity"], accel_ms2=ch["plate"],
                         excitation_freq_hz=99.0,
                         params=ImpactParams(identify_decoder=identify))
    t_true = imp[0]
    found = sum(bool(np.any(np.abs(log.t_s - t) < 0.5e-3)) for t in t_true)
    assert found >= 0.98 * t_true.size and log.n_impacts <= t_true.size + 2
    return chain, log


def test_plate_ringing_does_not_bias_the_delay():
    # An undeclared 3rd-order 7.7 kHz Butterworth (0.76 sample at 25.6 kHz) and the plate's
    # higher modes ringing in the vibrometer (2 % damping: they never settle between
    # impacts).  Two things went wrong here (issue 28):
    # * the long forced-mode fits cannot follow the ringing after an impact, and the step's
    #   centroid between them was 1.1 samples late at every impact alike (resolved, standard
    #   error 0.006 sample); the delay is now measured between short quadratic flanks;
    # * the step looks unsettled at the fits' near ends, so the detector tries fits moved
    #   out by its settling time; there the per-impact centroids scatter by tens of samples
    #   (the ringing differs at every impact, a decoder's step response does not), and that
    #   estimate was applied (4.4 samples): the velocities read there failed the reversal
    #   test for 72 of the 77 impacts.  It is now used only where it is resolved.
    chain, log = _ringing_undeclared(3, 7748.66, 0.04, seed=1)
    fs = chain.fs_hz
    assert log.step_guard_s == 0.0 and log.velocity_delay_window_s == 0.0
    # measured 0.10 sample early (29 Nov 2026); 0.3 sample is a third of the bias it replaced
    assert log.velocity_delay_applied_s == pytest.approx(chain.velocity_delay_s, abs=0.3 / fs)
    # the two estimators (short flanks, long fits) disagree by a sample here, and the
    # reported standard error says so (1.05 samples), where the per-impact scatter alone
    # gave 0.006: e's interval is widened by it
    assert log.velocity_delay_stderr_s * fs > 0.5


def test_a_delay_under_which_impacts_stop_reversing_is_not_applied():
    # A slow decoder (8th-order Butterworth at 2.66 kHz: 8.3 samples at 25.6 kHz) and the
    # plate's ringing: the steps' centroids are 3.5 samples late at every impact alike (a
    # resolved estimate), and read there the velocity fits of 44 of the 77 impacts no
    # longer reversed.  An impact reverses the velocity whatever the chain, so the delay is
    # left unapplied (the fit carries it into e's interval) and every impact is kept.
    chain, log = _ringing_undeclared(8, 2662.26, 0.71, seed=3, identify=False)
    fs = chain.fs_hz
    assert log.velocity_delay_applied_s == 0.0
    # the measurement stays in the log (the fit's interval uses it)
    assert log.velocity_delay_s * fs > 5.0
    # by default the decoder is identified from the steps (high-passed, which the plate's
    # ringing at a few hundred Hz hardly enters) and its delay applied: it is the chain's
    chain, log = _ringing_undeclared(8, 2662.26, 0.71, seed=3)
    assert log.decoder.startswith("a Butterworth low-pass of order 8")
    assert log.velocity_delay_applied_s * fs == pytest.approx(chain.velocity_delay_s * fs, abs=0.1)


def test_declared_delay_is_checked():
    chain = Chain(decoder="butterworth", decoder_order=4, decoder_cutoff_hz=10000.0,
                  decoder_delay_s=0.0, ring_in_velocity=False)
    plant, ch, imp = _run(chain)
    fs = chain.fs_hz
    # declared right (a chain whose velocity is on the accelerometer's time base, as the
    # fit puts it with group_delay_s): what remains is within its noise, nothing applied
    _, ch0, _ = _run(Chain(decoder_delay_s=0.0, ring_in_velocity=False))
    log = detect_impacts(fs, velocity_m_s=ch0["velocity"], accel_ms2=ch0["plate"],
                         excitation_freq_hz=99.0, velocity_delay_declared=True)
    assert abs(log.velocity_delay_s) < 0.1 / fs
    assert log.velocity_delay_applied_s == 0.0
    # declared wrong by 2 samples (a chain 2 samples later than its declaration says): the
    # declaration stands, the measurement contradicts it and the fit says so
    from rattle_lab.detect import velocity_delay_flags

    chain2 = Chain(decoder_delay_s=2.0 / fs, ring_in_velocity=False)
    _, ch2, _ = _run(chain2)
    log = detect_impacts(fs, velocity_m_s=ch2["velocity"], accel_ms2=ch2["plate"],
                         excitation_freq_hz=99.0, velocity_delay_declared=True)
    assert log.velocity_delay_applied_s == 0.0
    assert log.velocity_delay_s == pytest.approx(2.0 / fs, abs=0.1 / fs)
    (flag,) = velocity_delay_flags(log, declared=True)
    assert flag.startswith("channel_delay_contradicted: ")
    # the same record undeclared: the 2 samples are beyond their uncertainty, applied and
    # flagged (a log detected as declared applied nothing, and is not flagged as estimated)
    assert velocity_delay_flags(log, declared=False) == ()
    log = detect_impacts(fs, velocity_m_s=ch2["velocity"], accel_ms2=ch2["plate"],
                         excitation_freq_hz=99.0)
    assert log.velocity_delay_applied_s == pytest.approx(2.0 / fs, abs=0.1 / fs)
    assert velocity_delay_flags(log, declared=False)[0].startswith("channel_delay_estimated: ")


def test_measurand_share_on_exact_motion():
    # noiseless: the plate is at the gap at every impact; an absolute vibrometer adds the
    # base velocity.  The impacts of the first periods fall at varying phases (transient)
    from independent_campaign import simulate

    plant = Plant()
    f = 99.0
    W = 2 * math.pi * f
    levels = np.full(80, 1.5 * _grazing_ms2(plant, f))
    fs = 25600.0
    ts, _, v, ti, vin, vout = simulate(plant, W, levels, fs)
    a_b = levels[0] * np.sin(W * ts)
    v_b = -levels[0] / W * np.cos(W * ts)
    for vel, truth in ((v, 0.0), (v + v_b, 1.0)):
        m = measurand_share(vel + 3e-3, fs, 0.0, ti, a_b, fs, 0.0, f, jumps_m_s=vout - vin)
        assert abs(m.value - truth) < 4 * m.stderr and m.stderr < 0.1
        assert m.verdict == ("relative" if truth == 0.0 else "absolute")
    # impacts all at one phase of the base motion: nothing to tell them apart
    t_same = (np.arange(40) + 0.3) / f
    m = measurand_share(v_b, fs, 0.0, t_same, a_b, fs, 0.0, f)
    assert m.verdict == "undetermined"


def test_a_wide_coefficient_far_from_the_other_reading_decides_the_measurand():
    # the first rule needs the 95 % interval within 0.5 of a reading; the second decides an
    # interval that holds one reading and lies over 4 standard errors from the other (light
    # ringing on the independent generator's steady dwell of an absolute vibrometer: 1.20
    # +- 0.23, 5.2 from relative)
    from rattle_lab.detect._timing import measurand_verdict

    assert measurand_verdict(1.20, 0.231) == "absolute"        # second rule only
    assert measurand_verdict(-0.15, 0.24) == "relative"        # second rule only
    assert measurand_verdict(0.10, 0.10) == "relative"         # first rule
    assert measurand_verdict(0.57, 0.18) == "undetermined"     # 3.2 and 2.4 se away
    assert measurand_verdict(4.57, 2.02) == "undetermined"     # holds neither
    assert measurand_verdict(1.0, float("nan")) == "undetermined"
    # a false decision is a coefficient beyond 4 (or, by the first rule, about 4) standard
    # errors from its truth: under 1e-4 of normal draws, whatever the standard error
    rng = np.random.default_rng(5)
    for se in (0.05, 0.1, 0.2, 0.3, 0.5):
        for truth, wrong in ((0.0, "absolute"), (1.0, "relative")):
            beta = truth + se * rng.standard_normal(20000)
            false = sum(measurand_verdict(float(b), se) == wrong for b in beta)
            assert false <= 2, (se, truth, false)


@pytest.mark.slow
@pytest.mark.parametrize("measurand", [
    "panel_relative_to_striker",
    # (was xfail on the first merge, where an undetermined measurand withheld e; on chain2
    # one run is inferred absolute and the other kept within the widened interval)
    "panel_absolute"])
def test_schema_v1_nothing_declared_through_the_cli(tmp_path, measurand):
    """The issue's campaign as a lab writes it: schema v1, a causal 4th-order Butterworth
    decoder at 10 kHz (18 us), nothing declared.  e from the ratios within 3 %, its interval
    covers the truth, and the fit says what it estimated."""
    plant = Plant()
    chain = Chain(decoder="butterworth", decoder_order=4, decoder_cutoff_hz=10000.0,
                  decoder_delay_s=0.0, ring_in_velocity=False, measurand=measurand,
                  schema_version=1)
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in (93.0, 99.0)]
    path = tmp_path / "v1.h5"
    write_campaign(path, plant, chain, runs, seed=3)
    store = tmp_path / "s.h5"
    ingest([path], store, quiet=True)
    proc = run_command("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    flags = out["data_quality"]
    assert sum("channel_delay_estimated" in f for f in flags) == 2
    ratio = out["fits"].get("restitution_ratio")
    inferred = [f for f in flags if "measurand_inferred" in f]
    undetermined = [f for f in flags if "measurand_undetermined" in f]
    assert len(inferred) + len(undetermined) == 2
    word = "relative to the striker" if measurand != "panel_absolute" else "panel_absolute"
    assert all(word in f for f in inferred)
    assert inferred, flags
    assert ratio is not None, out["not_fitted"]
    assert ratio["value"] == pytest.approx(plant.e, rel=0.03)
    assert abs(ratio["value"] - plant.e) <= 1.96 * ratio["stderr"]


# --- the review fixes: undeclared chains keep e with an honest interval -------------------

def test_delay_indistinguishable_from_zero_is_not_applied_and_unresolved_steps_are_named():
    """An undeclared delay is applied only beyond 4 standard errors; per-impact delays
    spread over a sample (steps whose timing the sampling limits) are only known to the
    sample.  Synthetic centroids: Gaussian scatter (closed-form median error) and the
    clustered +-0.5 sample pattern of an unfiltered jump at three sampling phases."""
    from rattle_lab.detect._timing import DelayEstimate, delay_significant

    rng = np.random.default_rng(7)
    ta = np.cumsum(rng.uniform(120, 140, 60))
    small = channel_delay(ta + 0.004 + 0.05 * rng.standard_normal(60), ta)
    assert small.resolved and not delay_significant(small)
    # median of 60 N(0, 0.05): standard error 1.2533 * 0.05 / sqrt(60) = 0.0081 sample
    assert small.stderr == pytest.approx(0.0081, rel=0.35)
    decoder = channel_delay(ta + 0.476 + 0.02 * rng.standard_normal(60), ta)
    assert decoder.resolved and delay_significant(decoder)
    assert decoder.value == pytest.approx(0.476, abs=4 * decoder.stderr)
    # an unfiltered jump: +0.5 at two of three phases, -0.5 at the third; the median says
    # 0.48 with a tiny MAD, the truth is 0
    pattern = np.tile([0.48, 0.5, -0.47], 20) + 0.01 * rng.standard_normal(60)
    jump = channel_delay(ta + pattern, ta)
    assert not jump.resolved and not delay_significant(jump)
    assert jump.stderr >= 1 / math.sqrt(12)
    assert not delay_significant(DelayEstimate(float("nan"), float("nan"), 0))


class _Log:
    """The ImpactLog fields the fit's chain systematics read."""

    def __init__(self, e, *, d=float("nan"), se=float("nan"), applied=0.0, slope=float("nan"),
                 diff=0.0, alt_se=float("nan"), fs=25600.0):
        self.e = np.asarray(e, dtype=float)
        self.velocity_delay_s, self.velocity_delay_stderr_s = d, se
        self.velocity_delay_applied_s, self.e_per_delay_s = applied, slope
        self.velocity_delay_window_s, self.e_window_change = 0.0, 0.0
        self.e_measurand_diff, self.e_measurand_alt_se, self.fs_hz = diff, alt_se, fs


def test_delay_left_at_zero_still_widens_e_by_its_pooled_uncertainty():
    from rattle_lab.fit._chain import delay_systematic

    fs = 25600.0
    logs = [_Log([0.6] * 10, d=0.01 / fs, se=0.02 / fs, slope=0.3 * fs) for _ in range(4)]
    se, notes = delay_systematic(logs)
    # pooled: 0.01 +- 0.02 / sqrt(4) samples; rms hypot(0.01, 0.01); e moves 0.3 per sample
    assert se == pytest.approx(0.3 * math.hypot(0.01, 0.01), rel=1e-9)
    assert len(notes) == 1 and "left at zero" in notes[0]
    assert delay_systematic([_Log([0.6] * 10)]) == (0.0, [])


def test_a_declared_delay_the_flights_instants_disagree_with_widens_e():
    # A declared delay stands; with ringing carried on, the flights' own impact instants
    # measure what is left after it (velocity_delay_method "flights", nothing applied).
    # Pooled over the runs like an undeclared delay left at zero, and with its own note:
    # 0.05 +- 0.02 / sqrt(3) samples, e moving 0.13 per sample.
    from rattle_lab.fit._chain import delay_systematic

    fs = 25600.0
    logs = []
    for _ in range(3):
        log = _Log([0.55] * 10, d=0.05 / fs, se=0.02 / fs, slope=0.13 * fs)
        log.velocity_delay_method = "flights"
        logs.append(log)
    se, notes = delay_systematic(logs)
    assert se == pytest.approx(0.13 * math.hypot(0.05, 0.02 / math.sqrt(3)), rel=1e-9)
    assert len(notes) == 1 and notes[0].startswith("the declared delay is used")
    # applied (undeclared, read at the instants): the applied runs' term instead
    for log in logs:
        log.velocity_delay_applied_s = 1.0 / fs
    se_a, notes_a = delay_systematic(logs)
    assert se_a == pytest.approx(0.13 * 0.02, rel=1e-9)
    assert "applied in 3 runs" in notes_a[0]


def test_undetermined_measurand_widens_or_is_established_across_runs():
    from rattle_lab.fit._chain import measurand_systematic

    rng = np.random.default_rng(3)
    e = [0.6 + 0.01 * rng.standard_normal(40) for _ in range(3)]
    # the absolute readings scatter from run to run (-0.2, +0.1, +0.3): the relative ones
    # agree, so the runs establish the relative reading and nothing is added
    logs = [_Log(x, diff=dd, alt_se=0.003) for x, dd in zip(e, (-0.2, 0.1, 0.3))]
    se, note = measurand_systematic(logs)
    assert se == 0.0 and "relative readings of e agree" in note
    # absolute readings that agree as well: e could be either, the interval spans both
    logs = [_Log(x, diff=0.05, alt_se=0.003) for x in e]
    se, note = measurand_systematic(logs)
    assert se == pytest.approx(0.05) and "+0.0500" in note
    # one such run among runs whose measurand is known: its share of the ratios
    se, _ = measurand_systematic([_Log(e[0], diff=0.05, alt_se=0.003), _Log(e[1]), _Log(e[2])])
    assert se == pytest.approx(0.05 / 3)
    assert measurand_systematic([_Log(x) for x in e]) == (0.0, "")


@pytest.mark.parametrize("case", ["heavy", "light"])
def test_a_measurand_one_run_establishes_is_taken_where_another_cannot_tell(tmp_path, case):
    # Absolute vibrometers, nothing declared, the plate's higher modes ringing in them.
    # heavy: benchmarks/chain_timing.py's seed 36 chain (a 3rd-order 5.5 kHz Bessel decoder
    # with 0.2 samples more delay, ringing at 15 % of critical).  With the flight model's
    # velocities the steady 99 Hz dwell establishes panel_absolute (coefficient 0.957 +-
    # 0.082); the 93 Hz dwell reads 0.777 +- 0.142, which since 29 Nov 2026 (nineteenth
    # session: an interval holding one reading and 4 standard errors from the other) decides
    # it too.  e was +19.9 % at the seventeenth session's start, -0.11 % after it.
    # light: `--seed0 50`'s seed 54 chain (a 3rd-order 5.9 kHz Bessel, +0.82 sample, ringing
    # at 2 %): the 99 Hz dwell reads 1.20 +- 0.23 (absolute by the second rule alone), the
    # 93 Hz dwell 4.6 +- 2.0 (it cannot tell): the campaign's reading is taken there
    # (`measurand_if_undetermined`).  e was +21 % with both undetermined.  Asserted: the
    # issue's 3 %, the interval covering, each run's flag and where its reading came from;
    # and the same e where the user gives the measurand.
    from rattle_lab.detect import DetectParams
    from rattle_lab.detect._chain import CAMPAIGN_MEASURAND_NOTE
    from rattle_lab.exceptions import ParameterError
    from rattle_lab.workflow import fit_store

    plant = Plant()
    if case == "heavy":
        chain = Chain(decoder="bessel", decoder_order=3, decoder_cutoff_hz=5471.67,
                      decoder_delay_s=0.21 / 25600.0, measurand="panel_absolute",
                      ring_zeta=(0.15, 0.15, 0.15), declare_delay=False, declare_measurand=False)
        seed, from_campaign = 36, ()
    else:
        chain = Chain(decoder="bessel", decoder_order=3, decoder_cutoff_hz=5926.64,
                      decoder_delay_s=0.8205 / 25600.0, measurand="panel_absolute",
                      ring_zeta=(0.02, 0.02, 0.02), declare_delay=False, declare_measurand=False)
        seed, from_campaign = 54, ("dwell_93",)
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in (93.0, 99.0)]
    write_campaign(tmp_path / "c.h5", plant, chain, runs, seed=seed)
    ingest([tmp_path / "c.h5"], tmp_path / "s.h5", quiet=True)
    res = fit_store(tmp_path / "s.h5", write=False, quiet=True)
    flags = {r.run_id: r.chain_flags for r in res.runs}
    for run_id in ("dwell_93", "dwell_99"):
        assert any(f.startswith("measurand_inferred: panel_absolute")
                   and (CAMPAIGN_MEASURAND_NOTE in f) == (run_id in from_campaign)
                   for f in flags[run_id]), flags
    e = res.summary.fits.restitution_ratio
    assert e.value == pytest.approx(plant.e, rel=0.03)
    assert abs(e.value - plant.e) <= 1.96 * e.stderr
    given = fit_store(tmp_path / "s.h5", write=False, quiet=True,
                      detect={"measurand_if_undetermined": "panel_absolute"})
    assert given.summary.fits.restitution_ratio.value == pytest.approx(e.value, rel=1e-9)
    with pytest.raises(ParameterError, match="measurand_if_undetermined"):
        DetectParams.from_mapping({"measurand_if_undetermined": "absolute"})


@pytest.mark.parametrize("measurand, truth", [("panel_relative_to_striker", 0.0),
                                               ("panel_absolute", 1.0)])
def test_lightly_damped_modes_ringing_on_are_taken_out_of_the_measurand_regression(measurand,
                                                                                  truth):
    # The measurand regression integrates the velocity from impact to impact; modes that
    # ring on past the next impact (this generator's 171, 293 and 390 Hz at 2 % of critical)
    # leave their tails in that integral.  On the generator's steady 99 Hz dwell (true
    # impact times and jumps given) the coefficient came out 0.57 +- 0.18 for a relative
    # vibrometer (truth 0) and 1.56 +- 0.18 for an absolute one (truth 1): 3 standard
    # errors off.  With the modes' integrated tails as regressors (their amplitudes the
    # regression's): 0.10 +- 0.28 and 1.09 +- 0.28 (measured).  Asserted: within 2 standard
    # errors with them, beyond 2 without (the bias the regressors remove).
    chain = Chain(measurand=measurand)
    plant, chans, (t, v_in, v_out) = _run(chain, f_hz=99.0, periods=80, seed=3)
    fs = chain.fs_hz
    modes = tuple((f, z * 2 * math.pi * f) for f, z in zip(chain.ring_hz, chain.ring_zeta))
    args = (chans["velocity"], fs, 0.0, t + chain.velocity_delay_s, chans["base"], fs, 0.0, 99.0)
    without = measurand_share(*args, jumps_m_s=v_out - v_in)
    with_modes = measurand_share(*args, jumps_m_s=v_out - v_in, ring_modes=modes)
    assert abs(with_modes.value - truth) < 2.0 * with_modes.stderr
    assert abs(without.value - truth) > 2.0 * without.stderr


def test_the_integrated_tails_recursion_is_the_double_sum():
    # measurand_share's ringing regressors by recursion over the impacts (linear in their
    # number) against the double sum written out (quadratic): to 1e-12 relative (300
    # steps of a few roundings each; measured 1e-15)
    from rattle_lab.detect._timing import _integrated_tails

    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0.0, 1.0, 300))
    jump = rng.normal(size=300)
    p = complex(-21.5, 2 * math.pi * 171.0)
    dt = t[:, None] - t[None, :]
    past = dt > 0
    direct = np.sum(np.where(past, jump[None, :] * (np.exp(p * np.where(past, dt, 0.0)) - 1.0)
                             / p, 0.0), axis=1)
    got = _integrated_tails(t, jump, p)
    assert np.max(np.abs(got - direct)) <= 1e-12 * np.max(np.abs(direct))


def test_impacts_without_both_velocities_stay_out_of_the_measurand_regression(tmp_path):
    # An absolute vibrometer behind a 2nd-order 20 kHz Bessel decoder at 51.2 kHz, +1.3
    # samples, nothing declared, no ringing (`chain_timing.py --table`'s third row).  Each
    # record ends mid-flight and the detector keeps a trigger in its last samples as an
    # impact whose v_out cannot be fitted.  Taken into the measurand regression with a jump
    # of 0, that one point put the coefficient at 11.0 and 6.0 (0: relative, 1: absolute),
    # both runs undetermined, and e +17.9 %.  Left out: 1.12 and 1.18 (measured), and e
    # -1.67 %.  Asserted: both runs' measurand inferred panel_absolute from their own data,
    # e within the 3 %, the interval covering.
    from rattle_lab.detect._chain import CAMPAIGN_MEASURAND_NOTE
    from rattle_lab.workflow import fit_store

    plant = Plant()
    chain = Chain(fs_hz=51200.0, decoder="bessel", decoder_order=2, decoder_cutoff_hz=20000.0,
                  decoder_delay_s=1.3 / 51200, measurand="panel_absolute",
                  ring_in_velocity=False, declare_delay=False, declare_measurand=False)
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in (93.0, 99.0)]
    write_campaign(tmp_path / "c.h5", plant, chain, runs, seed=3)
    ingest([tmp_path / "c.h5"], tmp_path / "s.h5", quiet=True)
    res = fit_store(tmp_path / "s.h5", write=False, quiet=True)
    for r in res.runs:
        assert any(f.startswith("measurand_inferred: panel_absolute")
                   and CAMPAIGN_MEASURAND_NOTE not in f for f in r.chain_flags), r.chain_flags
    e = res.summary.fits.restitution_ratio
    assert e.value == pytest.approx(plant.e, rel=0.03)
    assert abs(e.value - plant.e) <= 1.96 * e.stderr


def test_heavily_damped_ringing_modes_are_found_and_e_holds(tmp_path):
    # The plate's higher modes (171, 293, 390 Hz) at 15 % of critical damping ring in the
    # vibrometer; a declared 7th-order 2 kHz Butterworth decoder; two 80-period dwells
    # (93 and 99 Hz, as benchmarks/chain_timing.py), fitted as `rattle-lab fit` does.  The
    # campaign's mode search once took a "mode" at its region's lower edge (104 Hz, 1.1
    # f_s: the fundamental's misfit) before the 171 Hz mode, and e came out 12.7 % high
    # (the 99 Hz run's 16 %).  Now: no mode at the edge, the strongest mode found within
    # 3 % (the search's resolution is 5 %: two modes closer are refused), and e within the
    # issue's 3 % with its 95 % interval covering the truth.
    from rattle_lab.workflow import fit_store

    plant = Plant()
    chain = Chain(decoder="butterworth", decoder_order=7, decoder_cutoff_hz=2056.12,
                  decoder_delay_s=0.01 / 25600.0, ring_zeta=(0.15, 0.15, 0.15))
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in (93.0, 99.0)]
    write_campaign(tmp_path / "c.h5", plant, chain, runs, seed=6)
    ingest([tmp_path / "c.h5"], tmp_path / "s.h5", quiet=True)
    res = fit_store(tmp_path / "s.h5", write=False, quiet=True)
    modes = {m for r in res.runs if r.impacts is not None for m in r.impacts.ring_modes}
    assert modes
    # the region's edge is 1.1 times the runs' median fitted f_s (about 104 Hz here); the
    # plate's ringing modes are all above 1.7 f_s
    assert min(f for f, _ in modes) > 1.2 * plant.f_s_hz
    assert min(f for f, _ in modes) == pytest.approx(chain.ring_hz[0], rel=0.03)
    e = res.summary.fits.restitution_ratio
    assert e.value == pytest.approx(plant.e, rel=0.03)
    assert abs(e.value - plant.e) <= 1.96 * e.stderr


def test_a_run_in_periodic_motion_takes_the_plates_fundamental_from_the_campaign(tmp_path):
    # Light ringing (2 %) in a relative vibrometer behind a declared 5th-order 8.0 kHz
    # Bessel decoder at 25.6 kHz; the two dwells of benchmarks/chain_timing.py (its seed 10
    # chain, declared).  The 99 Hz dwell settles into period-1 impacts after ten periods:
    # it repeats one flight, where the fundamental's free response and the forced response
    # nearly trade off, and its own search put the fundamental at 92.8-95.8 Hz decaying at
    # 8.6-16.6 1/s (truth 96.0 Hz and 6.03 1/s); e came out 3.9 % high.  The fundamental
    # is the plate's, as the ringing modes are: searched on both runs together it comes out
    # at 96.005 Hz and 5.93 1/s (measured), and e +1.3 % (with the dwells' forced
    # amplitude held).  Asserted: the frequency within 0.3 % and the decay within 15 %
    # (the 93 Hz run alone found 96.01 and 5.88; two 80-period dwells with 25 and 77
    # impacts), e within the 3 % and its 95 % interval covering the truth.
    from rattle_lab.workflow import fit_store

    plant = Plant()
    chain = Chain(fs_hz=25600.0, decoder="bessel", decoder_order=5,
                  decoder_cutoff_hz=8025.29, decoder_delay_s=2.45 / 25600.0)
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in (93.0, 99.0)]
    write_campaign(tmp_path / "c.h5", plant, chain, runs, seed=10)
    ingest([tmp_path / "c.h5"], tmp_path / "s.h5", quiet=True)
    res = fit_store(tmp_path / "s.h5", write=False, quiet=True)
    found = {r.impacts.params.ring_fundamental for r in res.runs
             if r.impacts is not None and r.impacts.ring_modes}
    assert len(found) == 1
    f_s, sigma = found.pop()
    assert f_s == pytest.approx(plant.f_s_hz, rel=0.003)
    assert sigma == pytest.approx(plant.zeta * 2 * math.pi * plant.f_s_hz, rel=0.15)
    e = res.summary.fits.restitution_ratio
    assert e.value == pytest.approx(plant.e, rel=0.03)
    assert abs(e.value - plant.e) <= 1.96 * e.stderr
    assert any("the fundamental: 96.0" in n for n in e.notes)


@pytest.mark.parametrize("chain, f_hz", [
    (Chain(decoder="bessel", decoder_order=4, decoder_cutoff_hz=8000.0,
           decoder_delay_s=1.5 / 25600.0, ring_zeta=(0.15, 0.15, 0.15)), 99.0),
    (Chain(decoder="bessel", decoder_order=6, decoder_cutoff_hz=3000.0,
           decoder_delay_s=2.7 / 25600.0, ring_zeta=(0.02, 0.02, 0.02)), 93.0),
    (Chain(decoder="butterworth", decoder_order=4, decoder_cutoff_hz=5000.0,
           decoder_delay_s=1.5 / 25600.0, ring_zeta=(0.15, 0.15, 0.15)), 93.0),
], ids=["bessel4-8k-heavy", "bessel6-3k-light", "butter4-5k-heavy"])
def test_the_flights_own_impact_instants_measure_the_vibrometer_delay(chain, f_hz):
    # With the ringing modes carried on, the flight model's fundamental has a displacement
    # on each side of an impact, and the two meet at the impact
    # (rattle_lab.detect._flights._continuity_lag): the impact's instant in the
    # vibrometer's own record, whatever the decoder does to the velocity step and however
    # the modes ring.  Given the impacts' true instants (an accelerometer's) and the
    # generator's modes, the lag found is the decoder's DC group delay plus its extra delay
    # (2.2-6.2 samples here): within 0.1 sample (measured 0.001-0.011 on these runs, at
    # most 0.08 over the 40 of 48 generator runs, 24 random chains, whose estimate held
    # with twice the pads), and e read there within 1 % of the truth's (measured 0.02-0.23
    # %).
    from rattle_lab.detect._flights import flight_velocities

    plant, chans, (t_true, v_in, v_out) = _run(chain, f_hz=f_hz, periods=80, seed=3)
    fs = chain.fs_hz
    k = t_true * fs
    modes = [(f, z * 2 * math.pi * f) for f, z in zip(chain.ring_hz, chain.ring_zeta)]
    fit = flight_velocities(chans["velocity"], fs, f_hz, k, np.full(k.size, 13.0), v_in,
                            v_out, modes, carried=True)
    assert fit.lag_note == "" and fit.lag_n >= 20
    assert fit.lag_samples == pytest.approx(chain.velocity_delay_s * fs, abs=0.1)
    assert fit.lag_stderr_samples < 0.1
    m = fit.from_flights
    e_fit = np.median(-fit.v_out_m_s[m] / fit.v_in_m_s[m])
    assert e_fit == pytest.approx(np.median(-v_out[m] / v_in[m]), rel=0.01)
    assert fit.e_per_lag > 0   # read later, |v_in| is smaller and |v_out| larger: e rises
