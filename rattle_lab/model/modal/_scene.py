"""One call from a scene to physical signals: plate ringing at a sensor point and the sound.

:func:`modal_channels` is what a synthetic rig calls to give its records the ringing of
the higher modes and the radiated sound of a modal impact model, instead of a
single-mode motion with a canned contact kernel.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError
from ._simulate import simulate_modal
from ._sound import C_AIR_M_S, peak_per_impact, plate_surface, rayleigh_pressure, residual_pressure
from ._system import Contact, ModalSystem
from ._types import EpisodeLog, ModalResult, ModalState


@dataclass(frozen=True, eq=False)
class ModalChannels:
    """Signals of one run of the modal model on a uniform time grid.

    Attributes
    ----------
    t_s : numpy.ndarray
        Sample times [s].
    displacement_m, velocity_m_s : numpy.ndarray
        Plate deflection ``w`` and its rate at the sensor point (all modes summed).
    mic_pa : numpy.ndarray
        Sound pressure at the microphone [Pa] (Rayleigh integral, baffled plate, with delay).
    impacts : EpisodeLog
        The contact episodes (truth).
    mic_peak_pa : numpy.ndarray
        Peak ``|p|`` [Pa] after each impact (from its arrival to the next one's).
    state : ModalState
        End state, to continue with the next piece of a ramp.
    result : ModalResult
        The full simulation (dense).
    """

    t_s: np.ndarray
    displacement_m: np.ndarray
    velocity_m_s: np.ndarray
    mic_pa: np.ndarray
    impacts: EpisodeLog
    mic_peak_pa: np.ndarray
    state: ModalState
    result: ModalResult


def modal_channels(system: ModalSystem, contact: Contact | None, t_s: npt.ArrayLike, *,
                   state: ModalState | None = None, sensor_xy_m: tuple[float, float] | None = None,
                   mic_xyz_m: tuple[float, float, float] | None = None, n_grid: int = 30,
                   oversample: int = 8) -> ModalChannels:
    """Simulate ``system`` over the grid ``t_s`` and return sensor and microphone signals.

    Parameters
    ----------
    system : ModalSystem
        Built by :func:`plate_system` (the shapes are needed away from the striker).
    contact : Contact or None
        Contact law (None: Kelvin-Voigt with the thesis striker).
    t_s : array_like
        Uniform sample times [s], starting at ``state.t_s`` (0 by default).
    state : ModalState, optional
        Start state (e.g. the previous piece's ``state``; change the forcing between
        pieces with ``system.replace(pressure_pa=..., freq_hz=..., phase_rad=...)``,
        keeping ``Omega t + phase`` continuous).  The sound of a piece uses the
        motion of that piece only, so the first ``R/c`` (~1 ms) of a continued piece
        lacks the previous piece's contribution.
    sensor_xy_m : (float, float), optional
        Vibrometer point on the plate [m] (default: the striker's point).
    mic_xyz_m : (float, float, float), optional
        Microphone [m] (default 0.3 m in front of the plate centre, as in the thesis's
        experiment, chapter 6).
    n_grid : int
        Surface elements per side for the Rayleigh integral.
    oversample : int
        Fine steps per sample for the propagation delays.

    Returns
    -------
    ModalChannels
    """
    if system.plate is None or system.modes is None:
        raise ParameterError("`system` must come from `plate_system` (mode shapes needed)")
    t = np.asarray(t_s, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ParameterError("`t_s` must be a 1-d grid of at least 2 times")
    t0 = 0.0 if state is None else state.t_s
    if abs(t[0] - t0) > 1e-12 * max(1.0, abs(t0)):
        raise ParameterError(f"`t_s` must start at the state's time {t0}, started at {t[0]}")
    plate = system.plate
    res = simulate_modal(system, contact, duration_s=float(t[-1] - t0), state=state, dense=True)
    xs, ys = (system.striker_xi * plate.a_m, system.striker_eta * plate.b_m) if sensor_xy_m is None else sensor_xy_m
    W = np.asarray(system.modes.evaluate(xs / plate.a_m, ys / plate.b_m), dtype=float)  # type: ignore[attr-defined, type-var]
    p, v = res.modal_state(t)
    sq = np.sqrt(system.modal_mass_kg)
    disp = W @ (p / sq[:, None])
    vel = W @ (v / sq[:, None])
    mic = (0.5 * plate.a_m, 0.5 * plate.b_m, 0.3) if mic_xyz_m is None else tuple(map(float, mic_xyz_m))

    def velocity(tt: np.ndarray) -> np.ndarray:
        # before the start the plate is taken to move as at the start (held state)
        return res.modal_velocity_m_s(np.clip(tt, t0, res.state.t_s))

    pressure = rayleigh_pressure(plate_surface(system, n_grid), velocity, t, mic, oversample=oversample)  # type: ignore[arg-type]
    if system.corrected:
        pressure = pressure + residual_pressure(
            system, lambda tt: res.residual_deflection_m(np.clip(tt, t0, res.state.t_s)), t, mic)  # type: ignore[arg-type]
    delay = float(np.hypot(np.hypot(mic[0] - xs, mic[1] - ys), mic[2])) / C_AIR_M_S
    peaks = peak_per_impact(pressure, t, res.impacts.t_s, delay)
    return ModalChannels(t_s=t, displacement_m=np.asarray(disp), velocity_m_s=np.asarray(vel), mic_pa=pressure,
                         impacts=res.impacts, mic_peak_pa=peaks, state=res.state, result=res)
