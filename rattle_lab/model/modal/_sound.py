"""Sound of the plate: the Rayleigh integral of a baffled plate, with propagation delay.

For a plate in an infinite rigid baffle the pressure at ``r`` is (Rayleigh)::

    p(r, t) = rho_0 / (2 pi) int_S  w''(r', t - R / c) / R  dA',     R = |r - r'|,

and with ``w' = sum_k W_k(r') q_k'(t)``, ``p = d Phi / dt`` where
``Phi(t) = sum_k sum_e g_ke q_k'(t - tau_e)``, ``g_ke = rho_0 dA_e W_k(r_e) / (2 pi R_e)``,
``tau_e = R_e / c`` (surface cut into elements ``e``).  ``Phi`` is built on a time grid
``oversample`` times finer than the output, each element's delay shared linearly
between the two nearest fine-grid delays (error ``~ (omega h)**2 / 8``, ``h`` the fine
step) and applied per mode as one short convolution.  The output sample ``n`` is the
mean pressure over ``[t_n - dt/2, t_n + dt/2]``, ``(Phi(t_n + dt/2) - Phi(t_n - dt/2)) / dt``:
exact for the impulses of a rigid contact too (their pressure is a delta, whose mean
over a sample is finite).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.signal import fftconvolve

from rattle_lab.exceptions import ParameterError

#: Air at 20 degC.
C_AIR_M_S = 343.0
RHO_AIR_KG_M3 = 1.204


@dataclass(frozen=True, eq=False)
class RadiatingSurface:
    """A baffled surface in the plane z = 0, cut into elements.

    Attributes
    ----------
    points_m : numpy.ndarray
        Element centres ``(x, y)`` [m], shape (n_e, 2).
    area_m2 : numpy.ndarray
        Element areas [m^2], shape (n_e,).
    shapes : numpy.ndarray
        ``W_k`` at the centres (nondimensional), shape (n_modes, n_e): the normal
        velocity is ``sum_k W_k q_k'``.
    """

    points_m: np.ndarray
    area_m2: np.ndarray
    shapes: np.ndarray


def plate_surface(system: object, n_x: int = 40, n_y: int | None = None) -> RadiatingSurface:
    """Midpoint grid of ``n_x`` x ``n_y`` elements over the plate of a :class:`ModalSystem`.

    Raises
    ------
    ParameterError
        If the system was not built from a plate (``plate_system``) or a count is < 1.
    """
    plate = getattr(system, "plate", None)
    modes = getattr(system, "modes", None)
    if plate is None or modes is None:
        raise ParameterError("the sound needs a ModalSystem built by `plate_system` (mode shapes on the plate)")
    n_y = n_x if n_y is None else n_y
    if n_x < 1 or n_y < 1:
        raise ParameterError(f"`n_x`, `n_y` must be >= 1, were {n_x}, {n_y}")
    xi = (np.arange(n_x) + 0.5) / n_x
    eta = (np.arange(n_y) + 0.5) / n_y
    X, Y = np.meshgrid(xi, eta, indexing="xy")
    shapes = modes.evaluate(X.ravel(), Y.ravel())  # type: ignore[attr-defined]
    pts = np.column_stack([X.ravel() * plate.a_m, Y.ravel() * plate.b_m])
    area = np.full(pts.shape[0], plate.a_m * plate.b_m / (n_x * n_y))
    return RadiatingSurface(points_m=pts, area_m2=area, shapes=np.asarray(shapes))


def rayleigh_pressure(surface: RadiatingSurface, modal_velocity: Callable[[np.ndarray], np.ndarray],
                      t_s: npt.ArrayLike, mic_xyz_m: tuple[float, float, float], *,
                      c_m_s: float = C_AIR_M_S, rho_air_kg_m3: float = RHO_AIR_KG_M3,
                      oversample: int = 8) -> np.ndarray:
    """Pressure [Pa] at the microphone, sample means on a uniform grid ``t_s``.

    Parameters
    ----------
    surface : RadiatingSurface
        The baffled radiator.
    modal_velocity : callable
        ``t -> q'(t)`` [m/s], shape (n_modes, t.size), for any times (including the
        delayed ones before ``t_s[0]``).
    t_s : array_like
        Uniform output times [s], at least 2.
    mic_xyz_m : (float, float, float)
        Microphone position [m], ``z > 0`` (in front of the baffle).
    c_m_s, rho_air_kg_m3 : float
        Speed of sound and density of the air.
    oversample : int
        Fine time steps per output step for the delays (>= 1).

    Returns
    -------
    numpy.ndarray
        Pressure [Pa] at the times ``t_s``.
    """
    t = np.asarray(t_s, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ParameterError("`t_s` must be a 1-d grid of at least 2 times")
    dt = float(t[1] - t[0])
    if not (dt > 0 and np.allclose(np.diff(t), dt, rtol=1e-9, atol=0)):
        raise ParameterError("`t_s` must be uniform and increasing")
    mx, my, mz = map(float, mic_xyz_m)
    if not mz > 0:
        raise ParameterError(f"the microphone must be in front of the baffle (z > 0), was z = {mz}")
    if int(oversample) != oversample or oversample < 1:
        raise ParameterError(f"`oversample` must be an integer >= 1, was {oversample}")
    os_ = int(oversample)
    h = dt / os_
    R = np.sqrt((surface.points_m[:, 0] - mx) ** 2 + (surface.points_m[:, 1] - my) ** 2 + mz**2)
    tau = R / c_m_s
    pos = tau / h
    j0 = np.floor(pos).astype(np.int64)
    frac = pos - j0
    jmin = int(j0.min())
    jmax = int(j0.max()) + 1
    n_taps = jmax - jmin + 1
    w = rho_air_kg_m3 * surface.area_m2 / (2.0 * math.pi * R)  # (n_e,)
    n_modes = surface.shapes.shape[0]
    kern = np.zeros((n_modes, n_taps))
    for k in range(n_modes):
        g = surface.shapes[k] * w
        np.add.at(kern[k], j0 - jmin, g * (1.0 - frac))
        np.add.at(kern[k], j0 - jmin + 1, g * frac)
    # Fine grid: Phi is needed at t_n - dt/2 + m h for m = 0 .. n_t * os.
    n_out = t.size * os_ + 1
    base = t[0] - 0.5 * dt
    n_fine = n_out + n_taps - 1
    t_fine = base - jmax * h + h * np.arange(n_fine)
    v = np.asarray(modal_velocity(t_fine), dtype=float).reshape(n_modes, n_fine)
    phi = np.zeros(n_out)
    for k in range(n_modes):
        full = fftconvolve(v[k], kern[k], mode="valid")  # index m: sum_j kern[j] v[m + n_taps - 1 - j]
        phi += full[:n_out]
    return np.asarray((phi[os_::os_] - phi[:-os_:os_])[: t.size] / dt)


def residual_pressure(system: object, deflection: Callable[[np.ndarray], np.ndarray], t_s: npt.ArrayLike,
                      mic_xyz_m: tuple[float, float, float], *, c_m_s: float = C_AIR_M_S,
                      rho_air_kg_m3: float = RHO_AIR_KG_M3) -> np.ndarray:
    """Sound [Pa] of the omitted modes' element, sample means on the uniform grid ``t_s``.

    The element's dashpot force ``Z r'`` drives the omitted modes, whose volume
    acceleration is ``eta Z r'`` (``eta = system.residual_volume_m2_kg``; for an infinite
    plate ``eta = 1/m''`` and this is the exact ``rho_0 F / (2 pi m'' R)`` below
    coincidence): a baffled point source at the striker,
    ``p = rho_0 eta Z r'(t - R/c) / (2 pi R)``.  The mean over a sample is
    ``(r(t + dt/2 - R/c) - r(t - dt/2 - R/c)) / dt`` times the rest, exact.
    Zeros when the system has no element.
    """
    t = np.asarray(t_s, dtype=float)
    if not getattr(system, "corrected", False):
        return np.zeros(t.size)
    plate = system.plate  # type: ignore[attr-defined]
    if plate is None:
        raise ParameterError("the sound needs a ModalSystem built by `plate_system`")
    dt = float(t[1] - t[0])
    xs = system.striker_xi * plate.a_m  # type: ignore[attr-defined]
    ys = system.striker_eta * plate.b_m  # type: ignore[attr-defined]
    mx, my, mz = map(float, mic_xyz_m)
    R = math.sqrt((mx - xs) ** 2 + (my - ys) ** 2 + mz**2)
    tau = R / c_m_s
    gain = (rho_air_kg_m3 * system.residual_volume_m2_kg  # type: ignore[attr-defined]
            * system.local_impedance_n_s_m / (2.0 * math.pi * R))  # type: ignore[attr-defined]
    edges = np.append(t - 0.5 * dt, t[-1] + 0.5 * dt) - tau
    r = np.asarray(deflection(edges), dtype=float)
    return np.asarray(gain * np.diff(r) / dt)


#: The stated microphone of :func:`measured_peak`: flat, then a 2nd-order Butterworth
#: low-pass with -3 dB at 20 kHz (IEC 61672-1 class 1 free-field microphones are
#: specified to 20 kHz; the filter is its upper band edge).
MIC_CORNER_HZ = 20000.0


def microphone(p_pa: np.ndarray, fs_hz: float, corner_hz: float = MIC_CORNER_HZ) -> np.ndarray:
    """The pressure as the stated microphone reads it (causal, as the analogue chain)."""
    from scipy.signal import butter, sosfilt

    if not corner_hz < 0.5 * fs_hz:
        return np.asarray(p_pa, dtype=float)
    sos = butter(2, corner_hz, btype="low", fs=fs_hz, output="sos")
    return np.asarray(sosfilt(sos, np.asarray(p_pa, dtype=float)))


def measured_peak(p_pa: np.ndarray, fs_hz: float) -> tuple[float, float]:
    """``(peak |p| [Pa] through the microphone, max Fast level [dB re 20 uPa])`` of a record.

    Fast: the exponential time weighting of IEC 61672-1 (tau = 0.125 s) on the
    microphone's mean square, Z (flat) frequency weighting.
    """
    from scipy.signal import lfilter

    pm = microphone(p_pa, fs_hz)
    # the sampled first-order lag on p^2, from rest (the model layer does not import acoustics/)
    a = math.exp(-1.0 / (fs_hz * 0.125))
    fast = lfilter([1.0 - a], [1.0, -a], pm**2)
    lf = 10.0 * math.log10(max(float(np.max(fast)), 1e-300) / (20e-6) ** 2)
    return float(np.max(np.abs(pm))), lf


def piston_surface(radius_m: float, n_rings: int, n_theta: int = 64) -> RadiatingSurface:
    """A circular piston of radius ``radius_m`` centred at the origin, polar midpoint elements."""
    if not radius_m > 0 or n_rings < 1 or n_theta < 1:
        raise ParameterError("`radius_m` must be > 0 and `n_rings`, `n_theta` >= 1")
    dr = radius_m / n_rings
    r = (np.arange(n_rings) + 0.5) * dr
    th = (np.arange(n_theta) + 0.5) * 2 * math.pi / n_theta
    Rg, Tg = np.meshgrid(r, th, indexing="ij")
    pts = np.column_stack([(Rg * np.cos(Tg)).ravel(), (Rg * np.sin(Tg)).ravel()])
    # exact ring areas pi ((r + dr/2)^2 - (r - dr/2)^2) / n_theta = 2 pi r dr / n_theta
    area = (2 * math.pi * Rg * dr / n_theta).ravel()
    return RadiatingSurface(points_m=pts, area_m2=area, shapes=np.ones((1, pts.shape[0])))


def peak_per_impact(p_pa: np.ndarray, t_s: np.ndarray, impact_t_s: np.ndarray, delay_s: float) -> np.ndarray:
    """Peak ``|p|`` [Pa] from each impact's arrival to the next one's (or the end)."""
    out = np.full(impact_t_s.size, np.nan)
    arrive = impact_t_s + delay_s
    for i in range(impact_t_s.size):
        hi = arrive[i + 1] if i + 1 < impact_t_s.size else t_s[-1] + 1.0
        sel = (t_s >= arrive[i]) & (t_s < hi)
        if np.any(sel):
            out[i] = float(np.max(np.abs(p_pa[sel])))
    return out
