"""Results of ``rattle-lab fit``: the frozen result classes.

Their place in the store (``/results``), :func:`write_results` and
:func:`read_results` belong to :mod:`rattle_lab.store` and are re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rattle_lab.detect import RunResult  # (moved to detect, issue 29; old caches name it here)
from rattle_lab.store import (RESULTS_VERSION, StoredResults, read_results,  # noqa: F401
                              write_results)
from rattle_lab.detect.thresholds import ThresholdCurve
from ._summary import FitSummary


@dataclass(frozen=True)
class StoreFit:
    """Everything ``rattle-lab fit`` derives from a store.

    Attributes
    ----------
    runs : tuple of RunResult
    thresholds : ThresholdCurve
    summary : FitSummary
        The fits with units and uncertainties, run counts, skipped runs
        (:meth:`FitSummary.to_dict` is what ``/results`` stores and ``--json`` prints).
    provenance : dict
        Function, parameters, package version and the inputs' SHA-256.
    """

    runs: tuple[RunResult, ...]
    thresholds: ThresholdCurve
    summary: FitSummary
    provenance: dict[str, Any]


__all__ = ["RunResult", "StoreFit", "StoredResults", "read_results", "write_results"]
