"""The explorer's choices: parameter names, parts, views, their labels and slider ranges."""

from __future__ import annotations

from typing import Any, Literal

ParamName = Literal["F", "accel_ms2", "omega", "zeta", "e", "gap_m"]
Part = Literal["total", "forced", "transient", "excitation"]
Quantity = Literal["x", "v", "a"]
AmplitudeMode = Literal["F", "accel"]
SweepChoice = Literal["omega", "A", "e"]
ImpactView = Literal["time", "phase"]

PARAM_NAMES: tuple[ParamName, ...] = ("F", "accel_ms2", "omega", "zeta", "e", "gap_m")
PARTS: tuple[Part, ...] = ("total", "forced", "transient", "excitation")
QUANTITIES: tuple[Quantity, ...] = ("x", "v", "a")
AMPLITUDE_MODES: tuple[AmplitudeMode, ...] = ("F", "accel")
SWEEP_CHOICES: tuple[SweepChoice, ...] = ("omega", "A", "e")
IMPACT_VIEWS: tuple[ImpactView, ...] = ("time", "phase")

#: Default save target, in the current directory.
DEFAULT_SAVE_PATH = "rattle_explore.h5"

_PART_LABELS: dict[Part, str] = {"total": "total", "forced": "forced part",
                                 "transient": "transient part", "excitation": "excitation"}
_PART_STYLE: dict[Part, dict[str, Any]] = {
    "total": {"color": "black", "lw": 1.0},
    "forced": {"color": "tab:red", "lw": 0.9, "ls": "--"},
    "transient": {"color": "goldenrod", "lw": 0.9, "ls": ":"},
    "excitation": {"color": "tab:green", "lw": 0.9, "ls": "-."},
}
_Y_LABELS: dict[Quantity, str] = {
    "x": "displacement x = x_s/h\n(nondimensional)",
    "v": "velocity dx/dt\n(nondimensional)",
    "a": "acceleration d2x/dt2\n(nondimensional)",
}
_AMPLITUDE_LABELS: dict[AmplitudeMode, str] = {"F": "F (nondim.)", "accel": "A_e [m/s^2]"}
_SWEEP_LABELS: dict[SweepChoice, str] = {"omega": "omega", "A": "A (amplitude)", "e": "e"}
_IMPACT_VIEW_LABELS: dict[ImpactView, str] = {"time": "v_in vs time",
                                              "phase": "v_in vs phase"}
_SWEEP_X_LABELS: dict[str, str] = {
    "omega": "forcing frequency omega = f/f_s (nondimensional)",
    "F": "forcing amplitude F (nondimensional)",
    "accel": "base-acceleration amplitude A_e [m/s^2]",
    "e": "coefficient of restitution e (nondimensional)",
}

#: Slider ranges (nondimensional, gap in mm); widened to include a start value outside them.
_RANGES: dict[str, tuple[float, float]] = {
    "F": (0.0, 1.0), "omega": (0.2, 3.0), "zeta": (0.0, 0.3), "e": (0.0, 1.0),
    "gap_mm": (0.1, 5.0),
}
