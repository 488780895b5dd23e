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
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams, SDFState, simulate

from ._dask import check_execution, chunk_rows, run_chunks
from ._sweep import (
    KIND_CODES,
    KIND_NAMES,
    PERIOD_RTOL,
    _check_classification_window,
    _check_int,
    classify_settled,
)
from .lyapunov import lyapunov_from_result

MapKind = Literal["regime", "basin"]

__all__ = [
    "AttractorMap",
    "regime_map",
    "basin_map",
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


