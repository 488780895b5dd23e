"""The impact map of the SDF oscillator and Newton shooting for m/n periodic orbits.

The impact map takes one impact (forcing phase ``theta``, incoming velocity
``u``) to the next.  The flight between is the closed form of
:mod:`rattle_lab.model.sdf._flow`; the next contact is located rigorously
(:func:`rattle_lab.model.analysis._motion.first_contact`), so no contact is missed
for want of a fine grid.  Its Jacobian is exact
(:func:`rattle_lab.model.analysis._saltation.impact_map_jacobian`), which Newton's
method uses; the Floquet multipliers of the converged orbit are the
eigenvalues of the monodromy ``prod_k S_k Phi(s_k)`` built from saltation
matrices.

Sticking (the mass resting on the stop) and complete chatter are not part of
the impact map; orbits with them are outside its scope (use
:func:`rattle_lab.model.sdf.simulate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from rattle_lab.exceptions import ConvergenceError, ParameterError, SimulationError
from rattle_lab.model.sdf import SimImpacts, SDFParams
from . import _motion
from ._saltation import impact_map_jacobian, impact_saltation, transition_matrix

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class PeriodicOrbit:
    """An m/n periodic orbit: ``m`` impacts in ``n`` forcing periods (nondimensional).

    Attributes
    ----------
    params : SDFParams
        The model parameters.
    m, n : int
        Impacts per period and forcing periods per period.
    period : float
        ``2 n pi / omega``.
    t : ndarray, shape (m,)
        Impact times within one period, relative to the first (``t[0] = 0``).
    phase : ndarray, shape (m,)
        Forcing phase at each impact, in ``[0, 2 pi)``.
    v_im : ndarray, shape (m,)
        Incoming velocity at each impact.
    multipliers : tuple of complex
        Floquet multipliers (eigenvalues of ``prod_k S_k Phi(s_k)``), larger
        modulus first.
    stable : bool
        Both multipliers strictly inside the unit circle.
    instability : {"none", "saddle-node", "period-doubling"}
        A real multiplier ``> 1`` or ``< -1``, if any.
    residual : float
        Final Newton residual ``max(|d phase|, |d v_im|)``.
    iterations : int
        Newton iterations used.
    """

    params: SDFParams
    m: int
    n: int
    period: float
    t: np.ndarray
    phase: np.ndarray
    v_im: np.ndarray
    multipliers: tuple[complex, complex]
    stable: bool
    instability: Literal["none", "saddle-node", "period-doubling"]
    residual: float
    iterations: int

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary."""
        return {"m": self.m, "n": self.n, "period": self.period, "t": self.t.tolist(),
                "phase": self.phase.tolist(), "v_im": self.v_im.tolist(),
                "multipliers": [[m.real, m.imag] for m in self.multipliers],
                "stable": self.stable, "instability": self.instability,
                "residual": self.residual, "iterations": self.iterations}


def _step(params: SDFParams, theta0: float, u0: float, max_periods: float) -> tuple[float, float]:
    """Flight time and incoming velocity of the next impact after one at ``(theta0, u0)``."""
    rebound = params.e * u0
    if not rebound > 0.0:
        raise SimulationError(
            f"the impact map needs a rebound e * v_im > 0, was {rebound} (sticking or chatter; "
            "use rattle_lab.model.sdf.simulate)")
    fl = _motion.flights_from_state(params.F, params.omega, params.zeta, theta0, 1.0, -rebound)
    m2 = float(fl.bounds()[0])
    # x(t) <= 1 - e u t + M2 t^2 / 2 < 1 on (0, 2 e u / M2): start the search at e u / M2.
    t_first = rebound / m2
    t_end = max_periods * TWO_PI / params.omega
    t1 = _motion.first_contact(fl, t_first, t_end)
    if t1 is None:
        raise SimulationError(
            f"no impact within {max_periods} forcing periods after the impact at phase {theta0}")
    _, v1, _ = _motion.evaluate(fl, t1)
    return t1, float(v1)


def impact_map(params: SDFParams, phase: float, v_im: float, *,
               max_periods: float = 100.0) -> tuple[float, float, float]:
    """One step of the impact map: from one impact to the next.

    Parameters
    ----------
    params : SDFParams
        Model parameters (``e > 0``).
    phase : float
        Forcing phase at the impact.
    v_im : float
        Incoming velocity of the impact (> 0); the mass leaves with ``-e v_im``.
    max_periods : float
        Give up after this many forcing periods without contact.

    Returns
    -------
    dt, phase1, v_im1 : float
        Flight time, forcing phase (in ``[0, 2 pi)``) and incoming velocity of
        the next impact.

    Raises
    ------
    SimulationError
        If there is no rebound (``e v_im <= 0``) or no contact within ``max_periods``.

    Examples
    --------
    >>> import numpy as np
    >>> from rattle_lab.model.sdf import SDFParams
    >>> from rattle_lab.model.analysis.orbits import one_over_n_orbits
    >>> p = SDFParams(F=0.2, omega=1.1, zeta=0.05, e=0.6)
    >>> orb = one_over_n_orbits(p, 1)[1]
    >>> dt, ph, v = impact_map(p, orb.phase, orb.v_im)
    >>> bool(np.isclose(dt, orb.period) and np.isclose(v, orb.v_im))
    True
    """
    dt, v1 = _step(params, float(phase), float(v_im), max_periods)
    return dt, float(np.mod(phase + params.omega * dt, TWO_PI)), v1


def _classify(M: np.ndarray) -> tuple[tuple[complex, complex], bool, str]:
    lam = np.linalg.eigvals(M).astype(complex)
    lam = lam[np.argsort(-np.abs(lam))]
    tr, det = float(np.trace(M)), float(np.linalg.det(M))
    p_plus, p_minus = 1.0 - tr + det, 1.0 + tr + det
    stable = bool(np.all(np.abs(lam) < 1.0))
    kind = "saddle-node" if p_plus < 0.0 else "period-doubling" if p_minus < 0.0 else "none"
    return (complex(lam[0]), complex(lam[1])), stable, kind


def find_periodic_orbit(params: SDFParams, phase: float, v_im: float, m: int, n: int, *,
                        tol: float = 1e-11, max_iter: int = 40) -> PeriodicOrbit:
    """Newton shooting for an m/n orbit from a guess of one of its impacts.

    Solves ``P^m(theta, u) = (theta + 2 pi n, u)`` for the impact map ``P``
    with its exact Jacobian; the multipliers come from saltation matrices.

    Parameters
    ----------
    params : SDFParams
        Model parameters (``e > 0``).
    phase, v_im : float
        Guess: forcing phase and incoming velocity of one impact of the orbit.
    m, n : int
        Impacts per period and forcing periods per period (>= 1).
    tol : float
        Convergence: ``max(|d phase|, |d v_im| / max(1, v_im)) <= tol``.
    max_iter : int
        Newton iterations allowed.

    Raises
    ------
    ConvergenceError
        If Newton does not converge, or the converged impacts span a number of
        forcing periods other than ``n``.
    SimulationError
        If an iterate has no rebound or no next contact.
    """
    for name, val in (("m", m), ("n", n)):
        if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or val < 1:
            raise ParameterError(f"`{name}` must be an integer >= 1, was {val!r}")
    if not (math.isfinite(v_im) and v_im > 0.0):
        raise ParameterError(f"`v_im` must be finite and > 0, was {v_im}")
    w = params.omega
    scale_w = np.diag([w, 1.0])
    scale_inv = np.diag([1.0 / w, 1.0])
    theta, u = float(phase), float(v_im)
    residual = math.inf
    for it in range(1, max_iter + 1):  # noqa: B007 (``it`` is read after the loop)
        th, uu = theta, u
        J = np.eye(2)
        for _ in range(m):
            dt, u1 = _step(params, th, uu, 4.0 * n + 4.0)
            th1 = th + w * dt
            J = impact_map_jacobian(params.F, params.zeta, params.e, th, uu, dt, th1, u1) @ J
            th, uu = th1, u1
        r = np.array([th - theta - TWO_PI * n, uu - u])
        residual = max(abs(r[0]), abs(r[1]) / max(1.0, abs(u)))
        if abs(r[0]) > math.pi:
            raise ConvergenceError(
                f"{m} impacts from phase {theta:.6g}, v_im {u:.6g} span "
                f"{(th - theta) / TWO_PI:.3f} forcing periods, not n = {n}")
        if residual <= tol:
            break
        Jtheta = scale_w @ J @ scale_inv
        try:
            delta = np.linalg.solve(Jtheta - np.eye(2), -r)
        except np.linalg.LinAlgError as exc:
            raise ConvergenceError(f"singular Newton matrix at phase {theta}, v_im {u}") from exc
        lam = 1.0
        while u + lam * delta[1] <= 0.0 and lam > 1e-6:
            lam *= 0.5
        theta, u = theta + lam * delta[0], u + lam * delta[1]
    else:
        raise ConvergenceError(
            f"Newton shooting for a {m}/{n} orbit did not converge in {max_iter} iterations "
            f"(residual {residual:.3g} > tol {tol})")
    # One more pass at the solution for the orbit's impacts and its monodromy.
    ts, phases, vs = [0.0], [theta % TWO_PI], [u]
    th, uu, t_acc = theta, u, 0.0
    M = np.eye(2)
    for k in range(m):
        dt, u1 = _step(params, th, uu, 4.0 * n + 4.0)
        th1 = th + w * dt
        M = impact_saltation(params.F, params.zeta, params.e, th1, u1) @ transition_matrix(
            params.zeta, dt) @ M
        t_acc += dt
        if k < m - 1:
            ts.append(t_acc)
            phases.append(th1 % TWO_PI)
            vs.append(u1)
        th, uu = th1, u1
    # A guess from a slowly settling attractor can make Newton converge to a shorter orbit
    # traversed m/d times; report the shortest period.
    for d in range(1, m):
        if m % d == 0 and (n * d) % m == 0 and _repeats(np.array(phases), np.array(vs), d):
            return find_periodic_orbit(params, theta % TWO_PI, u, d, n * d // m, tol=tol,
                                       max_iter=max_iter)
    mults, stable, kind = _classify(M)
    return PeriodicOrbit(params=params, m=int(m), n=int(n), period=TWO_PI * n / w,
                         t=np.array(ts), phase=np.array(phases), v_im=np.array(vs),
                         multipliers=mults, stable=stable, instability=kind,  # type: ignore[arg-type]
                         residual=float(residual), iterations=it)


def _repeats(phase: np.ndarray, v: np.ndarray, d: int, rtol: float = 1e-8) -> bool:
    """Whether the impact sequence repeats after ``d`` impacts."""
    dph = np.angle(np.exp(1j * (phase[d:] - phase[:-d])))
    return bool(np.all(np.abs(dph) <= TWO_PI * rtol)
                and np.all(np.abs(v[d:] - v[:-d]) <= rtol * np.max(np.abs(v))))


def periodic_orbit_from_impacts(params: SDFParams, impacts: SimImpacts, *, max_m: int = 16,
                                rtol: float = 1e-5, tol: float = 1e-11) -> PeriodicOrbit:
    """Detect the period of a simulated attractor from its impacts, then refine by shooting.

    The smallest ``m <= max_m`` is sought for which the last impacts repeat
    after ``m`` impacts (velocity within ``rtol`` of the largest, phase within
    ``2 pi rtol``) at a whole number ``n`` of forcing periods (to within
    ``1e-3``); :func:`find_periodic_orbit` then refines the last impact.

    Parameters
    ----------
    params : SDFParams
        The parameters that were simulated.
    impacts : rattle_lab.model.sdf.SimImpacts
        Impacts of a run long enough to have settled (``result.impacts`` of
        :func:`rattle_lab.model.sdf.simulate`); at least ``2 max_m + 1`` of them, or
        ``3 m + 1`` for the period found.
    max_m : int
        Largest number of impacts per period tried.
    rtol : float
        Tolerance of the repetition test.
    tol : float
        Newton tolerance (see :func:`find_periodic_orbit`).

    Raises
    ------
    ConvergenceError
        If no period is found (chaotic, quasi-periodic or unsettled motion) or
        Newton fails.
    """
    if not isinstance(impacts, SimImpacts):
        raise ParameterError(f"`impacts` must be a SimImpacts, was {type(impacts).__name__}")
    t, ph, v = impacts.t, impacts.phase, impacts.v_in
    N = t.size
    if N < 4:
        raise ConvergenceError(f"only {N} impacts recorded; a periodic orbit needs more")
    w = params.omega
    v_scale = float(np.max(np.abs(v[-min(N, 2 * max_m + 1):])))
    for m in range(1, int(max_m) + 1):
        L = m + 1  # comparisons required
        if N < m + L:
            break
        j = np.arange(N - m - L, N - m)
        dv = np.abs(v[j + m] - v[j])
        dph = np.abs(np.angle(np.exp(1j * (ph[j + m] - ph[j]))))
        cycles = w * (t[j + m] - t[j]) / TWO_PI
        n = int(round(float(cycles[-1])))
        if (n >= 1 and np.all(dv <= rtol * v_scale) and np.all(dph <= TWO_PI * rtol)
                and np.all(np.abs(cycles - n) <= 1e-3)):
            return find_periodic_orbit(params, float(ph[-1]), float(v[-1]), m, n, tol=tol)
    raise ConvergenceError(
        f"no periodic impact sequence with m <= {max_m} found in the last {N} impacts "
        f"(rtol={rtol}); the motion may be chaotic, quasi-periodic, sticking or not settled")
