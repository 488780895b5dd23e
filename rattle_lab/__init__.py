"""rattle_lab: rattle-noise engineering, from exact impact models to shaker-lab data.

The public surface is listed in ``__all__`` (pinned by a test).  Names are
loaded lazily from their modules on first use, so ``import rattle_lab`` (and the
CLI's start-up) stays fast and does not import numba, scipy or h5py until they
are needed.
"""

from __future__ import annotations

import importlib
from typing import Any

from rattle_lab._version import __version__
from rattle_lab.exceptions import RattleLabError

#: public name -> module that defines it
_LAZY: dict[str, str] = {
    # the nondimensional SDF model and its exact simulator
    "SDFParams": "rattle_lab.model.sdf",
    "SDFState": "rattle_lab.model.sdf",
    "simulate": "rattle_lab.model.sdf",
    # plate model and scaling
    "Plate": "rattle_lab.model.plate",
    "ritz_modes": "rattle_lab.model.plate",
    "table_modes": "rattle_lab.model.plate",
    "SDFScaling": "rattle_lab.model.scaling",
    "grazing_F": "rattle_lab.model.linear",
    "grazing_omegas": "rattle_lab.model.linear",
    "linear_impact_velocity": "rattle_lab.model.linear",
    # analysis
    "one_over_n_orbits": "rattle_lab.model.analysis",
    "bifurcation_sets": "rattle_lab.model.analysis",
    "sweep": "rattle_lab.model.analysis",
    "sweep_up_down": "rattle_lab.model.analysis",
    "lyapunov_exponent": "rattle_lab.model.analysis",
    "regime_map": "rattle_lab.model.analysis",
    # records and ingestion
    "read": "rattle_lab.records",
    "write_record": "rattle_lab.records",
    "Record": "rattle_lab.records",
    "ingest": "rattle_lab.store",
    "read_catalogue": "rattle_lab.store",
    "open_stored_record": "rattle_lab.store",
    # synthetic rigs
    "load_scene": "rattle_lab.rig",
    "synthesize": "rattle_lab.rig",
    "write_synthetic": "rattle_lab.rig",
    # detection and fitting
    "detect_impacts": "rattle_lab.detect",
    "sound_peaks": "rattle_lab.detect",
    "fit_grazing": "rattle_lab.fit",
    "fit_store": "rattle_lab.workflow",
    "read_results": "rattle_lab.store",
    # reports and pipelines
    "write_report": "rattle_lab.workflow",
    "load_pipeline_file": "rattle_lab.workflow.pipeline",
    "run_pipeline": "rattle_lab.workflow.pipeline",
}

__all__ = ["__version__", "RattleLabError", *_LAZY]


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'rattle_lab' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
