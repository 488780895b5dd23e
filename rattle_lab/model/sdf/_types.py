"""Data objects of the nondimensional SDF impact oscillator.

The model (thesis eq. 2.33), in nondimensional time ``tau`` (written ``t``)::

    x'' + 2 zeta x' + x = F cos(theta(t)),    theta(t) = omega t + phi,   for x < 1
    x(t+) = x(t-),  x'(t+) = -e x'(t-)                                  at x = 1

``x`` is the modal displacement divided by the gap, so the stop is at x = 1.
All quantities here are nondimensional (thesis eq. 2.28-2.32).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.model._constants import TWO_PI


#: Smallest nonzero magnitude accepted for F, x and v: the simulator's derivative
#: bounds and Taylor coefficients would underflow below it.
TINY = 1e-150


def _finite(name: str, value: float, tiny_ok: bool = True) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(f"`{name}` must be finite, was {value}")
    if not tiny_ok and 0.0 < abs(value) < TINY:
        raise ParameterError(f"`{name}` must be 0 or of magnitude >= {TINY:g}, was {value}")
    return value


@dataclass(frozen=True)
class SDFParams:
    """Parameters of the nondimensional SDF impact oscillator.

    Attributes
    ----------
    F : float
        Forcing amplitude, nondimensional (eq. 2.31: ``F_es / (omega_s**2 h)``), >= 0.
    omega : float
        Forcing frequency over the modal frequency, nondimensional (eq. 2.28), > 0.
    zeta : float
        Modal damping ratio, nondimensional (eq. 2.32), >= 0.
    e : float
        Coefficient of restitution at the stop, 0 <= e <= 1.
    """

    F: float
    omega: float
    zeta: float
    e: float

    def __post_init__(self) -> None:
        for name in ("F", "omega", "zeta", "e"):
            object.__setattr__(self, name, _finite(name, getattr(self, name), name != "F"))
        if self.F < 0:
            raise ParameterError(f"`F` must be >= 0, was {self.F}")
        if self.omega <= 0:
            raise ParameterError(f"`omega` must be > 0, was {self.omega}")
        if self.zeta < 0:
            raise ParameterError(f"`zeta` must be >= 0, was {self.zeta}")
        if not 0.0 <= self.e <= 1.0:
            raise ParameterError(f"`e` must be in [0, 1], was {self.e}")

    @property
    def period(self) -> float:
        """Forcing period ``2 pi / omega`` (nondimensional time)."""
        return TWO_PI / self.omega

    def replace(self, **changes: float) -> SDFParams:
        """Return a copy with some parameters changed (validated again)."""
        values = {"F": self.F, "omega": self.omega, "zeta": self.zeta, "e": self.e}
        values.update(changes)
        return SDFParams(**values)


@dataclass(frozen=True)
class SDFState:
    """State of the oscillator at time ``t``.

    Attributes
    ----------
    t : float
        Nondimensional time.
    x : float
        Displacement over the gap, <= 1.
    v : float
        Velocity ``dx/dt``.
    theta : float
        Forcing phase ``omega t + phi`` at time ``t``, reduced to [0, 2 pi).
        Carrying ``theta`` (rather than ``phi``) from one call to the next keeps
        the forcing phase continuous when ``omega`` changes between calls, as
        the thesis's ``setF_related`` does.
    stuck : bool
        True while the mass rests on the stop (x = 1, v = 0) pushed by the force.
    """

    t: float = 0.0
    x: float = 0.0
    v: float = 0.0
    theta: float = 0.0
    stuck: bool = False

    def __post_init__(self) -> None:
        for name in ("t", "x", "v", "theta"):
            object.__setattr__(self, name, _finite(name, getattr(self, name)))
        if self.x > 1.0:
            raise ParameterError(f"`x` must be <= 1 (the stop is at x = 1), was {self.x}")
        if self.stuck and (self.x != 1.0 or self.v != 0.0):
            raise ParameterError("a stuck state must have x = 1 and v = 0")
        object.__setattr__(self, "theta", math.fmod(self.theta, TWO_PI) % TWO_PI)

    @classmethod
    def _from_kernel(cls, t: float, x: float, v: float, theta: float, stuck: bool) -> SDFState:
        """The state a simulator kernel ended in, without re-validation.

        The kernel's state is finite with ``x <= 1`` and a stuck state on the stop by
        construction (checked cheaply; otherwise the checked constructor raises); the
        phase is reduced as ``__post_init__`` does.
        """
        if not (math.isfinite(t + x + v + theta) and x <= 1.0
                and (not stuck or (x == 1.0 and v == 0.0))):
            return cls(t=t, x=x, v=v, theta=theta, stuck=stuck)
        obj = object.__new__(cls)
        d = obj.__dict__
        d["t"] = t
        d["x"] = x
        d["v"] = v
        d["theta"] = math.fmod(theta, TWO_PI) % TWO_PI
        d["stuck"] = stuck
        return obj


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class SimImpacts:
    """Every impact of a run, in time order.

    Attributes
    ----------
    t : ndarray
        Impact times (nondimensional).
    phase : ndarray
        Forcing phase ``omega t + phi`` at impact, reduced to [0, 2 pi).
    v_in : ndarray
        Incoming velocity ``x'(t-)`` (> 0, towards the stop).
    v_out : ndarray
        Outgoing velocity magnitude ``e * v_in`` (the mass leaves with ``-v_out``).
    """

    t: np.ndarray
    phase: np.ndarray
    v_in: np.ndarray
    v_out: np.ndarray

    def __post_init__(self) -> None:
        for name in ("t", "phase", "v_in", "v_out"):
            object.__setattr__(self, name, _ro(getattr(self, name)))

    def __len__(self) -> int:
        return int(self.t.size)

    @classmethod
    def _from_columns(cls, cols: np.ndarray) -> SimImpacts:
        """The log of a kernel's impact block ``cols``, shape (4, n), C-contiguous float.

        The block is made read-only and its rows (contiguous views) become the fields:
        the same object as ``SimImpacts(*cols)``, without a copy or check per field.
        """
        if not (cols.dtype == np.float64 and cols.flags.c_contiguous and cols.shape[0] == 4):
            return cls(t=cols[0], phase=cols[1], v_in=cols[2], v_out=cols[3])
        cols.setflags(write=False)
        obj = object.__new__(cls)
        d = obj.__dict__   # the frozen dataclass's fields, set without its __setattr__
        d["t"] = cols[0]
        d["phase"] = cols[1]
        d["v_in"] = cols[2]
        d["v_out"] = cols[3]
        return obj


@dataclass(frozen=True)
class Crossings:
    """Upward crossings of x = 0 (the thesis's ``v_{x=0}^+``).

    Attributes
    ----------
    t : ndarray
        Crossing times.
    v : ndarray
        Velocity at the crossing (> 0).
    """

    t: np.ndarray
    v: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "t", _ro(self.t))
        object.__setattr__(self, "v", _ro(self.v))

    def __len__(self) -> int:
        return int(self.t.size)


@dataclass(frozen=True)
class DenseSamples:
    """Dense output on a caller-given time grid; only the requested fields are set.

    Attributes
    ----------
    t : ndarray
        The sample times.
    x, v, a : ndarray or None
        Displacement, velocity and acceleration ``x''`` (zero while stuck).
    forced : ndarray or None
        The forced (particular, steady-state linear) part of x.
    transient : ndarray or None
        ``x - forced``: the homogeneous part carried since the last event.
    excitation : ndarray or None
        The excitation ``F cos(theta(t))``.
    """

    t: np.ndarray
    x: np.ndarray | None = None
    v: np.ndarray | None = None
    a: np.ndarray | None = None
    forced: np.ndarray | None = None
    transient: np.ndarray | None = None
    excitation: np.ndarray | None = None


@dataclass(frozen=True)
class SimResult:
    """What :func:`rattle_lab.model.sdf.simulate` returns.

    Attributes
    ----------
    params : SDFParams
        The parameters simulated.
    method : str
        ``"exact"``, ``"exact-python"`` or ``"rk4-thesis"``.
    impacts : rattle_lab.model.sdf.SimImpacts
        Every impact, in time order (chatter micro-impacts included, up to the
        accumulation point).
    accumulations : ndarray
        Times of complete-chatter accumulation points (each followed by sticking).
    sticking : ndarray
        Shape (n, 2): start and end time of each interval spent stuck on the stop.
    crossings : Crossings or None
        Upward x = 0 crossings, when asked for.
    dense : DenseSamples or None
        Samples on the requested grid, when asked for.
    state : SDFState
        The state at the end; pass it as ``state=`` to continue.
    n_events : int
        Number of events processed (impacts, releases, accumulations).
    micro_bounce : ndarray
        Shape (n, 3): start, end and estimated bounce count of each interval of
        elastic (e = 1) micro-bouncing on the stop that was averaged rather
        than followed bounce by bounce (see ``_kernel.micro_bounce``); empty
        unless e = 1 and the force pushes into the stop.  Impacts inside these
        intervals are not in ``impacts``.
    """

    params: SDFParams
    method: str
    impacts: SimImpacts
    accumulations: np.ndarray
    sticking: np.ndarray
    crossings: Crossings | None
    dense: DenseSamples | None
    state: SDFState
    n_events: int = field(default=0)
    micro_bounce: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))

    @classmethod
    def _from_kernel(cls, params: SDFParams, method: str, impacts: SimImpacts,
                     accumulations: np.ndarray, sticking: np.ndarray,
                     crossings: Crossings | None, dense: DenseSamples | None, state: SDFState,
                     n_events: int, micro_bounce: np.ndarray) -> SimResult:
        """The result of a simulator kernel, built without the frozen dataclass's per-field
        ``__setattr__`` (it has no ``__post_init__``; the same object otherwise)."""
        obj = object.__new__(cls)
        d = obj.__dict__
        d["params"] = params
        d["method"] = method
        d["impacts"] = impacts
        d["accumulations"] = accumulations
        d["sticking"] = sticking
        d["crossings"] = crossings
        d["dense"] = dense
        d["state"] = state
        d["n_events"] = n_events
        d["micro_bounce"] = micro_bounce
        return obj
