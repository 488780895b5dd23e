"""Independent high-precision references for impact sequences of the SDF oscillator.

Used by the tests and the benchmarks to judge the simulators (a test helper, not a
test module; it is not shipped with the package).  Two references, sharing no code with the simulators:

* :func:`mpmath_impacts`: event-driven, with the closed-form solution between
  events evaluated in mpmath at ``dps`` digits, and an impact search that
  carries a proof that no crossing of the stop was skipped (see
  :func:`_Flow.first_impact`).
* :func:`scipy_impacts`: ``scipy.integrate.solve_ivp`` with a terminal event
  ``x - 1 = 0`` and a restart after each impact (what a careful user would do
  with a general-purpose integrator).

The model, nondimensional (thesis eq. 2.33)::

    x'' + 2 zeta x' + x = F cos(theta0 + omega t)   for x < 1,    v -> -e v at x = 1

Both functions start at ``t = 0`` from ``(x0, v0)`` with forcing phase
``theta0``.  mpmath is imported lazily: it is a test dependency only.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from rattle_lab.exceptions import ParameterError, SimulationError

__all__ = [
    "ReferenceImpacts",
    "ScipyImpacts",
    "check_closed_form_against_odefun",
    "closed_form_xv",
    "mpmath_impacts",
    "scipy_impacts",
]


def _mp() -> Any:
    try:
        import mpmath
    except ImportError as exc:  # pragma: no cover - mpmath is a test dependency
        raise ImportError("the mpmath reference needs mpmath: pip install 'rattle-lab[test]'") from exc
    return mpmath.mp


def _check_params(F: float, omega: float, zeta: float, e: float, x0: float, v0: float, duration: float) -> None:
    for name, value in {"F": F, "omega": omega, "zeta": zeta, "e": e, "x0": x0, "v0": v0,
                        "duration": duration}.items():  # fmt: skip
        if not math.isfinite(float(value)):
            raise ParameterError(f"`{name}` must be finite, was {value}")
    if omega <= 0:
        raise ParameterError(f"`omega` must be > 0, was {omega}")
    if zeta < 0:
        raise ParameterError(f"`zeta` must be >= 0, was {zeta}")
    if not 0.0 <= e <= 1.0:
        raise ParameterError(f"`e` must be in [0, 1], was {e}")
    if duration < 0:
        raise ParameterError(f"`duration` must be >= 0, was {duration}")
    if x0 > 1.0 or (x0 == 1.0 and v0 > 0.0):
        raise ParameterError(f"the start must not lie beyond the stop: x0={x0}, v0={v0}")


class _Flow:
    """Closed-form flow of the linear oscillator from one event, in mpmath.

    With ``theta(s) = theta_s + omega s`` the particular (steady-state) part is
    ``x_p = A_c cos(theta) + A_s sin(theta)``; substituting into the ODE gives::

        (1 - omega^2) A_c + 2 zeta omega A_s = F,   (1 - omega^2) A_s - 2 zeta omega A_c = 0
        A_c = F (1 - omega^2)/D,   A_s = 2 F zeta omega / D,   D = (1 - omega^2)^2 + (2 zeta omega)^2

    The homogeneous part ``y = x - x_p`` with ``y(0) = y0``, ``y'(0) = u0`` is::

        zeta < 1 (wd = sqrt(1 - zeta^2)):
            y  = exp(-zeta s) (y0 cos(wd s) + (u0 + zeta y0)/wd sin(wd s))
            y' = exp(-zeta s) (u0 cos(wd s) - (y0 + zeta u0)/wd sin(wd s))
        zeta = 1:
            y  = exp(-s) (y0 + (u0 + y0) s)
            y' = exp(-s) (u0 - (u0 + y0) s)
        zeta > 1 (b = sqrt(zeta^2 - 1)):
            y  = exp(-zeta s) (y0 cosh(b s) + (u0 + zeta y0)/b sinh(b s))
            y' = exp(-zeta s) (u0 cosh(b s) - (y0 + zeta u0)/b sinh(b s))

    Derivative bounds used by the impact search: every derivative of ``y`` is
    itself a homogeneous solution, and for any homogeneous solution ``z`` the
    energy ``(z^2 + z'^2)/2`` does not increase (its rate is ``-2 zeta z'^2``),
    so ``|y^(k)(s)| <= sqrt(y^(k)(0)^2 + y^(k+1)(0)^2)`` for all ``s >= 0``;
    ``|x_p^(k)| <= omega^k sqrt(A_c^2 + A_s^2)``.
    """

    def __init__(self, mp: Any, P: tuple[Any, ...], theta_s: Any, x0: Any, v0: Any) -> None:
        F, omega, zeta = P[0], P[1], P[2]
        self.mp = mp
        self.F, self.omega, self.zeta = F, omega, zeta
        D = (1 - omega**2) ** 2 + (2 * zeta * omega) ** 2
        if D == 0:
            raise ParameterError("undamped resonance (zeta = 0, omega = 1) has no periodic particular solution")
        self.Ac = F * (1 - omega**2) / D
        self.As = 2 * F * zeta * omega / D
        self.theta_s = theta_s
        c, s_ = mp.cos_sin(theta_s)
        self.y0 = x0 - (self.Ac * c + self.As * s_)
        self.u0 = v0 - omega * (-self.Ac * s_ + self.As * c)
        if zeta < 1:
            self.kind = 0
            self.wd = mp.sqrt(1 - zeta**2)
        elif zeta == 1:
            self.kind = 1
        else:
            self.kind = 2
            self.wd = mp.sqrt(zeta**2 - 1)
        # Derivatives of y at s = 0 (y'' = -2 zeta y' - y), and the bounds.
        d = [self.y0, self.u0]
        for _ in range(4):
            d.append(-2 * zeta * d[-1] - d[-2])
        R = mp.sqrt(self.Ac**2 + self.As**2)
        self.M = [omega**k * R + mp.sqrt(d[k] ** 2 + d[k + 1] ** 2) for k in range(5)]

    def xva(self, s: Any) -> tuple[Any, Any, Any]:
        """Displacement, velocity and acceleration at local time ``s``."""
        mp = self.mp
        zeta, y0, u0 = self.zeta, self.y0, self.u0
        th = self.theta_s + self.omega * s
        c, sn = mp.cos_sin(th)
        xp = self.Ac * c + self.As * sn
        vp = self.omega * (-self.Ac * sn + self.As * c)
        ex = mp.exp(-zeta * s)
        if self.kind == 0:
            cw, sw = mp.cos_sin(self.wd * s)
            y = ex * (y0 * cw + (u0 + zeta * y0) / self.wd * sw)
            u = ex * (u0 * cw - (y0 + zeta * u0) / self.wd * sw)
        elif self.kind == 1:
            y = ex * (y0 + (u0 + y0) * s)
            u = ex * (u0 - (u0 + y0) * s)
        else:
            cw, sw = mp.cosh(self.wd * s), mp.sinh(self.wd * s)
            y = ex * (y0 * cw + (u0 + zeta * y0) / self.wd * sw)
            u = ex * (u0 * cw - (y0 + zeta * u0) / self.wd * sw)
        x = xp + y
        v = vp + u
        return x, v, self.F * c - 2 * zeta * v - x

    # ---- impact search -------------------------------------------------------------

    def first_impact(self, s_lo: Any, length: Any, w_max: Any) -> Any | None:
        """First ``s`` in ``(s_lo, length]`` with ``x(s) = 1``; ``None`` if there is none.

        The caller guarantees ``x < 1`` on ``(0, s_lo]``.  The interval is
        scanned in pieces of at most ``w_max``; a piece is cleared only with a
        proof, using the bounds ``M2 >= |x''|`` and ``M3 >= |x'''|``:

        * ``max(x(a), x(b)) + M2 w^2/8 < 1`` (a function whose second derivative
          is bounded by M2 lies at most ``M2 w^2/8`` above its chord), or
        * ``x`` is monotone on the piece (``v`` bounded away from 0 with
          ``|v'| <= M2``) and below 1 at both ends, or
        * ``x`` is concave on the piece with one maximum (found as the root of
          ``v``) below 1;

        otherwise the piece is halved.  A grazing impact therefore cannot be
        skipped; it is found through the maximum of ``x``.  A piece whose end
        is at or beyond the stop holds a root; it is refined once ``x`` is
        proven increasing on it.
        """
        if s_lo >= length:
            return None
        a = s_lo
        xa, va, _ = self.xva(a)
        w = min(w_max, s_lo) if s_lo > 0 else w_max
        while a < length:
            b = min(a + w, length)
            xb, vb, _ = self.xva(b)
            r = self._root_in(a, b, xa, va, xb, vb, 0)
            if r is not None:
                return r
            a, xa, va = b, xb, vb
            w = min(2 * w, w_max)
        return None

    def _root_in(self, a: Any, b: Any, xa: Any, va: Any, xb: Any, vb: Any, depth: int) -> Any | None:
        w = b - a
        M2, M3 = self.M[2], self.M[3]
        vmid = (va + vb) / 2
        if xb >= 1:
            if vmid - M2 * w / 2 > 0:  # x increasing on [a, b]: one root
                return self._solve(lambda s: self.xva(s)[0] - 1, lambda s: self.xva(s)[1], a, b)
        else:
            if max(xa, xb) + M2 * w * w / 8 < 1:
                return None
            if vmid + M2 * w / 2 < 0 or vmid - M2 * w / 2 > 0:  # monotone, ends below 1
                return None
            if va > 0 > vb:
                aa = self.xva(a)[2]
                ab = self.xva(b)[2]
                if (aa + ab) / 2 + M3 * w / 2 < 0:  # concave: one maximum
                    sm = self._solve(lambda s: -self.xva(s)[1], lambda s: -self.xva(s)[2], a, b)
                    if self.xva(sm)[0] >= 1:
                        return self._solve(lambda s: self.xva(s)[0] - 1, lambda s: self.xva(s)[1], a, sm)
                    return None
        if depth > 400 or w <= self.mp.eps * 16 * max(1, abs(b)):
            raise SimulationError(f"mpmath reference: cannot resolve the motion near s={self.mp.nstr(a, 20)}")
        m = (a + b) / 2
        xm, vm, _ = self.xva(m)
        r = self._root_in(a, m, xa, va, xm, vm, depth + 1)
        if r is not None:
            return r
        return self._root_in(m, b, xm, vm, xb, vb, depth + 1)

    def _solve(self, f: Callable[[Any], Any], df: Callable[[Any], Any], lo: Any, hi: Any) -> Any:
        """Root of an increasing ``f`` with ``f(lo) < 0 <= f(hi)``: safeguarded Newton.

        mpmath's own bracketing solvers (``findroot`` with ``illinois``,
        ``pegasus``, ``anderson``) were seen to return points far from the
        root near a double root (a grazing impact), so the bracket is kept here
        and a Newton step is taken only when it lands inside it.
        """
        mp = self.mp
        tol = mp.eps * 4 * max(1, abs(hi))
        dx_old = dx = hi - lo
        s = (lo + hi) / 2
        fs, ds = f(s), df(s)
        for _ in range(10 * mp.prec):
            # Numerical Recipes' rtsafe: bisect when Newton would leave the
            # bracket or is not shrinking the step fast enough.
            if ((s - hi) * ds - fs) * ((s - lo) * ds - fs) > 0 or abs(2 * fs) > abs(dx_old * ds):
                dx_old, dx = dx, (hi - lo) / 2
                s = lo + dx
            else:
                dx_old, dx = dx, fs / ds
                s = s - dx
            if abs(dx) <= tol:
                return s
            fs, ds = f(s), df(s)
            if fs < 0:
                lo = s
            else:
                hi = s
        return s


@dataclass(frozen=True)
class ReferenceImpacts:
    """Impact sequence from the mpmath closed-form reference (nondimensional).

    Attributes
    ----------
    t, v_in : tuple of mpf
        Impact times and incoming velocities (> 0), at ``dps`` digits.
    accumulations : tuple of mpf
        Chatter accumulation times, each followed by sticking.  The chatter is
        followed impact by impact until the outgoing velocity falls below
        ``v_stick``; the rest of the (geometric) sequence is summed in closed
        form, ``t_inf = t_n + 2 v_out/(a (1 - e))``, error O(v_out^2).
    sticking : tuple of (mpf, mpf)
        Start and end of each interval spent on the stop.
    t_end, x_end, v_end : mpf
        State at the end of the run.
    stuck_end : bool
        Whether the run ends on the stop.
    dps : int
        Working precision in decimal digits.
    """

    t: tuple[Any, ...]
    v_in: tuple[Any, ...]
    accumulations: tuple[Any, ...]
    sticking: tuple[tuple[Any, Any], ...]
    t_end: Any
    x_end: Any
    v_end: Any
    stuck_end: bool
    dps: int

    @property
    def t_float(self) -> np.ndarray:
        """Impact times as float64."""
        return np.array([float(t) for t in self.t], dtype=float)

    @property
    def v_in_float(self) -> np.ndarray:
        """Incoming velocities as float64."""
        return np.array([float(v) for v in self.v_in], dtype=float)


def closed_form_xv(
    F: float, omega: float, zeta: float, x0: float, v0: float, theta0: float, s: float | Any, dps: int = 40
) -> tuple[Any, Any]:
    """Closed-form ``(x, v)`` of the free linear oscillator (no stop) at time ``s``, in mpmath.

    All quantities nondimensional; the forcing is ``F cos(theta0 + omega s)``.
    The parameters are converted to mpf exactly (binary floats are exact).
    """
    mp = _mp()
    with mp.workdps(dps):
        P = (mp.mpf(F), mp.mpf(omega), mp.mpf(zeta))
        fl = _Flow(mp, P, mp.mpf(theta0), mp.mpf(x0), mp.mpf(v0))
        x, v, _ = fl.xva(mp.mpf(s))
        return +x, +v


def check_closed_form_against_odefun(
    F: float, omega: float, zeta: float, x0: float, v0: float, theta0: float,
    s_points: Sequence[float], dps: int = 30,
) -> float:  # fmt: skip
    """Largest difference between :func:`closed_form_xv` and ``mpmath.odefun``.

    ``mpmath.odefun`` integrates the ODE by Taylor series at the working
    precision, independently of the closed form.  Returns the maximum over
    ``s_points`` of ``max(|dx|, |dv|)`` as a float.
    """
    mp = _mp()
    with mp.workdps(dps):
        Fm, om, zm, th = mp.mpf(F), mp.mpf(omega), mp.mpf(zeta), mp.mpf(theta0)

        def rhs(s: Any, y: Sequence[Any]) -> list[Any]:
            return [y[1], Fm * mp.cos(th + om * s) - 2 * zm * y[1] - y[0]]

        sol = mp.odefun(rhs, 0, [mp.mpf(x0), mp.mpf(v0)])
        worst = mp.mpf(0)
        for s in sorted(s_points):
            xo, vo = sol(mp.mpf(s))
            xc, vc = closed_form_xv(F, omega, zeta, x0, v0, theta0, s, dps=dps)
            worst = max(worst, abs(xo - xc), abs(vo - vc))
        return float(worst)


def mpmath_impacts(
    F: float,
    omega: float,
    zeta: float,
    e: float,
    x0: float,
    v0: float,
    theta0: float,
    duration: float,
    dps: int = 40,
    *,
    max_events: int = 200_000,
) -> ReferenceImpacts:
    """Impact sequence from the closed-form solution evaluated at ``dps`` digits.

    Event-driven: between events the motion is the closed form of
    :class:`_Flow`; each impact is the first root of ``x(s) = 1`` found by a
    scan that proves the absence of roots it skips (fine pieces, bounds on the
    derivatives, the local maxima of ``x`` as roots of ``v``), refined by a
    safeguarded Newton iteration to full working precision.  At an impact
    ``v -> -e v``.  Chatter: once the outgoing velocity is below
    ``v_stick = 10**(5 - dps/2)`` while the force presses the mass onto the
    stop (``a_stop = F cos(theta) - 1 > 0``, varying little over the remaining
    sequence), the rest of the geometric sequence is summed in closed form and
    the mass sticks until ``F cos(theta) = 1`` (release).  All quantities are
    nondimensional; the run starts at ``t = 0``.

    Slow (a few ms per impact at dps 40, in pure Python); meant for up to a few
    thousand impacts.

    Raises
    ------
    ParameterError
        For invalid parameters or a start beyond the stop.
    SimulationError
        If ``max_events`` is exceeded or a start on the stop cannot be resolved.
    """
    _check_params(F, omega, zeta, e, x0, v0, duration)
    mp = _mp()
    with mp.workdps(dps):
        Fm, om, zm, em = mp.mpf(F), mp.mpf(omega), mp.mpf(zeta), mp.mpf(e)
        P = (Fm, om, zm)
        T_end = mp.mpf(duration)
        th0 = mp.mpf(theta0)
        w_max = min(2 * mp.pi, 2 * mp.pi / om) / 16
        tiny = mp.mpf(10) ** (5 - dps)
        v_stick = mp.mpf(10) ** (5 - dps / 2)

        imp_t: list[Any] = []
        imp_v: list[Any] = []
        accs: list[Any] = []
        sticks: list[tuple[Any, Any]] = []

        t = mp.mpf(0)
        x, v = mp.mpf(x0), mp.mpf(v0)
        stuck = False
        a_stop0 = Fm * mp.cos(th0) - 1
        if x == 1 and v == 0 and a_stop0 > 0:
            stuck = True
        for _ in range(max_events):
            if t >= T_end:
                break
            theta = th0 + om * t
            if stuck:
                # On the stop while F cos(theta) > 1; release at F cos(theta) = 1 going down.
                alpha = mp.acos(1 / Fm)
                phi = theta - 2 * mp.pi * mp.floor((theta + mp.pi) / (2 * mp.pi))  # in [-pi, pi)
                t_rel = t + max(alpha - phi, 0) / om
                if t_rel >= T_end:
                    sticks.append((t, T_end))
                    t, x, v = T_end, mp.mpf(1), mp.mpf(0)
                    break
                sticks.append((t, t_rel))
                t, x, v, stuck = t_rel, mp.mpf(1), mp.mpf(0), False
                continue
            fl = _Flow(mp, P, theta, x, v)
            if x < 1:
                s_lo = mp.mpf(0)
            else:
                s_lo = _safe_start(fl, v, tiny)
            s_imp = fl.first_impact(s_lo, T_end - t, w_max)
            if s_imp is None:
                x, v, _ = fl.xva(T_end - t)
                t = T_end
                break
            _, v_in, _ = fl.xva(s_imp)
            t = t + s_imp
            imp_t.append(t)
            imp_v.append(v_in)
            v_out = em * v_in
            theta = th0 + om * t
            a_stop = Fm * mp.cos(theta) - 1
            jerk = -Fm * om * mp.sin(theta)
            if v_out < v_stick and a_stop > 0 and em < 1:
                t_rest = 2 * v_out / (a_stop * (1 - em))
                if t_rest * abs(jerk) < mp.mpf("1e-3") * a_stop:
                    t = t + t_rest
                    accs.append(t)
                    x, v, stuck = mp.mpf(1), mp.mpf(0), True
                    continue
            x, v = mp.mpf(1), -v_out
        else:
            raise SimulationError(f"mpmath reference: more than max_events={max_events} events")
        return ReferenceImpacts(
            t=tuple(imp_t), v_in=tuple(imp_v), accumulations=tuple(accs), sticking=tuple(sticks),
            t_end=t, x_end=x, v_end=v, stuck_end=stuck, dps=dps,
        )  # fmt: skip


def _safe_start(fl: _Flow, v0: Any, tiny: Any) -> Any:
    """A time ``s_lo > 0`` with ``x < 1`` on ``(0, s_lo]``, for a start on the stop.

    Taylor's theorem with the derivative bounds of :class:`_Flow`: with the
    first of ``v0, a0, j0`` that is not negligible (it must be negative),
    ``x - 1 <= d_m s^m/m! + M_{m+1} s^{m+1}/(m+1)!`` stays negative up to
    ``s = -d_m (m+1)/M_{m+1}``; half of that (or a third) is returned.
    """
    mp = fl.mp
    _, _, a0 = fl.xva(mp.mpf(0))
    j0 = -fl.F * fl.omega * mp.sin(fl.theta_s) - 2 * fl.zeta * a0 - v0
    if v0 < -tiny:
        return -v0 / fl.M[2]
    if a0 < -tiny:
        return -a0 / fl.M[3]
    if abs(a0) <= tiny and j0 < -tiny:
        return -j0 / fl.M[4]
    raise SimulationError(
        f"mpmath reference: the mass on the stop is pushed into it (v={mp.nstr(v0, 5)}, a={mp.nstr(a0, 5)})"
    )


# ---- scipy solve_ivp with terminal events -------------------------------------------------


@dataclass(frozen=True)
class ScipyImpacts:
    """Impacts found by ``solve_ivp`` with terminal events and restarts (nondimensional).

    Attributes
    ----------
    t, v_in : ndarray
        Impact times (event times) and incoming velocities.
    n_rhs : int
        Right-hand-side evaluations, summed over all restarts.
    n_segments : int
        Number of ``solve_ivp`` calls.
    n_missed_dense : int
        Excursions beyond ``x = 1 + dense_tol`` seen in the dense output between
        events (impacts the event detection missed); 0 if the check is off.
    dense_ok : bool
        ``n_missed_dense == 0``.
    truncated : bool
        The run stopped at ``max_impacts`` before ``duration``.
    """

    t: np.ndarray
    v_in: np.ndarray
    n_rhs: int
    n_segments: int
    n_missed_dense: int
    dense_ok: bool
    truncated: bool


def scipy_impacts(
    F: float,
    omega: float,
    zeta: float,
    e: float,
    x0: float,
    v0: float,
    theta0: float,
    duration: float,
    method: Literal["RK45", "DOP853", "Radau", "BDF", "LSODA", "RK23"] = "DOP853",
    rtol: float = 1e-12,
    atol: float | None = None,
    *,
    v_stick: float = 1e-6,
    dense_check: bool = True,
    dense_tol: float = 1e-12,
    n_dense_per_period: int = 2000,
    max_impacts: int = 100_000,
) -> ScipyImpacts:
    """Impacts from ``scipy.integrate.solve_ivp`` with a terminal event and restarts.

    The event is ``x - 1`` (``direction = +1``, terminal).  After an impact the
    solve restarts from ``x = 1``, ``v = -e v_in``; so that the restart point
    itself (where ``x - 1 = 0``) is not taken for an event, the event function
    returns -1 at the restart time and ``x - 1`` after it.  A simple sticking
    rule ends chatter: if ``e v_in < v_stick`` while the force presses the
    mass onto the stop (``F cos(theta) > 1``), it stays there until
    ``F cos(theta) = 1``.  ``v_stick`` must stay well above
    ``sqrt(2 eps) ~ 2e-8``: a flight with outgoing velocity ``v`` rises only
    ``v^2/(2 a)`` above the stop's neighbourhood, which float64 cannot resolve
    near ``x = 1`` below that, and the chatter then stalls at ``v ~ 1e-8``
    (seen with DOP853).  ``atol`` defaults to ``rtol`` (the states are of
    order 1).  All quantities nondimensional; the run starts at ``t = 0``.

    With ``dense_check`` the dense output of every segment is sampled
    ``n_dense_per_period`` times per forcing period; each run of samples
    above ``1 + dense_tol`` counts as a missed impact.
    """
    from scipy.integrate import solve_ivp

    _check_params(F, omega, zeta, e, x0, v0, duration)
    if atol is None:
        atol = rtol
    two_zeta = 2.0 * zeta

    def rhs(t: float, y: np.ndarray) -> list[float]:
        return [y[1], F * math.cos(theta0 + omega * t) - two_zeta * y[1] - y[0]]

    dt_dense = 2.0 * math.pi / omega / n_dense_per_period
    imp_t: list[float] = []
    imp_v: list[float] = []
    n_rhs = 0
    n_seg = 0
    n_missed = 0
    truncated = False
    t = 0.0
    y = np.array([x0, v0], dtype=float)
    stuck = x0 == 1.0 and v0 == 0.0 and F * math.cos(theta0) > 1.0
    while t < duration:
        if stuck:
            alpha = math.acos(1.0 / F)
            theta = theta0 + omega * t
            phi = theta - 2.0 * math.pi * math.floor((theta + math.pi) / (2.0 * math.pi))
            t = min(duration, t + max(alpha - phi, 0.0) / omega)
            y = np.array([1.0, 0.0])
            stuck = False
            continue
        t_start = t

        def event(tt: float, yy: np.ndarray, t_start: float = t_start) -> float:
            return -1.0 if tt <= t_start else float(yy[0] - 1.0)

        event.terminal = True  # type: ignore[attr-defined]
        event.direction = 1.0  # type: ignore[attr-defined]
        sol = solve_ivp(rhs, (t, duration), y, method=method, rtol=rtol, atol=atol, events=event,
                        dense_output=dense_check)  # fmt: skip
        n_rhs += int(sol.nfev)
        n_seg += 1
        if not sol.success:
            raise SimulationError(f"solve_ivp failed at t={t}: {sol.message}")
        t_stop = float(sol.t[-1])
        if dense_check and t_stop > t_start:
            n = max(2, round((t_stop - t_start) / dt_dense) + 1)
            xs = sol.sol(np.linspace(t_start, t_stop, n))[0]
            above = xs > 1.0 + dense_tol
            n_missed += int(np.count_nonzero(above[1:] & ~above[:-1]) + above[0])
        if sol.status == 1:
            te = float(sol.t_events[0][0])
            v_in = float(sol.y_events[0][0][1])
            imp_t.append(te)
            imp_v.append(v_in)
            if len(imp_t) >= max_impacts:
                truncated = True
                break
            v_out = e * v_in
            t = te
            y = np.array([1.0, -v_out])
            if v_out < v_stick and F * math.cos(theta0 + omega * te) > 1.0:
                stuck = True
        else:
            t = duration
    return ScipyImpacts(
        t=np.array(imp_t, dtype=float), v_in=np.array(imp_v, dtype=float), n_rhs=n_rhs, n_segments=n_seg,
        n_missed_dense=n_missed, dense_ok=n_missed == 0, truncated=truncated,
    )  # fmt: skip
