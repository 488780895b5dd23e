"""Multi-mode plate impact model (issue 14): N plate modes against a point striker.

* :func:`plate_system` / :class:`ModalSystem`: modes from the plate solver, modal damping,
  uniform-pressure forcing, striker position and gap.
* :func:`simulate_modal`: event-driven exact simulation with a rigid (restitution),
  Kelvin-Voigt or Hertz contact; impacts reported as contact episodes.
* :func:`rayleigh_pressure`: the sound at a microphone (baffled plate, with delay).
* :func:`modal_channels`: sensor and microphone signals of a run (for synthetic rigs).
"""

from ._scene import ModalChannels, modal_channels
from ._simulate import simulate_modal
from ._sound import (C_AIR_M_S, MIC_CORNER_HZ, RadiatingSurface, measured_peak, microphone,
                     peak_per_impact, plate_surface, rayleigh_pressure, residual_pressure)
from ._spl import predicted_spl_slope
from ._system import (CONTACT_NAMES, THESIS_HERTZ_N_M15, THESIS_PLATE, THESIS_STRIKER_STIFFNESS_N_M,
                      Contact, HertzContact, KelvinVoigtContact, ModalSystem, RigidContact, contact_from_name,
                      infinite_plate_impedance, plate_system, rayleigh_zeta)
from ._types import ContactLog, EpisodeLog, ModalResult, ModalState

__all__ = [
    "CONTACT_NAMES",
    "MIC_CORNER_HZ",
    "THESIS_HERTZ_N_M15",
    "THESIS_PLATE",
    "THESIS_STRIKER_STIFFNESS_N_M",
    "ContactLog",
    "EpisodeLog",
    "HertzContact",
    "KelvinVoigtContact",
    "ModalChannels",
    "ModalResult",
    "ModalState",
    "ModalSystem",
    "RadiatingSurface",
    "RigidContact",
    "contact_from_name",
    "infinite_plate_impedance",
    "measured_peak",
    "microphone",
    "modal_channels",
    "plate_surface",
    "plate_system",
    "predicted_spl_slope",
    "rayleigh_pressure",
    "rayleigh_zeta",
    "residual_pressure",
    "simulate_modal",
    "C_AIR_M_S",
    "Contact",
    "peak_per_impact",
]
