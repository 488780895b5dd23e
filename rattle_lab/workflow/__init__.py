"""The one orchestrator: pipelines (their configuration, caching and provenance) and the demo.

``rattle-lab fit`` is the preset pipeline that ends at the fit's results; ``rattle-lab run``
runs any pipeline file; ``rattle-lab demo`` is simulate, ingest, fit and report.  The report
of a store is computed here (:func:`gather`, :func:`build_report_content`: the fit's bands,
the model pages' simulations) and drawn by :mod:`rattle_lab.report` (:func:`write_report`
does both).
"""

from typing import Any

from rattle_lab.workflow._fit import fit_store
from rattle_lab.workflow.pipeline import (STAGES, Pipeline, PipelineRun, detect_runs,
                                          load_pipeline_file, parse_pipeline, run_pipeline)

__all__ = ["STAGES", "Pipeline", "PipelineRun", "load_pipeline_file", "parse_pipeline",
           "run_pipeline", "detect_runs", "fit_store", "write_report", "build_report_content",
           "build_pages", "gather", "ReportData", "SECTIONS", "shock_lines"]

#: The report's names, imported on first use (they import matplotlib, which `rattle-lab fit`
#: does not need: its start-up pays only for what it runs).
_REPORT_NAMES = ("SECTIONS", "ReportData", "build_pages", "build_report_content", "gather",
                 "write_report", "shock_lines")


def __getattr__(name: str) -> Any:
    if name in _REPORT_NAMES:
        from rattle_lab.workflow import _report

        return getattr(_report, name)
    raise AttributeError(f"module 'rattle_lab.workflow' has no attribute {name!r}")
