"""Rayleigh-integral sound of the modal model: the baffled circular piston and grid convergence."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.exceptions import ParameterError
from rattle_lab.modal import KelvinVoigtContact, plate_system, simulate_modal
from rattle_lab.modal._sound import (C_AIR_M_S, RHO_AIR_KG_M3, piston_surface, plate_surface,
                                     rayleigh_pressure)


def _piston_reference(t: np.ndarray, dt: float, z: float, a: float, w: float) -> np.ndarray:
    """Mean over each sample of the closed-form on-axis pressure of a baffled piston.

    p(z, t) = rho c [u(t - z/c) - u(t - sqrt(z^2 + a^2)/c)] for any u(t); with
    u = sin(w t) the sample mean uses U = -cos(w t)/w.
    """
    def U(x):
        return -np.cos(w * x) / w
    t1, t2 = z / C_AIR_M_S, math.hypot(z, a) / C_AIR_M_S
    mean_u = lambda d: (U(t + dt / 2 - d) - U(t - dt / 2 - d)) / dt  # noqa: E731
    return RHO_AIR_KG_M3 * C_AIR_M_S * (mean_u(t1) - mean_u(t2))


@pytest.mark.parametrize("z", [0.05, 0.3])
def test_piston_on_axis_matches_closed_form_and_converges(z):
    a, f = 0.1, 1500.0
    w = 2 * math.pi * f
    fs = 48000.0
    t = np.arange(0.0, 0.01, 1 / fs)
    ref = _piston_reference(t, 1 / fs, z, a, w)
    errs = []
    for n_rings in (25, 50, 100):
        surf = piston_surface(a, n_rings, n_theta=8)
        p = rayleigh_pressure(surf, lambda tt: np.sin(w * tt)[None, :], t, (0.0, 0.0, z), oversample=16)
        errs.append(np.max(np.abs(p - ref)) / np.max(np.abs(ref)))
    # Midpoint rings converge as (dr)^2; the linear delay sharing adds ~(w h)^2/8 = 1e-5.
    assert errs[2] < 1e-3
    assert errs[0] / errs[2] > 8  # second order: 16 in theory, less where the delay error shows


def test_plate_sound_converges_in_the_surface_grid():
    system = plate_system(n_modes=4, pressure_pa=285.0, freq_hz=115.6, skip_unexcited=True)
    res = simulate_modal(system, KelvinVoigtContact(), cycles=6, dense=True)
    t = np.arange(0.0, res.state.t_s - 0.002, 1 / 40000.0)
    mic = (0.127, 0.1143, 0.3)
    vel = res.modal_velocity_m_s
    ps = {n: rayleigh_pressure(plate_surface(system, n), vel, t, mic) for n in (10, 20, 40, 80)}
    d1 = np.max(np.abs(ps[20] - ps[40]))
    d2 = np.max(np.abs(ps[40] - ps[80]))
    assert np.max(np.abs(ps[80])) > 0.01  # it rattles audibly
    assert d2 < 0.35 * d1  # the midpoint rule converges (second order: 1/4)
    assert d2 < 5e-3 * np.max(np.abs(ps[80]))  # 80x80 elements: within 0.5 % of the peak


def test_rayleigh_pressure_rejects_bad_input():
    surf = piston_surface(0.1, 4)
    with pytest.raises(ParameterError, match="in front"):
        rayleigh_pressure(surf, lambda tt: np.zeros((1, tt.size)), np.arange(10) / 1e3, (0, 0, -1.0))
    with pytest.raises(ParameterError, match="uniform"):
        rayleigh_pressure(surf, lambda tt: np.zeros((1, tt.size)), np.array([0.0, 1.0, 3.0]), (0, 0, 1.0))
