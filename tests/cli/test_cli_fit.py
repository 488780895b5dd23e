"""``rattle-lab fit``: run the installed entry point on a small synthetic store.

The store is built from :func:`rattle_lab.rig._handbuilt.synthetic_campaign`
(ramp runs whose thresholds follow eq. 3.4 with the thesis values, a quiet dwell
run and a run without plate channels).  Its thresholds are quasi-static by
construction, so its pipeline asks for ``restitution_method = "quasi-static"``; the
ramp model is checked on the synthetic rig's default scene, whose thresholds come from
the exact dynamics.
"""

from __future__ import annotations

import json
import re

import h5py
import numpy as np
import pytest

from rattle_lab.rig._handbuilt import synthetic_campaign
from rattle_lab.exceptions import ParameterError
from rattle_lab.fit import load_pipeline
from rattle_lab.workflow import fit_store
from rattle_lab.store import ingest
from rattle_lab.records import write_record
from rattle_lab.store import StoreError
from rattle_lab.fit._results import read_results
from record_factory import run_cli, run_cli_on_terminal


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("fitcli")
    record, truth = synthetic_campaign(up_freq_hz=(85.0, 93.0, 95.5, 96.0, 96.5, 99.0, 106.0),
                                       down_freq_hz=(106.0, 112.0), duration_s=0.6)
    rec_path = write_record(d / "campaign.h5", record)
    store = d / "store.h5"
    ingest([rec_path], store, quiet=True)
    pipeline = d / "pipeline.toml"
    pipeline.write_text("[detect]\non = 12.0\n\n[fit]\nparticipation = 1.2\n"
                        "restitution_method = \"quasi-static\"\n\n[report]\nx = 1\n")
    return store, pipeline, truth


def test_cli_fit_json(campaign):
    store, pipeline, truth = campaign
    proc = run_cli("fit", str(store), "--pipeline", str(pipeline), "--json")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    out = json.loads(proc.stdout)
    g = out["fits"]["grazing"]
    assert g["gap_m"]["value"] == pytest.approx(truth.gap_m, rel=0.02)
    assert g["gap_m"]["unit"] == "m" and g["gap_m"]["stderr"] > 0
    assert g["f_s_hz"]["value"] == pytest.approx(truth.f_s_hz, rel=0.005)
    assert g["zeta"]["value"] == pytest.approx(truth.zeta, rel=0.10)
    assert out["fits"]["restitution_ratio"]["value"] == pytest.approx(truth.e, abs=0.01)
    down = out["fits"]["restitution_down"]
    assert down["value"] == pytest.approx(truth.e, abs=0.05)
    assert down["method"] == "quasi-static" and down["n"] == 2 and down["unit"] == "1"
    assert down["stderr"] > 0 and down["ci"][0] < down["value"] < down["ci"][1]
    assert "damping_ramp" not in out["fits"]     # only the ramp method refits zeta
    slope = truth.acoustics.gain_pa_per_m_s * truth.acoustics.peaks()[1]
    assert out["fits"]["spl_law_max"]["linear"]["slope"] == pytest.approx(slope, rel=0.03)
    assert out["skipped"] == [{"input_key": out["skipped"][0]["input_key"], "run_id": "base_only",
                               "reason": "no plate_velocity or plate_acceleration channel"}]
    quiet = [r for r in out["runs"] if r["run_id"] == "dwell_quiet"]
    assert quiet[0]["n_impacts"] == 0 and quiet[0]["pattern"] == "no impact"


def test_cli_fit_table_and_results_in_store(campaign):
    store, _, truth = campaign
    proc = run_cli("fit", str(store))
    assert proc.returncode == 0 and proc.stderr == ""
    assert "grazing.gap_m" in proc.stdout and "skipped" in proc.stdout
    assert "grazing.participation (fixed)" in proc.stdout
    # the default restitution method replays the ramps, and the table says so
    assert "damping_ramp.zeta (ramp replay)" in proc.stdout
    assert "restitution_down.e (ramp)" in proc.stdout
    res = read_results(store)
    assert res.provenance["function"] == "rattle_lab.workflow.fit_store"
    assert len(res.provenance["inputs"]) == 1
    assert set(res.thresholds) == {"freq_hz", "up_ms2", "down_ms2", "hysteresis_ms2", "up_se_ms2",
                                   "down_se_ms2"}
    key = next(k for k in res.runs if k[1] == "ramp_up_96p0")
    run = res.runs[key]
    assert run["status"] == "ok" and run["pattern"] == "1/1"
    np.testing.assert_allclose(run["t_s"], truth.impacts["ramp_up_96p0"][0], atol=1 / 12800)
    # per-impact peak levels, dB re 20 uPa
    np.testing.assert_allclose(run["spl_max_db"], 20 * np.log10(run["p_max_pa"] / 20e-6))
    np.testing.assert_allclose(run["spl_first_db"], 20 * np.log10(run["p_first_pa"] / 20e-6))
    skipped = next(v for k, v in res.runs.items() if k[1] == "base_only")
    assert skipped["status"] == "skipped" and "t_s" not in skipped
    with h5py.File(store, "r") as fh:     # the records are still there, untouched
        assert list(fh["records"]) == [key[0]]


def test_fit_store_library_call_matches(campaign):
    store, _, _ = campaign
    result = fit_store(store, fit={"participation": 1.2}, write=False)
    assert result.summary.n_runs == 11 and result.summary.n_ok == 10


def test_cli_bad_store_exit_2(tmp_path):
    proc = run_cli("fit", str(tmp_path / "missing.h5"), "--json")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "no such store" in proc.stderr


def test_cli_bad_pipeline_exit_2(campaign, tmp_path):
    store, _, _ = campaign
    bad = tmp_path / "bad.toml"
    bad.write_text("[detect]\nbogus = 1\n")
    proc = run_cli("fit", str(store), "--pipeline", str(bad))
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert "unknown key 'bogus'" in proc.stderr


def test_load_pipeline_errors(tmp_path):
    assert load_pipeline(None) == {"detect": {}, "fit": {}}
    with pytest.raises(ParameterError, match=r"cannot read pipeline TOML"):
        load_pipeline(tmp_path / "nope.toml")
    f = tmp_path / "p.toml"
    f.write_text("detect = 3\n")
    with pytest.raises(ParameterError, match=r"\[detect\] must be a table"):
        load_pipeline(f)
    f.write_text("[fit]\nzeta = 3\n")
    with pytest.raises(ParameterError, match=r"\[fit\]: unknown key 'zeta'"):
        load_pipeline(f)
    f.write_text("[fit]\nrestitution_method = \"fast\"\n")
    with pytest.raises(ParameterError, match=r"\[fit\]: `restitution_method` must be one of "
                                             r"\('ramp', 'quasi-static'\), was 'fast'"):
        load_pipeline(f)
    for bad in ("0", "1.5", "true"):
        f.write_text(f"[fit]\nlevel_hold_periods = {bad}\n")
        with pytest.raises(ParameterError, match=r"`level_hold_periods` must be an integer >= 1"):
            load_pipeline(f)
    f.write_text("[fit]\nrestitution_method = \"ramp\"\nlevel_hold_periods = 2\n")
    assert load_pipeline(f)["fit"] == {"restitution_method": "ramp", "level_hold_periods": 2}


def test_fit_store_errors(campaign, tmp_path):
    store, _, _ = campaign
    with pytest.raises(ParameterError, match=r"unknown fit parameter 'bogus'"):
        fit_store(store, fit={"bogus": 1}, write=False)
    with pytest.raises(ParameterError, match=r"`restitution_method` must be one of"):
        fit_store(store, fit={"restitution_method": "exact"}, write=False)
    with pytest.raises(StoreError, match=r"no such store"):
        read_results(tmp_path / "none.h5")
    empty = tmp_path / "empty.h5"
    h5py.File(empty, "w").close()
    with pytest.raises(StoreError, match=r"/results: no results"):
        read_results(empty)


@pytest.fixture(scope="module")
def rig_store(synthetic_campaign_record, tmp_path_factory):
    """The default scene (the rig's exact dynamics, 3 s ramps) ingested into a store."""
    store = tmp_path_factory.mktemp("rigfit") / "store.h5"
    ingest([synthetic_campaign_record], store, quiet=True)
    return store


def test_fit_store_ramp_model_on_the_default_scene(rig_store, synthetic_campaign_record):
    """The ramp model on the rig's ramps (3 s at 95-98 Hz, 6 s at 100 Hz; the level changes
    every forcing period, the fit's default ``level_hold_periods = 1``).

    Truth: zeta = 0.0085, e = 0.6.  The grazing fit reads the ramp lag as 7 % more damping;
    the ramp model recovers zeta to 1 %.  e comes from the downward ramps above resonance:
    the 97 and 98 Hz ones carry little information on e (the disappearance moves by less
    than a cycle's level change between e = 0.3 and 0.6), the 100 Hz one pins it; the
    demo's run gives 0.589 +- 0.024, and 3 standard errors (or 0.06) is the tolerance."""
    fit = fit_store(rig_store, fit={"participation": 1.2442}, write=True)
    fits = fit.summary.fits
    assert fits.grazing.zeta.value == pytest.approx(0.0085, rel=0.10)
    damping = fits.damping_ramp
    assert damping.value == pytest.approx(0.0085, rel=0.01) and damping.n == 5
    assert abs(damping.value / 0.0085 - 1) < abs(fits.grazing.zeta.value / 0.0085 - 1)
    down = fits.restitution_down
    assert down.method == "ramp" and down.run_ids == ("down_097", "down_098", "down_100")
    assert down.zeta_used == damping.value and down.stderr_from_zeta >= 0
    assert down.ci_low < 0.6 < down.ci_high and 0 < down.stderr < 0.05
    assert abs(down.value - 0.6) < min(3 * down.stderr, 0.06)
    assert "restitution_down" not in fit.summary.not_fitted
    # issue 15: the ramp lag biases eq. (3.4)'s gap too (-0.3 %, outside its own interval);
    # the ramp-corrected fit removes each threshold's replayed lag: its intervals hold the
    # truth (1.3 mm, 96 Hz, 0.0085) and it is closer than eq. (3.4) on the raw levels
    # (only gap / participation enters eq. 3.4: with the thesis's 1.2442 passed in, the gap's
    # truth is 1.3 mm x 1.2442 / the rig's own participation)
    with h5py.File(synthetic_campaign_record, "r") as fh:
        gap_truth = 1.3e-3 * 1.2442 / float(fh["rig"].attrs["modal_participation"])
    ramp = fits.grazing_ramp
    for name, truth in (("gap_m", gap_truth), ("f_s_hz", 96.0), ("zeta", 0.0085)):
        est = getattr(ramp, name)
        assert est.ci_low <= truth <= est.ci_high, name
    gap_qs = fits.grazing.gap_m
    assert abs(ramp.gap_m.value / gap_truth - 1) < abs(gap_qs.value / gap_truth - 1)
    assert gap_qs.bias_rel == pytest.approx(gap_qs.value / ramp.gap_m.value - 1)
    assert "the ramp lag bends eq. (3.4): gap is -" in gap_qs.bias_note
    assert down.zeta_used == pytest.approx(ramp.zeta.value, rel=0.01)
    res = read_results(rig_store)
    assert res.summary["fits"]["restitution_down"]["method"] == "ramp"
    run = next(v for k, v in res.runs.items() if k[1] == "down_098")
    assert run["threshold_censored"] == 0 and run["threshold_ramp_duration_s"] == 3.0
    assert run["threshold_ramp_start_ms2"] == pytest.approx(26.0, abs=0.1)
    assert run["threshold_ramp_end_ms2"] == pytest.approx(2.0, abs=0.1)


@pytest.fixture(scope="module")
def progress_store(tmp_path_factory):
    """The smallest hand-built campaign whose report still has its model section (and so its
    "model sweeps" bar): four upward ramps (the grazing fit's minimum) and one downward, no
    extra runs.  Half the fit and report time of :func:`campaign`'s store."""
    d = tmp_path_factory.mktemp("progress")
    record, _ = synthetic_campaign(up_freq_hz=(93.0, 95.5, 96.5, 99.0), down_freq_hz=(106.0,),
                                   duration_s=0.6, extra_runs=False)
    store = d / "store.h5"
    ingest([write_record(d / "campaign.h5", record)], store, quiet=True)
    return store


def test_fit_and_report_draw_progress_bars_on_a_terminal_only(progress_store, tmp_path):
    # (piped, without a terminal, no bar is drawn: test_cli_fit_table_and_results_in_store
    # runs the same `rattle-lab fit STORE` piped and asserts that its stderr is empty.  The
    # report's own "model sweeps" bar on a terminal is asserted by
    # tests/cli/test_cli_run.py::test_demo_on_a_terminal_shows_progress_bars, whose demo
    # draws the report; here --quiet must silence it on a terminal too.)
    store = progress_store
    rc, text = run_cli_on_terminal("fit", str(store))
    assert rc == 0, text[-2000:]
    assert re.search(r"detect: +\d+%\|", text)          # tqdm: "detect:  40%|"
    assert "grazing.gap_m" in text
    rc, text = run_cli_on_terminal("report", str(store), "-o", str(tmp_path / "q.pdf"), "--quiet")
    assert rc == 0 and "%|" not in text and text.strip().endswith("q.pdf")
