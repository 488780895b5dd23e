"""Largest Lyapunov exponent of the SDF impact oscillator, exactly from the impact log.

Between impacts the motion is linear, so a perturbation ``dz = (dx, dv)`` of
the state is carried over a free flight of duration ``s`` by the transition
matrix of the homogeneous flow (:func:`rattle_lab.model.sdf.homogeneous_transition`)::

    Phi(s) = [[Ec + zeta Es, Es], [-Es, Ec - zeta Es]]

and across an impact at forcing phase ``theta`` with incoming velocity ``u``
by the saltation matrix (:mod:`rattle_lab.model.analysis._saltation`)::

    S = [[-e, 0], [(1 + e)(F cos(theta) - 1) / u, -e]]

The tangent dynamics along a simulated trajectory is therefore the product of
these matrices taken at the logged impacts: no variational equation is
integrated, and the only inputs are the impact times, phases and incoming
velocities (:class:`rattle_lab.model.sdf.SimImpacts`).  One tangent vector is carried
through the product and renormalised after every factor (and at least every
``2 pi / omega`` of flight, so that nothing under- or overflows); the sum of
the logarithms of the norms over the measuring window, divided by its length,
is the largest exponent (Benettin et al. 1980; for impacting systems Müller
1995).  The sum of both exponents follows from the determinants alone,
``det S = e^2`` and ``det Phi(s) = exp(-2 zeta s)``::

    lambda_1 + lambda_2 = (2 N log(e) - 2 zeta L) / L

for ``N`` impacts in a window of length ``L``.

Sticking
    While the mass rests on the stop (after a complete-chatter accumulation
    point) every state is carried to the same state (x = 1, v = 0), and it is
    released at the phase ``arccos(1 / F)`` whatever happened before: the
    tangent map over a stuck interval is zero, and the exponent of a stretch
    that contains one is ``-inf``.  A stuck interval during the warm-up only
    restarts the tangent vector at the release.

Units
    Exponents are per unit of nondimensional time (multiply by ``2 pi / omega``
    for the exponent per forcing period).  For a periodic orbit of period ``T``
    the largest exponent is ``log |mu_1| / T`` with ``mu_1`` the Floquet
    multiplier of largest modulus.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numba
import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.model._constants import TWO_PI
from rattle_lab.model.sdf import SDFParams, SDFState, SimResult, simulate

LyapunovStatus = Literal["ok", "sticking", "grazing-impact", "micro-bounce"]

__all__ = ["LyapunovResult", "lyapunov_exponent", "lyapunov_from_result", "tangent_log_growth"]

# Status codes of the compiled loop.
_OK, _STICKING, _GRAZING = 0, 1, 2


@dataclass(frozen=True)
class LyapunovResult:
    """Largest Lyapunov exponent of a stretch of trajectory (nondimensional).

    Attributes
    ----------
    exponent : float
        ``lambda_1 = (1 / L) sum log(|w_{k+1}| / |w_k|)`` over the measuring
        window of length ``L`` (per unit nondimensional time); ``-inf`` if the
        mass sticks to the stop in the window (status ``"sticking"``), NaN if
        undefined (status ``"grazing-impact"`` or ``"micro-bounce"``).
    exponent_sum : float
        ``lambda_1 + lambda_2 = (2 N log(e) - 2 zeta L) / L`` from the
        determinants (module docstring); ``-inf`` if ``e = 0`` or sticking.
    per_period : float
        ``exponent * 2 pi / omega``: the exponent per forcing period.
    t_start, t_stop : float
        The measuring window (after the warm-up), nondimensional time.
    n_impacts : int
        ``N``: impacts in the window.
    n_sticking : int
        Stuck intervals that overlap the window.
    status : {"ok", "sticking", "grazing-impact", "micro-bounce"}
        ``"grazing-impact"``: an impact with ``v_in = 0`` (the saltation matrix
        is infinite); ``"micro-bounce"``: the simulator averaged elastic
        micro-bouncing (``e = 1``) whose impacts are not logged.
    """

    exponent: float
    exponent_sum: float
    per_period: float
    t_start: float
    t_stop: float
    n_impacts: int
    n_sticking: int
    status: LyapunovStatus

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary; ``-inf`` becomes the string ``"-inf"``, NaN None."""
        def num(x: float) -> float | str | None:
            if math.isnan(x):
                return None
            if math.isinf(x):
                return "-inf" if x < 0 else "inf"
            return float(x)

        return {"exponent": num(self.exponent), "exponent_sum": num(self.exponent_sum),
                "per_period": num(self.per_period), "t_start": self.t_start,
                "t_stop": self.t_stop, "n_impacts": self.n_impacts,
                "n_sticking": self.n_sticking, "status": self.status}


# ---------------------------------------------------------------------------
# Compiled tangent propagation
# ---------------------------------------------------------------------------

@numba.njit(cache=True, nogil=True)
def _phi(zeta: float, s: float) -> tuple[float, float, float, float]:
    """Transition matrix of the homogeneous flow over ``s`` (see ``_flow``)."""
    if zeta < 1.0:
        wd = math.sqrt((1.0 - zeta) * (1.0 + zeta))
        d = math.exp(-zeta * s)
        Ec = d * math.cos(wd * s)
        Es = d * math.sin(wd * s) / wd
    elif zeta == 1.0:
        d = math.exp(-s)
        Ec = d
        Es = d * s
    else:
        mu = math.sqrt((zeta - 1.0) * (zeta + 1.0))
        e1 = math.exp(-s / (zeta + mu))
        e2 = math.exp((-zeta - mu) * s)
        Ec = 0.5 * (e1 + e2)
        Es = e1 * (-math.expm1(-2.0 * mu * s)) / (2.0 * mu)
    return Ec + zeta * Es, Es, -Es, Ec - zeta * Es


@numba.njit(cache=True, nogil=True)
def _tangent(t_imp: np.ndarray, th_imp: np.ndarray, v_imp: np.ndarray, stick: np.ndarray,
             F: float, zeta: float, e: float, t0: float, t_reseed: float,
             checkpoints: np.ndarray, w0x: float, w0v: float, hmax: float
             ) -> tuple[np.ndarray, np.ndarray, int]:
    """Carry a tangent vector from ``t0`` through flights and impacts.

    Returns ``(log_growth, directions, status)``: the cumulative
    ``log(|w(t)| / |w(t0)|)`` and the unit vector ``w(t) / |w(t)|`` at each
    checkpoint (sorted, >= t0).  An impact at a checkpoint time is applied
    before the checkpoint is recorded.  A stuck interval ending before
    ``t_reseed`` restarts the vector at the release with zero growth;
    one overlapping [t_reseed, end] makes the growth -inf from its start on
    (status 1).  An impact with ``v_in = 0`` gives NaN (status 2).
    """
    n_cp = checkpoints.shape[0]
    out = np.full(n_cp, np.nan)
    dirs = np.full((n_cp, 2), np.nan)
    n_imp = t_imp.shape[0]
    n_stk = stick.shape[0]
    norm0 = math.hypot(w0x, w0v)
    wx = w0x / norm0
    wv = w0v / norm0
    logsum = 0.0
    t = t0
    i = 0
    while i < n_imp and t_imp[i] <= t0:
        i += 1
    j = 0
    while j < n_stk and stick[j, 1] <= t0:
        j += 1
    status = 0
    k = 0
    while k < n_cp:
        # next event: impact, start of a stuck interval, or the checkpoint
        tn = checkpoints[k]
        kind = 0
        if i < n_imp and t_imp[i] <= tn:
            tn = t_imp[i]
            kind = 1
        if j < n_stk and max(stick[j, 0], t0) < tn:
            tn = max(stick[j, 0], t0)
            kind = 2
        while t < tn:  # free flight, renormalised at least every hmax
            s = min(hmax, tn - t)
            a, b, c, d = _phi(zeta, s)
            nx = a * wx + b * wv
            nv = c * wx + d * wv
            r = math.hypot(nx, nv)
            logsum += math.log(r)
            wx = nx / r
            wv = nv / r
            t = tn if s == tn - t else t + s
        if kind == 0:
            out[k] = logsum
            dirs[k, 0] = wx
            dirs[k, 1] = wv
            k += 1
        elif kind == 1:
            u = v_imp[i]
            if u <= 0.0:
                status = 2
                break
            c = (1.0 + e) * (F * math.cos(th_imp[i]) - 1.0) / u
            nx = -e * wx
            nv = c * wx - e * wv
            r = math.hypot(nx, nv)
            if r == 0.0:  # e = 0 and w along v: the perturbation is annihilated
                status = 1
                break
            logsum += math.log(r)
            wx = nx / r
            wv = nv / r
            i += 1
        else:
            if stick[j, 1] > t_reseed:
                status = 1
                break
            # stuck: every state goes to (1, 0); restart at the release
            t = stick[j, 1]
            wx = w0x / norm0
            wv = w0v / norm0
            logsum = 0.0
            while i < n_imp and t_imp[i] <= t:
                i += 1
            j += 1
    if status == 1:
        while k < n_cp:
            out[k] = -np.inf
            k += 1
    return out, dirs, status


# ---------------------------------------------------------------------------
# Public functions
# ---------------------------------------------------------------------------

def _check_params(params: object) -> SDFParams:
    if not isinstance(params, SDFParams):
        raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
    return params


def tangent_log_growth(params: SDFParams, result: SimResult, times: np.ndarray, *,
                       t_start: float, w0: tuple[float, float] = (1.0, 0.0)
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Growth of a tangent vector along a simulated trajectory, from its impact log.

    Parameters
    ----------
    params : SDFParams
        The parameters of ``result`` (nondimensional).
    result : SimResult
        A run of :func:`rattle_lab.model.sdf.simulate` covering ``[t_start, max(times)]``.
    times : array_like
        Sorted times ``>= t_start`` at which to report.
    t_start : float
        Where the perturbation ``w0`` is applied.
    w0 : (float, float)
        Initial perturbation direction ``(dx, dv)``.

    Returns
    -------
    log_growth : ndarray
        ``log(|J(t) w0| / |w0|)`` at each time, ``J(t)`` the tangent map from
        ``t_start`` (``-inf`` after a stuck interval).
    direction : ndarray, shape (n, 2)
        ``J(t) w0 / |J(t) w0|``.

    Raises
    ------
    ParameterError
        If ``times`` is not sorted or starts before ``t_start``.
    """
    params = _check_params(params)
    t_cp = np.asarray(times, dtype=float).ravel()
    if t_cp.size and (np.any(np.diff(t_cp) < 0) or t_cp[0] < t_start):
        raise ParameterError(f"`times` must be sorted and >= t_start = {t_start}")
    if not (math.isfinite(w0[0]) and math.isfinite(w0[1]) and math.hypot(*w0) > 0):
        raise ParameterError(f"`w0` must be a finite nonzero vector, was {w0}")
    imp = result.impacts
    stick = np.ascontiguousarray(result.sticking, dtype=float).reshape(-1, 2)
    growth, dirs, _ = _tangent(imp.t, imp.phase, imp.v_in, stick, params.F, params.zeta,
                               params.e, float(t_start), float(t_start), t_cp,
                               float(w0[0]), float(w0[1]), _hmax(params))
    return growth, dirs


def _hmax(params: SDFParams) -> float:
    return min(TWO_PI, params.period)


def lyapunov_from_result(result: SimResult, *, t_start: float, warmup: float = 0.0,
                         w0: tuple[float, float] = (1.0, 1.0)) -> LyapunovResult:
    """Largest Lyapunov exponent over ``[t_start + warmup, result.state.t]``.

    The tangent vector starts at ``t_start`` along ``w0`` and is carried
    through ``warmup`` time units without measuring, so that it aligns with
    the most expanding direction; the exponent is measured over the rest.

    Parameters
    ----------
    result : SimResult
        A run of :func:`rattle_lab.model.sdf.simulate` (method ``"exact"``) that
        started at ``t_start``.
    t_start : float
        Start time of ``result`` (nondimensional).
    warmup : float
        Warm-up time, ``0 <= warmup < duration``.
    w0 : (float, float)
        Initial tangent direction.

    Returns
    -------
    LyapunovResult

    Raises
    ------
    ParameterError
        If the window is empty.
    """
    params = result.params
    t_stop = float(result.state.t)
    t_meas = float(t_start) + float(warmup)
    if not (warmup >= 0.0 and t_meas < t_stop):
        raise ParameterError(f"`warmup` must be in [0, {t_stop - t_start}), was {warmup}")
    imp = result.impacts
    stick = np.ascontiguousarray(result.sticking, dtype=float).reshape(-1, 2)
    in_window = (imp.t > t_meas) & (imp.t <= t_stop)
    n_imp = int(np.count_nonzero(in_window))
    n_stick = int(np.count_nonzero((stick[:, 1] > t_meas) & (stick[:, 0] < t_stop)))
    length = t_stop - t_meas
    period = params.period

    def done(exponent: float, total: float, status: LyapunovStatus) -> LyapunovResult:
        return LyapunovResult(exponent=exponent, exponent_sum=total,
                              per_period=exponent * period, t_start=t_meas, t_stop=t_stop,
                              n_impacts=n_imp, n_sticking=n_stick, status=status)

    if result.micro_bounce.size:
        return done(math.nan, math.nan, "micro-bounce")
    if n_imp == 0:
        total = -2.0 * params.zeta
    elif params.e == 0.0:
        total = -math.inf
    else:
        total = (2.0 * n_imp * math.log(params.e) - 2.0 * params.zeta * length) / length
    growth, _, status = _tangent(imp.t, imp.phase, imp.v_in, stick, params.F, params.zeta,
                                 params.e, float(t_start), t_meas,
                                 np.array([t_meas, t_stop]), float(w0[0]), float(w0[1]),
                                 _hmax(params))
    if status == _GRAZING:
        return done(math.nan, total, "grazing-impact")
    if status == _STICKING:
        return done(-math.inf, -math.inf, "sticking")
    return done(float((growth[1] - growth[0]) / length), total, "ok")


def lyapunov_exponent(params: SDFParams, *, cycles: float = 500.0, warmup_cycles: float = 50.0,
                      state: SDFState | None = None) -> LyapunovResult:
    """Largest Lyapunov exponent of the motion from ``state`` (nondimensional).

    Simulates ``cycles`` forcing periods with the exact solver and measures
    the exponent over the last ``cycles - warmup_cycles`` of them (see
    :func:`lyapunov_from_result`).  The trajectory's own transient is part of
    the warm-up: start from a state on the attractor (e.g. the end state of
    a sweep step) for an attractor's exponent.

    Parameters
    ----------
    params : SDFParams
        ``F``, ``omega``, ``zeta``, ``e``.
    cycles : float
        Forcing periods simulated, > ``warmup_cycles``.
    warmup_cycles : float
        Forcing periods to align the tangent vector before measuring, >= 0.
    state : SDFState, optional
        Initial state (default: at rest at x = 0, phase 0).

    Returns
    -------
    LyapunovResult

    Raises
    ------
    ParameterError
        If ``cycles <= warmup_cycles`` or either is negative.

    Examples
    --------
    A stable 1/1 orbit at ``F = 0.2, omega = 1.1`` has complex multipliers of
    modulus ``sqrt(det)``, so ``lambda_1 = lambda_2 = (lambda_1 + lambda_2) / 2``:

    >>> import numpy as np
    >>> from rattle_lab.model.sdf import SDFParams
    >>> res = lyapunov_exponent(SDFParams(F=0.2, omega=1.1, zeta=0.05, e=0.6), cycles=2000)
    >>> bool(np.isclose(res.exponent, res.exponent_sum / 2, atol=2e-3))
    True
    """
    params = _check_params(params)
    cycles, warmup_cycles = float(cycles), float(warmup_cycles)
    if not (math.isfinite(warmup_cycles) and warmup_cycles >= 0.0):
        raise ParameterError(f"`warmup_cycles` must be >= 0, was {warmup_cycles}")
    if not (math.isfinite(cycles) and cycles > warmup_cycles):
        raise ParameterError(f"`cycles` must be > warmup_cycles = {warmup_cycles}, was {cycles}")
    state = SDFState() if state is None else state
    res = simulate(params, cycles=cycles, state=state)
    return lyapunov_from_result(res, t_start=state.t, warmup=warmup_cycles * params.period)
