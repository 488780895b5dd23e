"""The modal plate-striker system: modes, damping, forcing, striker, contact laws.

A plate's deflection is ``w(x, y, t) = sum_k q_k(t) W_k(x, y)`` (thesis eq. 2.4)
and each mode obeys (eq. 2.10, with the contact force added)::

    M_k (q_k'' + 2 zeta_k omega_k q_k' + omega_k**2 q_k) = L_k P_e cos(Omega t + phi) - W_k(x_s, y_s) f_c

with the modal mass ``M_k = rho h_p int W_k**2 dA = rho h_p a**2 Q2_k`` (eq. 2.13,
2.17), the load integral ``L_k = int W_k dA = a**2 Q1_k`` (eq. 2.14, 2.16) of the
uniform pressure, and the contact force ``f_c >= 0`` that the striker at
``(x_s, y_s)`` exerts when the plate's deflection there reaches the gap.  The
model works in mass-normalised coordinates ``p_k = sqrt(M_k) q_k``::

    p_k'' + 2 zeta_k omega_k p_k' + omega_k**2 p_k = phi_k cos(theta) - beta_k f_c,
    phi_k = L_k P_e / sqrt(M_k),   beta_k = W_k(x_s, y_s) / sqrt(M_k),

so that the deflection at the striker is ``delta + gap = sum_k beta_k p_k`` and
the modal energy is ``sum_k (p_k'**2 + omega_k**2 p_k**2) / 2``.  The effective
mass of the plate at the striker, ``1 / sum_k beta_k**2``, falls as modes are
added (a plate's point impedance is finite): a rigid contact then becomes a
cluster of micro-impacts, and a compliant contact is the law that converges in N.

Omitted modes (issue 24)
    A truncated sum has neither the plate's local impedance nor the flexibility of the
    modes it leaves out.  With ``local_impedance_n_s_m = Z > 0`` the omitted modes are
    represented at the contact point by a spring ``k_r`` in parallel with a dashpot ``Z``,
    in series between the retained modes and the striker: the contact point sits at
    ``sum_k beta_k p_k - r`` and the local deflection ``r`` obeys ``k_r r + Z r' = f_c``.
    Its mobility ``i omega / (k_r + i omega Z)`` is the omitted modes' static residual
    flexibility ``1 / k_r`` well below their frequencies (the residual-flexibility or
    mode-acceleration correction, Craig & Kurdila, *Fundamentals of Structural Dynamics*,
    2nd ed., 2006, section 14.3) and the infinite-plate point impedance
    ``Z = 8 sqrt(D m'')`` well above (Cremer, Heckl & Petersson, *Structure-Borne Sound*,
    3rd ed., 2005, section 5.3; the plate model of Zener, Phys. Rev. 59, 669 (1941)).
    :func:`plate_system` sets both from the asymptotic modal density: a point of a thin
    plate has ``sum_k beta_k**2 delta(omega - omega_k) ~ 2 / (pi Z)`` on average, so the
    modes above the cut ``omega_c`` (midway between the last retained and the first
    omitted mode) have the residual flexibility ``2 / (pi Z omega_c)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.plate import Plate

ContactName = Literal["rigid", "kelvin-voigt", "hertz"]
CONTACT_NAMES: tuple[str, ...] = ("rigid", "kelvin-voigt", "hertz")

#: Thesis FEM plate (section 5.1.1): a = 0.254 m clamped, b = 0.2286 m free, 1 mm aluminium.
THESIS_PLATE = Plate(a_m=0.254, b_m=0.2286, h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0, edges="CFCF")
#: Thesis striker (section 5.1.1): steel truss, length 0.019 m, cross-section 0.4 cm^2;
#: axial stiffness E A / L with E = 2.1e11 Pa (the text's "7 x 2^11" is read as steel's modulus).
THESIS_STRIKER_STIFFNESS_N_M = 2.1e11 * 0.4e-4 / 0.019
#: Hertz constant (4/3) E* sqrt(R) of a steel ball tip of radius 5 mm on aluminium
#: (E* from E, nu of both: 2.1e11, 0.3 and 7e10, 0.34).
THESIS_HERTZ_N_M15 = 4.0 / 3.0 / ((1 - 0.3**2) / 2.1e11 + (1 - 0.34**2) / 7e10) * math.sqrt(5e-3)


#: Beam functions per side for the modal model's Ritz solve: 24 x 24 resolves the first
#: ~100 modes of the thesis plate; lambda_1 of CFCF (free edges converge slowly, from
#: above) moves by 3e-4 relative from 24 to 28 terms.
MODAL_N_TERMS = 24
#: At most this many terms per side.  (Until 29 Nov 2026 this was 32: from 28 terms the
#: solve's tie-breaking between (numerically) equal eigenvalues took modes of different
#: symmetry 1e3 apart in lambda**2 for equal and swapped their shapes, which looked like a
#: basis that "mixes up modes" from 34 terms; fixed in :func:`~rattle_lab.model.plate._ritz.
#: _rotate_degenerate`.  With the fix, 32, 36, 40 and 48 terms give the same first 20
#: excited modes.)  48 terms hold 576 functions of each symmetry, enough for N = 256
#: excited modes; the solve takes about 12 s.
MODAL_N_TERMS_MAX = 48


def _pos(name: str, v: float, allow_zero: bool = False) -> float:
    x = float(v)
    if not math.isfinite(x) or x < 0 or (x == 0 and not allow_zero):
        raise ParameterError(f"`{name}` must be finite and {'>=' if allow_zero else '>'} 0, was {v}")
    return x


@dataclass(frozen=True)
class RigidContact:
    """Rigid unilateral contact with Newton restitution ``e`` at the contact point.

    Attributes
    ----------
    e : float
        Restitution of the contact-point velocity, 0 <= e <= 1 (nondimensional).
    """

    e: float = 0.8
    name: str = field(default="rigid", init=False)

    def __post_init__(self) -> None:
        e = float(self.e)
        if not (0.0 <= e <= 1.0):
            raise ParameterError(f"`e` must lie in [0, 1], was {self.e}")
        object.__setattr__(self, "e", e)


@dataclass(frozen=True)
class KelvinVoigtContact:
    """Linear spring-dashpot contact: ``f_c = k delta + c delta'`` while > 0 (and delta > 0).

    Attributes
    ----------
    stiffness_n_m : float
        Striker stiffness ``k`` [N/m] (default: the thesis's truss striker, E A / L).
    damping_n_s_m : float
        Striker damping ``c`` [N s/m], >= 0.
    """

    stiffness_n_m: float = THESIS_STRIKER_STIFFNESS_N_M
    damping_n_s_m: float = 0.0
    name: str = field(default="kelvin-voigt", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness_n_m", _pos("stiffness_n_m", self.stiffness_n_m))
        object.__setattr__(self, "damping_n_s_m", _pos("damping_n_s_m", self.damping_n_s_m, True))


@dataclass(frozen=True)
class HertzContact:
    """Hertz contact ``f_c = k_H delta**1.5`` while ``delta > 0``.

    Attributes
    ----------
    stiffness_n_m15 : float
        ``k_H`` [N/m^1.5] (default: a 5 mm steel ball tip on aluminium).
    """

    stiffness_n_m15: float = THESIS_HERTZ_N_M15
    name: str = field(default="hertz", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness_n_m15", _pos("stiffness_n_m15", self.stiffness_n_m15))


Contact = RigidContact | KelvinVoigtContact | HertzContact


def contact_from_name(name: str, *, e: float = 0.8, stiffness_n_m: float | None = None,
                      damping_n_s_m: float = 0.0, hertz_n_m15: float | None = None) -> Contact:
    """The contact law named ``name`` ("rigid", "kelvin-voigt", "hertz")."""
    if name == "rigid":
        return RigidContact(e=e)
    if name == "kelvin-voigt":
        return KelvinVoigtContact(THESIS_STRIKER_STIFFNESS_N_M if stiffness_n_m is None else stiffness_n_m,
                                  damping_n_s_m)
    if name == "hertz":
        return HertzContact(THESIS_HERTZ_N_M15 if hertz_n_m15 is None else hertz_n_m15)
    raise ParameterError(f"`contact` must be one of {CONTACT_NAMES}, was {name!r}")


@dataclass(frozen=True, eq=False)
class ModalSystem:
    """N plate modes, a uniform harmonic pressure and a striker behind a gap.

    Attributes
    ----------
    omega_rad_s : numpy.ndarray
        Modal angular frequencies ``omega_k`` [rad/s], shape (N,), > 0.
    zeta : numpy.ndarray
        Modal damping ratios, 0 <= zeta_k < 1 (nondimensional).
    modal_mass_kg : numpy.ndarray
        ``M_k = rho h_p int W_k**2 dA`` [kg] (eq. 2.13 with the shapes' own normalisation).
    load_m2 : numpy.ndarray
        ``L_k = int W_k dA`` [m^2] (eq. 2.14): the participation in a uniform pressure.
    shape_at_striker : numpy.ndarray
        ``W_k(x_s, y_s)`` (nondimensional, the shapes' normalisation).
    gap_m : float
        Distance from the plate at rest to the striker [m], > 0.
    pressure_pa : float
        Amplitude ``P_e`` of the uniform pressure ``P_e cos(Omega t + phi)`` [Pa], >= 0.
    freq_hz : float
        Forcing frequency ``Omega / 2 pi`` [Hz], > 0.
    phase_rad : float
        Forcing phase ``phi`` at t = 0 [rad].
    plate : Plate or None
        The plate the modes came from (None for hand-built systems).
    striker_xi, striker_eta : float
        Striker position ``(x_s/a, y_s/b)`` (nan for hand-built systems).
    modes : object
        The :class:`rattle_lab.model.plate.PlateModes` used (None for hand-built systems);
        gives the shapes anywhere for the sound.
    local_impedance_n_s_m : float
        ``Z`` [N s/m] of the omitted modes' element at the contact point (module
        docstring); 0 (default): no element, the plain truncated sum.
    residual_compliance_m_n : float
        ``1 / k_r`` [m/N], the omitted modes' static flexibility at the contact point;
        > 0 when ``Z > 0``, 0 otherwise.
    residual_volume_m2_kg : float
        ``eta`` [m^2/kg]: the omitted modes' volume acceleration per newton of the
        element's dashpot force, ``1/m'' - sum_k L_k W_k(x_s, y_s) / M_k`` (the full sum
        is ``1/m''`` by completeness); radiates as a baffled point source at the
        striker (:func:`~rattle_lab.model.modal.residual_pressure`).
    """

    omega_rad_s: np.ndarray
    zeta: np.ndarray
    modal_mass_kg: np.ndarray
    load_m2: np.ndarray
    shape_at_striker: np.ndarray
    gap_m: float
    pressure_pa: float
    freq_hz: float
    phase_rad: float = 0.0
    plate: Plate | None = None
    striker_xi: float = float("nan")
    striker_eta: float = float("nan")
    modes: object = None
    local_impedance_n_s_m: float = 0.0
    residual_compliance_m_n: float = 0.0
    residual_volume_m2_kg: float = 0.0

    def __post_init__(self) -> None:
        arrays = {}
        n = None
        for name in ("omega_rad_s", "zeta", "modal_mass_kg", "load_m2", "shape_at_striker"):
            arr = np.array(getattr(self, name), dtype=float).reshape(-1)
            if n is None:
                n = arr.size
            if arr.size != n or n == 0:
                raise ParameterError(f"`{name}` must have one value per mode ({n}), had {arr.size}")
            if not np.all(np.isfinite(arr)):
                raise ParameterError(f"`{name}` must be finite, was {arr}")
            arr.setflags(write=False)
            arrays[name] = arr
        if np.any(arrays["omega_rad_s"] <= 0):
            raise ParameterError(f"`omega_rad_s` must be > 0 (rigid-body modes are not modelled), was "
                                 f"{arrays['omega_rad_s']}")
        z = arrays["zeta"]
        if np.any((z < 0) | (z >= 1)):
            k = int(np.flatnonzero((z < 0) | (z >= 1))[0])
            raise ParameterError(f"`zeta` must satisfy 0 <= zeta < 1 for every mode, mode {k + 1} had {z[k]}")
        if np.any(arrays["modal_mass_kg"] <= 0):
            raise ParameterError(f"`modal_mass_kg` must be > 0, was {arrays['modal_mass_kg']}")
        for name, arr in arrays.items():
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "gap_m", _pos("gap_m", self.gap_m))
        object.__setattr__(self, "pressure_pa", _pos("pressure_pa", self.pressure_pa, True))
        object.__setattr__(self, "freq_hz", _pos("freq_hz", self.freq_hz))
        ph = float(self.phase_rad)
        if not math.isfinite(ph):
            raise ParameterError(f"`phase_rad` must be finite, was {self.phase_rad}")
        object.__setattr__(self, "phase_rad", ph)
        # Shapes are normalised to order one (1 at the centre or at max |W|): below 1e-9 the
        # striker is on a node line to rounding (e.g. a clamped edge gives ~5e-16).
        if not np.any(np.abs(self.shape_at_striker) > 1e-9):
            raise ParameterError("the striker sits on a node line of every mode (all |W_k(x_s, y_s)| <= 1e-9)")
        Zl = _pos("local_impedance_n_s_m", self.local_impedance_n_s_m, True)
        Gr = _pos("residual_compliance_m_n", self.residual_compliance_m_n, True)
        if (Zl > 0) != (Gr > 0):
            raise ParameterError("`local_impedance_n_s_m` and `residual_compliance_m_n` must be both > 0 "
                                 f"(omitted modes represented) or both 0, were {Zl} and {Gr}")
        eta = float(self.residual_volume_m2_kg)
        if not math.isfinite(eta):
            raise ParameterError(f"`residual_volume_m2_kg` must be finite, was {self.residual_volume_m2_kg}")
        object.__setattr__(self, "local_impedance_n_s_m", Zl)
        object.__setattr__(self, "residual_compliance_m_n", Gr)
        object.__setattr__(self, "residual_volume_m2_kg", eta)
        W = 2.0 * math.pi * self.freq_hz
        if np.any((self.zeta == 0) & (self.omega_rad_s == W) & (self.pressure_pa > 0)):
            raise ParameterError("undamped resonance (zeta = 0 and omega_k = Omega) has no periodic response")

    # -------------------------------------------------------------- derived, mass-normalised
    @property
    def n_modes(self) -> int:
        """Number of modes N."""
        return int(self.omega_rad_s.size)

    @property
    def Omega_rad_s(self) -> float:
        """Forcing angular frequency [rad/s]."""
        return 2.0 * math.pi * self.freq_hz

    @property
    def beta(self) -> np.ndarray:
        """``W_k(x_s, y_s) / sqrt(M_k)`` [kg^-1/2]."""
        return np.asarray(self.shape_at_striker / np.sqrt(self.modal_mass_kg))

    @property
    def phi(self) -> np.ndarray:
        """Mass-normalised load amplitude ``L_k P_e / sqrt(M_k)`` [N kg^-1/2]."""
        return np.asarray(self.load_m2 * self.pressure_pa / np.sqrt(self.modal_mass_kg))

    @property
    def corrected(self) -> bool:
        """Whether the omitted modes are represented at the contact point (``Z > 0``)."""
        return self.local_impedance_n_s_m > 0.0

    def point_mobility(self, omega_rad_s: npt.ArrayLike) -> np.ndarray:
        """Driving-point mobility ``v / F`` [m/(N s)] at the striker, complex, ``e^{i omega t}``.

        ``sum_k beta_k**2 i omega / (omega_k**2 - omega**2 + 2 i zeta_k omega_k omega)``
        plus the omitted modes' element ``i omega / (k_r + i omega Z)`` when present.
        """
        w = np.asarray(omega_rad_s, dtype=float)
        b2 = self.beta**2
        den = (self.omega_rad_s[:, None] ** 2 - w[None, :] ** 2
               + 2j * (self.zeta * self.omega_rad_s)[:, None] * w[None, :])
        y = np.sum(b2[:, None] * 1j * w[None, :] / den, axis=0)
        if self.corrected:
            y = y + 1j * w / (1.0 / self.residual_compliance_m_n + 1j * w * self.local_impedance_n_s_m)
        return np.asarray(y.reshape(np.shape(w)))

    @property
    def effective_mass_kg(self) -> float:
        """Plate mass seen at the striker, ``1 / sum_k beta_k**2`` [kg]."""
        return float(1.0 / np.sum(self.beta**2))

    def replace(self, **changes: object) -> ModalSystem:
        """A copy with some fields changed (validated again)."""
        values = {name: getattr(self, name) for name in self.__dataclass_fields__}
        values.update(changes)
        return ModalSystem(**values)  # type: ignore[arg-type]


def plate_system(plate: Plate = THESIS_PLATE, *, n_modes: int = 8, gap_m: float = 1e-3,
                 striker_xy_m: tuple[float, float] | None = None, pressure_pa: float = 285.0,
                 freq_hz: float = 99.8, zeta: float | npt.ArrayLike = 0.05, phase_rad: float = 0.0,
                 n_terms: int | None = None, skip_unexcited: bool = False,
                 omitted_modes: bool = False) -> ModalSystem:
    """The modal system of a plate from the Rayleigh-Ritz solver (closed form for SSSS).

    Parameters
    ----------
    plate : Plate
        Geometry, material and edges (default: the thesis's FEM plate, section 5.1.1).
    n_modes : int
        Number of modes N, >= 1 (the lowest N of the plate; see ``skip_unexcited``).
    gap_m : float
        Gap to the striker [m] (thesis: 1 mm).
    striker_xy_m : (float, float) or None
        Striker position ``(x_s, y_s)`` [m] on the plate; default the centre.
    pressure_pa, freq_hz, phase_rad : float
        The uniform pressure ``P_e cos(2 pi f t + phi)`` (thesis section 5.3: 285 Pa,
        99.8 Hz (omega = 0.95) or 115.6 Hz (omega = 1.1)).
    zeta : float or array_like
        Modal damping ratio(s), one value or one per mode (thesis: 2 zeta = 0.1).
    n_terms : int or None
        Beam functions per side in the Ritz solver; default :data:`MODAL_N_TERMS` (24),
        the same for every N so that a study in N keeps the same modes (more only
        where ``2 sqrt(modes solved) + 4`` exceeds it).
    skip_unexcited : bool
        Keep only modes that both the pressure and a centred striker can excite
        (doubly symmetric, ``Q1 != 0``), N of them.  Other modes take no energy from a
        centred striker and are not forced, so they do not change the motion.
    omitted_modes : bool
        Represent the modes left out at the contact point (module docstring): the
        infinite-plate impedance ``Z = 8 sqrt(D m'')`` in parallel with the residual
        flexibility ``2 / (pi Z omega_c)``, ``omega_c`` midway between the last retained
        and the next mode seen at the striker.  The CLI and ``[model] kind = "modal"``
        scenes turn it on; off here so that ``N = 1`` stays the SDF model.

    Returns
    -------
    ModalSystem

    Raises
    ------
    ParameterError
        If an argument is out of range (the striker off the plate, N < 1, ...).
    """
    from rattle_lab.model.plate import ritz_modes

    n = int(n_modes)
    if n != n_modes or n < 1:
        raise ParameterError(f"`n_modes` must be an integer >= 1, was {n_modes}")
    xs, ys = (0.5 * plate.a_m, 0.5 * plate.b_m) if striker_xy_m is None else map(float, striker_xy_m)
    if not (0.0 <= xs <= plate.a_m and 0.0 <= ys <= plate.b_m):
        raise ParameterError(f"`striker_xy_m` must lie on the plate [0, {plate.a_m}] x [0, {plate.b_m}], "
                             f"was ({xs}, {ys})")
    # the scalars first (ModalSystem checks them again): a bad one is refused before the
    # Ritz solve, which takes seconds for the CLI's 64 modes
    _pos("gap_m", gap_m)
    _pos("pressure_pa", pressure_pa, True)
    _pos("freq_hz", freq_hz)
    n_solve = 4 * n + 4 if skip_unexcited else (n + 4 if omitted_modes else n)
    terms = n_terms if n_terms is not None else min(max(MODAL_N_TERMS, int(math.ceil(2.0 * math.sqrt(n_solve))) + 4),
                                                    MODAL_N_TERMS_MAX)
    modes = ritz_modes(plate.aspect_ratio, plate.edges, nu=plate.nu, n_modes=n_solve, n_terms=terms)
    keep = np.arange(n)
    if skip_unexcited:
        keep = np.flatnonzero(np.abs(modes.Q1) > 1e-9 * np.max(np.abs(modes.Q1)))[:n]
        if keep.size < n:
            raise ParameterError(f"only {keep.size} excited modes among the first {n_solve}; lower `n_modes`")
    lam = modes.lam[keep]
    if np.any(lam <= 1e-6):
        raise ParameterError(f"plate edges {plate.edges} have rigid-body modes, which this model does not handle")
    omega = np.asarray(plate.omega_rad_s(lam), dtype=float)
    a2 = plate.a_m**2
    shape = modes.evaluate(xs / plate.a_m, ys / plate.b_m)[keep]
    z = np.broadcast_to(np.asarray(zeta, dtype=float), (keep.size,)) if np.ndim(zeta) == 0 else np.asarray(zeta)
    if z.size != keep.size:
        raise ParameterError(f"`zeta` must be one value or one per mode ({keep.size}), had {z.size}")
    mass = plate.mass_per_area_kg_m2 * a2 * modes.Q2[keep]
    extra: dict[str, float] = {}
    if omitted_modes:
        extra = _omitted(plate, modes, keep, shape, mass, a2 * modes.Q1[keep], xs, ys)
    return ModalSystem(
        omega_rad_s=omega, zeta=z, modal_mass_kg=mass,
        load_m2=a2 * modes.Q1[keep], shape_at_striker=shape, gap_m=gap_m, pressure_pa=pressure_pa,
        freq_hz=freq_hz, phase_rad=phase_rad, plate=plate, striker_xi=xs / plate.a_m,
        striker_eta=ys / plate.b_m, modes=_ModeSubset(modes, keep), **extra)


def infinite_plate_impedance(plate: Plate) -> float:
    """Driving-point impedance ``Z = 8 sqrt(D m'')`` [N s/m] of the infinite thin plate (real).

    Cremer, Heckl & Petersson, *Structure-Borne Sound* (2005), section 5.3.

    Examples
    --------
    >>> round(infinite_plate_impedance(THESIS_PLATE), 1)
    33.8
    """
    return 8.0 * math.sqrt(plate.flexural_rigidity_nm * plate.mass_per_area_kg_m2)


def _omitted(plate: Plate, modes: object, keep: np.ndarray, shape: np.ndarray, mass: np.ndarray,
             load: np.ndarray, xs: float, ys: float) -> dict[str, float]:
    """``local_impedance_n_s_m``, ``residual_compliance_m_n``, ``residual_volume_m2_kg`` of the omitted modes."""
    Z = infinite_plate_impedance(plate)
    w_all = np.asarray(plate.omega_rad_s(modes.lam), dtype=float)  # type: ignore[attr-defined]
    w_n = float(np.max(w_all[keep]))
    W_all = np.asarray(modes.evaluate(xs / plate.a_m, ys / plate.b_m), dtype=float)  # type: ignore[attr-defined, type-var]
    seen = np.abs(W_all) > 1e-9
    seen[keep] = False
    above = w_all[seen & (w_all > w_n)]
    # The next mode seen at the striker (or, if none was solved, one mean spacing above:
    # 1 / n(omega) of the doubly symmetric quarter, n = S sqrt(m''/D) / (4 pi) per rad/s).
    spacing = 4.0 * math.pi / (plate.a_m * plate.b_m * math.sqrt(plate.mass_per_area_kg_m2
                                                                  / plate.flexural_rigidity_nm)) / 4.0
    w_next = float(np.min(above)) if above.size else w_n + spacing
    w_c = 0.5 * (w_n + w_next)
    G = 2.0 / (math.pi * Z * w_c)
    eta = 1.0 / plate.mass_per_area_kg_m2 - float(np.sum(load * shape / mass))
    return {"local_impedance_n_s_m": Z, "residual_compliance_m_n": G, "residual_volume_m2_kg": eta}


@dataclass(frozen=True, eq=False)
class _ModeSubset:
    """Shapes of selected Ritz modes, evaluated anywhere (``W_k(xi, eta)``)."""

    modes: object
    keep: np.ndarray

    def evaluate(self, xi: npt.ArrayLike, eta: npt.ArrayLike) -> np.ndarray:
        return np.asarray(self.modes.evaluate(xi, eta)[self.keep])  # type: ignore[attr-defined]


def rayleigh_zeta(omega_rad_s: npt.ArrayLike, zeta_1: float = 0.05, zeta_2: float = 0.05) -> np.ndarray:
    """Rayleigh damping ``2 zeta = alpha / omega + beta omega`` through modes 1 and 2 (eq. 5.1).

    Parameters
    ----------
    omega_rad_s : array_like
        Modal angular frequencies [rad/s], at least two, the first two distinct.
    zeta_1, zeta_2 : float
        Damping ratios of the first two modes (thesis: 2 zeta = 0.1 for both).

    Returns
    -------
    numpy.ndarray
        ``zeta_k``; values >= 1 mean overdamped modes, which :class:`ModalSystem` rejects.

    Examples
    --------
    >>> import numpy as np
    >>> z = rayleigh_zeta([100.0, 200.0, 400.0])
    >>> bool(np.allclose(z[:2], 0.05))
    True
    """
    w = np.asarray(omega_rad_s, dtype=float)
    if w.size < 2 or w[0] == w[1]:
        raise ParameterError("`omega_rad_s` needs two distinct first values for Rayleigh damping")
    A = np.array([[1.0 / w[0], w[0]], [1.0 / w[1], w[1]]])
    alpha, beta = np.linalg.solve(A, [2.0 * zeta_1, 2.0 * zeta_2])
    return np.asarray(0.5 * (alpha / w + beta * w))
