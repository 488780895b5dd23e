"""Slow parameter sweeps of the SDF impact oscillator (thesis 4.2-4.3, Fig. 4-3 to 4-5).

A sweep steps one parameter (``omega``, ``F``, ``e`` or the gap) through a
grid.  At each value the exact simulator (:func:`rattle_lab.model.sdf.simulate`)
runs ``cycles`` forcing periods from the state the previous value ended in,
with the forcing phase continuous (the state's ``theta`` carries over), which
is the thesis's model of a slow sweep experiment (4.2; Appendix A.1,
``fillv_impbuffer``).  The first ``discard`` periods are discarded (thesis:
100 and 70).  Over the kept periods it records

* the incoming impact velocities ``v_im`` and their forcing phases;
* the velocities ``v_{x=0}^+`` of the upward crossings of ``x = 0``;
* the average impact velocity per forcing cycle, ``sum(v_im) / n_kept``
  (the thesis's ``v_average += vm / periods``, Appendix A.1), so a 1/n orbit
  has ``v_im / n``;
* the regime: no impact, ``m/n`` periodic, or aperiodic
  (:func:`classify_impacts`), and for aperiodic motion its largest Lyapunov
  exponent (:mod:`rattle_lab.model.analysis.lyapunov`), so that chaos is a measured
  statement.  An ``m/n`` match must be settled (:func:`classify_settled`): a
  transient still converging to a shorter period (a 1/3 orbit near its period
  doubling matches 2/6 first) is run longer on a side run until it settles,
  else it is called ``"unsettled"``; a wrong period is never reported.  Likewise a
  window without a period whose Lyapunov exponent is negative is a transient, not
  chaos: it is run on the same way (``"aperiodic"`` is reported only with an exponent
  >= 0, or where none was computed);
* the linear estimate of the impact velocity (eq. 4.7-4.11,
  :func:`rattle_lab.model.linear.linear_impact_velocity`), NaN where linear theory
  predicts no impact.

The gap
    At fixed dimensional forcing ``F_es`` the nondimensional forcing is
    ``F = F_es / (omega_s^2 h)`` (eq. 2.31), so ``1/F = omega_s^2 h / F_es`` is
    the gap in units of the static deflection ``F_es / omega_s^2``, and
    ``v_im / F = omega_s v_sim / F_es`` is proportional to the dimensional
    impact velocity (eq. 4.5).  A ``"gap"`` sweep steps ``gap = 1/F`` with
    ``omega``, ``zeta`` and ``e`` (and the dimensional forcing) held fixed, and
    its results are presented as ``v_im / F`` against ``1/F`` (Fig. 4-4).  The
    nondimensional state ``(x, v)`` is carried to the next value unchanged, as
    for the other parameters.

Compiled calls
    A whole sweep direction (all values, discarded and kept periods) runs in calls
    of the compiled kernel (:func:`rattle_lab.model.sdf._kernel.run_sweep`) of about
    :data:`SWEEP_CALL_CYCLES` forcing periods each, the state carried from call to
    call, the same motion bit for bit as one ``simulate`` call per window (and a
    Ctrl-C lands between two calls, within a fraction of a second); the first
    classification of every window is a second compiled call
    (:func:`rattle_lab.model.analysis._periods._classify_windows`, what
    :func:`classify_settled` computes first), and only a match that has not
    settled goes through :func:`classify_settled` (run longer); Lyapunov
    exponents follow from the recorded end states.

All quantities are nondimensional.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab._progress import progress
from rattle_lab._version import __version__
from rattle_lab.exceptions import NumericalWarning, ParameterError, SimulationError
from rattle_lab.model.linear import linear_impact_velocity
from rattle_lab.model.sdf import SDFParams, SDFState

from ._periods import (  # re-exported: the period detection lived here before the split
    KIND_CODES,  # noqa: F401
    KIND_NAMES,
    PERIOD_RTOL,
    SETTLE_CYCLES,
    Regime,
    RegimeKind,  # noqa: F401
    _check_int,
    _classify,  # noqa: F401
    _classify_windows,
    classify_impacts,
    classify_settled,
    periodic_label_settled,
)
from ._sweep_results import (  # re-exported: the results and their CSV lived here before
    CSV_COLUMNS,  # noqa: F401
    Direction,
    Sweep,
    SweepParam,
    SweepPoint,
    write_sweeps_csv,
)
from .lyapunov import lyapunov_exponent

LyapunovMode = Literal["aperiodic", "all", "none"]
SWEEP_PARAMS: tuple[SweepParam, ...] = ("omega", "F", "e", "gap")
DIRECTIONS: tuple[Direction, ...] = ("up", "down")
LYAPUNOV_MODES: tuple[LyapunovMode, ...] = ("aperiodic", "all", "none")

__all__ = [
    "Regime",
    "SweepPoint",
    "Sweep",
    "classify_impacts",
    "classify_settled",
    "periodic_label_settled",
    "sweep_values",
    "sweep",
    "sweep_up_down",
    "write_sweeps_csv",
]


# ---------------------------------------------------------------------------
# The sweep
# ---------------------------------------------------------------------------

def sweep_values(start: float, stop: float, step: float) -> np.ndarray:
    """The grid ``start, start + step, ..., stop`` (ascending, ``stop`` included).

    ``(stop - start) / step`` must be an integer to within 1e-9 of a step, so
    that up and down sweeps visit exactly the same values.

    Raises
    ------
    ParameterError
        If ``step <= 0``, ``stop <= start`` or the step does not divide the range.

    Examples
    --------
    >>> v = sweep_values(0.85, 1.3, 0.001)
    >>> v.size, bool(abs(v[-1] - 1.3) < 1e-12)
    (451, True)
    """
    start, stop, step = float(start), float(stop), float(step)
    for name, x in (("start", start), ("stop", stop), ("step", step)):
        if not math.isfinite(x):
            raise ParameterError(f"`{name}` must be finite, was {x}")
    if step <= 0:
        raise ParameterError(f"`step` must be > 0, was {step}")
    if stop <= start:
        raise ParameterError(f"`stop` must be > start = {start}, was {stop}")
    k = (stop - start) / step
    n = round(k)
    if abs(k - n) > 1e-9 * max(1.0, k):
        raise ParameterError(f"`step` = {step} must divide stop - start = {stop - start}")
    if n + 1 > 10**7:
        raise ParameterError(f"`step` = {step} gives {n + 1} values (at most 10**7)")
    return start + step * np.arange(n + 1)


def _params_at(param: SweepParam, base: SDFParams, value: float) -> SDFParams:
    if param == "gap":
        if not value > 0:
            raise ParameterError(f"`gap` values must be > 0, was {value}")
        return base.replace(F=1.0 / value)
    try:
        return base.replace(**{param: value})
    except ParameterError as exc:
        raise ParameterError(f"sweep of `{param}`: {exc}") from None


def _check_classification_window(cycles: object, discard: object, n_max: object,
                                 rtol: float) -> tuple[int, int, int]:
    """Validate the simulated and discarded forcing periods and the period detection.

    Shared by the sweeps and the maps (:mod:`rattle_lab.model.analysis.maps`).

    Parameters
    ----------
    cycles, discard : object
        Forcing periods simulated (>= 1) and discarded (>= 0, < ``cycles``); integers.
    n_max : object
        Largest period looked for, in forcing periods: an integer with two periods
        fitting in the kept ``cycles - discard``.
    rtol : float
        Tolerance of :func:`classify_impacts`, finite and > 0.

    Returns
    -------
    cycles, discard, n_max : int

    Raises
    ------
    ParameterError
        On an invalid argument, naming it and its value.
    """
    cycles_i = _check_int("cycles", cycles, 1)
    discard_i = _check_int("discard", discard, 0)
    if discard_i >= cycles_i:
        raise ParameterError(f"`discard` must be < cycles = {cycles_i}, was {discard_i}")
    n_max_i = _check_int("n_max", n_max, 1)
    if 2 * n_max_i > cycles_i - discard_i:
        raise ParameterError(
            f"`n_max` must be <= (cycles - discard) / 2 = {(cycles_i - discard_i) // 2} "
            f"(two periods must fit in the kept cycles), was {n_max_i}")
    if not (math.isfinite(rtol) and rtol > 0):
        raise ParameterError(f"`rtol` must be finite and > 0, was {rtol}")
    return cycles_i, discard_i, n_max_i


def _check_settings(param: object, cycles: object, discard: object, n_max: object,
                    rtol: float, lyapunov: object, lyapunov_cycles: float,
                    lyapunov_warmup: float) -> tuple[int, int, int]:
    if param not in SWEEP_PARAMS:
        raise ParameterError(f"`param` must be one of {SWEEP_PARAMS}, was {param!r}")
    cycles_i, discard_i, n_max_i = _check_classification_window(cycles, discard, n_max, rtol)
    if lyapunov not in LYAPUNOV_MODES:
        raise ParameterError(f"`lyapunov` must be one of {LYAPUNOV_MODES}, was {lyapunov!r}")
    if not (math.isfinite(lyapunov_warmup) and lyapunov_warmup >= 0):
        raise ParameterError(f"`lyapunov_warmup` must be >= 0, was {lyapunov_warmup}")
    if not (math.isfinite(lyapunov_cycles) and lyapunov_cycles > lyapunov_warmup):
        raise ParameterError(
            f"`lyapunov_cycles` must be > lyapunov_warmup = {lyapunov_warmup}, was {lyapunov_cycles}")
    return cycles_i, discard_i, n_max_i


#: Forcing periods per compiled call of a sweep (about 0.1 s of work): a sweep direction runs
#: as consecutive calls of this size, the state carried over exactly, so that a Ctrl-C (held
#: while a call runs, :func:`~rattle_lab.model.sdf._compiled.signals_deferred`) lands within
#: a fraction of a second however long the sweep.  The motion is the same to the last bit.
SWEEP_CALL_CYCLES = 20_000


def _run_sweep(all_params: Sequence[SDFParams], state: SDFState, discard: int, kept: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Run a sweep direction in compiled calls of :data:`SWEEP_CALL_CYCLES` forcing periods;
    raise and warn as ``simulate`` does.

    Returns the arrays of :func:`rattle_lab.model.sdf._kernel.run_sweep` for the whole
    direction (as one call would).
    """
    from rattle_lab.model.sdf import jit_kernel, signals_deferred

    zeta = all_params[0].zeta
    F = np.array([q.F for q in all_params])
    w = np.array([q.omega for q in all_params])
    e = np.array([q.e for q in all_params])
    per_call = max(1, SWEEP_CALL_CYCLES // max(1, discard + kept))
    t, x, v, th, stuck = state.t, state.x, state.v, state.theta, bool(state.stuck)
    parts = []
    for lo in range(0, len(all_params), per_call):
        hi = min(lo + per_call, len(all_params))
        with signals_deferred():  # a Ctrl-C while the arrays are boxed would crash the process
            part = jit_kernel.run_sweep(F[lo:hi], w[lo:hi], e[lo:hi], zeta, t, x, v, th, stuck,
                                        float(discard), float(kept))
        parts.append(part)
        bad = np.flatnonzero(part[4][:, 1] != 0)
        if bad.size:
            q = all_params[lo + int(bad[0])]
            raise SimulationError(
                f"event budget exhausted in the sweep at F={q.F}, omega={q.omega}, "
                f"zeta={q.zeta}, e={q.e}; shorten `cycles`")
        t, x, v, th, stuck_f = part[3][-1, 1:].tolist()
        stuck = stuck_f != 0.0
    imp = np.concatenate([p[0] for p in parts])
    crs = np.concatenate([p[1] for p in parts])
    ends = np.concatenate([p[3] for p in parts])
    info = np.concatenate([p[4] for p in parts])
    off = np.zeros((len(all_params) + 1, 2), dtype=np.int64)
    base = np.zeros(2, dtype=np.int64)
    row = 0
    for p in parts:
        n = p[3].shape[0]
        off[row + 1:row + n + 1] = p[2][1:] + base
        base = base + p[2][-1]
        row += n
    unresolved = int(np.sum(info[:, 2]))
    if unresolved:
        warnings.warn(f"{unresolved} event searches of the sweep were settled at the work cap; "
                      "impacts in them are located only to the resolution reached",
                      NumericalWarning, stacklevel=3)
    return imp, crs, off, ends, info


def sweep(param: SweepParam, values: ArrayLike, *, base: SDFParams, direction: Direction = "up",
          cycles: int = 100, discard: int = 70, state: SDFState | None = None, n_max: int = 12,
          rtol: float = PERIOD_RTOL, lyapunov: LyapunovMode = "aperiodic",
          lyapunov_cycles: float = 300.0, lyapunov_warmup: float = 50.0,
          settle_cycles: float = SETTLE_CYCLES, quiet: bool = True) -> Sweep:
    """Slow sweep of one parameter with the state carried from value to value (thesis 4.2).

    Parameters
    ----------
    param : {"omega", "F", "e", "gap"}
        The swept parameter.  ``"gap"`` is ``1/F`` at fixed dimensional
        forcing (module docstring): each value sets ``F = 1 / value``.
    values : array_like
        The grid, ascending (e.g. :func:`sweep_values`); visited in ascending
        order for ``direction="up"`` and descending for ``"down"``.
    base : SDFParams
        The fixed parameters (nondimensional); its value of the swept
        parameter (and of ``F`` for ``"gap"``) is ignored.
    direction : {"up", "down"}
        Sweep direction.
    cycles : int
        Forcing periods simulated at each value (thesis: 100).
    discard : int
        Of which the first are discarded (thesis: 70).
    state : SDFState, optional
        State at the first value (default: at rest at x = 0, phase 0).
    n_max : int
        Largest period (in forcing periods) the classification looks for;
        at most ``(cycles - discard) / 2``.
    rtol : float
        Tolerance of the period detection (:func:`classify_impacts`).
    lyapunov : {"aperiodic", "all", "none"}
        Where to compute the largest Lyapunov exponent: at aperiodic values
        (default), everywhere, or nowhere.  It is measured on a side run of
        ``lyapunov_cycles`` periods from the value's end state (the sweep
        itself continues from that end state, unaffected), the first
        ``lyapunov_warmup`` of them aligning the tangent vector.
    lyapunov_cycles, lyapunov_warmup : float
        See ``lyapunov``.
    settle_cycles : float
        A periodic match in the kept window that is still converging (to a
        shorter period, say a 1/3 orbit near its period doubling that matches
        2/6 first) is not reported: the motion is run longer, on a side run of
        at most this many forcing periods, until it settles, else the regime
        is ``"unsettled"`` (:func:`classify_settled`).  The same holds for an
        aperiodic window whose Lyapunov exponent is negative.
    quiet : bool
        No progress bar (one is drawn on a terminal otherwise).

    Returns
    -------
    Sweep

    Raises
    ------
    ParameterError
        On an invalid argument, naming it and its value.

    Examples
    --------
    >>> from rattle_lab.model.sdf import SDFParams
    >>> base = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)
    >>> sw = sweep("omega", [1.0, 1.1, 1.2], base=base)
    >>> sw.labels
    ['1/1', '1/1', '1/1']
    """
    if not isinstance(base, SDFParams):
        raise ParameterError(f"`base` must be an SDFParams, was {type(base).__name__}")
    if direction not in DIRECTIONS:
        raise ParameterError(f"`direction` must be one of {DIRECTIONS}, was {direction!r}")
    cycles_i, discard_i, n_max_i = _check_settings(param, cycles, discard, n_max, rtol,
                                                   lyapunov, lyapunov_cycles, lyapunov_warmup)
    settle_cycles = float(settle_cycles)
    if not (math.isfinite(settle_cycles) and settle_cycles >= 0):
        raise ParameterError(f"`settle_cycles` must be finite and >= 0, was {settle_cycles}")
    grid = np.asarray(values, dtype=float).ravel()
    if grid.size == 0:
        raise ParameterError("`values` must not be empty")
    if not np.all(np.isfinite(grid)):
        raise ParameterError(f"`values` must be finite, was {grid[~np.isfinite(grid)][0]}")
    if grid.size > 1 and np.any(np.diff(grid) <= 0):
        raise ParameterError("`values` must be strictly ascending (use `direction` to sweep down)")
    order = grid if direction == "up" else grid[::-1]
    all_params = [_params_at(param, base, float(x)) for x in order]  # validate all first
    state = SDFState() if state is None else state
    if not isinstance(state, SDFState):
        raise ParameterError(f"`state` must be an SDFState, was {type(state).__name__}")
    initial = state
    kept = cycles_i - discard_i
    # Eq. (4.7)-(4.11), once for the whole grid (NaN where linear theory has no impact)
    linear = np.atleast_1d(linear_impact_velocity(np.array([q.F for q in all_params]),
                                                  np.array([q.omega for q in all_params]),
                                                  base.zeta))
    # The whole direction in compiled calls (rattle_lab.model.sdf._kernel.run_sweep): at each
    # value `discard` periods without crossings (a second call from the same state and
    # forcing phase is the same motion, and the cheaper one), then the kept periods.
    imp_all, crs_all, off, ends, info = _run_sweep(all_params, state, discard_i, kept)
    # The classification every window needs first (classify_settled's), in one compiled
    # call; a match that has not settled goes through classify_settled, run longer.
    first = _classify_windows(np.ascontiguousarray(imp_all[:, 0]),
                              np.ascontiguousarray(imp_all[:, 2]), off[:, 0], ends[:, 0],
                              ends[:, 1], np.array([q.period for q in all_params]), n_max_i,
                              float(rtol)).tolist()
    # Python numbers once (indexing numpy arrays one number at a time costs more)
    off_imp = off[:, 0].tolist()
    off_crs = off[:, 1].tolist()
    end_rows = ends.tolist()
    sticking = info[:, 0].tolist()
    crs_v = crs_all[:, 1]
    points: list[SweepPoint] = []
    for i, (value, p, v_lin) in enumerate(progress(
            zip(order.tolist(), all_params, linear.tolist()), total=len(all_params),
            desc=f"{direction}-sweep of {param}", quiet=quiet, unit="value")):
        imp = imp_all[off_imp[i]:off_imp[i + 1]]
        t0, t_end, x_end, v_end, th_end, stuck_end = end_rows[i]
        state = SDFState._from_kernel(t_end, x_end, v_end, th_end, bool(stuck_end))
        kind, m, n, settled = first[i]
        if settled:  # as classify_settled returns it
            regime, extra = Regime(kind=KIND_NAMES[kind], m=m, n=n), 0.0
        else:
            regime, extra = classify_settled(p, imp[:, 0], imp[:, 2], t_start=t0,
                                             end_state=state, n_max=n_max_i, rtol=float(rtol),
                                             settle_cycles=settle_cycles)
        lyap = None
        if lyapunov == "all" or (lyapunov == "aperiodic" and regime.kind == "aperiodic"):
            lyap = lyapunov_exponent(p, cycles=lyapunov_cycles, warmup_cycles=lyapunov_warmup,
                                     state=state)
            if regime.kind == "aperiodic" and lyap.exponent < 0:
                # no period in the window, yet nearby motions converge: a transient on its
                # way to an orbit, not chaos.  Run on until the period settles, or say so.
                regime, more = classify_settled(p, imp[:, 0], imp[:, 2], t_start=t0,
                                                end_state=state, n_max=n_max_i, rtol=float(rtol),
                                                settle_cycles=settle_cycles, converging=True)
                extra += more
        v_in = imp[:, 2]
        points.append(SweepPoint(
            value=value, params=p,
            impact_velocities=v_in.copy(), impact_phases=imp[:, 1].copy(),
            crossing_velocities=crs_v[off_crs[i]:off_crs[i + 1]].copy(),
            mean_impact_velocity=float(v_in.sum() / kept),
            regime=regime, sticking=bool(sticking[i]),
            lyapunov=lyap,
            linear_impact_velocity=v_lin, settle_cycles=extra))
    provenance: dict[str, object] = {
        "package": "rattle_lab", "version": __version__,
        "function": "rattle_lab.model.analysis.sweep",
        "arguments": {"param": param, "direction": direction, "n_values": int(grid.size),
                      "first": float(grid[0]), "last": float(grid[-1]),
                      "base": {"F": base.F, "omega": base.omega, "zeta": base.zeta, "e": base.e},
                      "cycles": cycles_i, "discard": discard_i, "n_max": n_max_i,
                      "rtol": float(rtol), "lyapunov": lyapunov,
                      "lyapunov_cycles": float(lyapunov_cycles),
                      "lyapunov_warmup": float(lyapunov_warmup),
                      "settle_cycles": settle_cycles,
                      "initial_state": {"t": initial.t, "x": initial.x, "v": initial.v,
                                        "theta": initial.theta, "stuck": initial.stuck}},
    }
    return Sweep(param=param, direction=direction, points=tuple(points), base=base,
                 cycles=cycles_i, discard=discard_i, initial_state=initial, final_state=state,
                 provenance=provenance)


def sweep_up_down(param: SweepParam, values: ArrayLike, *, base: SDFParams,
                  state: SDFState | None = None, **options: object) -> tuple[Sweep, Sweep]:
    """An up-sweep followed by a down-sweep that starts from the up-sweep's final state.

    Like a slow experiment that goes up and comes back (thesis Fig. 4-3 (a),
    (b)).  ``options`` are the keyword arguments of :func:`sweep`.

    Returns
    -------
    (Sweep, Sweep)
        The up- and the down-sweep.
    """
    up = sweep(param, values, base=base, direction="up", state=state, **options)  # type: ignore[arg-type]
    down = sweep(param, values, base=base, direction="down", state=up.final_state,
                 **options)  # type: ignore[arg-type]
    return up, down
