"""What a pipeline declares: its stages and outputs, and the pipeline file that names them.

:func:`parse_pipeline` validates a parsed TOML document (the format is described in
:mod:`rattle_lab.workflow.pipeline`, which runs it) into a frozen :class:`Pipeline`;
:func:`load_pipeline_file` reads one from a file or, by name, from the pipelines shipped
with rattle_lab.  Nothing here runs a stage.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rattle_lab._resources import read_pipeline_toml
from rattle_lab.exceptions import ParameterError

Stage = Literal["simulate", "ingest", "detect", "thresholds", "fit", "report"]

#: Stages in execution order.
STAGES: tuple[Stage, ...] = ("simulate", "ingest", "detect", "thresholds", "fit", "report")
#: What each stage needs.
DEPENDS: dict[Stage, tuple[Stage, ...]] = {
    "simulate": (), "ingest": ("simulate",), "detect": ("ingest",), "thresholds": ("detect",),
    "fit": ("thresholds", "detect"), "report": ("fit", "ingest")}
#: Output names a pipeline may request, and the stage that makes each.
OUTPUTS: dict[str, Stage] = {"store": "ingest", "detections": "detect",
                             "thresholds": "thresholds", "results": "fit", "report": "report"}
#: Keys of the tables this module validates itself ([detect] and [fit] are the fit's).
_OWN_KEYS: dict[str, dict[str, Any]] = {"simulate": {"seed": None},
                                        "ingest": {"allow_flagged": False},
                                        "report": {"model": True}}


@dataclass(frozen=True)
class Pipeline:
    """A parsed pipeline file.

    Attributes
    ----------
    name : str
        Names the default store (``OUT/name.h5``) and report (``OUT/name.pdf``).
    outputs : tuple of str
        Requested outputs (keys of :data:`OUTPUTS`).
    params : dict of str to dict
        Parameters per table: ``simulate, ingest, detect, fit, report``.
    description : str
    source : str
        The file it was read from ("" if built in code).
    """

    name: str
    outputs: tuple[str, ...]
    params: dict[str, dict[str, Any]]
    description: str = ""
    source: str = ""


# --- the pipeline file -----------------------------------------------------------------------

def parse_pipeline(doc: Mapping[str, Any], source: str = "<pipeline>") -> Pipeline:
    """A :class:`Pipeline` from a parsed TOML document.

    Raises
    ------
    ParameterError
        For an unknown table, key or output (the message names it).
    """
    from rattle_lab.fit import FIT_KEYS
    from rattle_lab.detect import DetectParams

    known = {"pipeline", "simulate", "ingest", "detect", "thresholds", "fit", "report"}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise ParameterError(f"{source}: unknown table [{unknown[0]}] (known: "
                             f"{', '.join(sorted(known))})")
    head = doc.get("pipeline", {})
    if not isinstance(head, Mapping):
        raise ParameterError(f"{source}: [pipeline] must be a table")
    bad = sorted(set(head) - {"name", "description", "outputs"})
    if bad:
        raise ParameterError(f"{source}: [pipeline]: unknown key {bad[0]!r}")
    name = head.get("name", Path(source).stem if source != "<pipeline>" else "pipeline")
    if not isinstance(name, str) or not name or any(c in name for c in "/\\"):
        raise ParameterError(f"{source}: [pipeline] name must be a plain file stem, was {name!r}")
    outputs = head.get("outputs", ["report"])
    if isinstance(outputs, str):
        outputs = [outputs]
    for out in outputs:
        if out not in OUTPUTS:
            raise ParameterError(f"{source}: [pipeline] outputs: unknown output {out!r} "
                                 f"(known: {', '.join(OUTPUTS)})")
    if not outputs:
        raise ParameterError(f"{source}: [pipeline] outputs must name at least one output")
    allowed = {"fit": set(FIT_KEYS), "thresholds": set(), **{k: set(v) for k, v in
                                                             _OWN_KEYS.items()}}
    values = doc.get("detect", {})
    if not isinstance(values, Mapping):
        raise ParameterError(f"{source}: [detect] must be a table")
    DetectParams.from_mapping(values, f"{source}: [detect]: ")   # its keys and values checked
    params: dict[str, dict[str, Any]] = {"detect": dict(values)}
    for table, keys in allowed.items():
        values = doc.get(table, {})
        if not isinstance(values, Mapping):
            raise ParameterError(f"{source}: [{table}] must be a table")
        bad = sorted(set(values) - keys)
        if bad:
            hint = (" (n_confirm belongs to [fit], as in `rattle-lab fit --pipeline`)"
                    if table == "thresholds" else "")
            raise ParameterError(f"{source}: [{table}]: unknown key {bad[0]!r}{hint}")
        params[table] = {**_OWN_KEYS.get(table, {}), **dict(values)}
    seed = params["simulate"]["seed"]
    if seed is not None and (not isinstance(seed, int) or isinstance(seed, bool)):
        raise ParameterError(f"{source}: [simulate] seed must be an integer, was {seed!r}")
    for table, key in (("ingest", "allow_flagged"), ("report", "model")):
        if not isinstance(params[table][key], bool):
            raise ParameterError(f"{source}: [{table}] {key} must be true or false, "
                                 f"was {params[table][key]!r}")
    params["fit"] = {**FIT_KEYS, **params["fit"]}
    params.pop("thresholds")
    return Pipeline(name, tuple(outputs), params, str(head.get("description", "")), source)


def load_pipeline_file(path: str | os.PathLike[str]) -> Pipeline:
    """Read and validate a pipeline TOML file.

    Raises
    ------
    ParameterError
        If the file cannot be read or is invalid.
    """
    doc, where = read_pipeline_toml(path)
    return parse_pipeline(doc, where)


__all__ = ["Stage", "STAGES", "DEPENDS", "OUTPUTS", "Pipeline", "parse_pipeline",
           "load_pipeline_file"]
