"""Periodic orbits of the nondimensional SDF impact oscillator and their stability.

Two kinds of orbit are computed here:

* **1/n orbits** (one impact every ``n`` forcing periods, thesis 3.1-3.3) in
  closed form: the impact velocity solves a quadratic (eq. 3.5), the forcing
  phase follows, existence is ``v_im > 0`` with no intermediate contact, and
  the Floquet multipliers come exactly from the impact's saltation matrix.
  The derivation is in :mod:`rattle_lab.model.analysis._one_over_n`.
* **m/n orbits** (``m`` impacts in ``n`` forcing periods) by Newton shooting on
  the impact map, started from a simulated attractor
  (:func:`periodic_orbit_from_impacts`) or a guess (:func:`find_periodic_orbit`).

All quantities are nondimensional (thesis eq. 2.28-2.33).  The thesis's
roots ``v01`` / ``v02`` are, by its text (``v02`` grows with ``F`` and is the
only positive root when ``b < 0``), the smaller / larger root; they are called
``"lo"`` / ``"hi"`` here.  (The thesis's formulas 3.9-3.10 print them the other
way round for ``a < 0``.)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams
from . import _one_over_n as _on
from ._shooting import PeriodicOrbit, find_periodic_orbit, impact_map, periodic_orbit_from_impacts

Branch = Literal["lo", "hi"]
Instability = Literal["none", "saddle-node", "period-doubling"]
EventKind = Literal["grazing", "saddle-node", "period-doubling", "secondary-grazing"]

__all__ = [
    "OneOverNOrbit",
    "BranchEvent",
    "PeriodicOrbit",
    "one_over_n_orbits",
    "impact_quadratic",
    "impact_velocities",
    "orbit_forcing",
    "floquet_multipliers",
    "orbit_clearance",
    "grazing_forcing",
    "saddle_node_forcing",
    "branch_events",
    "impact_map",
    "find_periodic_orbit",
    "periodic_orbit_from_impacts",
]


def _check_n(n: object) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or int(n) < 1:
        raise ParameterError(f"`n` must be an integer >= 1, was {n!r}")
    return int(n)


def _check_model(zeta: float, e: float) -> tuple[float, float]:
    zeta, e = float(zeta), float(e)
    if not (math.isfinite(zeta) and zeta >= 0.0):
        raise ParameterError(f"`zeta` must be >= 0, was {zeta}")
    if not (math.isfinite(e) and 0.0 <= e <= 1.0):
        raise ParameterError(f"`e` must be in [0, 1], was {e}")
    return zeta, e


def _check_omega(omega: ArrayLike) -> np.ndarray:
    w = np.asarray(omega, dtype=float)
    if not np.all(np.isfinite(w) & (w > 0.0)):
        bad = w[~(np.isfinite(w) & (w > 0.0))].ravel()[0] if w.ndim else w
        raise ParameterError(f"`omega` must be finite and > 0, was {float(bad)}")
    return w


# ---------------------------------------------------------------------------
# Vectorised closed forms
# ---------------------------------------------------------------------------

def impact_quadratic(n: int, omega: ArrayLike, zeta: float, e: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coefficients of the impact-velocity quadratic, eq. (3.5) of the thesis.

    ``a v^2 + b v + c = 0`` with ``c = F^2 + c'``, in the variable ``v = v_im``
    (incoming impact velocity, nondimensional).  For the thesis's ``v0 = e v_im``
    divide ``a`` by ``e^2`` and ``b`` by ``e``.

    Parameters
    ----------
    n : int
        Forcing periods per impact (>= 1).
    omega : array_like
        Forcing frequency, nondimensional, > 0.
    zeta, e : float
        Damping ratio (>= 0) and coefficient of restitution (in [0, 1]).

    Returns
    -------
    a, b, c_prime : ndarray
        ``a = -D (p1^2 + q^2) < 0``, ``b = 2 D p1``, ``c' = -D < 0`` where
        ``D = (1 - omega^2)^2 + (2 zeta omega)^2`` (see
        :mod:`rattle_lab.model.analysis._one_over_n`).

    Examples
    --------
    >>> import numpy as np
    >>> a, b, cp = impact_quadratic(2, 0.95, 0.05, 0.6)
    >>> bool(a < 0 and cp < 0 and np.isclose(cp, -((1 - 0.95**2)**2 + 0.095**2)))
    True
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    return _on.quadratic(_on.family(n, _check_omega(omega), zeta, e))


def impact_velocities(n: int, F: ArrayLike, omega: ArrayLike, zeta: float, e: float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Both roots ``(v_lo, v_hi)`` of eq. (3.5): the 1/n orbits' impact velocities.

    Returns NaN where the roots are complex (below the saddle-node, eq. 3.11).
    Roots ``<= 0`` are returned as computed; they are not physical orbits.

    Examples
    --------
    >>> import numpy as np
    >>> lo, hi = impact_velocities(1, 0.2, 1.0, 0.05, 0.6)
    >>> bool(lo < 0 < hi and np.isclose(hi, 0.3289, atol=1e-4))
    True
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    F = np.asarray(F, dtype=float)
    if np.any(~np.isfinite(F) | (F < 0)):
        raise ParameterError(f"`F` must be finite and >= 0, was {F}")
    return _on.roots(_on.family(n, _check_omega(omega), zeta, e), F)


def orbit_forcing(n: int, omega: ArrayLike, v_im: ArrayLike, zeta: float, e: float
                  ) -> tuple[np.ndarray, np.ndarray]:
    """The forcing ``(F, phase)`` that has a 1/n orbit with impact velocity ``v_im``.

    The 1/n orbit is fixed by ``(omega, v_im)`` alone; ``F`` and the forcing
    phase at the impact (in ``[0, 2 pi)``) follow explicitly.

    Examples
    --------
    >>> import numpy as np
    >>> F, phase = orbit_forcing(1, 1.0, 0.3289, 0.05, 0.6)
    >>> bool(np.isclose(F, 0.2, atol=1e-4))
    True
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    return _on.forcing(_on.family(n, _check_omega(omega), zeta, e), v_im)


def floquet_multipliers(n: int, omega: ArrayLike, v_im: ArrayLike, zeta: float, e: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Floquet multipliers of the 1/n orbit with impact velocity ``v_im``, larger first.

    Eigenvalues of the monodromy ``S Phi(T)`` (saltation matrix of the impact
    times the flight's transition matrix), from its trace and determinant.

    Examples
    --------
    >>> import numpy as np
    >>> l1, l2 = floquet_multipliers(1, 1.0, 0.3289, 0.05, 0.6)
    >>> bool(np.isclose(abs(l1 * l2), 0.36 * np.exp(-0.2 * np.pi)))
    True
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    tr, det = _on.trace_det(_on.family(n, _check_omega(omega), zeta, e), v_im)
    return _on.multipliers(tr, det)


def orbit_clearance(n: int, omega: ArrayLike, v_im: ArrayLike, zeta: float, e: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``(1 - x_max, t_max)`` over the interior local maxima of the 1/n orbit.

    Positive clearance means no intermediate contact; it is ``+inf`` where
    ``x`` has no interior local maximum.  ``t_max`` is the time after the
    impact.  The thesis's ``r`` (eq. 3.15) is ``-clearance``.  The maxima are
    enumerated rigorously (see :mod:`rattle_lab.model.analysis._motion`), not sampled.
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    return _on.clearance(_on.family(n, _check_omega(omega), zeta, e), v_im)


def grazing_forcing(omega: ArrayLike, zeta: float) -> np.ndarray:
    """Eq. (3.4): the forcing at which the linear (impact-free) response just touches the stop.

    ``F = sqrt((1 - omega^2)^2 + (2 zeta omega)^2)``, nondimensional.

    Examples
    --------
    >>> import numpy as np
    >>> bool(np.isclose(grazing_forcing(1.0, 0.05), 0.1))
    True
    """
    w = _check_omega(omega)
    zeta, _ = _check_model(zeta, 0.0)
    return np.sqrt(((1.0 - w) * (1.0 + w)) ** 2 + (2.0 * zeta * w) ** 2)


def saddle_node_forcing(n: int, omega: ArrayLike, zeta: float, e: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (3.11): the forcing ``F_sn`` where the two 1/n roots merge, and the velocity there.

    ``F_sn = sqrt(D) |q| / sqrt(p1^2 + q^2)`` at ``v_sn = p1 / (p1^2 + q^2)``
    (eq. 3.13).  Returned for every ``omega``; the fold is a physical orbit
    only where ``v_sn > 0`` (``b > 0``) and its clearance is positive.

    Examples
    --------
    >>> import numpy as np
    >>> F_sn, v_sn = saddle_node_forcing(1, 1.2295757, 0.05, 0.6)
    >>> bool(np.isclose(F_sn, 0.2, atol=1e-6) and v_sn > 0)
    True
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    fam = _on.family(n, _check_omega(omega), zeta, e)
    A = fam.p1 ** 2 + fam.q ** 2
    return np.sqrt(fam.D) * np.abs(fam.q) / np.sqrt(A), fam.p1 / A


# ---------------------------------------------------------------------------
# One orbit, fully described
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class OneOverNOrbit:
    """A 1/n orbit: one impact every ``n`` forcing periods (all nondimensional).

    Attributes
    ----------
    params : SDFParams
        The model parameters.
    n : int
        Forcing periods per impact; the period is ``T = 2 n pi / omega``.
    branch : {"lo", "hi"}
        Smaller / larger root of eq. (3.5) (the thesis's ``v01`` / ``v02``).
    v_im : float
        Incoming impact velocity ``x'(T-)``; the rebound is ``-e v_im``.
    phase : float
        Forcing phase ``omega t + phi`` at the impact, in ``[0, 2 pi)`` (the
        convention of :class:`rattle_lab.model.sdf.SimImpacts`).
    period : float
        ``2 n pi / omega``.
    clearance : float
        ``1 - x_max`` over the interior local maxima of ``x`` (``+inf`` if none,
        NaN if ``v_im <= 0``); the thesis's ``r = -clearance`` (eq. 3.15).
    t_max : float
        Time after the impact of that maximum (NaN if none).
    exists : bool
        ``v_im > 0`` and ``clearance > 0``: the orbit is a motion of the model.
    multipliers : tuple of complex
        Floquet multipliers (eigenvalues of ``S Phi(T)``), larger modulus first;
        NaN if ``v_im <= 0``.
    trace, det : float
        Trace and determinant of the monodromy (``det = e^2 exp(-2 zeta T)``).
    stable : bool or None
        Both multipliers strictly inside the unit circle.  ``None`` when the
        orbit does not exist (``exists`` is False: the impact velocity is not
        positive, or the trajectory reaches the stop between impacts): a
        motion that is not one of the model has no stability verdict.
    instability : {"none", "saddle-node", "period-doubling"} or None
        Which way a multiplier is outside the unit circle: real ``> 1`` (lost
        or gained through +1, a saddle-node) or real ``< -1`` (through -1, a
        period doubling); ``None`` when the orbit does not exist.

    Notes
    -----
    Existence and stability are two verdicts: ``multipliers``, ``trace`` and
    ``det`` are those of the formal fixed point of the impact map (also where
    it is not a motion of the model, for continuation), but only an existing
    orbit is classified.
    """

    params: SDFParams
    n: int
    branch: Branch
    v_im: float
    phase: float
    period: float
    clearance: float
    t_max: float
    exists: bool
    multipliers: tuple[complex, complex]
    trace: float
    det: float
    stable: bool | None
    instability: Instability | None

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary (non-finite numbers become None)."""
        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {
            "n": self.n, "branch": self.branch, "v_im": num(self.v_im),
            "phase": num(self.phase), "period": num(self.period),
            "clearance": num(self.clearance), "t_max": num(self.t_max),
            "exists": self.exists,
            "multipliers": [[num(m.real), num(m.imag)] for m in self.multipliers],
            "multiplier_moduli": [num(abs(m)) for m in self.multipliers],
            "trace": num(self.trace), "det": num(self.det),
            "stable": self.stable, "instability": self.instability,
        }


def _classify(tr: float, det: float) -> tuple[bool, Instability]:
    p_plus = 1.0 - tr + det   # characteristic polynomial at +1
    p_minus = 1.0 + tr + det  # ... at -1
    if not (math.isfinite(p_plus) and math.isfinite(p_minus)):
        return False, "none"
    stable = p_plus > 0.0 and p_minus > 0.0 and det < 1.0
    if p_plus < 0.0:
        return stable, "saddle-node"
    if p_minus < 0.0:
        return stable, "period-doubling"
    return stable, "none"


def one_over_n_orbits(params: SDFParams, n: int) -> tuple[OneOverNOrbit, ...]:
    """Both 1/n orbits at ``params`` (thesis 3.1-3.3), physical or not.

    Parameters
    ----------
    params : SDFParams
        Nondimensional ``F``, ``omega``, ``zeta``, ``e``.
    n : int
        Forcing periods per impact (>= 1).

    Returns
    -------
    tuple of OneOverNOrbit
        ``(lo, hi)`` when eq. (3.5) has real roots, else empty.  Check
        ``exists`` on each; ``stable`` is ``None`` where it is False.

    Raises
    ------
    ParameterError
        If ``n`` is not an integer >= 1.

    Examples
    --------
    >>> import numpy as np
    >>> from rattle_lab.model.sdf import SDFParams
    >>> lo, hi = one_over_n_orbits(SDFParams(F=0.2, omega=1.1, zeta=0.05, e=0.6), 1)
    >>> (hi.exists, hi.stable), (lo.exists, lo.stable, lo.instability)
    ((True, True), (True, False, 'saddle-node'))
    """
    n = _check_n(n)
    if not isinstance(params, SDFParams):
        raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
    fam = _on.family(n, params.omega, params.zeta, params.e)
    lo, hi = _on.roots(fam, params.F)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return ()
    v = np.array([float(lo), float(hi)])
    _, phase = _on.forcing(fam, v)
    tr, det = _on.trace_det(fam, v)
    clear, t_max = _on.clearance(fam, np.where(v > 0.0, v, np.nan))
    l1, l2 = _on.multipliers(tr, det)
    out = []
    for i, branch in enumerate(("lo", "hi")):
        physical = v[i] > 0.0
        exists = bool(physical and clear[i] > 0.0)
        stable: bool | None = None
        instability: Instability | None = None
        if physical:
            mults = (complex(l1[i]), complex(l2[i]))
            if exists:
                stable, instability = _classify(float(tr[i]), float(det[i]))
        else:
            mults = (complex(math.nan, math.nan),) * 2
        out.append(OneOverNOrbit(
            params=params, n=n, branch=branch, v_im=float(v[i]),  # type: ignore[arg-type]
            phase=float(phase[i]), period=float(fam.T),
            clearance=float(clear[i]), t_max=float(t_max[i]),
            exists=exists, multipliers=mults,
            trace=float(tr[i]) if physical else math.nan, det=float(det[i]),
            stable=stable, instability=instability))
    return tuple(out)


# ---------------------------------------------------------------------------
# Bifurcations met along a frequency sweep at fixed F
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class BranchEvent:
    """A bifurcation of a 1/n branch met when ``omega`` is swept at fixed ``F``.

    Attributes
    ----------
    n : int
        The orbit type 1/n.
    kind : {"grazing", "saddle-node", "period-doubling", "secondary-grazing"}
        ``grazing``: ``v_im = 0`` (born from the impact-free orbit, on eq. 3.4);
        ``saddle-node``: the two roots merge (eq. 3.11; multiplier +1);
        ``period-doubling``: a multiplier passes -1;
        ``secondary-grazing``: an interior maximum of ``x`` touches the stop.
    branch : {"lo", "hi", "both"}
        The root on which it happens (``both`` for the saddle-node).
    omega : float
        Where (nondimensional frequency), to ``xtol = 1e-12``.
    F : float
        The fixed forcing amplitude.
    v_im : float
        Impact velocity there.
    exists : bool
        The orbit exists (``v_im > 0``, positive clearance) at
        ``omega +- 1e-6`` on at least one side: the event is physical.
    stable : bool
        The orbit is stable on at least one side where it exists.
    """

    n: int
    kind: EventKind
    branch: Literal["lo", "hi", "both"]
    omega: float
    F: float
    v_im: float
    exists: bool
    stable: bool

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary."""
        return {"n": self.n, "kind": self.kind, "branch": self.branch, "omega": self.omega,
                "F": self.F, "v_im": self.v_im, "exists": self.exists, "stable": self.stable}


def _branch_quantities(n: int, F: float, omega: np.ndarray, zeta: float, e: float,
                       branch: str) -> dict[str, np.ndarray]:
    fam = _on.family(n, omega, zeta, e)
    lo, hi = _on.roots(fam, F)
    v = np.asarray(lo if branch == "lo" else hi, dtype=float)
    vv = np.where(v > 0.0, v, np.nan)
    tr, det = _on.trace_det(fam, vv)
    clear, _ = _on.clearance(fam, vv)
    return {"v": v, "p_minus": 1.0 + tr + det, "p_plus": 1.0 - tr + det, "clearance": clear,
            "disc": _on.discriminant(fam, F)}


def branch_events(n: int, F: float, *, omega_range: tuple[float, float], zeta: float, e: float,
                  n_omega: int = 400) -> tuple[BranchEvent, ...]:
    """Bifurcations of the 1/n orbits met when ``omega`` sweeps ``omega_range`` at fixed ``F``.

    Each boundary condition (``v_im = 0``, zero discriminant, ``P(-1) = 0``,
    zero clearance) is bracketed on a grid of ``n_omega`` frequencies and
    solved by Brent's method to ``xtol = 1e-12``; two events of one kind
    closer than the grid step can be missed.

    Parameters
    ----------
    n : int
        Orbit type 1/n.
    F : float
        Forcing amplitude, nondimensional, > 0.
    omega_range : (float, float)
        Sweep interval, ``0 < lo < hi``.
    zeta, e : float
        Damping ratio and restitution.
    n_omega : int
        Grid points of the bracketing scan (>= 3).

    Returns
    -------
    tuple of BranchEvent
        Sorted by ``omega``.

    Examples
    --------
    >>> ev = branch_events(1, 0.2, omega_range=(1.1, 1.3), zeta=0.05, e=0.6, n_omega=50)
    >>> [(x.kind, round(x.omega, 3)) for x in ev]
    [('saddle-node', 1.23)]
    """
    n = _check_n(n)
    zeta, e = _check_model(zeta, e)
    F = float(F)
    if not (math.isfinite(F) and F > 0.0):
        raise ParameterError(f"`F` must be finite and > 0, was {F}")
    w_lo, w_hi = (float(x) for x in omega_range)
    if not (math.isfinite(w_lo) and math.isfinite(w_hi) and 0.0 < w_lo < w_hi):
        raise ParameterError(f"`omega_range` must satisfy 0 < lo < hi, was {omega_range}")
    if int(n_omega) < 3:
        raise ParameterError(f"`n_omega` must be >= 3, was {n_omega}")
    grid = np.linspace(w_lo, w_hi, int(n_omega))
    events: list[BranchEvent] = []

    def scalar(branch: str, key: str) -> Callable[[float], float]:
        return lambda w: float(_branch_quantities(n, F, np.array([w]), zeta, e, branch)[key][0])

    def side_info(branch: str, w: float) -> tuple[bool, bool]:
        ws = np.array([w - 1e-6, w + 1e-6])
        exists_any, stable_any = False, False
        for b in (("lo", "hi") if branch == "both" else (branch,)):
            q = _branch_quantities(n, F, ws, zeta, e, b)
            ex = (q["v"] > 0.0) & (q["clearance"] > 0.0)
            st = ex & (q["p_minus"] > 0.0) & (q["p_plus"] > 0.0)
            exists_any |= bool(np.any(ex))
            stable_any |= bool(np.any(st))
        return exists_any, stable_any

    def add(kind: str, branch: str, func: Callable[[float], float], a: float, b: float) -> None:
        w = brentq(func, a, b, xtol=1e-12, rtol=4 * np.finfo(float).eps)
        fam = _on.family(n, w, zeta, e)
        if branch == "both":
            v = float(fam.p1 / (fam.p1 ** 2 + fam.q ** 2))
        else:
            lo, hi = _on.roots(fam, F)
            v = float(lo if branch == "lo" else hi)
        ex, st = side_info(branch, w)
        events.append(BranchEvent(n=n, kind=kind, branch=branch, omega=float(w), F=F,  # type: ignore[arg-type]
                                  v_im=v, exists=ex, stable=st))

    def brackets(values: np.ndarray) -> np.ndarray:
        ok = np.isfinite(values[:-1]) & np.isfinite(values[1:])
        return np.flatnonzero(ok & (np.sign(values[:-1]) != np.sign(values[1:])))

    disc = _on.discriminant(_on.family(n, grid, zeta, e), F)
    for i in brackets(disc):
        add("saddle-node", "both",
            lambda w: float(_on.discriminant(_on.family(n, w, zeta, e), F)), grid[i], grid[i + 1])
    # The branches end at the saddle-nodes: add points just on their real side, so that
    # events in the grid cell of a saddle-node are bracketed too.
    extra = [ev.omega + d for ev in events for d in (-1e-9, 1e-9)]
    grid = np.unique(np.concatenate([grid, np.clip(extra, w_lo, w_hi)]))
    for branch in ("lo", "hi"):
        q = _branch_quantities(n, F, grid, zeta, e, branch)
        for i in brackets(q["v"]):
            add("grazing", branch, scalar(branch, "v"), grid[i], grid[i + 1])
        for i in brackets(q["p_minus"]):
            add("period-doubling", branch, scalar(branch, "p_minus"), grid[i], grid[i + 1])
        clear = np.where(np.isinf(q["clearance"]), 1.0, q["clearance"])
        clearance_of = scalar(branch, "clearance")

        def finite_clearance(w: float, f: Callable[[float], float] = clearance_of) -> float:
            c = f(w)
            return 1.0 if math.isinf(c) else c  # +inf: no interior maximum at all

        for i in brackets(clear):
            add("secondary-grazing", branch, finite_clearance, grid[i], grid[i + 1])
    return tuple(sorted(events, key=lambda ev: ev.omega))
