"""The scene's ``[model] kind = "modal"`` options (issue 14): the spec and its parser.

:mod:`rattle_lab.rig._modal` simulates a scene with them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class ModalRigSpec:
    """Options of ``[model] kind = "modal"``.

    Attributes
    ----------
    modes : int
        Number of plate modes N (lowest N of the Ritz solver).
    contact : str
        "kelvin-voigt" (default), "hertz" or "rigid" (restitution ``model.e``).
    contact_stiffness_n_m, contact_damping_n_s_m : float or None
        Kelvin-Voigt striker (default: the thesis's truss striker, no damping).
    hertz_n_m15 : float or None
        Hertz constant (default: a 5 mm steel ball on aluminium).
    striker_x_m, striker_y_m : float or None
        Striker position on the plate (default: the centre).
    radiation_grid : int
        Surface elements per side in the Rayleigh integral.
    """

    modes: int = 8
    contact: str = "kelvin-voigt"
    contact_stiffness_n_m: float | None = None
    contact_damping_n_s_m: float = 0.0
    hertz_n_m15: float | None = None
    striker_x_m: float | None = None
    striker_y_m: float | None = None
    radiation_grid: int = 30


def parse_modal(reader: Any) -> ModalRigSpec:
    """Pop the modal keys of ``[model]`` from a scene reader (``_scene._Reader``)."""
    spec = ModalRigSpec(modes=reader.integer("modes", 8, low=1),
                        contact=reader.string("contact", "kelvin-voigt",
                                              choices=("kelvin-voigt", "hertz", "rigid")),
                        contact_stiffness_n_m=reader.positive("contact_stiffness_n_m"),
                        contact_damping_n_s_m=reader.number("contact_damping_n_s_m", 0.0, low=0.0),
                        hertz_n_m15=reader.positive("hertz_n_m15"),
                        striker_x_m=reader.number("striker_x_m", None, low=0.0),
                        striker_y_m=reader.number("striker_y_m", None, low=0.0),
                        radiation_grid=reader.integer("radiation_grid", 30, low=2))
    return spec
