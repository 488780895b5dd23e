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

from typing import TYPE_CHECKING

from rattle_lab._lazy import lazy_names

if TYPE_CHECKING:
    from ._build import RunSummary, Synthesis, resolve_modal, synthesize, write_synthetic
    from ._counter import StageCounter
    from ._motion import Modal, Piece, RunMotion, schedule, simulate_run, true_thresholds
    from ._scene import Scene, SceneError, load_scene, parse_scene

#: public name -> submodule that defines it, loaded on first use: reading a scene
#: (``load_scene``) does not import the simulator and SciPy's signal package (seconds), so
#: that a scene that cannot be read is refused at once
_LAZY: dict[str, str] = {
    "RunSummary": "_build", "Synthesis": "_build", "resolve_modal": "_build",
    "synthesize": "_build", "write_synthetic": "_build",
    "StageCounter": "_counter",
    "Modal": "_motion", "Piece": "_motion", "RunMotion": "_motion", "schedule": "_motion",
    "simulate_run": "_motion", "true_thresholds": "_motion",
    "Scene": "_scene", "SceneError": "_scene", "load_scene": "_scene", "parse_scene": "_scene",
}

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

__getattr__, __dir__ = lazy_names(__name__, globals(), _LAZY)
