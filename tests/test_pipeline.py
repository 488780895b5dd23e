"""Pipelines (:mod:`rattle_lab.pipeline`): lazy DAG, content-hash cache, Dask scale-out.

Stage executions are counted through :attr:`PipelineRun.executed`.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rattle_lab.exceptions import ParameterError
from rattle_lab.fit import fit_store
from rattle_lab.pipeline import (Pipeline, load_pipeline_file, needed_stages, parse_pipeline,
                                 read_detections, run_pipeline)
from rattle_lab.results import read_results

PIPELINES = Path(__file__).resolve().parents[1] / "pipelines"


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


def test_cache_and_exact_reruns(synthetic_campaign_record: Path, tmp_path: Path) -> None:
    rec = [synthetic_campaign_record]
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
    assert (tmp_path / "t.pdf").is_file()
    # a lost output is remade even with an unchanged key
    (tmp_path / "t.pdf").unlink()
    rep2 = run_pipeline(_pipe(["report"], detect={"on": 11.0}, fit={"outlier_k": 4.0},
                              report={"model": False}), rec, store=store, out_dir=tmp_path)
    assert rep2.executed == ["report"]


def test_scene_input_is_simulated_once(tmp_path: Path) -> None:
    pipe = _pipe(["store"])
    first = run_pipeline(pipe, ["default"], out_dir=tmp_path)
    assert first.executed == ["simulate", "ingest"]
    assert (tmp_path / "default.h5").is_file() and first.store == tmp_path / "t.h5"
    assert run_pipeline(pipe, ["default"], out_dir=tmp_path).executed == []
    seeded = run_pipeline(_pipe(["store"], simulate={"seed": 5}), ["default"], out_dir=tmp_path)
    assert seeded.executed == ["simulate", "ingest"]  # same run ids, new data: store rebuilt
    from rattle_lab.ingest import read_catalogue

    assert read_catalogue(seeded.store, level="runs")["input_key"].nunique() == 1


def test_input_errors(tmp_path: Path) -> None:
    with pytest.raises(ParameterError, match="no such file"):
        run_pipeline(_pipe(["store"]), [tmp_path / "absent.h5"], out_dir=tmp_path)
    with pytest.raises(ParameterError, match="at least one"):
        run_pipeline(_pipe(["store"]), [], out_dir=tmp_path)
    with pytest.raises(ParameterError, match="is not a directory"):
        run_pipeline(_pipe(["store"]), ["default"], out_dir=tmp_path / "nodir")


def _as_plain(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        return {f.name: _as_plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, (tuple, list)):
        return [_as_plain(x) for x in obj]
    if isinstance(obj, np.ndarray):
        return ("array", obj.dtype.str, [_as_plain(x) for x in obj.tolist()])
    if isinstance(obj, float) and np.isnan(obj):
        return "nan"
    return obj


def test_dask_local_cluster_equals_serial(synthetic_campaign_record: Path, tmp_path: Path
                                         ) -> None:
    distributed = pytest.importorskip("distributed")
    pipe = _pipe(["detections"])
    serial = run_pipeline(pipe, [synthetic_campaign_record], store=tmp_path / "serial.h5",
                          out_dir=tmp_path)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        par = run_pipeline(pipe, [synthetic_campaign_record], store=tmp_path / "dask.h5",
                           out_dir=tmp_path, scheduler=client.scheduler.address)
    assert serial.executed == par.executed == ["ingest", "detect"]
    a, b = read_detections(tmp_path / "serial.h5"), read_detections(tmp_path / "dask.h5")
    assert len(a) == 10
    assert _diff(_as_plain(a), _as_plain(b)) == []


def _diff(a: Any, b: Any, path: str = "") -> list[str]:
    if isinstance(a, dict):
        return [d for k in a for d in _diff(a[k], b.get(k), f"{path}.{k}")]
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _diff(x, y, f"{path}[{i}]")]
    return [] if a == b else [f"{path}: {str(a)[:200]} != {str(b)[:200]}"]
