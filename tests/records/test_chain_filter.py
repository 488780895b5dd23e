"""A channel declares its low-pass filter instead of its delay (schema v2, issue 28 item 1).

Labs know their vibrometer decoder's setting (family, order, cut-off) more often than its
delay to the microsecond.  ``filter_type``, ``filter_order``, ``filter_cutoff_hz`` and, for a
digital filter, ``filter_sample_rate_hz`` declare it; the filter's low-frequency group delay
(:func:`rattle_lab.records.filter_group_delay_s`) is then compensated like a declared
``group_delay_s`` and checked against the impacts in the same way.

References: the closed form of a Butterworth low-pass's DC group delay,
``1 / (wc sin(pi / 2n))``; and the independent generator's own decoders
(``tests/independent_campaign.py``: poles of its own analog prototypes, its own Bessel
magnitude normalisation by bisection, its own bilinear transform), whose DC delay it computes
as ``sum Re 1/(1 - z_k) - n/2`` samples.
"""

from __future__ import annotations

import math

import h5py
import numpy as np
import pytest
from independent_campaign import Chain, Plant, iir_dc_delay_s, write_campaign
from record_factory import channels, make_record, write

from rattle_lab.exceptions import ParameterError, SchemaError
from rattle_lab.fit._results import read_results
from rattle_lab.records import declared_delay_s, filter_group_delay_s, read
from rattle_lab.store import ingest
from rattle_lab.workflow import fit_store


@pytest.mark.parametrize("order", range(1, 9))
def test_analog_butterworth_delay_is_the_closed_form(order):
    # a sum of n positive terms of size ~1/wc: relative rounding ~n eps
    fc = 7000.0
    closed = 1.0 / (2 * math.pi * fc * math.sin(math.pi / (2 * order)))
    assert filter_group_delay_s("butterworth", order, fc) == pytest.approx(closed, rel=1e-13)


@pytest.mark.parametrize("kind", ["butterworth", "bessel"])
@pytest.mark.parametrize("order,fc,fs", [(2, 2000.0, 25600.0), (4, 10000.0, 25600.0),
                                         (6, 5000.0, 51200.0), (8, 20000.0, 51200.0),
                                         (8, 2000.0, 51200.0)])
def test_digital_delay_equals_the_independent_generator(kind, order, fc, fs):
    # the generator's poles come from np.roots of the reverse Bessel polynomial (degree 8:
    # relative errors ~1e-13) and a bisection of the -3 dB point to 1e-15: 1e-10 is ample
    assert filter_group_delay_s(kind, order, fc, fs) == pytest.approx(
        iir_dc_delay_s(kind, order, fc, fs), rel=1e-10)


def test_declared_delay_takes_group_delay_s_first_and_refuses_half_a_filter(tmp_path):
    base = channels()[0]
    assert declared_delay_s(base) is None
    import dataclasses

    ch = dataclasses.replace(base, filter_type="bessel", filter_order=4, filter_cutoff_hz=8e3)
    assert declared_delay_s(ch) == filter_group_delay_s("bessel", 4, 8e3)
    assert declared_delay_s(dataclasses.replace(ch, group_delay_s=5e-6)) == 5e-6
    with pytest.raises(ParameterError, match="declared together"):
        dataclasses.replace(base, filter_type="bessel", filter_order=4)
    with pytest.raises(ParameterError, match="filter_order is an integer from 1 to 16"):
        dataclasses.replace(ch, filter_order=2.5)
    with pytest.raises(ParameterError, match="twice filter_cutoff_hz"):
        dataclasses.replace(ch, filter_sample_rate_hz=12e3)


def test_a_declared_filter_round_trips_as_schema_v2_and_half_a_filter_is_refused(tmp_path):
    import dataclasses

    rec = make_record()
    run = rec.runs[0]
    vel = [dataclasses.replace(c, filter_type="butterworth", filter_order=4,
                               filter_cutoff_hz=10e3, filter_sample_rate_hz=51200.0)
           if c.quantity == "plate_velocity" else c for c in run.channels]
    path = write(tmp_path, "f.h5", dataclasses.replace(
        rec, runs=(dataclasses.replace(run, channels=tuple(vel)),)))
    with h5py.File(path, "r") as fh:
        assert int(fh.attrs["schema_version"]) == 2
    with read(path) as back:
        ch = back.runs[0].channel("velocity")
        assert (ch.filter_type, ch.filter_order, ch.filter_cutoff_hz, ch.filter_sample_rate_hz) \
            == ("butterworth", 4, 10e3, 51200.0)
    with h5py.File(path, "r+") as fh:
        del fh["runs/dwell_094/channels/velocity"].attrs["filter_order"]
    with pytest.raises(SchemaError, match=r"/runs/dwell_094/channels/velocity: the declared "
                                          r"filter: .*declared together"):
        read(path)


def _grazing_ms2(plant: Plant, f_hz: float) -> float:
    w = 2 * math.pi * plant.f_s_hz
    r = f_hz / plant.f_s_hz
    return plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) / plant.q


def test_a_campaign_that_declares_its_decoder_filter_is_timed_by_it(tmp_path):
    # the decoder (causal 4th-order Butterworth, 10 kHz, at 25.6 kHz: 18.3 us, under
    # half a sample) declared by its setting alone: the fit compensates the filter's delay
    # (no estimated-delay flag, nothing contradicted), impact times to a tenth of a sample and
    # e within 3 % (the acceptance) of the generator's truth
    plant = Plant()
    chain = Chain(ring_in_velocity=False, decoder="butterworth", decoder_delay_s=0.0,
                  declare_delay=False, declare_filter=True)
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in (93.0, 99.0)]
    path = tmp_path / "c.h5"
    truth = write_campaign(path, plant, chain, runs, seed=7)
    store = tmp_path / "s.h5"
    ingest([path], store, quiet=True)
    fit = fit_store(store)
    assert not [f for f in fit.summary.data_quality if "channel_delay" in f], \
        fit.summary.data_quality
    res = read_results(store)
    for (_key, run_id), d in res.runs.items():
        t_true, v_in, _ = truth.impacts[run_id]
        t_det, e_det = np.asarray(d["t_s"]), np.asarray(d["e"])
        k = np.array([int(np.argmin(np.abs(t_det - t))) for t in t_true])
        near = np.abs(t_det[k] - t_true) < 0.5e-3
        assert near.mean() >= 0.99, run_id
        assert abs(np.median(t_det[k[near]] - t_true[near])) < 0.1 / chain.fs_hz, run_id
        big = near & (np.abs(v_in) >= 0.1)
        assert big.sum() >= 20
        assert np.median(e_det[k[big]]) == pytest.approx(plant.e, rel=0.03), run_id
