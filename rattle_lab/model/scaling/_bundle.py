"""SDFScaling: every conversion bundled for one mode and one gap."""

from __future__ import annotations

from dataclasses import dataclass

import numpy.typing as npt

from rattle_lab.exceptions import ParameterError

from rattle_lab.model._checks import FloatOrArray, _excited_participation, _positive
from rattle_lab.model._constants import TWO_PI
from ._forcing import F_from_accel, F_from_pressure, accel_ms2_from_F
from ._plate import omega_s_rad_s, participation_factor
from ._variables import (
    displacement_m_from_x,
    freq_hz_from_omega,
    omega_from_freq,
    tau_from_time,
    time_s_from_tau,
    x_from_displacement,
)
from ._velocity import impact_velocity_ms, v_im_from_velocity


# --------------------------------------------------------------------------- bundled scaling
@dataclass(frozen=True)
class NondimensionalExcitation:
    """A sinusoidal excitation in the nondimensional SDF model.

    Attributes
    ----------
    F : float or numpy.ndarray
        Forcing amplitude ``F_es / (omega_s**2 h)`` (eq. 2.31), nondimensional.
    omega : float or numpy.ndarray
        Forcing frequency ``omega_e / omega_s`` (eq. 2.28), nondimensional.
    """

    F: FloatOrArray
    omega: FloatOrArray


@dataclass(frozen=True)
class PhysicalExcitation:
    """A sinusoidal base excitation in physical units.

    Attributes
    ----------
    freq_hz : float or numpy.ndarray
        Excitation frequency ``f = omega f_s`` [Hz].
    accel_ms2 : float or numpy.ndarray
        Base-acceleration amplitude ``A_e`` [m/s^2] (eq. 2.1).
    pressure_pa : float or numpy.ndarray or None
        Equivalent pressure amplitude ``P_e = rho h_p A_e`` [Pa] (eq. 2.3); None when the
        scaling has no ``mass_per_area_kg_m2``.
    """

    freq_hz: FloatOrArray
    accel_ms2: FloatOrArray
    pressure_pa: FloatOrArray | None


@dataclass(frozen=True)
class SDFScaling:
    """Scales of one plate mode with one gap: physical <-> nondimensional SDF model.

    Built on the pure functions of :mod:`rattle_lab.model.scaling`.

    Attributes
    ----------
    omega_s_rad_s : float
        Modal angular frequency ``omega_s`` [rad/s] (eq. 2.25), > 0.
    gap_m : float
        Gap ``h`` between plate and striker [m], > 0.
    participation : float
        ``Q1 / Q2`` of the mode (eq. 2.16-2.19, 2.27), != 0.
    mass_per_area_kg_m2 : float or None
        ``rho h_p`` [kg/m^2]; needed only for pressures.

    Examples
    --------
    >>> import numpy as np
    >>> s = SDFScaling.from_modal_data(lam=27.4, Q1=0.5, Q2=0.402, gap_m=1e-3, a_m=0.254,
    ...                                h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0)
    >>> bool(np.isclose(s.f_s_hz, 105.45, atol=0.01))
    True
    >>> ex = s.to_nondimensional(freq_hz=105.45, pressure_pa=285.0)
    >>> bool(np.isclose(ex.F, 0.30, atol=0.005))
    True
    """

    omega_s_rad_s: float
    gap_m: float
    participation: float
    mass_per_area_kg_m2: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega_s_rad_s", float(_positive("omega_s_rad_s", self.omega_s_rad_s)))
        object.__setattr__(self, "gap_m", float(_positive("gap_m", self.gap_m)))
        object.__setattr__(self, "participation", float(_excited_participation(self.participation)))
        if self.mass_per_area_kg_m2 is not None:
            object.__setattr__(self, "mass_per_area_kg_m2",
                               float(_positive("mass_per_area_kg_m2", self.mass_per_area_kg_m2)))

    @classmethod
    def from_modal_data(cls, *, lam: float, Q1: float, Q2: float, gap_m: float, a_m: float,
                        h_p_m: float, E_pa: float, nu: float, rho_kg_m3: float) -> SDFScaling:
        """Scaling of a plate mode given by ``lambda``, ``Q1``, ``Q2`` (eq. 2.16-2.25).

        Parameters
        ----------
        lam, Q1, Q2 : float
            Modal data (eq. 2.18, 2.19, 2.25), nondimensional; ``lam > 0``.
        gap_m : float
            Gap [m].
        a_m, h_p_m, E_pa, nu, rho_kg_m3 : float
            Plate side along x [m], thickness [m], Young's modulus [Pa], Poisson's
            ratio, density [kg/m^3].

        Returns
        -------
        SDFScaling

        Raises
        ------
        ParameterError
            If an argument is out of range or ``Q1 == 0``.
        """
        _positive("lam", lam)
        return cls(
            omega_s_rad_s=float(omega_s_rad_s(lam, a_m, h_p_m, E_pa, nu, rho_kg_m3)),
            gap_m=gap_m,
            participation=float(participation_factor(Q1, Q2)),
            mass_per_area_kg_m2=float(_positive("rho_kg_m3", rho_kg_m3) * _positive("h_p_m", h_p_m)),
        )

    @property
    def f_s_hz(self) -> float:
        """Modal frequency ``omega_s / (2 pi)`` [Hz]."""
        return self.omega_s_rad_s / TWO_PI

    def _mass_per_area(self) -> float:
        if self.mass_per_area_kg_m2 is None:
            raise ParameterError("`pressure_pa` needs `mass_per_area_kg_m2` (rho h_p) in the SDFScaling, was None")
        return self.mass_per_area_kg_m2

    def to_nondimensional(self, *, freq_hz: npt.ArrayLike, accel_ms2: npt.ArrayLike | None = None,
                          pressure_pa: npt.ArrayLike | None = None) -> NondimensionalExcitation:
        """``F`` and ``omega`` of a base acceleration or a pressure (eq. 2.3, 2.27, 2.28, 2.31).

        Parameters
        ----------
        freq_hz : float or array
            Excitation frequency [Hz].
        accel_ms2, pressure_pa : float or array
            Exactly one of them: base-acceleration amplitude [m/s^2] or pressure amplitude [Pa].

        Returns
        -------
        NondimensionalExcitation

        Raises
        ------
        ParameterError
            If neither or both amplitudes are given, or a value is out of range.
        """
        if (accel_ms2 is None) == (pressure_pa is None):
            raise ParameterError(
                f"give exactly one of `accel_ms2` and `pressure_pa`, was accel_ms2={accel_ms2!r}, "
                f"pressure_pa={pressure_pa!r}"
            )
        if accel_ms2 is not None:
            F = F_from_accel(accel_ms2, self.participation, self.omega_s_rad_s, self.gap_m)
        else:
            F = F_from_pressure(pressure_pa, self.participation, self._mass_per_area(),  # type: ignore[arg-type]
                                self.omega_s_rad_s, self.gap_m)
        return NondimensionalExcitation(F=F, omega=omega_from_freq(freq_hz, self.f_s_hz))

    def to_physical(self, F: npt.ArrayLike, omega: npt.ArrayLike) -> PhysicalExcitation:
        """Frequency, base acceleration and pressure giving nondimensional ``F``, ``omega``.

        Parameters
        ----------
        F : float or array
            Nondimensional forcing amplitude, >= 0.
        omega : float or array
            Nondimensional forcing frequency, >= 0.

        Returns
        -------
        PhysicalExcitation
            ``pressure_pa`` is None when ``mass_per_area_kg_m2`` is None.

        Raises
        ------
        ParameterError
            If a value is out of range.
        """
        accel = accel_ms2_from_F(F, self.participation, self.omega_s_rad_s, self.gap_m)
        pressure = None if self.mass_per_area_kg_m2 is None else accel * self.mass_per_area_kg_m2
        return PhysicalExcitation(freq_hz=freq_hz_from_omega(omega, self.f_s_hz), accel_ms2=accel,
                                  pressure_pa=pressure)

    def velocity_ms(self, v_im: npt.ArrayLike) -> FloatOrArray:
        """Physical velocity of a nondimensional one (eq. 4.4); see :func:`impact_velocity_ms`."""
        return impact_velocity_ms(v_im, self.omega_s_rad_s, self.gap_m)

    def v_im(self, velocity_ms: npt.ArrayLike) -> FloatOrArray:
        """Nondimensional velocity of a physical one (eq. 4.4); see :func:`v_im_from_velocity`."""
        return v_im_from_velocity(velocity_ms, self.omega_s_rad_s, self.gap_m)

    def tau(self, time_s: npt.ArrayLike) -> FloatOrArray:
        """Nondimensional time ``omega_s t``; see :func:`tau_from_time`."""
        return tau_from_time(time_s, self.omega_s_rad_s)

    def time_s(self, tau: npt.ArrayLike) -> FloatOrArray:
        """Time [s] of a nondimensional time; see :func:`time_s_from_tau`."""
        return time_s_from_tau(tau, self.omega_s_rad_s)

    def x(self, displacement_m: npt.ArrayLike) -> FloatOrArray:
        """Nondimensional displacement ``x_s / h`` (eq. 2.30)."""
        return x_from_displacement(displacement_m, self.gap_m)

    def displacement_m(self, x: npt.ArrayLike) -> FloatOrArray:
        """Modal displacement ``x h`` [m] (eq. 2.30 inverted)."""
        return displacement_m_from_x(x, self.gap_m)
