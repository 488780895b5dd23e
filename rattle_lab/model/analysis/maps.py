"""Regime maps, basins of attraction and the disturbance study (thesis 4.2, 4.3.3, Fig. 4-7).

Each point of these studies is an independent run of the exact simulator, so
they are cut into chunks and run serially, on a pool of local worker processes
(``workers``) or on a Dask cluster (``scheduler``) (:mod:`rattle_lab.model.analysis._dask`);
the results do not depend on how they were run (tested bit for bit).

Regime map
    The attractor reached from one initial state (default: at rest, ``x = 0``,
    forcing phase 0) at every point of an ``(F, omega)`` grid, classified
    from its impacts (:func:`rattle_lab.model.analysis._sweep.classify_impacts`):
    no impact, ``m/n`` periodic, or aperiodic, with the largest Lyapunov
    exponent of aperiodic motion (:mod:`rattle_lab.model.analysis.lyapunov`).
Basins
    The same classification over a grid of initial states ``(x0, v0)`` at one
    parameter point and initial forcing phase.
Disturbance study (4.3.3, Fig. 4-6, 4-7)
    Above resonance and below the grazing forcing, the impact-free response
    coexists with the 1/1 impacting orbit (the hysteresis region between the
    1/1 saddle-node, eq. 3.11, and grazing, eq. 3.4).  Starting on the
    impact-free response, the mass receives a velocity kick as it crosses
    ``x = 0`` upwards; the smallest kick after which impacts are *sustained*
    is found by a scan and bisection (:func:`disturbance_threshold`).  The
    thesis's demarcation curves of Fig. 4-7 are the level curves of this
    threshold over ``(F, omega)``.

For a study of many thousands of points: one point of ``cycles = 150``
forcing periods costs about half a millisecond with the compiled simulator;
pass ``workers`` or ``scheduler`` to spread the chunks.

All quantities are nondimensional.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf._flow import particular_coeffs
from rattle_lab.model.sdf._types import SDFParams, SDFState
from rattle_lab.model.sdf._simulate import simulate
from ._dask import check_execution, chunk_rows, run_chunks
from .lyapunov import lyapunov_from_result
from ._sweep import (
    KIND_CODES,
    KIND_NAMES,
    PERIOD_RTOL,
    _check_classification_window,
    _check_int,
    classify_settled,
)

MapKind = Literal["regime", "basin"]

__all__ = [
    "AttractorMap",
    "DisturbanceMap",
    "regime_map",
    "basin_map",
    "disturbance_threshold",
    "disturbance_map",
    "plot_attractor_map",
    "plot_disturbance_map",
]

# Columns of the per-point result rows of _attractor_rows.
_C_KIND, _C_M, _C_N, _C_MEAN, _C_MAX, _C_LYAP, _C_STICK = range(7)
_N_COLS = 7


# ---------------------------------------------------------------------------
# Per-point work (module level: picklable for Dask)
# ---------------------------------------------------------------------------

def _attractor_rows(task: tuple[np.ndarray, tuple[int, int, int, float, bool]]) -> np.ndarray:
    """Classify the attractor of each row ``(F, omega, zeta, e, x0, v0, theta0)``."""
    rows, (cycles, discard, n_max, rtol, lyapunov) = task
    out = np.empty((rows.shape[0], _N_COLS))
    kept = cycles - discard
    for k in range(rows.shape[0]):
        F, w, z, e, x0, v0, th0 = (float(q) for q in rows[k])
        p = SDFParams(F=F, omega=w, zeta=z, e=e)
        res = simulate(p, cycles=cycles, state=SDFState(x=x0, v=v0, theta=th0))
        t_keep = discard * p.period
        imp = res.impacts
        i0 = int(np.searchsorted(imp.t, t_keep, side="left"))
        t, v = imp.t[i0:], imp.v_in[i0:]
        regime, _ = classify_settled(p, t, v, t_start=t_keep, end_state=res.state,
                                     n_max=n_max, rtol=rtol)
        kind, m, n = KIND_CODES[regime.kind], regime.m, regime.n
        lyap = math.nan
        if lyapunov and kind == 2:
            lyap = lyapunov_from_result(res, t_start=0.0, warmup=t_keep).exponent
        stuck = res.sticking.shape[0] > 0 and bool(np.any(res.sticking[:, 1] > t_keep))
        out[k] = (kind, m, n, float(np.sum(v)) / kept, float(np.max(v)) if v.size else 0.0,
                  lyap, float(stuck))
    return out


def _impact_free_start(p: SDFParams, kick: float) -> SDFState:
    """On the impact-free response at its upward x = 0 crossing, with ``kick`` added to v."""
    A_c, A_s = particular_coeffs(p.F, p.omega, p.zeta)
    amplitude = math.hypot(float(A_c), float(A_s))
    # x_p = R cos(theta - delta) is 0 and rising at theta = delta - pi/2, with v = omega R.
    theta0 = math.atan2(float(A_s), float(A_c)) - 0.5 * math.pi
    return SDFState(x=0.0, v=p.omega * amplitude + kick, theta=theta0)


def _sustained(p: SDFParams, kick: float, cycles: int, check_cycles: int) -> bool:
    res = simulate(p, cycles=cycles, state=_impact_free_start(p, kick))
    t_check = (cycles - check_cycles) * p.period
    if res.impacts.t.size and res.impacts.t[-1] >= t_check:
        return True
    return res.sticking.shape[0] > 0 and bool(res.sticking[-1, 1] >= t_check)


def _threshold(p: SDFParams, kick_max: float, kick_tol: float, n_scan: int, cycles: int,
               check_cycles: int) -> float:
    grazing = math.hypot((1.0 - p.omega) * (1.0 + p.omega), 2.0 * p.zeta * p.omega)
    if p.F >= grazing:
        return math.nan  # no impact-free response to disturb (eq. 3.4)
    lo, hi = 0.0, math.inf
    for j in range(1, n_scan + 1):
        kick = kick_max * j / n_scan
        if _sustained(p, kick, cycles, check_cycles):
            hi = kick
            break
        lo = kick
    if math.isinf(hi):
        return math.inf
    while hi - lo > kick_tol:
        mid = 0.5 * (lo + hi)
        if _sustained(p, mid, cycles, check_cycles):
            hi = mid
        else:
            lo = mid
    return hi


def _disturbance_rows(task: tuple[np.ndarray, tuple[float, float, int, int, int]]) -> np.ndarray:
    """Disturbance threshold of each row ``(F, omega, zeta, e)``."""
    rows, (kick_max, kick_tol, n_scan, cycles, check_cycles) = task
    out = np.empty(rows.shape[0])
    for k in range(rows.shape[0]):
        F, w, z, e = (float(q) for q in rows[k])
        out[k] = _threshold(SDFParams(F=F, omega=w, zeta=z, e=e), kick_max, kick_tol, n_scan,
                            cycles, check_cycles)
    return out


# ---------------------------------------------------------------------------
# Attractor maps: regime maps and basins
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class AttractorMap:
    """The attractor reached at every point of a 2-D grid (regime map or basins).

    Arrays have shape ``(y.size, x.size)``: rows follow ``y``, columns ``x``.

    Attributes
    ----------
    kind : {"regime", "basin"}
        A regime map over ``(F, omega)`` or basins over ``(v0, x0)``.
    x_name, y_name : str
        ``"omega"`` and ``"F"`` (regime) or ``"x0"`` and ``"v0"`` (basin).
    x, y : ndarray
        The grid axes (nondimensional).
    fixed : dict
        The fixed quantities: ``zeta``, ``e`` and the initial state
        (``x0``, ``v0``, ``theta0``) of a regime map; ``F``, ``omega``,
        ``zeta``, ``e``, ``theta0`` of a basin map.
    code : ndarray of int
        0 no impact, 1 periodic, 2 aperiodic, 3 unsettled: a periodic match still
        converging after the extra periods of
        :func:`~rattle_lab.model.analysis._sweep.classify_settled`
        (:data:`rattle_lab.model.analysis._sweep.KIND_CODES`).
    m, n : ndarray of int
        ``m/n`` of periodic points (0 elsewhere).
    mean_impact_velocity : ndarray
        ``sum(v_im) / (cycles - discard)`` over the kept periods.
    max_impact_velocity : ndarray
        Largest ``v_im`` in the kept periods (0 without impacts).
    lyapunov : ndarray
        Largest Lyapunov exponent (per unit time) of aperiodic points, measured
        over the kept periods after the discarded ones as warm-up; NaN where
        not computed, ``-inf`` where the mass sticks.
    sticking : ndarray of bool
        The mass stuck to the stop in the kept periods.
    cycles, discard, n_max : int
        Periods simulated, discarded, and the largest period looked for.
    rtol : float
        Tolerance of the period detection.
    provenance : dict
        What made it.
    """

    kind: MapKind
    x_name: str
    y_name: str
    x: np.ndarray
    y: np.ndarray
    fixed: dict[str, float]
    code: np.ndarray
    m: np.ndarray
    n: np.ndarray
    mean_impact_velocity: np.ndarray
    max_impact_velocity: np.ndarray
    lyapunov: np.ndarray
    sticking: np.ndarray
    cycles: int
    discard: int
    n_max: int
    rtol: float
    provenance: dict[str, object] = field(default_factory=dict)

    def labels(self) -> np.ndarray:
        """Label of every point: ``"no impact"``, ``"m/n"``, ``"aperiodic"`` or ``"unsettled"``."""
        out = np.empty(self.code.shape, dtype=object)
        for idx in np.ndindex(self.code.shape):
            c = int(self.code[idx])
            out[idx] = f"{int(self.m[idx])}/{int(self.n[idx])}" if c == 1 else KIND_NAMES[c]\
                .replace("no-impact", "no impact")
        return out

    def counts(self) -> dict[str, int]:
        """Number of points per label, most frequent first."""
        labels, counts = np.unique(self.labels().ravel().astype(str), return_counts=True)
        order = np.argsort(-counts, kind="stable")
        return {str(labels[i]): int(counts[i]) for i in order}

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary (2-D lists, rows along ``y``; NaN/inf become None)."""
        def grid(a: np.ndarray) -> list[list[float | None]]:
            return [[float(v) if math.isfinite(v) else None for v in row] for row in a.tolist()]

        return {"kind": self.kind, "x_name": self.x_name, "y_name": self.y_name,
                "x": self.x.tolist(), "y": self.y.tolist(), "fixed": self.fixed,
                "labels": self.labels().tolist(), "code": self.code.tolist(),
                "m": self.m.tolist(), "n": self.n.tolist(),
                "mean_impact_velocity": grid(self.mean_impact_velocity),
                "max_impact_velocity": grid(self.max_impact_velocity),
                "lyapunov": grid(self.lyapunov), "sticking": self.sticking.tolist(),
                "counts": self.counts(), "cycles": self.cycles, "discard": self.discard,
                "n_max": self.n_max, "rtol": self.rtol, "provenance": self.provenance}


def _axis(name: str, values: ArrayLike) -> np.ndarray:
    a = np.asarray(values, dtype=float).ravel()
    if a.size == 0:
        raise ParameterError(f"`{name}` must not be empty")
    if not np.all(np.isfinite(a)):
        raise ParameterError(f"`{name}` must be finite, was {a[~np.isfinite(a)][0]}")
    return a


def _check_map_settings(cycles: object, discard: object, n_max: object, rtol: float,
                        chunk_size: object, workers: object, scheduler: object
                        ) -> tuple[int, int, int, int, str | None]:
    cycles_i, discard_i, n_max_i = _check_classification_window(cycles, discard, n_max, rtol)
    _check_int("chunk_size", chunk_size, 1)
    workers_i, sched = check_execution(workers, scheduler)
    return cycles_i, discard_i, n_max_i, workers_i, sched


def _run_attractors(rows: np.ndarray, shape: tuple[int, int], settings: tuple[Any, ...],
                    chunk_size: int, workers: int, scheduler: str | None, desc: str,
                    quiet: bool) -> np.ndarray:
    chunks = [(c, settings) for c in chunk_rows(rows, chunk_size)]
    parts = run_chunks(_attractor_rows, chunks, workers=workers, scheduler=scheduler, desc=desc,
                       quiet=quiet)
    return np.concatenate(parts, axis=0).reshape(shape + (_N_COLS,))


def _build(kind: MapKind, x_name: str, y_name: str, x: np.ndarray, y: np.ndarray,
           fixed: dict[str, float], res: np.ndarray, cycles: int, discard: int, n_max: int,
           rtol: float, provenance: dict[str, object]) -> AttractorMap:
    return AttractorMap(
        kind=kind, x_name=x_name, y_name=y_name, x=x, y=y, fixed=fixed,
        code=res[..., _C_KIND].astype(np.int8), m=res[..., _C_M].astype(np.int64),
        n=res[..., _C_N].astype(np.int64), mean_impact_velocity=res[..., _C_MEAN],
        max_impact_velocity=res[..., _C_MAX], lyapunov=res[..., _C_LYAP],
        sticking=res[..., _C_STICK] != 0.0, cycles=cycles, discard=discard, n_max=n_max,
        rtol=rtol, provenance=provenance)


def regime_map(F: ArrayLike, omega: ArrayLike, *, zeta: float = 0.05, e: float = 0.6,
               state: SDFState | None = None, cycles: int = 150, discard: int = 100,
               n_max: int = 12, rtol: float = PERIOD_RTOL, lyapunov: bool = True,
               chunk_size: int = 256, workers: int = 1, scheduler: str | None = None,
               quiet: bool = True) -> AttractorMap:
    """Classify the attractor at every point of an ``(F, omega)`` grid.

    Every point starts from the same ``state`` and runs ``cycles`` forcing
    periods; the last ``cycles - discard`` are classified.  Each point is
    independent (no continuation, unlike :func:`rattle_lab.model.analysis._sweep.sweep`),
    so where attractors coexist the map shows the one ``state`` leads to.

    Parameters
    ----------
    F, omega : array_like
        Grid axes (nondimensional), ``F >= 0``, ``omega > 0``.
    zeta, e : float
        Damping ratio and restitution.
    state : SDFState, optional
        Initial state of every point (default: at rest at x = 0, phase 0).
    cycles, discard : int
        Forcing periods simulated and discarded (default 150 and 100: from a
        cold start the transients are longer than in a sweep).
    n_max : int
        Largest period looked for (<= ``(cycles - discard) / 2``).
    rtol : float
        Tolerance of the period detection (:func:`~rattle_lab.model.analysis._sweep.classify_impacts`).
    lyapunov : bool
        Measure the largest Lyapunov exponent of aperiodic points (over the
        kept periods, from the same run: no extra simulation).
    chunk_size : int
        Points per chunk of work.
    workers : int
        Local worker processes (1: serial; more: a process pool, no Dask).
    scheduler : str, optional
        Address of a running ``dask.distributed`` scheduler.
    quiet : bool
        No progress bar.

    Returns
    -------
    AttractorMap
        ``kind="regime"``, ``x = omega``, ``y = F``.

    Raises
    ------
    ParameterError
        On an invalid argument.

    Examples
    --------
    >>> rm = regime_map([0.05, 0.2], [1.0], cycles=100, discard=70)
    >>> rm.labels()[:, 0].tolist()
    ['no impact', '1/1']
    """
    Fa, wa = _axis("F", F), _axis("omega", omega)
    cycles_i, discard_i, n_max_i, workers_i, sched = _check_map_settings(
        cycles, discard, n_max, rtol, chunk_size, workers, scheduler)
    state = SDFState() if state is None else state
    if not isinstance(state, SDFState) or state.stuck or state.t != 0.0:
        raise ParameterError(f"`state` must be an SDFState at t = 0, not stuck, was {state!r}")
    SDFParams(F=float(Fa.min()), omega=float(wa.min()), zeta=zeta, e=e)  # validate once
    SDFParams(F=float(Fa.max()), omega=float(wa.max()), zeta=zeta, e=e)
    FF, WW = np.meshgrid(Fa, wa, indexing="ij")
    rows = np.column_stack([FF.ravel(), WW.ravel(), np.full(FF.size, float(zeta)),
                            np.full(FF.size, float(e)), np.full(FF.size, state.x),
                            np.full(FF.size, state.v), np.full(FF.size, state.theta)])
    settings = (cycles_i, discard_i, n_max_i, float(rtol), bool(lyapunov))
    res = _run_attractors(rows, FF.shape, settings, int(chunk_size), workers_i, sched,
                          "regime map", quiet)
    fixed = {"zeta": float(zeta), "e": float(e), "x0": state.x, "v0": state.v,
             "theta0": state.theta}
    provenance: dict[str, object] = {
        "package": "rattle_lab", "version": __version__,
        "function": "rattle_lab.model.analysis.regime_map",
        "arguments": {"n_F": int(Fa.size), "n_omega": int(wa.size), **fixed,
                      "cycles": cycles_i, "discard": discard_i, "n_max": n_max_i,
                      "rtol": float(rtol), "lyapunov": bool(lyapunov)}}
    return _build("regime", "omega", "F", wa, Fa, fixed, res, cycles_i, discard_i, n_max_i,
                  float(rtol), provenance)


def basin_map(params: SDFParams, x0: ArrayLike, v0: ArrayLike, *, theta0: float = 0.0,
              cycles: int = 150, discard: int = 100, n_max: int = 12,
              rtol: float = PERIOD_RTOL, lyapunov: bool = True, chunk_size: int = 256,
              workers: int = 1, scheduler: str | None = None,
              quiet: bool = True) -> AttractorMap:
    """Basins of attraction: the attractor reached from each initial state ``(x0, v0)``.

    Parameters
    ----------
    params : SDFParams
        The parameter point (nondimensional).
    x0, v0 : array_like
        Grid of initial displacement (``<= 1``) and velocity.
    theta0 : float
        Initial forcing phase of every point.
    cycles, discard, n_max, rtol, lyapunov, chunk_size, workers, scheduler, quiet
        As for :func:`regime_map`.

    Returns
    -------
    AttractorMap
        ``kind="basin"``, ``x = x0``, ``y = v0``.  Coexisting attractors of
        the same label are told apart by ``mean_impact_velocity``.

    Raises
    ------
    ParameterError
        On an invalid argument.

    Examples
    --------
    In the hysteresis region the impact-free response and the 1/1 orbit coexist:

    >>> from rattle_lab.model.sdf import SDFParams
    >>> bm = basin_map(SDFParams(F=0.2, omega=1.15, zeta=0.05, e=0.6), [0.0], [0.0, 1.0],
    ...                cycles=100, discard=70)
    >>> bm.labels()[:, 0].tolist()
    ['no impact', '1/1']
    """
    if not isinstance(params, SDFParams):
        raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
    xa, va = _axis("x0", x0), _axis("v0", v0)
    if np.any(xa > 1.0):
        raise ParameterError(f"`x0` must be <= 1 (the stop is at x = 1), was {xa[xa > 1.0][0]}")
    if not math.isfinite(theta0):
        raise ParameterError(f"`theta0` must be finite, was {theta0}")
    cycles_i, discard_i, n_max_i, workers_i, sched = _check_map_settings(
        cycles, discard, n_max, rtol, chunk_size, workers, scheduler)
    VV, XX = np.meshgrid(va, xa, indexing="ij")
    n_pts = VV.size
    rows = np.column_stack([np.full(n_pts, params.F), np.full(n_pts, params.omega),
                            np.full(n_pts, params.zeta), np.full(n_pts, params.e), XX.ravel(),
                            VV.ravel(), np.full(n_pts, float(theta0))])
    settings = (cycles_i, discard_i, n_max_i, float(rtol), bool(lyapunov))
    res = _run_attractors(rows, VV.shape, settings, int(chunk_size), workers_i, sched,
                          "basins", quiet)
    fixed = {"F": params.F, "omega": params.omega, "zeta": params.zeta, "e": params.e,
             "theta0": float(theta0)}
    provenance: dict[str, object] = {
        "package": "rattle_lab", "version": __version__,
        "function": "rattle_lab.model.analysis.basin_map",
        "arguments": {"n_x0": int(xa.size), "n_v0": int(va.size), **fixed, "cycles": cycles_i,
                      "discard": discard_i, "n_max": n_max_i, "rtol": float(rtol),
                      "lyapunov": bool(lyapunov)}}
    return _build("basin", "x0", "v0", xa, va, fixed, res, cycles_i, discard_i, n_max_i,
                  float(rtol), provenance)


# ---------------------------------------------------------------------------
# Disturbance study
# ---------------------------------------------------------------------------

def _check_disturbance(kick_max: float, kick_tol: float, n_scan: object, cycles: object,
                       check_cycles: object) -> tuple[int, int, int]:
    if not (math.isfinite(kick_max) and kick_max > 0):
        raise ParameterError(f"`kick_max` must be finite and > 0, was {kick_max}")
    if not (math.isfinite(kick_tol) and 0 < kick_tol < kick_max):
        raise ParameterError(f"`kick_tol` must be in (0, kick_max), was {kick_tol}")
    n_scan_i = _check_int("n_scan", n_scan, 1)
    cycles_i = _check_int("cycles", cycles, 2)
    check_i = _check_int("check_cycles", check_cycles, 1)
    if check_i >= cycles_i:
        raise ParameterError(f"`check_cycles` must be < cycles = {cycles_i}, was {check_i}")
    return n_scan_i, cycles_i, check_i


def disturbance_threshold(params: SDFParams, *, kick_max: float = 2.0, kick_tol: float = 1e-3,
                          n_scan: int = 20, cycles: int = 200, check_cycles: int = 20) -> float:
    """Smallest velocity kick that turns the impact-free response into sustained impact.

    The mass starts on the impact-free (linear) response as it crosses
    ``x = 0`` upwards, with velocity ``omega R + kick`` (``R = F / sqrt(D)``,
    eq. 4.7), as in the thesis's Fig. 4-6.  Impact is *sustained* if at least
    one impact (or a stuck interval) occurs in the last ``check_cycles`` of
    ``cycles`` forcing periods.  On the impact-free attractor the kick's
    transient decays like ``exp(-zeta t)``: with the defaults (``zeta = 0.05``)
    it has shrunk by ``exp(-50)`` or more before the check starts, so no
    transient impact is counted; a trajectory that comes close to the
    unstable 1/1 orbit lingers there for a time that grows only like
    ``log(1 / distance)``, so the bracket ends are classified correctly to
    within ``kick_tol``.

    The kicks ``kick_max * j / n_scan`` (``j = 1, 2, ...``) are tried in turn;
    the first one that sustains impact is refined by bisection against the
    previous one to ``kick_tol``.  A window of sustained impact narrower than
    ``kick_max / n_scan`` below the first one found can be missed.

    Parameters
    ----------
    params : SDFParams
        Nondimensional parameters; ``F`` below the grazing forcing (eq. 3.4).
    kick_max : float
        Largest kick tried (nondimensional velocity), > 0.
    kick_tol : float
        Width of the final bracket, in ``(0, kick_max)``.
    n_scan : int
        Number of kicks of the coarse scan.
    cycles, check_cycles : int
        Run length after the kick and the final window checked for impacts.

    Returns
    -------
    float
        The threshold kick (upper end of the final bracket, so that kick
        sustains impact); NaN if ``F`` is at or above the grazing forcing (no
        impact-free response exists); ``inf`` if no kick up to ``kick_max`` does.

    Raises
    ------
    ParameterError
        On an invalid argument.

    Examples
    --------
    >>> from rattle_lab.model.sdf import SDFParams
    >>> kick = disturbance_threshold(SDFParams(F=0.2, omega=1.15, zeta=0.05, e=0.6))
    >>> bool(0.0 < kick < 2.0)
    True
    """
    if not isinstance(params, SDFParams):
        raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
    n_scan_i, cycles_i, check_i = _check_disturbance(kick_max, kick_tol, n_scan, cycles,
                                                     check_cycles)
    return _threshold(params, float(kick_max), float(kick_tol), n_scan_i, cycles_i, check_i)


@dataclass(frozen=True)
class DisturbanceMap:
    """Disturbance thresholds over an ``(F, omega)`` grid (thesis Fig. 4-7).

    Attributes
    ----------
    F, omega : ndarray
        Grid axes (nondimensional).
    zeta, e : float
        Damping ratio and restitution.
    threshold : ndarray, shape (F.size, omega.size)
        Smallest kick that sustains impact (:func:`disturbance_threshold`):
        NaN at or above grazing, ``inf`` if none up to ``kick_max``.
    hysteresis : ndarray of bool
        The hysteresis region: ``omega > 1`` and ``F_sn(omega) < F < F_g(omega)``
        (1/1 saddle-node, eq. 3.11, and grazing, eq. 3.4), where the
        impact-free response and the 1/1 orbit coexist.
    kick_max, kick_tol : float
    n_scan, cycles, check_cycles : int
        The search settings.
    provenance : dict
        What made it.
    """

    F: np.ndarray
    omega: np.ndarray
    zeta: float
    e: float
    threshold: np.ndarray
    hysteresis: np.ndarray
    kick_max: float
    kick_tol: float
    n_scan: int
    cycles: int
    check_cycles: int
    provenance: dict[str, object] = field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary; ``inf`` becomes the string ``"inf"``, NaN None."""
        def cell(v: float) -> float | str | None:
            if math.isnan(v):
                return None
            return "inf" if math.isinf(v) else float(v)

        return {"kind": "disturbance", "F": self.F.tolist(), "omega": self.omega.tolist(),
                "zeta": self.zeta, "e": self.e,
                "threshold": [[cell(v) for v in row] for row in self.threshold.tolist()],
                "hysteresis": self.hysteresis.tolist(), "kick_max": self.kick_max,
                "kick_tol": self.kick_tol, "n_scan": self.n_scan, "cycles": self.cycles,
                "check_cycles": self.check_cycles, "provenance": self.provenance}


def _hysteresis_region(F: np.ndarray, omega: np.ndarray, zeta: float, e: float) -> np.ndarray:
    from .orbits import saddle_node_forcing

    F_sn, v_sn = saddle_node_forcing(1, omega, zeta, e)
    F_g = np.hypot((1.0 - omega) * (1.0 + omega), 2.0 * zeta * omega)
    ok = (omega > 1.0) & (v_sn > 0.0)
    return ok[None, :] & (F[:, None] > F_sn[None, :]) & (F[:, None] < F_g[None, :])


def disturbance_map(F: ArrayLike, omega: ArrayLike, *, zeta: float = 0.05, e: float = 0.6,
                    kick_max: float = 2.0, kick_tol: float = 1e-3, n_scan: int = 20,
                    cycles: int = 200, check_cycles: int = 20, chunk_size: int = 16,
                    workers: int = 1, scheduler: str | None = None,
                    quiet: bool = True) -> DisturbanceMap:
    """Disturbance thresholds (:func:`disturbance_threshold`) over an ``(F, omega)`` grid.

    The level curves ``threshold = V`` are the thesis's demarcation curves
    (Fig. 4-7): above the curve of ``V`` (larger ``F``) a kick ``V`` sets the
    system into sustained impact.

    Parameters
    ----------
    F, omega : array_like
        Grid axes (nondimensional).
    zeta, e : float
        Damping ratio and restitution.
    kick_max, kick_tol, n_scan, cycles, check_cycles
        As for :func:`disturbance_threshold`.
    chunk_size, workers, scheduler, quiet
        As for :func:`regime_map`.

    Returns
    -------
    DisturbanceMap

    Raises
    ------
    ParameterError
        On an invalid argument.
    """
    Fa, wa = _axis("F", F), _axis("omega", omega)
    n_scan_i, cycles_i, check_i = _check_disturbance(kick_max, kick_tol, n_scan, cycles,
                                                     check_cycles)
    _check_int("chunk_size", chunk_size, 1)
    workers_i, sched = check_execution(workers, scheduler)
    SDFParams(F=float(Fa.min()), omega=float(wa.min()), zeta=zeta, e=e)
    SDFParams(F=float(Fa.max()), omega=float(wa.max()), zeta=zeta, e=e)
    FF, WW = np.meshgrid(Fa, wa, indexing="ij")
    rows = np.column_stack([FF.ravel(), WW.ravel(), np.full(FF.size, float(zeta)),
                            np.full(FF.size, float(e))])
    settings = (float(kick_max), float(kick_tol), n_scan_i, cycles_i, check_i)
    chunks = [(c, settings) for c in chunk_rows(rows, int(chunk_size))]
    parts = run_chunks(_disturbance_rows, chunks, workers=workers_i, scheduler=sched,
                       desc="disturbance map", quiet=quiet)
    threshold = np.concatenate(parts).reshape(FF.shape)
    provenance: dict[str, object] = {
        "package": "rattle_lab", "version": __version__,
        "function": "rattle_lab.model.analysis.disturbance_map",
        "arguments": {"n_F": int(Fa.size), "n_omega": int(wa.size), "zeta": float(zeta),
                      "e": float(e), "kick_max": float(kick_max), "kick_tol": float(kick_tol),
                      "n_scan": n_scan_i, "cycles": cycles_i, "check_cycles": check_i}}
    return DisturbanceMap(F=Fa, omega=wa, zeta=float(zeta), e=float(e), threshold=threshold,
                          hysteresis=_hysteresis_region(Fa, wa, float(zeta), float(e)),
                          kick_max=float(kick_max), kick_tol=float(kick_tol), n_scan=n_scan_i,
                          cycles=cycles_i, check_cycles=check_i, provenance=provenance)


# ---------------------------------------------------------------------------
# Plots
# ---------------------------------------------------------------------------

def _save(fig: Any, path: str | Path) -> Path:
    from rattle_lab._atomic import atomic_path
    from .bifsets import check_plot_path

    path = Path(path)
    fmt = check_plot_path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, dpi=150)
    return path


def _boundary_curves(ax: Any, omega: np.ndarray, zeta: float, e: float, F_lim: tuple[float, float]
                     ) -> None:
    from .orbits import saddle_node_forcing

    w = np.linspace(float(omega.min()), float(omega.max()), 400)
    F_g = np.hypot((1.0 - w) * (1.0 + w), 2.0 * zeta * w)
    ax.plot(w, F_g, color="black", linewidth=1.5, label="grazing, eq. (3.4)")
    F_sn, v_sn = saddle_node_forcing(1, w, zeta, e)
    F_sn = np.where((w > 1.0) & (v_sn > 0.0), F_sn, np.nan)
    if np.any(np.isfinite(F_sn)):
        ax.plot(w, F_sn, color="black", linestyle="-.", linewidth=1.2,
                label="1/1 saddle-node, eq. (3.11)")
    ax.set_ylim(*F_lim)


def plot_attractor_map(amap: AttractorMap, path: str | Path, *, max_labels: int = 12) -> Path:
    """Plot a regime map or basins (one colour per regime label) and write it atomically.

    The ``max_labels - 1`` most frequent labels get their own colour, the rest
    share one (``"other"``).  A regime map also shows the grazing curve
    (eq. 3.4) and the 1/1 saddle-node (eq. 3.11).

    Parameters
    ----------
    amap : AttractorMap
        What :func:`regime_map` or :func:`basin_map` returned.
    path : str or Path
        ``.png``, ``.pdf`` or ``.svg``.
    max_labels : int
        Colours in the legend.

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        If the suffix is not supported.
    OutputError
        If the directory does not exist.
    """
    import matplotlib
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from .bifsets import check_plot_path

    check_plot_path(path)
    labels = amap.labels().astype(str)
    ranked = list(amap.counts())
    fixed_colors = {"no impact": "#ffffff", "aperiodic": "#222222", "unsettled": "#bbbbbb"}
    shown = ranked[:max_labels - 1] if len(ranked) > max_labels else ranked
    palette = list(matplotlib.colormaps["tab20"].colors)  # type: ignore[attr-defined]
    colors: list[Any] = []
    k = 0
    for lab in shown:
        if lab in fixed_colors:
            colors.append(fixed_colors[lab])
        else:
            colors.append(palette[k % len(palette)])
            k += 1
    index = {lab: i for i, lab in enumerate(shown)}
    other = len(shown)
    idx = np.vectorize(lambda s: index.get(s, other))(labels).astype(float)
    if len(shown) < len(ranked):
        colors.append("#999999")
    fig = Figure(figsize=(9.0, 6.0), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(amap.x, amap.y, idx, cmap=ListedColormap(colors), vmin=-0.5,
                  vmax=len(colors) - 0.5, shading="nearest")
    handles: list[Any] = [Patch(facecolor=c, edgecolor="0.5", label=lab)
                          for lab, c in zip(shown + (["other"] if len(shown) < len(ranked)
                                                     else []), colors)]
    if amap.kind == "regime":
        _boundary_curves(ax, amap.x, amap.fixed["zeta"], amap.fixed["e"],
                         (float(amap.y.min()), float(amap.y.max())))
        ax.set_xlim(float(amap.x.min()), float(amap.x.max()))
        ax.set_xlabel("forcing frequency omega (nondimensional)")
        ax.set_ylabel("forcing amplitude F (nondimensional)")
        ax.set_title(f"Regime map (zeta = {amap.fixed['zeta']:g}, e = {amap.fixed['e']:g}; "
                     f"{amap.cycles} periods, last {amap.cycles - amap.discard} classified)")
        handles.extend(ax.get_legend_handles_labels()[0])
    else:
        f = amap.fixed
        ax.set_xlabel("initial displacement x0 (nondimensional)")
        ax.set_ylabel("initial velocity v0 (nondimensional)")
        ax.set_title(f"Basins of attraction (F = {f['F']:g}, omega = {f['omega']:g}, "
                     f"zeta = {f['zeta']:g}, e = {f['e']:g}, theta0 = {f['theta0']:g})")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
              borderaxespad=0.0)
    return _save(fig, path)


def plot_disturbance_map(dmap: DisturbanceMap, path: str | Path, *,
                         levels: tuple[float, ...] = (0.1, 0.2, 0.4)) -> Path:
    """Plot the demarcation curves of thesis Fig. 4-7 and write the figure atomically.

    The threshold is shown in colour over the grid; the level curves
    ``threshold = V`` for each ``V`` in ``levels`` are the demarcation curves
    (a kick ``V`` sustains impact above the curve).  The grazing curve and the
    1/1 saddle-node bound the hysteresis region.

    Parameters
    ----------
    dmap : DisturbanceMap
        What :func:`disturbance_map` returned.
    path : str or Path
        ``.png``, ``.pdf`` or ``.svg``.
    levels : tuple of float
        Disturbance velocities of the demarcation curves (nondimensional).

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        If the suffix is not supported or ``levels`` are not positive.
    OutputError
        If the directory does not exist.
    """
    from matplotlib.figure import Figure

    from .bifsets import check_plot_path

    check_plot_path(path)
    lv = sorted(float(v) for v in levels)
    if not lv or any(not (math.isfinite(v) and v > 0) for v in lv):
        raise ParameterError(f"`levels` must be positive numbers, was {levels!r}")
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    fig = Figure(figsize=(9.5, 6.0), layout="constrained")
    ax = fig.add_subplot()
    th = dmap.threshold
    # above grazing (NaN): impact without any disturbance; inf: none up to kick_max
    cat = np.where(np.isnan(th), 0.0, np.where(np.isinf(th), 1.0, np.nan))
    ax.pcolormesh(dmap.omega, dmap.F, cat, cmap=ListedColormap(["#d9d9d9", "#ffffff"]),
                  vmin=-0.5, vmax=1.5, shading="nearest")
    mesh = ax.pcolormesh(dmap.omega, dmap.F, np.where(np.isfinite(th), th, np.nan),
                         cmap="viridis", shading="nearest", vmin=0.0, vmax=dmap.kick_max)
    fig.colorbar(mesh, ax=ax, label="threshold kick (nondimensional velocity)")
    if dmap.F.size > 1 and dmap.omega.size > 1:
        # for the level curves: above grazing every kick (even 0) gives impact; where no
        # kick up to kick_max does, the threshold is unknown (masked: no curve drawn there)
        filled = np.ma.masked_invalid(np.where(np.isnan(th), 0.0, np.where(np.isinf(th),
                                                                           np.nan, th)))
        cs = ax.contour(dmap.omega, dmap.F, filled, levels=lv, colors="red", linewidths=1.4)
        ax.clabel(cs, fmt=lambda v: f"V = {v:g}", fontsize=8)
    _boundary_curves(ax, dmap.omega, dmap.zeta, dmap.e, (float(dmap.F.min()), float(dmap.F.max())))
    ax.set_xlim(float(dmap.omega.min()), float(dmap.omega.max()))
    ax.set_xlabel("forcing frequency omega (nondimensional)")
    ax.set_ylabel("forcing amplitude F (nondimensional)")
    ax.set_title(f"Disturbance demarcation curves (zeta = {dmap.zeta:g}, e = {dmap.e:g})\n"
                 "a kick V at the upward x = 0 crossing sustains impact above the curve V",
                 fontsize=10)
    handles = ax.get_legend_handles_labels()[0] + [
        Patch(facecolor="#d9d9d9", edgecolor="0.5", label="above grazing: impact without kick"),
        Patch(facecolor="#ffffff", edgecolor="0.5",
              label=f"no sustained impact up to kick {dmap.kick_max:g}")]
    ax.legend(handles=handles, loc="lower right", fontsize=8)
    return _save(fig, path)
