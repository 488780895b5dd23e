"""Pipelines (:mod:`rattle_lab.workflow.pipeline`): lazy DAG, content-hash cache, Dask scale-out.

Stage executions are counted through :attr:`PipelineRun.executed`.
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import pypdf
from conftest import RATTLE_LAB, SMALL_CAMPAIGN

import rattle_lab.workflow.pipeline as pipeline_module
from rattle_lab.exceptions import ParameterError
from rattle_lab.workflow import fit_store
from rattle_lab.workflow.pipeline import (Pipeline, code_fingerprint, load_pipeline_file, needed_stages,
                                 parse_pipeline, read_detections, run_pipeline)
from rattle_lab.fit._results import read_results

PIPELINES = Path(__file__).resolve().parents[2] / "pipelines"
MAPPINGS = Path(__file__).resolve().parents[2] / "data_schema" / "mappings"


def _pipe(outputs: list[str], **tables: dict[str, Any]) -> Pipeline:
    return parse_pipeline({"pipeline": {"name": "t", "outputs": outputs}, **tables}, "t.toml")


def test_shipped_pipelines_parse() -> None:
    names = {p.stem: load_pipeline_file(p) for p in sorted(PIPELINES.glob("*.toml"))}
    assert set(names) == {"threshold_campaign", "spl_study", "full_campaign"}
    assert names["threshold_campaign"].outputs == ("results",)
    assert names["spl_study"].params["report"]["model"] is False
    assert names["full_campaign"].outputs == ("store", "results", "report")


@pytest.mark.parametrize(("doc", "match"), [
    ({"pipeline": {"outputs": ["pdf"]}}, "unknown output 'pdf'"),
    ({"pipeline": {"outputs": []}}, "at least one output"),
    ({"plot": {}}, r"unknown table \[plot\]"),
    ({"detect": {"onn": 1.0}}, r"\[detect\]: unknown key 'onn'"),
    ({"fit": {"gap": 1.0}}, r"\[fit\]: unknown key 'gap'"),
    ({"thresholds": {"n_confirm": 3}}, "n_confirm belongs to"),
    ({"simulate": {"seed": 1.5}}, "seed must be an integer"),
    ({"report": {"model": "yes"}}, "model must be true or false"),
    ({"pipeline": {"name": "a/b"}}, "plain file stem"),
])
def test_bad_pipeline_files(doc: dict[str, Any], match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        parse_pipeline(doc, "bad.toml")


def test_unreadable_pipeline_file(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="cannot read pipeline TOML"):
        load_pipeline_file(tmp_path / "absent.toml")


def test_needed_stages_are_lazy() -> None:
    assert needed_stages(["store"], scenes=False) == ["ingest"]
    assert needed_stages(["store"], scenes=True) == ["simulate", "ingest"]
    assert needed_stages(["thresholds"], scenes=False) == ["ingest", "detect", "thresholds"]
    assert needed_stages(["report"], scenes=False) == ["ingest", "detect", "thresholds", "fit",
                                                       "report"]


@pytest.mark.slow  # > 8 s (measured under load)
def test_cache_and_exact_reruns_and_outside_fits_are_noticed(small_campaign_record: Path,
                                                             tmp_path: Path) -> None:
    rec = [small_campaign_record]
    store = tmp_path / "s.h5"
    base = {"detect": {"on": 12.0}, "fit": {"outlier_k": 5.0}}
    first = run_pipeline(_pipe(["results"], **base), rec, store=store, out_dir=tmp_path)
    assert first.executed == ["ingest", "detect", "thresholds", "fit"]
    # the same results as `rattle-lab fit` with these parameters
    direct = tmp_path / "direct.h5"
    shutil.copyfile(store, direct)
    fit_store(direct, detect=base["detect"], fit=base["fit"])
    a, b = read_results(store), read_results(direct)
    assert json.dumps(a.summary, sort_keys=True) == json.dumps(b.summary, sort_keys=True)
    for name in ("freq_hz", "up_ms2", "down_ms2"):
        np.testing.assert_array_equal(a.thresholds[name], b.thresholds[name])
    again = run_pipeline(_pipe(["results"], **base), rec, store=store, out_dir=tmp_path)
    assert again.executed == [] and again.cached == ["ingest", "detect", "thresholds", "fit"]
    # a fit parameter reruns the fit only
    fit_changed = run_pipeline(_pipe(["results"], detect={"on": 12.0}, fit={"outlier_k": 4.0}),
                               rec, store=store, out_dir=tmp_path)
    assert fit_changed.executed == ["fit"]
    assert read_results(store).provenance["parameters"]["fit"]["outlier_k"] == 4.0
    # a detection parameter reruns detection and everything downstream of it
    det_changed = run_pipeline(_pipe(["results"], detect={"on": 11.0}, fit={"outlier_k": 4.0}),
                               rec, store=store, out_dir=tmp_path)
    assert det_changed.executed == ["detect", "thresholds", "fit"]
    # asking for less runs less; asking for the report adds only the report
    assert run_pipeline(_pipe(["store"]), rec, store=store, out_dir=tmp_path).executed == []
    rep = run_pipeline(_pipe(["report"], detect={"on": 11.0}, fit={"outlier_k": 4.0},
                             report={"model": False}), rec, store=store, out_dir=tmp_path)
    assert rep.executed == ["report"] and rep.outputs["report"] == tmp_path / "t.pdf"
    assert len(pypdf.PdfReader(tmp_path / "t.pdf").pages) == 9  # two summary pages, acoustics 2
    # a lost output is remade even with an unchanged key
    (tmp_path / "t.pdf").unlink()
    rep2 = run_pipeline(_pipe(["report"], detect={"on": 11.0}, fit={"outlier_k": 4.0},
                              report={"model": False}), rec, store=store, out_dir=tmp_path)
    assert rep2.executed == ["report"]
    # [report] model = true: the report only (one more page pair: the model predictions)
    with_model = run_pipeline(_pipe(["report"], detect={"on": 11.0}, fit={"outlier_k": 4.0}),
                              rec, store=store, out_dir=tmp_path)
    assert with_model.executed == ["report"]
    assert len(pypdf.PdfReader(tmp_path / "t.pdf").pages) == 11
    # `rattle-lab fit` run on the store by hand replaces /results: the fit stage is stale
    fit_store(store, detect={"on": 11.0}, fit={"outlier_k": 3.0})
    after = run_pipeline(_pipe(["results"], detect={"on": 11.0}, fit={"outlier_k": 4.0}),
                         rec, store=store, out_dir=tmp_path)
    assert after.executed == ["fit"] and after.cached == ["ingest", "detect", "thresholds"]
    assert read_results(store).provenance["via"] == "rattle_lab.workflow.pipeline"


@pytest.mark.slow  # > 8 s (measured under load)
def test_shipped_pipelines_run(small_campaign_record: Path, tmp_path: Path) -> None:
    rec = [small_campaign_record]
    thr = run_pipeline(load_pipeline_file(PIPELINES / "threshold_campaign.toml"), rec,
                       out_dir=tmp_path)
    assert thr.executed == ["ingest", "detect", "thresholds", "fit"]  # no report asked for
    assert thr.outputs == {"results": tmp_path / "threshold_campaign.h5"}
    fits = read_results(thr.store).summary["fits"]
    assert abs(fits["grazing"]["f_s_hz"]["value"] - 96.0) < 0.1  # the scene's truth: 96 Hz
    spl = run_pipeline(load_pipeline_file(PIPELINES / "spl_study.toml"), rec, out_dir=tmp_path)
    assert spl.executed == ["ingest", "detect", "thresholds", "fit", "report"]
    assert read_results(spl.store).summary["fits"]["spl_law_first"]["linear"]["r2"] > 0.9
    text = "".join(pg.extract_text() for pg in pypdf.PdfReader(spl.outputs["report"]).pages)
    assert "SPL first peak: slope" in text and "not requested (model=False)" in text
    full_pipe = load_pipeline_file(PIPELINES / "full_campaign.toml")
    scene = str(SMALL_CAMPAIGN)  # a scene input: simulated, then the whole chain
    full = run_pipeline(full_pipe, [scene], out_dir=tmp_path)
    assert full.executed == ["simulate", "ingest", "detect", "thresholds", "fit", "report"]
    assert set(full.outputs) == {"store", "results", "report"}
    reader = pypdf.PdfReader(full.outputs["report"])
    # summary 2 pages, rig, thresholds, patterns, waveforms, SPL, acoustics 2, 2 model pages
    assert len(reader.pages) == 11 and "model onset" in reader.pages[-1].extract_text()
    again = run_pipeline(full_pipe, [scene], out_dir=tmp_path)
    assert again.executed == []
    assert again.cached == ["simulate:small_campaign.h5", "ingest", "detect", "thresholds", "fit",
                            "report"]


def test_scene_input_is_simulated_once(tmp_path: Path) -> None:
    pipe = _pipe(["store"])
    scene = [str(SMALL_CAMPAIGN)]  # a scene file (a shipped scene's name is resolved as in
    # test_input_errors and the CLI tests)
    first = run_pipeline(pipe, scene, out_dir=tmp_path)
    assert first.executed == ["simulate", "ingest"]
    assert (tmp_path / "small_campaign.h5").is_file() and first.store == tmp_path / "t.h5"
    assert run_pipeline(pipe, scene, out_dir=tmp_path).executed == []
    seeded = run_pipeline(_pipe(["store"], simulate={"seed": 5}), scene, out_dir=tmp_path)
    assert seeded.executed == ["simulate", "ingest"]  # same run ids, new data: store rebuilt
    from rattle_lab.store import read_catalogue

    assert read_catalogue(seeded.store, level="runs")["input_key"].nunique() == 1


def test_input_errors(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="no such file"):
        run_pipeline(_pipe(["store"]), [tmp_path / "absent.h5"], out_dir=tmp_path)
    with pytest.raises(ParameterError, match="at least one"):
        run_pipeline(_pipe(["store"]), [], out_dir=tmp_path)
    # a missing out_dir is created (issue 16: `--out build/` in a fresh clone); a file is refused
    (tmp_path / "afile").write_text("x")
    with pytest.raises(ParameterError, match="is not a directory"):
        run_pipeline(_pipe(["store"]), ["default"], out_dir=tmp_path / "afile")


def _as_plain(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        return {f.name: _as_plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (tuple, list)):
        return [_as_plain(x) for x in obj]
    if isinstance(obj, dict):  # open mappings (a run's acoustics) may hold NaN too
        return {k: _as_plain(v) for k, v in obj.items()}
    if isinstance(obj, np.ndarray):
        return ("array", obj.dtype.str, [_as_plain(x) for x in obj.tolist()])
    if isinstance(obj, float) and np.isnan(obj):
        return "nan"
    return obj


# The Dask tests run rattle_lab in several processes: this one, the workers and the CLI.  Each
# imports the sources when it starts, so a source tree edited while the suite runs would give
# them different code, which the pipeline rightly refuses (each task checks the fingerprint).
# They therefore all run one snapshot of the sources, taken when the cluster starts.

@pytest.fixture(scope="module")
def pinned_sources(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of the rattle_lab package: PYTHONPATH for every process of the Dask tests."""
    root = tmp_path_factory.mktemp("pinned")
    # with its __pycache__ folders: numba's cache of the compiled kernels lies there, and is
    # valid for the copy (numba checks the source file's time stamp and size, which copytree
    # keeps), so the workers and CLI processes do not compile every kernel again
    shutil.copytree(Path(pipeline_module.__file__).parents[1], root / "rattle_lab")
    return root


@pytest.fixture(scope="module")
def cluster(pinned_sources: Path) -> Any:
    """A real ``dask.distributed`` LocalCluster of two worker processes (running the snapshot)."""
    distributed = pytest.importorskip("distributed")
    with pytest.MonkeyPatch.context() as mp:
        # spawned workers take this process's sys.path; rattle_lab, already imported here,
        # is not affected
        mp.syspath_prepend(str(pinned_sources))
        local = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                         dashboard_address=None)
    with local, distributed.Client(local) as client:
        yield client


def _pinned_cli(pinned: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    env["PYTHONPATH"] = str(pinned)
    return subprocess.run([str(RATTLE_LAB), *args],
                          capture_output=True, text=True, env=env, timeout=300, cwd=pinned)


@pytest.mark.slow  # > 8 s (measured under load)
def test_dask_local_cluster_equals_serial(small_campaign_record: Path, tmp_path: Path,
                                          cluster: Any, pinned_sources: Path) -> None:
    workers = set(cluster.run(code_fingerprint).values())
    probe = subprocess.run([sys.executable, "-c", "import rattle_lab.workflow.pipeline as p; "
                            "print(p.__file__, p.code_fingerprint())"], capture_output=True,
                           text=True, env={**os.environ, "PYTHONPATH": str(pinned_sources)},
                           cwd=tmp_path, check=True)  # not the checkout (first on sys.path)
    where, fingerprint = probe.stdout.split()
    assert Path(where).is_relative_to(pinned_sources) and workers == {fingerprint}
    pipe = tmp_path / "detect_only.toml"
    pipe.write_text('[pipeline]\nname = "det"\noutputs = ["detections"]\n')
    args = ("run", str(pipe), str(small_campaign_record), "--out", str(tmp_path))
    serial = _pinned_cli(pinned_sources, *args, "--store", str(tmp_path / "serial.h5"))
    par = _pinned_cli(pinned_sources, *args, "--store", str(tmp_path / "dask.h5"),
                      "--scheduler", cluster.scheduler.address)
    for proc in (serial, par):
        assert proc.returncode == 0, proc.stderr
        assert "detect: done" in proc.stderr and proc.stdout.startswith("detections\t")
    a, b = read_detections(tmp_path / "serial.h5"), read_detections(tmp_path / "dask.h5")
    assert len(a) == 11  # every run of the small campaign
    assert _diff(_as_plain(a), _as_plain(b)) == []


def test_the_fingerprint_is_taken_on_first_use_only() -> None:
    # importing the module reads no source file (issue 25); the first call hashes them and
    # later calls return that value without hashing again (the digest function is gone)
    code = ("import rattle_lab.workflow.pipeline as p; assert p._FINGERPRINT is None; "
            "f = p.code_fingerprint(); p._source_digest = None; "
            "assert p.code_fingerprint() == f; print(f)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == code_fingerprint()   # the same sources as this process


def _set_fingerprint(value: str) -> str:
    """Run on a worker: pretend it runs other code; return the fingerprint it had."""
    old = pipeline_module.code_fingerprint()   # taken on first use
    pipeline_module._FINGERPRINT = value
    return old


def test_workers_with_other_code_are_refused(small_campaign_record: Path, tmp_path: Path,
                                             cluster: Any) -> None:
    # e.g. another rattle_lab installed on the cluster, or sources edited after this process
    # imported them: the results would mix code versions, so the stage fails instead
    old = cluster.run(_set_fingerprint, "0.0.0+0000000000000000")
    assert "0.0.0+0000000000000000" not in old.values()
    try:
        with pytest.raises(ParameterError, match=r"a worker runs other rattle_lab code "
                                                 r"\(0\.0\.0\+0+\) than the caller"):
            run_pipeline(_pipe(["detections"]), [small_campaign_record],
                         store=tmp_path / "s.h5", out_dir=tmp_path,
                         scheduler=cluster.scheduler.address)
    finally:
        for address, value in old.items():
            cluster.run(_set_fingerprint, value, workers=[address])
    assert cluster.run(code_fingerprint) == old


def test_unreachable_scheduler_is_a_parameter_error(small_campaign_record: Path,
                                                    tmp_path: Path,
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("distributed")
    monkeypatch.setattr(pipeline_module, "CONNECT_TIMEOUT_S", 1)
    with pytest.raises(ParameterError, match=r"`scheduler` 'tcp://127\.0\.0\.1:9': cannot "
                                             r"connect"):
        run_pipeline(_pipe(["detections"]), [small_campaign_record],
                     store=tmp_path / "s.h5", out_dir=tmp_path, scheduler="tcp://127.0.0.1:9")
    with pytest.raises(ParameterError, match="`scheduler` must be an address"):
        run_pipeline(_pipe(["detections"]), [small_campaign_record],
                     store=tmp_path / "s.h5", out_dir=tmp_path, scheduler=" ")


def _diff(a: Any, b: Any, path: str = "") -> list[str]:
    if isinstance(a, dict):
        return [d for k in a for d in _diff(a[k], b.get(k), f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _diff(x, y, f"{path}[{i}]")]
    return [] if a == b else [f"{path}: {str(a)[:200]} != {str(b)[:200]}"]


def test_pipeline_fit_stage_equals_fit_store_with_chain_flags_and_shocks(tmp_path: Path) -> None:
    # One set of fits for both orchestrators (rattle_lab.fit.fit_runs): a store whose records
    # carry a measurement-chain flag (a v1 velocity channel that declares no measurand) and a
    # transient run (a hammer hit, cause and response) must give the pipeline's fit stage
    # exactly the summary of `rattle-lab fit`, flags and shocks included.
    from record_factory import write as write_factory_record

    from rattle_lab.detect.thresholds import tabulate_thresholds
    from rattle_lab.records import UncalibratedWarning
    from rattle_lab.store import ingest, read_catalogue

    # the hit in plain numpy (not the rig): a 0.3 ms half-sine force of 50 N at 1 ms and a
    # response ringing at 800 Hz from 50 us later, 25.6 kHz, a little noise on both
    fs = 25600.0
    t = np.arange(4096) / fs
    rng = np.random.default_rng(5)
    pulse = (t >= 1e-3) & (t < 1.3e-3)
    force = np.where(pulse, 50.0 * np.sin(np.pi * (t - 1e-3) / 0.3e-3), 0.0)
    tr = np.clip(t - 1.05e-3, 0.0, None)
    resp = np.where(t >= 1.05e-3, 30.0 * np.exp(-200.0 * tr) * np.sin(2 * np.pi * 800.0 * tr), 0.0)
    hit = tmp_path / "hit.npy"
    np.save(hit, np.vstack([t, force + 0.05 * rng.standard_normal(t.size),
                            resp + 0.02 * rng.standard_normal(t.size)]))
    store = tmp_path / "s.h5"
    ingest([write_factory_record(tmp_path)], store, quiet=True)
    with pytest.warns(UncalibratedWarning, match="assumed by the mapping"):
        ingest([hit], store, mapping=MAPPINGS / "hammer_npy.toml", quiet=True)
    via_pipeline = tmp_path / "p.h5"
    shutil.copyfile(store, via_pipeline)

    direct = fit_store(store, detect={}, fit={})
    assert any("measurand" in f for f in direct.summary.data_quality)
    (shock,) = direct.summary.transients
    assert [c["channel"] for c in shock.channels] == ["force", "response"]
    assert shock.channels[0]["onset_s"] == pytest.approx(1e-3, abs=2 / fs)

    pipe = _pipe(["results"])
    cat = read_catalogue(via_pipeline, level="runs")
    runs = [pipeline_module.detect_run(str(via_pipeline), k, r, pipe.params["detect"],
                                       pipe.params["fit"])
            for k, r in zip(cat["input_key"], cat["run_id"])]
    curve = tabulate_thresholds([r.threshold for r in runs if r.threshold is not None])
    pipeline_module._fit_and_write(via_pipeline, runs, curve, pipe)
    a, b = read_results(store).summary, read_results(via_pipeline).summary
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def test_a_product_cached_by_other_code_is_a_clear_error(tmp_path: Path) -> None:
    # A store cached by an older rattle_lab names classes that have since moved
    # (rattle_lab.results:RunResult); reading it says so instead of an ImportError.
    import h5py

    from rattle_lab.exceptions import DataError
    from rattle_lab.store import read_cached

    store = tmp_path / "old.h5"
    from rattle_lab.store import STORE_FORMAT, STORE_VERSION

    with h5py.File(store, "w") as fh:
        fh.attrs.update({"store_format": STORE_FORMAT, "store_version": STORE_VERSION})
        g = fh.create_group("pipeline_cache/thresholds")
        g.attrs["__class__"] = "rattle_lab.results:ThresholdCurve"
    with pytest.raises(DataError, match=r"rattle_lab.results:ThresholdCurve does not exist in "
                                        r"this rattle_lab .*run the stage again"):
        read_cached(store, "thresholds")
    # a moved class also re-keys the cached stages (3: ImpactLog gained velocity_note; 4: its
    # velocity offset, ringing share and ringing ratio; 5: its ring_modes; 6, 7: the channel
    # timing and measurand fields of issue 28; 8: velocity_delay_method and _note; 9: the
    # parameters' ring_fundamental; 10: the identified decoder, identify_decoder; 11: the
    # contact pulse's rule and the sound windows' guard, which change cached results; 12: the
    # flight model's ringing weights at their fixed point, likewise)
    assert pipeline_module.CACHE_FORMAT == 12


def _same(a: Any, b: Any) -> bool:
    """Equal to the last bit, through dataclasses, mappings, sequences and arrays."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        return type(a) is type(b) and all(_same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and bool(
            np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(map(_same, a, b))
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True
    return bool(a == b)


def test_a_pass_with_another_velocity_model_reuses_what_the_impact_times_give(
        small_campaign_record: Path) -> None:
    # issue 29: the campaign's ringing passes detect the runs again with another velocity
    # model; the sound, levels, acoustics, pattern and threshold follow from the impact
    # times alone and are taken from the first pass where the times are the same, bit for bit
    from rattle_lab.detect import analyse_run
    from rattle_lab.records import read

    rec = read(small_campaign_record)
    run = next(r for r in rec.runs if r.protocol == "amplitude_ramp_up")
    flights = {"velocity_model": "flights"}

    def analyse(detect: dict[str, Any], reuse: Any = None) -> Any:
        return analyse_run("k", run, detect=detect, fit={}, mic_distance_m=rec.rig.mic_distance_m,
                           reuse=reuse)

    first, fresh = analyse({}), analyse(flights)
    assert first.threshold is not None and first.acoustics is not None and first.peaks is not None
    assert np.array_equal(first.impacts.t_s, fresh.impacts.t_s)
    assert not _same(first.impacts, fresh.impacts)    # the velocities differ: a real second pass
    reused = analyse(flights, reuse=first)
    assert reused.acoustics is first.acoustics       # taken, not computed again ...
    assert _same(reused, fresh)                      # ... and the same as computed again
    # what a cluster's task gets (no sound, no samples) and the client puts back
    thin = pipeline_module._recognisable(first)
    assert thin.acoustics is None and thin.impacts.ringing_problem is None
    assert _same(pipeline_module._restored(first, analyse(flights, reuse=thin)), fresh)
    # impacts at other times: nothing is taken
    moved = dataclasses.replace(first, impacts=dataclasses.replace(
        first.impacts, t_s=first.impacts.t_s + 1e-4))
    again = analyse(flights, reuse=moved)
    assert again.acoustics is not first.acoustics and _same(again, fresh)
    assert _same(pipeline_module._restored(moved, again), fresh)
