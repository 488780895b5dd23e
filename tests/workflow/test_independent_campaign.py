"""Issue 15: the pipeline on a campaign we did not make (tests/independent_campaign.py).

The generator shares no code with rattle_lab: its own exact SDF flow (closed-form free
and forced response, bisection for the impacts), its own measurement chain (vibrometer
decoder delay of 18 us after an 8 kHz low-pass, DC offsets, 50 Hz hum, noise, 16-bit
quantisation, higher plate modes ringing in the plate accelerometer after every impact),
written straight into the data_schema layout with h5py.  The record is ingested and
fitted through ``rattle-lab``'s commands (:func:`record_factory.run_command`).

Tolerances: impact times within 10 us (a fifth of a sample at 25.6 kHz); the median ``e`` of the impacts with
``|v_in| >= 0.1 m/s`` within 5 % (the per-impact scatter from noise and truncated fit
windows is ~0.05; 60-80 impacts per run make the median good to ~2 %).

When the vibrometer also sees the higher modes (here 28 % of each velocity jump,
``ring_in_velocity=True``), ``e`` from the local velocity fits is the contact point's, not
the first mode's (~1.0 instead of 0.55): the local fits cannot separate modes 1.8 times
apart in frequency over a few milliseconds.  The fit then finds the modes across the runs
and takes the velocities from the flight model (the last test).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from independent_campaign import Chain, Plant, write_campaign
from rattle_lab.store import ingest
from record_factory import run_command

FREQS_HZ = (93.0, 99.0)


def _grazing_ms2(plant: Plant, f_hz: float) -> float:
    w = 2 * math.pi * plant.f_s_hz
    r = f_hz / plant.f_s_hz
    return plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) / plant.q


def _campaign(tmp_path, chain: Chain, seed: int = 3):
    plant = Plant()
    runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
             "levels": np.full(80, 1.5 * _grazing_ms2(plant, f))} for f in FREQS_HZ]
    path = tmp_path / f"campaign_{seed}.h5"
    truth = write_campaign(path, plant, chain, runs, seed=seed)
    store = tmp_path / f"store_{seed}.h5"
    ingest([path], store, quiet=True)
    proc = run_command("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    return plant, truth, store, json.loads(proc.stdout)


def _matched(store, truth):
    """Per run: (true t, detected t, detected e) of matched impacts; false and missed counts."""
    from rattle_lab.fit._results import read_results

    res = read_results(store)
    out = {}
    for (_key, run_id), d in res.runs.items():
        t_true, v_in, _ = truth.impacts[run_id]
        t_det, e_det = np.asarray(d["t_s"]), np.asarray(d["e"])
        pairs, used = [], set()
        for t, v in zip(t_true, v_in):
            k = int(np.argmin(np.abs(t_det - t))) if t_det.size else -1
            if k >= 0 and abs(t_det[k] - t) < 0.5e-3 and k not in used:
                used.add(k)
                pairs.append((t, t_det[k], e_det[k], v))
        out[run_id] = (np.array(pairs), t_det.size - len(used), t_true.size - len(pairs))
    return out


def test_relative_vibrometer_with_declared_delay(tmp_path):
    chain = Chain(ring_in_velocity=False)
    plant, truth, store, summary = _campaign(tmp_path, chain)
    assert summary["participation"] == {"value": plant.q, "source": "rig modal_participation"}
    assert summary["data_quality"] == []
    n_true = n_hit = n_det = 0
    for run_id, (pairs, false, missed) in _matched(store, truth).items():
        n_true += pairs.shape[0] + missed
        n_hit += pairs.shape[0]
        n_det += pairs.shape[0] + false
        # the decoder's 18 us is taken off: impact times to a fifth of a sample
        assert abs(np.median(pairs[:, 1] - pairs[:, 0])) < 10e-6, run_id
        big = np.abs(pairs[:, 3]) >= 0.1
        assert big.sum() >= 20
        assert np.median(pairs[big, 2]) == pytest.approx(plant.e, rel=0.05), run_id
    assert n_hit / n_true >= 0.99 and n_hit / n_det >= 0.99     # recall and precision


def test_undeclared_delay_is_measured(tmp_path):
    # The same chain without group_delay_s: the vibrometer is 18 us (0.46 sample) late
    # against the plate accelerometer's contact pulses; before issue 28 the velocity fits
    # were read at the wrong instant and e came out ~10 % low.  The delay is now measured
    # from the impacts (velocity step centroid less contact pulse centroid), used and named.
    plant, truth, store, summary = _campaign(tmp_path, Chain(ring_in_velocity=False,
                                                             declare_delay=False))
    delays = [f for f in summary["data_quality"] if "channel_delay_estimated" in f]
    assert len(delays) == 2
    for f in delays:
        us = float(re.search(r"by ([0-9.]+) \+- ", f).group(1))
        assert abs(us - 18.0) < 0.1e6 / 25600, f      # within a tenth of a sample
    for run_id, (pairs, _, _) in _matched(store, truth).items():
        big = np.abs(pairs[:, 3]) >= 0.1
        assert np.median(pairs[big, 2]) == pytest.approx(plant.e, rel=0.05), run_id


def test_absolute_vibrometer_is_made_relative_with_the_base(tmp_path):
    # An absolute vibrometer adds the base velocity to both sides of each jump; the fit
    # takes it off (base accelerometer, local sine at the excitation frequency).
    chain = Chain(ring_in_velocity=False, measurand="panel_absolute")
    plant, truth, store, summary = _campaign(tmp_path, chain)
    assert summary["data_quality"] == []
    for run_id, (pairs, _, _) in _matched(store, truth).items():
        big = np.abs(pairs[:, 3]) >= 0.1
        assert np.median(pairs[big, 2]) == pytest.approx(plant.e, rel=0.05), run_id


def test_undeclared_or_uncorrectable_measurand_is_flagged(tmp_path):
    import h5py

    chain = Chain(ring_in_velocity=False, measurand="panel_absolute")
    plant = Plant()
    path = tmp_path / "c.h5"
    levels = np.full(20, 1.5 * _grazing_ms2(plant, 99.0))
    write_campaign(path, plant, chain, [
        {"run_id": "no_base", "protocol": "sine_dwell", "freq_hz": 99.0, "levels": levels},
        {"run_id": "undeclared", "protocol": "sine_dwell", "freq_hz": 99.0, "levels": levels}],
        seed=5)
    with h5py.File(path, "r+") as fh:
        del fh["runs/no_base/channels/base"]
        del fh["runs/undeclared/channels/velocity"].attrs["measurand"]
    store = tmp_path / "s.h5"
    ingest([path], store, quiet=True)
    proc = run_command("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    key = out["runs"][0]["input_key"]
    flags = sorted(out["data_quality"])
    assert flags[0] == f"{key}/no_base: velocity_panel_absolute"
    # issue 28: the undeclared measurand is inferred from the data, or named undetermined
    assert len(flags) == 2 and re.match(
        rf"{key}/undeclared: measurand_(inferred: panel_absolute|undetermined)", flags[1]), flags
    table = run_command("fit", str(store), "--quiet").stdout
    assert f"data-quality flag: {key}/no_base: velocity_panel_absolute" in table


def test_lightly_damped_ringing_in_the_vibrometer_is_found_across_the_runs(tmp_path):
    """With the higher modes in the vibrometer (this generator's modes at 171, 293 and 390 Hz,
    2 % of critical, 28 % of each velocity jump, ringing on past the next impact) the local
    fits read e ~1 for 0.55, and no run's own flight model measures their share on these
    steady dwells (and the test for ringing passes one of them by: the tails are in the
    residual before each impact too).  The fit finds the modes across the two runs (each
    impact's ringing carried on, the runs' impact times differ) and takes v_in and v_out
    from the flight model with them.  Tolerances: the modes' frequencies within 1 % (the
    search's scatter over seeds 3 and 4 and the 9-run campaigns was 0.3 %); e within 6 %
    (two runs of 50 impacts; the run means scatter by about 3 %; +3.9 % seen; +2.9 % over
    seeds 3-5 until 29 Nov 2026, -0.7 % once the plate's fundamental was searched on both
    runs together, +0.2 % with the dwells' forced amplitude held, half-widths 2.8-2.9 %)
    and its reported 95 % interval (two runs: Student t with one degree of
    freedom) covers the truth; no ringing flag."""
    plant, _, _, summary = _campaign(tmp_path, Chain(ring_in_velocity=True))
    assert not {"e_ratio_ringing_uncorrected", "e_ratio_ring_modes_one_run"} & set(
        summary["data_quality"])
    ratio = summary["fits"]["restitution_ratio"]
    (note,) = [n for n in ratio["notes"] if "ringing carried on" in n]
    assert "found across 2 runs" in note
    found = [float(x) for x in re.findall(r"([0-9.]+) Hz \(decay", note)]
    assert len(found) == 3
    for f_true, f in zip(Chain().ring_hz, sorted(found)):
        assert abs(f / f_true - 1) < 0.01, (found, note)
    assert abs(ratio["value"] / plant.e - 1) < 0.06, ratio
    assert abs(ratio["value"] - plant.e) <= 1.96 * ratio["stderr"], ratio
    assert ratio["n"] >= 80 and ratio["n_runs"] == 2

def test_heavily_damped_ringing_that_one_run_misses_is_searched_across_the_runs(tmp_path):
    """The same modes at 15 % of critical (decays 161, 276, 367 1/s: gone within two
    flights).  One run's own flight model finds them (a share of 24 % of each jump), the
    other's does not (the 171 Hz mode decays more slowly than that search allows), so a
    share from one run was taken off every ratio: e +16 to +20 % over seeds 3-5, with
    95 % intervals that missed.  Since 29 Nov 2026 a run whose model found no modes sends
    every ringing run's flights to the campaign's search (tails carried on), which
    alternates with the runs' fundamentals; the declared delay is checked against the
    flights' own impact instants, their disagreement in the interval: e +0.73, +0.70,
    +0.61 % over seeds 3-5 (-2.1 to -1.7 % with the search alone), each interval covering
    (half-widths 1.6-1.8 % of e); +0.47, +0.48, +0.43 % (half-widths 2.2-2.4 %) once the
    plate's fundamental was searched on both runs together, +0.42, +0.48, +0.40 % (2.3-2.7
    %) with the dwells' forced amplitude held (29 Nov, seventeenth session).
    Tolerance: 3 %,
    the issue's (a tolerance in reach of the search-alone figures, so that this checks the
    path, not the last refinement)."""
    plant, _, _, summary = _campaign(tmp_path, Chain(ring_in_velocity=True,
                                                     ring_zeta=(0.15,) * 3))
    assert not [f for f in summary["data_quality"] if "ringing" in f], summary["data_quality"]
    ratio = summary["fits"]["restitution_ratio"]
    (note,) = [n for n in ratio["notes"] if "ringing carried on" in n]
    assert "found across 2 runs" in note
    found = sorted(float(x) for x in re.findall(r"([0-9.]+) Hz \(decay", note))
    assert abs(found[0] / Chain().ring_hz[0] - 1) < 0.03, note
    assert abs(ratio["value"] / plant.e - 1) < 0.03, ratio
    assert abs(ratio["value"] - plant.e) <= 1.96 * ratio["stderr"], ratio


def test_ringing_modes_from_one_run_are_flagged(tmp_path):
    """A record of one run: the modes are searched in it alone, where their tails and the
    fundamental's free response can trade off (single 1.5 s ramps of this generator gave e
    -9.5 % and +9.8 %); the fit still corrects, but names it with a data-quality flag and a
    note.  On this single dwell e came out +4.3 %: within 10 % is asserted (the one-run
    range seen), so this checks the path, not the accuracy."""
    plant = Plant()
    path = tmp_path / "one.h5"
    write_campaign(path, plant, Chain(ring_in_velocity=True),
                   [{"run_id": "dwell_97", "protocol": "sine_dwell", "freq_hz": 97.0,
                     "levels": np.full(100, 1.3 * _grazing_ms2(plant, 97.0))}], seed=1)
    store = tmp_path / "one_store.h5"
    ingest([path], store, quiet=True)
    proc = run_command("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert "e_ratio_ring_modes_one_run" in summary["data_quality"]
    ratio = summary["fits"]["restitution_ratio"]
    assert any("found in one run" in n for n in ratio["notes"])
    assert any("one run only" in n for n in ratio["notes"])
    assert abs(ratio["value"] / plant.e - 1) < 0.10, ratio


def test_an_unphysical_e_from_the_ratios_keeps_the_ramp_corrected_fits(tmp_path):
    """The ramp replays (ramp-corrected grazing fit, zeta ramp) need an e only for their
    confirming impacts.  Local velocity fits read a ringing plate's tails (the higher modes
    at 2 % of critical in the vibrometer) and give e about 1.08 here; that value must not
    cost the campaign those fits (they were refused: "`e` must be in [0, 1]").  The
    replays then use e = 0.6 (the onset hardly depends on it), and the corrected gap
    keeps within 1 % of the truth (issue 15's target is 2 %; the rig's campaigns give
    -0.11 %)."""
    from rattle_lab.workflow import fit_store

    plant = Plant()
    runs = []
    for f in (93.0, 95.0, 97.0, 98.0):
        n = int(2.0 * f)
        g = _grazing_ms2(plant, f)
        runs.append({"run_id": f"up_{f:g}", "protocol": "amplitude_ramp_up", "freq_hz": f,
                     "levels": np.linspace(0.5 * g, 1.5 * g, n)})
        runs.append({"run_id": f"down_{f:g}", "protocol": "amplitude_ramp_down",
                     "freq_hz": f, "levels": np.linspace(1.5 * g, 0.3 * g, n)})
    write_campaign(tmp_path / "c.h5", plant, Chain(ring_in_velocity=True), runs, seed=3)
    ingest([tmp_path / "c.h5"], tmp_path / "s.h5", quiet=True)
    s = fit_store(tmp_path / "s.h5", detect={"velocity_model": "local"}, write=False,
                  quiet=True).summary
    assert s.fits.restitution_ratio.value > 1.0   # what the local fits read
    assert "grazing_ramp" not in s.not_fitted and "damping_ramp" not in s.not_fitted
    gap = s.fits.grazing_ramp.gap_m
    assert gap.value == pytest.approx(plant.gap_m, rel=0.01)
