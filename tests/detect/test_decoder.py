"""Issue 28: the vibrometer's decoder identified from the impacts' steps and equalised.

References, independent of :mod:`rattle_lab.detect._decoder`:
* the filters: ``scipy.signal.butter`` / ``bessel`` (their own bilinear transform) and
  ``scipy.signal.lfilter`` to run them; the low-frequency group delay from the analog
  prototype (:func:`rattle_lab.records.filter_group_delay_s`) and from the independent
  generator's own formula (``tests/independent_campaign.py``);
* the records: the independent generator (plain numpy, its decoder applied through the FFT
  from its own analog prototypes).

Tolerances: the identified delay within 0.1 sample (as the delay tests of
``test_chain_timing.py``; measured on these chains: 0.01-0.05 sample) and the cut-off within
2 % (measured: 0.3 %); the equalised step centred within 1e-3 sample (the FIR's truncation to
64 periods of the cut-off leaves ~1e-4).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.signal import bessel, butter, freqz_zpk, lfilter

from independent_campaign import Chain, Plant, iir_dc_delay_s, measure
from rattle_lab.detect import FLAG_DELAY_ESTIMATED, FLAG_FILTER_IDENTIFIED, ImpactParams, \
    detect_impacts, velocity_delay_flags
from rattle_lab.detect._decoder import (DecoderFit, _zpk, dc_delay_samples, equalise,
                                        identify_decoder, response, settle_samples)
from rattle_lab.exceptions import ParameterError
from rattle_lab.records import filter_group_delay_s


@pytest.mark.parametrize("kind", ["butterworth", "bessel"])
@pytest.mark.parametrize("order", [1, 2, 4, 8])
def test_filters_are_scipys_design_and_delay(kind, order):
    fs, fc = 25600.0, 2700.0
    design = butter if kind == "butterworth" else bessel
    kw = {} if kind == "butterworth" else {"norm": "mag"}
    z, p, k = design(order, fc, fs=fs, output="zpk", **kw)
    z2, p2, k2 = _zpk(kind, order, fc, fs)
    assert np.allclose(np.sort_complex(p2), np.sort_complex(p), atol=1e-12)
    assert k2 == pytest.approx(k, rel=1e-12)
    f = np.linspace(0.0, fs / 2 * 0.99, 200)
    _, h = freqz_zpk(z, p, k, worN=f, fs=fs)
    assert np.allclose(response(kind, order, fc, fs, f), h, atol=1e-12)
    d = dc_delay_samples(kind, order, fc, fs)
    assert d == pytest.approx(filter_group_delay_s(kind, order, fc, fs) * fs, rel=1e-9)
    assert d == pytest.approx(iir_dc_delay_s(kind, order, fc, fs) * fs, rel=1e-9)


def _recognised(chain: Chain, seed: int = 2):
    """One 60-period dwell at 99 Hz (1.5 times grazing) of the independent generator and the
    detector's first pass on it (no identification)."""
    plant = Plant()
    w = 2 * math.pi * plant.f_s_hz
    r = 99.0 / plant.f_s_hz
    graze = plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) / plant.q
    ch, imp = measure(plant, chain, 2 * math.pi * 99.0, np.full(60, 1.5 * graze),
                      np.random.default_rng(seed))
    log = detect_impacts(chain.fs_hz, velocity_m_s=ch["velocity"], accel_ms2=ch["plate"],
                         excitation_freq_hz=99.0, params=ImpactParams(identify_decoder=False))
    return plant, ch, imp, log.recognition


@pytest.mark.parametrize("chain", [
    # the ringing decoder the step centroids put 0.47 sample early
    Chain(decoder="butterworth", decoder_order=8, decoder_cutoff_hz=3000.0,
          decoder_delay_s=1.2 / 25600.0, ring_in_velocity=False),
    # a slow one at 51.2 kHz: 20.8 samples, ringing for 1.6 ms
    pytest.param(Chain(fs_hz=51200.0, decoder="butterworth", decoder_order=8,
                       decoder_cutoff_hz=2000.0, decoder_delay_s=0.0, ring_in_velocity=False),
                 marks=pytest.mark.slow),
    Chain(decoder="bessel", decoder_order=6, decoder_cutoff_hz=5000.0,
          decoder_delay_s=0.7 / 25600.0, ring_in_velocity=False),
    # with the plate's higher modes ringing in the vibrometer (2 % damping): the high-pass
    # before the fit keeps them out
    Chain(decoder="butterworth", decoder_order=8, decoder_cutoff_hz=2700.0,
          decoder_delay_s=0.7 / 25600.0, ring_in_velocity=True),
], ids=["butter8-3k", "butter8-2k-51k", "bessel6-5k", "butter8-2.7k-ringing"])
def test_identifies_the_independent_generators_decoders(chain):
    _, ch, _, rec = _recognised(chain)
    fs = chain.fs_hz
    at = rec.t_idx[rec.keep]
    fit = identify_decoder(np.asarray(ch["velocity"]), at, fs, rec.delay.value)
    assert fit is not None
    assert (fit.kind, fit.order) == (chain.decoder, chain.decoder_order)
    assert fit.cutoff_hz == pytest.approx(chain.decoder_cutoff_hz, rel=0.02)
    assert fit.delay_samples == pytest.approx(chain.velocity_delay_s * fs, abs=0.1)
    assert fit.residual_share < 0.05 and fit.n_impacts >= 40


def test_a_decoder_of_no_family_searched_is_not_identified():
    # the generator's default decoder: a linear-phase FIR (8 kHz brick wall and a
    # fractional delay): no Butterworth or Bessel explains its steps (residual 13-24 % of an
    # ideal step's on these records), so none is claimed
    chain = Chain(decoder="fir", decoder_delay_s=18e-6, ring_in_velocity=False)
    _, ch, _, rec = _recognised(chain)
    at = rec.t_idx[rec.keep]
    assert identify_decoder(np.asarray(ch["velocity"]), at, chain.fs_hz, rec.delay.value) is None


def test_the_generators_ideal_vibrometer_keeps_each_jump_between_two_samples():
    # decoder "none" (benchmarks/chain_timing.py's ideal vibrometer): the velocity as it is.
    # Reference: the generator's own true impacts.  Between the samples either side of an
    # impact the velocity changes by the jump plus the flight's own change over at most one
    # sample (|acceleration| <= 900 m/s^2 here: 0.035 m/s at 25.6 kHz) plus quantisation
    # (6e-5 m/s; noise and hum off): measured 0.018 m/s at most.  The FIR decoder
    # spreads the same jumps over several samples: their largest one-sample change is 72-76 %
    # of the jump
    quiet = dict(ring_in_velocity=False, noise_v_m_s=0.0, hum_v_m_s=0.0)
    one_sample = {}
    for decoder in ("none", "fir"):
        chain = Chain(decoder=decoder, decoder_delay_s=0.0, **quiet)
        _, ch, (t, vin, vout), _ = _recognised(chain)
        k = np.ceil(t * chain.fs_hz).astype(int)
        v = np.asarray(ch["velocity"])
        big = np.abs(vout - vin) >= 0.3
        assert big.sum() >= 20
        one_sample[decoder] = ((v[k] - v[k - 1]) - (vout - vin))[big], (vout - vin)[big]
    err, _ = one_sample["none"]
    assert np.max(np.abs(err)) <= 0.04
    err, dv = one_sample["fir"]
    assert np.max((dv + err) / dv) < 0.85


def test_too_few_impacts_identify_nothing():
    v = np.zeros(5000)
    assert identify_decoder(v, np.array([1000.0, 2000.0]), 25600.0, 0.0) is None
    assert identify_decoder(v, np.arange(10) * 400.0 + 300.0, 25600.0, float("nan")) is None


@pytest.mark.parametrize("kind,order,fc,fs", [("butterworth", 8, 2000.0, 51200.0),
                                              ("butterworth", 8, 3000.0, 25600.0),
                                              ("bessel", 4, 10000.0, 25600.0)])
def test_equalised_step_is_centred_and_does_not_overshoot(kind, order, fc, fs):
    design = butter if kind == "butterworth" else bessel
    kw = {} if kind == "butterworth" else {"norm": "mag"}
    b, a = design(order, fc, fs=fs, **kw)
    k = np.arange(16384) - 8192
    through = lfilter(b, a, (k >= 0).astype(float))
    delay = dc_delay_samples(kind, order, fc, fs)
    fit = DecoderFit(kind, order, fc, 0.0, delay, 0.0, 50,
                     settle_samples(kind, order, fc, fs, 0.0, delay))
    y = equalise(through, fs, fit)
    dy = np.diff(y)[8000:8400]
    kk = k[1:][8000:8400]
    assert np.sum(kk * dy) / np.sum(dy) == pytest.approx(0.0, abs=1e-3)   # no delay left
    assert y[8000:8400].max() < 1.0 + 1e-3 and y[8000:8400].min() > -1e-3  # no overshoot
    assert y[12000] == pytest.approx(1.0, abs=1e-6)                         # unit gain
    # only advanced: the decoder's own step, its centroid moved onto the step
    y = equalise(through, fs, fit, shape=False)
    dy = np.diff(y)[7800:8800]
    kk = k[1:][7800:8800]
    assert np.sum(kk * dy) / np.sum(dy) == pytest.approx(0.0, abs=1e-2)
    assert y[8000:8400].max() > 1.0 + 1e-3 or kind == "bessel"            # still rings


def test_settling_times():
    # an 8th-order Butterworth at 2.66 kHz rings for about 1.2 ms after its delay at 25.6
    # kHz (beyond the detector's guards: equalised); a 4th-order one at 10 kHz for 0.5 ms
    slow = settle_samples("butterworth", 8, 2662.0, 25600.0, 0.0,
                          dc_delay_samples("butterworth", 8, 2662.0, 25600.0))
    fast = settle_samples("butterworth", 4, 10000.0, 25600.0, 0.0,
                          dc_delay_samples("butterworth", 4, 10000.0, 25600.0))
    assert 1.0e-3 < slow / 25600.0 < 1.5e-3
    assert fast / 25600.0 < 0.7e-3


def test_identified_decoder_is_flagged_with_its_delay():
    log = SimpleNamespace(velocity_delay_s=310e-6, velocity_delay_stderr_s=1e-6,
                          velocity_delay_n=56, velocity_delay_applied_s=306e-6, fs_hz=25600.0,
                          velocity_delay_method="steps", ringing_ratio=0.9,
                          decoder="a Butterworth low-pass of order 8, -3 dB at 3 kHz")
    flags = velocity_delay_flags(log, declared=False)
    assert flags[0].startswith(f"{FLAG_FILTER_IDENTIFIED}: the vibrometer's decoder reads as a "
                               "Butterworth")
    assert flags[1].startswith(f"{FLAG_DELAY_ESTIMATED}: the velocity lags the plate "
                               "accelerometer by 306.00 us (7.834 samples)")
    assert "+0.102 +- 0.026 samples" in flags[1]


def test_identify_decoder_parameter_is_a_boolean():
    with pytest.raises(ParameterError, match="identify_decoder"):
        ImpactParams(identify_decoder="yes")   # type: ignore[arg-type]
