"""The synthetic rig: scenes (TOML) -> simulated plate/striker campaigns with ground truth.

* :func:`load_scene` reads and validates a scene (``"default"``: the embedded demo scene).
* :func:`synthesize` runs the exact SDF simulator in physical units for every run of the
  protocol and synthesises the channels the scene records; :func:`write_synthetic` also
  writes the record.  Everything the rig knows goes into ``/truth``.
  ``[model] kind = "modal"`` (opt-in) simulates the plate's lowest modes against a point
  striker with :mod:`rattle_lab.model.modal` instead: physical ringing in the vibrometer and the
  plate accelerometer, the Rayleigh-integral sound at the microphone (see ``_modal``).
* :class:`StageCounter` counts the stages evaluated (skipped stages never run).
"""

from ._build import RunSummary, Synthesis, resolve_modal, synthesize, write_synthetic
from ._counter import StageCounter
from ._motion import Modal, Piece, RunMotion, schedule, simulate_run, true_thresholds
from ._scene import Scene, SceneError, load_scene, parse_scene

__all__ = [
    "load_scene",
    "parse_scene",
    "synthesize",
    "write_synthetic",
    "Scene",
    "SceneError",
    "StageCounter",
    "Synthesis",
    "RunSummary",
    "Modal",
    "Piece",
    "RunMotion",
    "schedule",
    "simulate_run",
    "true_thresholds",
    "resolve_modal",
]
