"""Predicted sound-pressure law: peak pressure per unit impact velocity.

With a Kelvin-Voigt contact, and the pressure load negligible over the few
milliseconds of an impact, the plate-striker system is linear during a contact
episode: an impact at velocity ``v`` from a plate moving in its main mode radiates
``v`` times the pressure of an impact at 1 m/s.  The peak pressure is then
``p = S v`` (a line through the origin; 20 dB per decade of ``v`` on the dB scale,
the thesis's linear SPL law, chapter 6).  :func:`predicted_spl_slope` computes ``S``
from one impact of the unforced plate arriving in mode 1 at 1 m/s.  In a steady
rattle the plate arrives with the ringing of the previous impact and the forced
shape, so a campaign's fitted slope scatters about ``S``.
"""

from __future__ import annotations

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._simulate import simulate_modal
from ._sound import C_AIR_M_S, plate_surface, rayleigh_pressure, residual_pressure
from ._system import Contact, ModalSystem
from ._types import ModalState


def predicted_spl_slope(system: ModalSystem, contact: Contact | None = None, *,
                        mic_xyz_m: tuple[float, float, float] | None = None, fs_hz: float = 50000.0,
                        n_grid: int = 30, v_in_m_s: float = 1.0) -> float:
    """Peak pressure per impact velocity, ``S`` [Pa/(m/s)], of one impact in mode 1.

    Parameters
    ----------
    system : ModalSystem
        From :func:`plate_system`; its forcing is switched off for the prediction.
    contact : Contact or None
        Contact law (None: Kelvin-Voigt, thesis striker).
    mic_xyz_m : (float, float, float), optional
        Microphone (default 0.3 m in front of the centre).
    fs_hz : float
        Sample rate of the pressure whose peak is taken [Hz] (sample means, as
        :func:`rayleigh_pressure`).
    n_grid : int
        Surface elements per side.
    v_in_m_s : float
        Impact velocity of the probe impact [m/s] (the result is per m/s; it matters
        only for a nonlinear (Hertz) contact).

    Returns
    -------
    float
        ``S`` = peak ``|p|`` over the first episode divided by its ``v_in``.
    """
    if system.plate is None:
        raise ParameterError("`system` must come from `plate_system` (mode shapes needed)")
    if not v_in_m_s > 0:
        raise ParameterError(f"`v_in_m_s` must be > 0, was {v_in_m_s}")
    quiet = system.replace(pressure_pa=0.0)
    # Mode 1 alone, just off the striker, moving towards it: p_1 = (gap - 1 ulp-ish) / beta_1.
    n = system.n_modes
    b1 = float(quiet.beta[0])
    if b1 == 0:
        raise ParameterError("mode 1 is not seen at the striker (W_1(x_s, y_s) = 0)")
    p0 = np.zeros(n)
    v0 = np.zeros(n)
    p0[0] = quiet.gap_m * (1 - 1e-9) / b1
    v0[0] = v_in_m_s / b1
    span = 4.0 / float(quiet.omega_rad_s[0])
    res = simulate_modal(quiet, contact, duration_s=span, state=ModalState(0.0, p0, v0), dense=True,
                         episode_gap_s=span)
    if len(res.contacts) == 0:
        raise ParameterError("the probe impact did not touch the striker")
    plate = system.plate
    mic = (0.5 * plate.a_m, 0.5 * plate.b_m, 0.3) if mic_xyz_m is None else mic_xyz_m
    t = np.arange(0.0, span, 1.0 / fs_hz)
    p = rayleigh_pressure(plate_surface(quiet, n_grid), lambda tt: res.modal_velocity_m_s(np.clip(tt, 0.0, span)),
                          t, mic)
    p = p + residual_pressure(quiet, lambda tt: res.residual_deflection_m(np.clip(tt, 0.0, span)), t, mic)
    # Only the impact's sound: the free mode-1 motion before it radiates (weakly) too.
    t_hit = float(res.contacts.t_start_s[0])
    delay = float(np.hypot(np.hypot(mic[0] - system.striker_xi * plate.a_m,
                                    mic[1] - system.striker_eta * plate.b_m), mic[2])) / C_AIR_M_S
    sel = t >= t_hit + delay - 2.0 / fs_hz
    return float(np.max(np.abs(p[sel])) / float(res.contacts.u_in_m_s[0]))
