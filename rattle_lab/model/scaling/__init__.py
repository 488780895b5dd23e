"""Conversions between the physical plate-striker problem and the nondimensional SDF model.

Chapter 2 of the thesis reduces the plate to one mode ``s`` with the modal
equation (eq. 2.26)::

    x_s'' + 2 zeta omega_s x_s' + omega_s**2 x_s = F_es cos(omega_e t + phi),   stop at x_s = h,

and nondimensionalises it (eq. 2.28-2.32)::

    omega = omega_e / omega_s,   tau = omega_s t,   x = x_s / h,   F = F_es / (omega_s**2 h).

Every conversion here is a pure function with the unit in its name; each has
its inverse.  :class:`SDFScaling` bundles them for one mode and one gap.

Symbols and units
-----------------
``lam``
    Nondimensional modal frequency ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25).
``Q1``, ``Q2``
    Nondimensional modal integrals (eq. 2.18, 2.19); ``participation = Q1 / Q2``.
``F_es_ms2``
    Modal forcing amplitude ``F_es = (L_s / m_s) P_e`` [m/s^2] (eq. 2.27).
``mass_per_area_kg_m2``
    ``rho h_p`` [kg/m^2].

All functions accept floats or numpy arrays (broadcast) and return the same.
"""

from __future__ import annotations

from ._bundle import NondimensionalExcitation, PhysicalExcitation, SDFScaling
from ._forcing import (
    F_es_from_accel,
    F_es_from_F,
    F_es_from_pressure,
    F_from_accel,
    F_from_F_es,
    F_from_pressure,
    accel_ms2_from_F,
    accel_ms2_from_pressure,
    pressure_pa_from_accel,
    pressure_pa_from_F,
)
from ._plate import f_s_hz, flexural_rigidity_nm, lam_from_f_s, omega_s_rad_s, participation_factor
from ._variables import (
    angular_rad_s_from_freq,
    displacement_m_from_x,
    freq_hz_from_omega,
    omega_from_freq,
    tau_from_time,
    time_s_from_tau,
    x_from_displacement,
)
from ._velocity import (
    gap_m_from_inv_F,
    impact_velocity_ms,
    inv_F_from_gap,
    v_im_from_velocity,
    v_im_over_F_from_velocity,
    velocity_ms_from_v_im_over_F,
)

__all__ = [
    "flexural_rigidity_nm",
    "omega_s_rad_s",
    "f_s_hz",
    "lam_from_f_s",
    "participation_factor",
    "pressure_pa_from_accel",
    "accel_ms2_from_pressure",
    "F_es_from_pressure",
    "F_es_from_accel",
    "F_from_F_es",
    "F_es_from_F",
    "F_from_accel",
    "accel_ms2_from_F",
    "F_from_pressure",
    "pressure_pa_from_F",
    "omega_from_freq",
    "freq_hz_from_omega",
    "tau_from_time",
    "time_s_from_tau",
    "x_from_displacement",
    "displacement_m_from_x",
    "impact_velocity_ms",
    "v_im_from_velocity",
    "inv_F_from_gap",
    "gap_m_from_inv_F",
    "v_im_over_F_from_velocity",
    "velocity_ms_from_v_im_over_F",
    "NondimensionalExcitation",
    "PhysicalExcitation",
    "SDFScaling",
    "angular_rad_s_from_freq",
]
