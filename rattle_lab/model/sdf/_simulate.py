"""Public entry point of the SDF simulator: :func:`simulate`."""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab.exceptions import NumericalWarning, ParameterError, SimulationError
from ._flow import homogeneous_transition, particular_state
from ._types import (
    TWO_PI,
    Crossings,
    DenseSamples,
    SimImpacts,
    SDFParams,
    SDFState,
    SimResult,
)

Method = Literal["exact", "exact-python", "rk4-thesis"]
DenseField = Literal["x", "v", "a", "forced", "transient", "excitation"]
_METHODS = ("exact", "exact-python", "rk4-thesis")
_DENSE_FIELDS = ("x", "v", "a", "forced", "transient", "excitation")
_DENSE_DEFAULT: tuple[DenseField, ...] = ("x", "v", "a")


def simulate(
    params: SDFParams,
    *,
    duration: float | None = None,
    cycles: float | None = None,
    state: SDFState | None = None,
    crossings: bool = False,
    dense_t: ArrayLike | None = None,
    dense_fields: Sequence[DenseField] = _DENSE_DEFAULT,
    method: Method = "exact",
    steps_per_period: int = 200,
    max_events: int | None = None,
) -> SimResult:
    """Simulate the nondimensional SDF impact oscillator.

    ``x'' + 2 zeta x' + x = F cos(omega t + phi)`` for ``x < 1``; at ``x = 1``
    the velocity maps ``v -> -e v`` (thesis eq. 2.33).  All quantities are
    nondimensional.

    Parameters
    ----------
    params : SDFParams
        Forcing amplitude ``F``, frequency ratio ``omega``, damping ``zeta`` and
        restitution ``e``.
    duration : float, optional
        Time to simulate (nondimensional).  Give exactly one of ``duration``
        and ``cycles``.
    cycles : float, optional
        Number of forcing periods ``2 pi / omega`` to simulate.
    state : SDFState, optional
        Initial state (default: at rest at x = 0, t = 0, phase 0).  Pass the
        previous result's ``state`` to continue a run, possibly with new
        parameters: the forcing phase stays continuous.
    crossings : bool
        Also record the upward x = 0 crossings and their velocities.
    dense_t : array_like, optional
        Non-decreasing sample times within ``[state.t, state.t + duration]`` at
        which to evaluate the motion.  Nothing dense is computed otherwise.
    dense_fields : sequence of str
        Which dense fields to return: any of ``"x"``, ``"v"``, ``"a"``,
        ``"forced"``, ``"transient"``, ``"excitation"``.
    method : {"exact", "exact-python", "rk4-thesis"}
        ``"exact"``: the compiled event-driven closed-form solver (default);
        ``"exact-python"``: the same algorithm, not compiled (reference);
        ``"rk4-thesis"``: the thesis's RK4 with linear impact prediction
        (Appendix A.1 ``evolve``), step ``T / steps_per_period``.
    steps_per_period : int
        Steps per forcing period for ``"rk4-thesis"`` (thesis: 200).
    max_events : int, optional
        Budget of events (impacts, releases, accumulations); default
        ``10**6 + 1000 * (cycles + 1)``.

    Returns
    -------
    SimResult

    Raises
    ------
    ParameterError
        On an invalid argument.
    SimulationError
        If the event budget is exhausted.

    Examples
    --------
    >>> import numpy as np
    >>> from rattle_lab.model.sdf import SDFParams, simulate
    >>> res = simulate(SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6), cycles=40)
    >>> bool(len(res.impacts) > 0 and np.all(res.impacts.v_in > 0))
    True
    """
    # The checks come in the order of the common call (exact method, `cycles`, a state,
    # no dense output): each is a cheap test on the fast path, and every failure raises
    # a ParameterError naming the argument.  A call's fixed cost is a few microseconds
    # (benchmarks/speed_goals.py), so the order and the number of steps here matter.
    if type(params) is not SDFParams and not isinstance(params, SDFParams):
        raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
    if method not in _METHODS:
        raise ParameterError(f"`method` must be one of {_METHODS}, was {method!r}")
    omega = params.omega
    if cycles is not None:
        if duration is not None:
            raise ParameterError("give exactly one of `duration` and `cycles`")
        try:
            cycles = float(cycles)
        except (TypeError, ValueError):
            raise ParameterError(f"`cycles` must be a number, was {cycles!r}") from None
        if not (cycles >= 0.0 and cycles < math.inf):   # NaN fails the first test
            raise ParameterError(f"`cycles` must be finite and >= 0, was {cycles}")
        duration = cycles * (TWO_PI / omega)
    elif duration is None:
        raise ParameterError("give exactly one of `duration` and `cycles`")
    else:
        cycles = None
    try:
        duration = float(duration)
    except (TypeError, ValueError):
        raise ParameterError(f"`duration` must be a number, was {duration!r}") from None
    if not (duration >= 0.0 and duration < math.inf):
        raise ParameterError(f"`duration` must be finite and >= 0, was {duration}")
    if state is None:
        state = _REST
    elif type(state) is not SDFState and not isinstance(state, SDFState):
        raise ParameterError(f"`state` must be an SDFState, was {type(state).__name__}")
    if max_events is None:
        n_periods = cycles if cycles is not None else duration * omega / TWO_PI
        max_events = 10**6 + int(1000 * (n_periods + 1.0))
    elif isinstance(max_events, bool) or not isinstance(max_events, int | np.integer):
        raise ParameterError(f"`max_events` must be an integer, was {max_events!r}")
    elif max_events <= 0:
        raise ParameterError(f"`max_events` must be > 0, was {max_events}")
    if dense_fields is not _DENSE_DEFAULT:
        fields = tuple(dense_fields)
        for name in fields:
            if name not in _DENSE_FIELDS:
                raise ParameterError(
                    f"`dense_fields` entries must be in {_DENSE_FIELDS}, was {name!r}")
    else:
        fields = _DENSE_DEFAULT
    t_grid: np.ndarray | None = None
    if dense_t is not None:
        t_grid = _checked_grid(dense_t, state.t, duration)

    if method == "rk4-thesis":
        return _simulate_rk4(params, state, duration, crossings, t_grid, steps_per_period)

    run = _RUN_PACKED[method == "exact"] or _run_packed(method == "exact")
    buf = run(params.F, omega, params.zeta, params.e, state.t, state.x, state.v, state.theta,
              bool(state.stuck), duration, bool(crossings), t_grid is not None,
              int(max_events))
    (n_imp, n_acc, n_stk, n_crs, n_seg, n_avg, t_end, x_end, v_end, th_end, stuck_end,
     n_events, status, n_unresolved) = buf[:_N_HEAD].tolist()
    if status != 0:
        raise SimulationError(
            f"event budget of {max_events} events exhausted at t = {t_end:.17g} "
            f"(F={params.F}, omega={params.omega}, zeta={params.zeta}, e={params.e}); "
            "raise `max_events` or shorten the run")
    if n_unresolved:
        warnings.warn(
            f"{int(n_unresolved)} event searches were settled at the work cap "
            f"(F={params.F}, omega={params.omega}, zeta={params.zeta}, e={params.e}); "
            "impacts in them are located only to the resolution reached",
            NumericalWarning, stacklevel=2)
    end = SDFState._from_kernel(t_end, x_end, v_end, th_end, stuck_end != 0.0)
    if buf.size == _N_HEAD and t_grid is None:   # nothing logged (a short call): no slicing
        return SimResult._from_kernel(params, method, _NO_IMPACTS, _NO_ACC, _NO_STICKING,
                                      _NO_CROSSINGS if crossings else None, None, end,
                                      int(n_events), _NO_MICRO)
    n_imp, n_acc, n_stk, n_crs, n_seg, n_avg = (int(n_imp), int(n_acc), int(n_stk),
                                                int(n_crs), int(n_seg), int(n_avg))
    k = _N_HEAD
    if n_imp:
        impacts = SimImpacts._from_columns(buf[k:k + 4 * n_imp].reshape(4, n_imp))
        k += 4 * n_imp
    else:
        impacts = _NO_IMPACTS
    acc = buf[k:k + n_acc] if n_acc else _NO_ACC
    k += n_acc
    stk = buf[k:k + 2 * n_stk].reshape(n_stk, 2) if n_stk else _NO_STICKING
    k += 2 * n_stk
    cross = None
    if crossings:
        c = buf[k:k + 2 * n_crs].reshape(2, n_crs)
        cross = Crossings(t=c[0], v=c[1])
    k += 2 * n_crs
    dense = None
    if t_grid is not None:
        segments = buf[k:k + 5 * n_seg].reshape(n_seg, 5)
        if n_seg == 0:  # zero duration: the initial state is the only segment
            xp0, vp0 = particular_state(params.F, params.omega, params.zeta, state.theta)
            segments = np.array([[state.t, state.theta, state.x - float(xp0),
                                  state.v - float(vp0), 1.0 if state.stuck else 0.0]])
        dense = dense_from_segments(params, segments, t_grid, fields)
    k += 5 * n_seg
    avg = buf[k:k + 3 * n_avg].reshape(n_avg, 3) if n_avg else _NO_MICRO
    return SimResult._from_kernel(params, method, impacts, acc, stk, cross, dense, end,
                                  int(n_events), avg)


def _checked_grid(dense_t: ArrayLike, t0: float, duration: float) -> np.ndarray:
    """``dense_t`` as a float array, checked: 1-D, finite, non-decreasing, in the run."""
    t_grid = np.asarray(dense_t, dtype=float)
    if t_grid.ndim != 1:
        raise ParameterError(f"`dense_t` must be one-dimensional, had shape {t_grid.shape}")
    if t_grid.size:
        if not np.all(np.isfinite(t_grid)):
            raise ParameterError("`dense_t` must be finite")
        if np.any(np.diff(t_grid) < 0):
            raise ParameterError("`dense_t` must be non-decreasing")
        t_stop = t0 + duration
        slack = 8 * np.finfo(float).eps * max(1.0, abs(t_stop))
        if t_grid[0] < t0 - slack or t_grid[-1] > t_stop + slack:
            raise ParameterError(
                f"`dense_t` must lie within [{t0}, {t_stop}], "
                f"was [{t_grid[0]}, {t_grid[-1]}]")
    return t_grid


_N_HEAD = 14   # rattle_lab.model.sdf._kernel.N_HEAD (asserted in the tests)
_NO_IMPACTS = SimImpacts(t=np.empty(0), phase=np.empty(0), v_in=np.empty(0), v_out=np.empty(0))
_NO_CROSSINGS = Crossings(t=np.empty(0), v=np.empty(0))
# the empty logs every short call returns: shared, and read-only as SimImpacts' arrays
_NO_ACC = np.empty(0)
_NO_STICKING = np.empty((0, 2))
_NO_MICRO = np.empty((0, 3))
for _a in (_NO_ACC, _NO_STICKING, _NO_MICRO):
    _a.setflags(write=False)
del _a
_REST = SDFState()
#: run_packed of (pure-Python kernel, compiled kernel), looked up on first use
_RUN_PACKED: list[Callable[..., np.ndarray] | None] = [None, None]


def _run_packed(compiled: bool) -> Callable[..., np.ndarray]:
    """``run_packed`` of the compiled (or pure-Python) kernel, imported on first use.

    For the compiled kernel this is the entry point of its one compiled signature, called
    without numba's dispatcher: the dispatcher works out the types of the 13 arguments
    on every call (about 0.3-0.5 us, a tenth of a short call), and :func:`simulate`
    always passes the same types (float, bool, int; the entry point converts them as
    the dispatcher would).  If that entry point cannot be found (another numba), the
    dispatcher is used.
    """
    from ._compiled import jit_kernel, python_kernel

    if not compiled:
        func: Callable[..., np.ndarray] = python_kernel.run_packed
    else:
        dispatcher = jit_kernel.run_packed
        func = dispatcher
        warm = (0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, 0.0, False, False, 1)
        dispatcher(*warm)   # loads (or compiles) the signature simulate() uses
        try:
            sig = tuple(dispatcher.typeof_pyval(a) for a in warm)
            entry = dispatcher.overloads[sig].entry_point
        except (AttributeError, KeyError, TypeError):  # pragma: no cover - another numba
            entry = None
        if callable(entry):
            func = entry
    _RUN_PACKED[compiled] = func
    return func


@dataclass(frozen=True)
class PieceRun:
    """What :func:`simulate_pieces` returns.

    Attributes
    ----------
    impact_t : ndarray
        Impact times of all pieces run, in time order.
    offsets : ndarray
        Piece ``j``'s impacts are ``impact_t[offsets[j]:offsets[j + 1]]``; length
        ``n_run + 1``.
    ends : ndarray
        Shape (n_run, 5): ``(t, x, v, theta, stuck)`` at the end of each piece run.
    """

    impact_t: np.ndarray
    offsets: np.ndarray
    ends: np.ndarray

    def state(self, j: int) -> SDFState:
        """The state at the end of piece ``j``."""
        t, x, v, th, stuck = (float(a) for a in self.ends[j])
        return SDFState(t=t, x=x, v=v, theta=th, stuck=stuck != 0.0)


def simulate_pieces(F: ArrayLike, *, omega: float, zeta: float, e: float, t_stop: ArrayLike,
                    state: SDFState, group_gap: float | None = None, group_size: int = 4,
                    quiet_time: float | None = None, quiet_ok: ArrayLike | None = None,
                    last_impact_t: float = math.nan) -> PieceRun:
    """Pieces of constant forcing amplitude in one compiled call, the state carried over.

    Piece ``j`` runs at ``F[j]`` until time ``t_stop[j]``: the same motion, to the last
    bit, as the loop ``state = simulate(SDFParams(F[j], omega, zeta, e),
    duration=max(0, t_stop[j] - state.t), state=state).state`` (tested), without its
    fixed cost per call.  Used to replay a ramp of the forcing level.

    Parameters
    ----------
    F : array_like
        Forcing amplitude of each piece, >= 0.
    omega, zeta, e : float
        As in :class:`SDFParams`.
    t_stop : array_like
        End time of each piece (nondimensional), same length as ``F``.
    state : SDFState
        State at the start of the first piece.
    group_gap, group_size : float, int
        Stop after the piece in which ``group_size`` consecutive impacts, each less than
        ``group_gap`` after the previous (nondimensional), are first complete.
    quiet_time : float, optional
        Stop after the first piece ``j`` without impacts with ``quiet_ok[j]`` that ends
        more than ``quiet_time`` after the last impact (``last_impact_t``: the last one
        before this call, NaN if none).
    quiet_ok : array_like of bool, optional
        Where the quiet stop may happen (default: every piece).
    last_impact_t : float
        Time of the last impact before ``state`` (NaN: none).

    Returns
    -------
    PieceRun
        The pieces run (all, or up to the stop).

    Raises
    ------
    ParameterError
        On invalid parameters or arrays of different lengths.
    SimulationError
        If a piece exhausts its event budget (as :func:`simulate` would).
    """
    F_arr = np.ascontiguousarray(F, dtype=float)
    t_arr = np.ascontiguousarray(t_stop, dtype=float)
    if F_arr.ndim != 1 or F_arr.shape != t_arr.shape:
        raise ParameterError(f"`F` and `t_stop` must be 1-D of one length, had shapes "
                             f"{F_arr.shape} and {t_arr.shape}")
    if F_arr.size:
        if not (np.all(np.isfinite(F_arr)) and F_arr.min() >= 0):
            raise ParameterError("`F` must be finite and >= 0")
        if not np.all(np.isfinite(t_arr)):
            raise ParameterError("`t_stop` must be finite")
    SDFParams(F=0.0, omega=omega, zeta=zeta, e=e)   # validates omega, zeta, e
    ok = (np.ones(F_arr.shape, dtype=np.bool_) if quiet_ok is None
          else np.ascontiguousarray(quiet_ok, dtype=np.bool_))
    if ok.shape != F_arr.shape:
        raise ParameterError(f"`quiet_ok` must have the shape of `F`, had {ok.shape}")
    if int(group_size) != group_size or group_size < 1:
        raise ParameterError(f"`group_size` must be an integer >= 1, was {group_size}")
    from ._compiled import jit_kernel, signals_deferred

    with signals_deferred():  # a Ctrl-C while the arrays are boxed would crash the process
        imp, off, ends, info = jit_kernel.run_pieces(
            F_arr, float(omega), float(zeta), float(e), float(state.t), float(state.x),
            float(state.v), float(state.theta), bool(state.stuck), t_arr,
            -1.0 if group_gap is None else float(group_gap), int(group_size),
            -1.0 if quiet_time is None else float(quiet_time), ok, float(last_impact_t))
    n_run = int(np.count_nonzero(info[:, 0] >= 0))
    off = off[:n_run + 1]
    ends = ends[:n_run]
    bad = np.flatnonzero(info[:n_run, 0] != 0)
    if bad.size:
        j = int(bad[0])
        raise SimulationError(f"event budget exhausted in piece {j} at t = {ends[j, 0]:.17g} "
                              f"(F={F_arr[j]}, omega={omega}, zeta={zeta}, e={e})")
    n_unresolved = float(info[:n_run, 1].sum())
    if n_unresolved:
        warnings.warn(
            f"{int(n_unresolved)} event searches were settled at the work cap "
            f"(omega={omega}, zeta={zeta}, e={e}); impacts in them are located only to the "
            "resolution reached", NumericalWarning, stacklevel=2)
    return PieceRun(impact_t=np.array(imp[:, 0]), offsets=off, ends=ends)


def dense_from_segments(params: SDFParams, segments: np.ndarray, t: np.ndarray,
                        fields: Sequence[str]) -> DenseSamples:
    """Evaluate the piecewise closed-form motion on the grid ``t``.

    ``segments`` rows are ``(t_start, theta0, y0, yd0, kind)`` as recorded by the
    kernel (kind 0: free flight with homogeneous initial state (y0, yd0);
    kind 1: stuck on the stop).  Displacements computed within rounding above
    the stop (at most a few ulp, next to an impact located to rounding) are
    reported as exactly 1.
    """
    F, w, z = params.F, params.omega, params.zeta
    idx = np.searchsorted(segments[:, 0], t, side="right") - 1
    idx = np.clip(idx, 0, len(segments) - 1)
    seg = segments[idx]
    s = np.maximum(t - seg[:, 0], 0.0)
    th = seg[:, 1] + w * s
    free = seg[:, 4] == 0.0
    Ec, Es = homogeneous_transition(z, s)
    y = (Ec + z * Es) * seg[:, 2] + Es * seg[:, 3]
    yd = -Es * seg[:, 2] + (Ec - z * Es) * seg[:, 3]
    xp, vp = particular_state(F, w, z, th, s)
    x = np.where(free, np.minimum(xp + y, 1.0), 1.0)
    v = np.where(free, vp + yd, 0.0)
    excitation = F * np.cos(th)
    out: dict[str, np.ndarray] = {}
    if "x" in fields:
        out["x"] = x
    if "v" in fields:
        out["v"] = v
    if "a" in fields:
        out["a"] = np.where(free, excitation - 2.0 * z * v - x, 0.0)
    if "forced" in fields:
        out["forced"] = xp
    if "transient" in fields:
        out["transient"] = x - xp
    if "excitation" in fields:
        out["excitation"] = excitation
    return DenseSamples(t=t, **out)


def _simulate_rk4(params: SDFParams, state: SDFState, duration: float, crossings: bool,
                  t_grid: np.ndarray | None, steps_per_period: int) -> SimResult:
    if t_grid is not None:
        raise ParameterError("`dense_t` is available for the exact methods only")
    if int(steps_per_period) != steps_per_period or steps_per_period < 4:
        raise ParameterError(f"`steps_per_period` must be an integer >= 4, was {steps_per_period}")
    from ._rk4_thesis import run_rk4_thesis

    (imp_t, imp_phase, imp_v_in, imp_v_out, cross_t, cross_v,
     t_end, x_end, v_end, theta_end, stuck_end) = run_rk4_thesis(
        params.F, params.omega, params.zeta, params.e, state.t, state.x, state.v, state.theta,
        duration, int(steps_per_period), bool(crossings))
    return SimResult(
        params=params,
        method="rk4-thesis",
        impacts=SimImpacts(t=imp_t, phase=imp_phase, v_in=imp_v_in, v_out=imp_v_out),
        accumulations=np.empty(0),
        sticking=np.empty((0, 2)),
        crossings=Crossings(t=cross_t, v=cross_v) if crossings else None,
        dense=None,
        micro_bounce=np.empty((0, 3)),
        state=SDFState(t=float(t_end), x=min(float(x_end), 1.0), v=float(v_end),
                       theta=float(theta_end) % TWO_PI,
                       stuck=bool(stuck_end) and float(x_end) >= 1.0 and float(v_end) == 0.0),
        n_events=len(imp_t),
    )
