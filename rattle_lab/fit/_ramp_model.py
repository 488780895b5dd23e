"""Thresholds of a finite-rate amplitude ramp, replayed through the exact simulator.

A threshold measured on an amplitude ramp is not the quasi-static boundary of the
model: the plate follows a changing level with the modal time constant
``1 / (zeta omega_s)`` (0.2 s for the thesis plate), and a downward ramp passes the
saddle-node of the 1/1 orbit (eq. 3.11) with the delay of a slow passage through a
fold.  On the 3-6 s ramps of the thesis campaign both move the disappearance level by
more than its whole dependence on ``e``.  So this module simulates the protocol itself:
the measured ramp (frequency, start and end level, duration) at candidate model
parameters, with the exact event-driven simulator (:func:`rattle_lab.model.sdf._simulate.simulate_pieces`:
one compiled call per replay, carrying the state and forcing phase from one forcing
period to the next; the same motion, bit for bit, as one ``simulate`` call per period,
without its fixed cost per call: timed over a fit of ``e`` by ``benchmarks/speed_goals.py``),
and reads the threshold off the simulated impacts exactly as
:mod:`rattle_lab.detect.thresholds` reads it off detected ones: the impact that starts (up)
or ends (down) the first/last sustained group (:func:`~rattle_lab.detect.thresholds.sustained_impact_time`), censored
within ``edge_cycles`` of the record's ends, and the ramp level at that instant.

Nondimensional form (thesis eq. 2.27-2.32): ``tau = omega_s t``, ``F = q A / (omega_s^2 h)``,
``omega = f / f_s``; each piece of ``level_hold_periods`` forcing periods (1: a continuous
ramp; a digital drive that updates its level every N periods, such as the synthetic rig
with ``piece_periods = N``, holds it for N) runs at the ramp level of its midpoint.

A measured threshold is quantised: impact comes once per forcing period (and the level
changes once per hold), so it is the level of one of the holds, uniformly somewhere
within one hold's level change ``level_hold_periods |dA/dt| / f`` of the boundary.  The
model averages ``n_phases`` replays whose forcing phase relative to the ramp is spread evenly over a period, which turns
the staircase of a single replay into (nearly) the expected value.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams, SDFState, simulate, simulate_pieces
from rattle_lab.detect.thresholds import Threshold, sustained_impact_time
from ._common import check_positive

Direction = Literal["up", "down"]
TWO_PI = 2.0 * math.pi
#: Linear amplitude (over the gap) at which a downward replay that starts below grazing
#: is first settled, to put it on the impacting branch (see :func:`model_threshold`).
_SETTLE_OVER_GRAZING = 1.25
#: A downward replay may stop early only where the linear amplitude is below this (over the gap).
_QUIET_AMPLITUDE = 0.95


@dataclass(frozen=True)
class RampSpec:
    """An amplitude ramp at constant frequency, as measured.

    Attributes
    ----------
    freq_hz : float
        Excitation frequency, Hz.
    direction : {"up", "down"}
        Ramp direction.
    level_start_ms2, level_end_ms2 : float
        Base-acceleration amplitude at the start and at the end of the record, m/s^2.
    duration_s : float
        Record length, s; the level is linear in between.
    """

    freq_hz: float
    direction: Direction
    level_start_ms2: float
    level_end_ms2: float
    duration_s: float

    def __post_init__(self) -> None:
        if self.direction not in ("up", "down"):
            raise ParameterError(f"`direction` must be 'up' or 'down', was {self.direction!r}")
        check_positive(freq_hz=self.freq_hz, duration_s=self.duration_s)
        for name in ("level_start_ms2", "level_end_ms2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ParameterError(f"`{name}` must be finite and >= 0, was {value}")

    @classmethod
    def from_threshold(cls, threshold: Threshold) -> RampSpec:
        """The measured ramp of a :class:`~rattle_lab.detect.thresholds.Threshold`.

        Raises
        ------
        ParameterError
            If the threshold carries no measured ramp (``ramp_start_ms2`` etc. NaN).
        """
        try:
            return cls(threshold.freq_hz, threshold.direction, threshold.ramp_start_ms2,
                       threshold.ramp_end_ms2, threshold.ramp_duration_s)
        except ParameterError as exc:
            raise ParameterError(f"run {threshold.run_id!r}: no measured ramp to replay "
                                 f"({exc})") from exc

    @property
    def rate_ms2_s(self) -> float:
        """``dA/dt``, m/s^3 (negative on a downward ramp)."""
        return (self.level_end_ms2 - self.level_start_ms2) / self.duration_s

    @property
    def step_ms2(self) -> float:
        """Level change over one forcing period, ``|dA/dt| / f``, m/s^2."""
        return abs(self.rate_ms2_s) / self.freq_hz

    def level_ms2(self, t_s: float) -> float:
        """Level at ``t_s`` seconds from the start of the record, m/s^2."""
        return self.level_start_ms2 + self.rate_ms2_s * t_s

    def time_s(self, level_ms2: float) -> float:
        """When the ramp passes ``level_ms2`` (may lie outside the record; NaN on a flat ramp)."""
        rate = self.rate_ms2_s
        return (level_ms2 - self.level_start_ms2) / rate if rate != 0 else float("nan")


@dataclass(frozen=True)
class ModelThreshold:
    """The threshold of a replayed ramp.

    Attributes
    ----------
    mean_ms2 : float
        Mean of the finite ``values_ms2``, m/s^2 (NaN if none is finite): the model of a
        measured threshold.
    std_ms2 : float
        Their standard deviation (``ddof=0``), m/s^2: the spread a single measurement has
        around ``mean_ms2`` (one cycle's quantisation, or more where the motion is irregular).
    values_ms2 : ndarray
        One threshold per forcing phase, m/s^2 (NaN when the replay saw no threshold:
        no sustained impact, or censored at the record's edge).
    t_s : ndarray
        The threshold impact's time in each replay, s from the record start.
    """

    mean_ms2: float
    std_ms2: float
    values_ms2: np.ndarray
    t_s: np.ndarray


def _ramp_particular_state(F: float, dF_dtau: float, omega: float, zeta: float, theta: float
                           ) -> tuple[float, float, float]:
    """State ``(x, v, X)`` on the particular solution of a linearly ramped forcing.

    For ``x'' + 2 zeta x' + x = (F + dF_dtau s) cos(theta + omega s)`` the particular
    solution is ``x = Re[((F + dF_dtau s) H - i dF_dtau H') exp(i (theta + omega s))]``
    with ``H = 1 / (1 - omega^2 + 2 i zeta omega)`` (the response of eq. 2.33 without the
    stop) and ``H' = dH/domega = H^2 (2 omega - 2 i zeta)``: the motion a linear ramp
    drives once the start transient has died, lag included.  Evaluated at ``s = 0``;
    ``X = |F H|`` is the quasi-static amplitude (``X = 1``: grazing, eq. 3.4).
    """
    H = 1.0 / complex(1.0 - omega * omega, 2.0 * zeta * omega)
    dH = H * H * complex(2.0 * omega, -2.0 * zeta)
    rot = complex(math.cos(theta), math.sin(theta))
    x = ((F * H - 1j * dF_dtau * dH) * rot).real
    v = ((dF_dtau * H + 1j * omega * F * H + omega * dF_dtau * dH) * rot).real
    return x, v, abs(F * H)


@functools.lru_cache(maxsize=256)
def _stable_orbit(F: float, omega: float, zeta: float, e: float) -> tuple[float, float] | None:
    """``(phase, v_im)`` of the stable 1/1 impacting orbit (the "hi" branch when both are
    listed), None when there is no stable, existing one.  Cached: the replays of one
    threshold at different forcing phases start at the same level."""
    params = SDFParams(F=F, omega=omega, zeta=zeta, e=e)
    from rattle_lab.model.analysis import one_over_n_orbits  # lazy: `rattle-lab fit` start-up

    stable = [o for o in one_over_n_orbits(params, 1) if o.exists and o.stable]
    if not stable:
        return None
    return float(stable[-1].phase), float(stable[-1].v_im)


def _orbit_state(F: float, omega: float, zeta: float, e: float, theta: float) -> SDFState | None:
    """State at forcing phase ``theta`` on the stable 1/1 impacting orbit (thesis 3.1-3.3).

    None when there is no stable, existing 1/1 orbit at these parameters.
    """
    orbit = _stable_orbit(F, omega, zeta, e)
    if orbit is None:
        return None
    phase, v_im = orbit
    params = SDFParams(F=F, omega=omega, zeta=zeta, e=e)
    at_impact = SDFState(x=1.0, v=-e * v_im, theta=phase)
    # follow the orbit from its impact to the wanted phase (less than one period)
    res = simulate(params, duration=((theta - phase) % TWO_PI) / omega, state=at_impact)
    return res.state


def _start_state(ramp: RampSpec, level_ms2: float, theta_w: float, tau_w: float, *,
                 F_per_ms2: float, omega_s: float, omega: float, zeta: float, e: float,
                 settle_tau: float) -> SDFState:
    """State at the replay's first instant, with forcing phase ``theta_w``.

    An upward replay below grazing starts on the particular solution of the ramped
    forcing (:func:`_ramp_particular_state`): the plate has followed the ramp, with its
    lag, from before the window.  A downward replay starts on the stable 1/1 orbit at the
    level (:func:`_orbit_state`); where there is none (and for a ramp that starts above
    grazing) it starts settled: from rest at the level, or, below grazing, first at
    ``_SETTLE_OVER_GRAZING`` times the grazing level, ``settle_tau`` each, as the
    synthetic rig does.  A replay that starts off the impacting branch that way sees its
    threshold early and is redone from the record's start (:func:`model_threshold`).
    """
    F_w = F_per_ms2 * level_ms2
    dF_dtau = F_per_ms2 * ramp.rate_ms2_s / omega_s
    x, v, X = _ramp_particular_state(F_w, dF_dtau, omega, zeta, theta_w)
    if ramp.direction == "up" and X < 1.0 and x < 1.0:
        return SDFState(t=tau_w, x=x, v=v, theta=theta_w)
    if ramp.direction == "down":
        on_orbit = _orbit_state(F_w, omega, zeta, e, theta_w)
        if on_orbit is not None:
            return SDFState(t=tau_w, x=on_orbit.x, v=on_orbit.v, theta=on_orbit.theta,
                            stuck=on_orbit.stuck)
    stages = [F_w]
    if X < 1.0:
        stages.insert(0, F_w * _SETTLE_OVER_GRAZING / X)
    # start the settling at the phase that makes it end at theta_w
    theta0 = (theta_w - omega * settle_tau * len(stages)) % TWO_PI
    state = SDFState(theta=theta0)
    for F in stages:
        state = simulate(SDFParams(F=F, omega=omega, zeta=zeta, e=e), duration=settle_tau,
                         state=state).state
    return SDFState(t=tau_w, x=state.x, v=state.v, theta=state.theta, stuck=state.stuck)


def _replay(ramp: RampSpec, t_w_s: float, phase: float, *, F_per_ms2: float, omega_s: float,
            omega: float, zeta: float, e: float, settle_tau: float, quiet_s: float,
            hold: int, n_confirm: int, max_gap_cycles: float, edge_cycles: float) -> float:
    """Time of the threshold impact of one replay from ``t_w_s`` (NaN if none or censored).

    An upward replay stops at its first sustained group (later impacts cannot change it).
    A downward one stops once it has been free of impacts for ``quiet_s`` while the
    linear amplitude is below ``_QUIET_AMPLITUDE``: the transient left by the last impact
    has decayed by ``exp(-quiet_s zeta omega_s)`` and the level only falls, so the motion
    cannot reach the stop again.

    All pieces run in one compiled call (:func:`~rattle_lab.model.sdf._simulate.simulate_pieces`), which
    stops where the stopping rule surely holds; the rule is then applied piece by piece
    to the impacts: the same threshold, bit for bit, as one ``simulate`` call per piece
    (:func:`_replay_per_piece`, tested), without its fixed cost per call.
    """
    f = ramp.freq_hz
    T = ramp.duration_s
    theta_w = (TWO_PI * f * t_w_s + phase) % TWO_PI
    state = _start_state(ramp, ramp.level_ms2(t_w_s), theta_w, omega_s * t_w_s,
                         F_per_ms2=F_per_ms2, omega_s=omega_s, omega=omega, zeta=zeta, e=e,
                         settle_tau=settle_tau)
    n_pieces = max(1, math.ceil((T - t_w_s) * f / hold - 1e-9))
    # quasi-static linear amplitude per unit level (the X of _ramp_particular_state)
    X_per_ms2 = F_per_ms2 / math.hypot(1.0 - omega * omega, 2.0 * zeta * omega)
    # the piece grid, with the very arithmetic (elementwise) of the per-piece loop
    starts_s = t_w_s + np.arange(n_pieces) * hold / f
    ends_s = t_w_s + np.arange(1, n_pieces + 1) * hold / f
    ends_s[-1] = T
    rate = ramp.rate_ms2_s
    levels = ramp.level_start_ms2 + rate * (0.5 * (starts_s + ends_s))
    up = ramp.direction == "up"
    quiet_ok = (X_per_ms2 * levels < _QUIET_AMPLITUDE) & (rate <= 0)
    gap_s = max_gap_cycles / f
    # the compiled call stops at a piece where the rule below surely holds (margins far
    # beyond rounding); the rule itself is then applied to the pieces run
    margin = 1.0 - 1e-9
    times = np.empty(0)
    t_thr = float("nan")
    j0 = 0
    while j0 < n_pieces:
        run = simulate_pieces(
            F_per_ms2 * levels[j0:], omega=omega, zeta=zeta, e=e, t_stop=omega_s * ends_s[j0:],
            state=state, group_gap=gap_s * omega_s * margin if up else None,
            group_size=n_confirm + 1, quiet_time=None if up else quiet_s * omega_s / margin,
            quiet_ok=quiet_ok[j0:], last_impact_t=times[-1] * omega_s if times.size else math.nan)
        n_before = times.size
        times = np.concatenate([times, run.impact_t / omega_s])
        n_upto = n_before + run.offsets[1:]          # impacts up to and with each piece run
        n_run = n_upto.size
        stop_k = n_run
        if up:
            # the first piece after which a sustained group is complete
            close = np.diff(times) <= gap_s
            if close.size >= n_confirm:
                full = np.flatnonzero(np.convolve(close, np.ones(n_confirm, dtype=int),
                                                  "valid") == n_confirm)
                full = full[full + n_confirm >= n_before]
                if full.size:
                    stop_k = int(np.searchsorted(n_upto, full[0] + n_confirm, side="right"))
                    times = times[:n_upto[stop_k]]
                    t_thr = sustained_impact_time(times, f, "up", n_confirm=n_confirm,
                                                  max_gap_cycles=max_gap_cycles)
        else:
            # the first piece without impacts, quiet_s after the last, where it may be quiet
            counts = np.diff(np.concatenate([[n_before], n_upto]))
            last_s = times[np.maximum(n_upto - 1, 0)] if times.size else np.full(n_run, np.nan)
            quiet = ((counts == 0) & (n_upto > 0) & quiet_ok[j0:j0 + n_run]
                     & (ends_s[j0:j0 + n_run] - last_s >= quiet_s))
            hits = np.flatnonzero(quiet)
            if hits.size:
                stop_k = int(hits[0])
                times = times[:n_upto[stop_k]]
        if stop_k < n_run:
            break
        state = run.state(n_run - 1)
        j0 += n_run
    if ramp.direction == "down":
        t_thr = sustained_impact_time(times, f, "down", n_confirm=n_confirm,
                                      max_gap_cycles=max_gap_cycles)
    if not math.isfinite(t_thr):
        return float("nan")
    from_edge = t_thr if ramp.direction == "up" else T - t_thr
    return t_thr if from_edge * f >= edge_cycles else float("nan")


def _replay_per_piece(ramp: RampSpec, t_w_s: float, phase: float, *, F_per_ms2: float,
                      omega_s: float, omega: float, zeta: float, e: float, settle_tau: float,
                      quiet_s: float, hold: int, n_confirm: int, max_gap_cycles: float,
                      edge_cycles: float) -> float:
    """:func:`_replay` with one :func:`~rattle_lab.model.sdf.simulate` call per piece.

    The reference the one-call replay is tested against (same threshold, bit for bit).

    An upward replay stops at its first sustained group (later impacts cannot change it).
    A downward one stops once it has been free of impacts for ``quiet_s`` while the
    linear amplitude is below ``_QUIET_AMPLITUDE``: the transient left by the last impact
    has decayed by ``exp(-quiet_s zeta omega_s)`` and the level only falls, so the motion
    cannot reach the stop again.
    """
    f = ramp.freq_hz
    T = ramp.duration_s
    theta_w = (TWO_PI * f * t_w_s + phase) % TWO_PI
    state = _start_state(ramp, ramp.level_ms2(t_w_s), theta_w, omega_s * t_w_s,
                         F_per_ms2=F_per_ms2, omega_s=omega_s, omega=omega, zeta=zeta, e=e,
                         settle_tau=settle_tau)
    n_pieces = max(1, math.ceil((T - t_w_s) * f / hold - 1e-9))
    # quasi-static linear amplitude per unit level (the X of _ramp_particular_state)
    X_per_ms2 = F_per_ms2 / math.hypot(1.0 - omega * omega, 2.0 * zeta * omega)
    times: list[float] = []
    t_thr = float("nan")
    for j in range(n_pieces):
        a = t_w_s + j * hold / f
        b = T if j == n_pieces - 1 else t_w_s + (j + 1) * hold / f
        level = ramp.level_ms2(0.5 * (a + b))
        params = SDFParams(F=F_per_ms2 * level, omega=omega, zeta=zeta, e=e)
        res = simulate(params, duration=max(0.0, omega_s * b - state.t), state=state)
        state = res.state
        if len(res.impacts):
            times.extend((res.impacts.t / omega_s).tolist())
            if ramp.direction == "up":   # the first sustained group cannot change once seen
                t_thr = sustained_impact_time(times, f, "up", n_confirm=n_confirm,
                                              max_gap_cycles=max_gap_cycles)
                if math.isfinite(t_thr):
                    break
        elif (ramp.direction == "down" and times and b - times[-1] >= quiet_s
              and ramp.rate_ms2_s <= 0 and X_per_ms2 * level < _QUIET_AMPLITUDE):
            break
    if ramp.direction == "down":
        t_thr = sustained_impact_time(times, f, "down", n_confirm=n_confirm,
                                      max_gap_cycles=max_gap_cycles)
    if not math.isfinite(t_thr):
        return float("nan")
    from_edge = t_thr if ramp.direction == "up" else T - t_thr
    return t_thr if from_edge * f >= edge_cycles else float("nan")


def model_threshold(ramp: RampSpec, *, e: float, gap_m: float, f_s_hz: float, zeta: float,
                    participation: float = 1.0, n_phases: int = 4, n_confirm: int = 3,
                    max_gap_cycles: float = 100.0, edge_cycles: float = 2.0,
                    level_hold_periods: int = 1, anchor_ms2: float | None = None,
                    window_time_constants: float = 4.0,
                    settle_time_constants: float = 8.0) -> ModelThreshold:
    """Threshold of ``ramp`` for the model ``(e, gap_m, f_s_hz, zeta, participation)``.

    Parameters
    ----------
    ramp : RampSpec
        The measured ramp.
    e : float
        Coefficient of restitution, in [0, 1].
    gap_m, f_s_hz, zeta, participation : float
        Modal model: gap (m), modal frequency (Hz), damping ratio (> 0) and ``q = Q1/Q2``.
    n_phases : int
        Replays, with the forcing phase at the ramp start spread evenly over a period.
    n_confirm, max_gap_cycles, edge_cycles
        As in :func:`rattle_lab.detect.thresholds.ramp_threshold`; pass the values used on the data.
    level_hold_periods : int
        Forcing periods over which the drive holds its level (1: continuous ramp), counted
        from the record's start.
    anchor_ms2 : float, optional
        Where the threshold is expected (the measured one).  The replay then starts
        ``window_time_constants`` modal time constants ``1 / (zeta omega_s)`` before the
        ramp reaches it instead of at the record's start, on the stable 1/1 orbit (down)
        or the ramped linear motion (up), see :func:`_start_state`: what the start leaves
        out decays as ``exp(-4) = 2 %`` over the window.  A replay whose threshold falls
        in the first half of that window, or that sees none, is redone from the record's
        start, so the anchor changes the cost, not the answer.  A downward replay also stops
        ``window_time_constants`` after its last impact once below grazing.
    settle_time_constants : float
        Settling time (in modal time constants) of a replay that starts on impacting motion.

    Returns
    -------
    ModelThreshold

    Raises
    ------
    ParameterError
        For a parameter out of range.

    Examples
    --------
    >>> ramp = RampSpec(100.0, "down", 50.0, 3.0, 6.0)     # the thesis plate's 100 Hz ramp
    >>> m = model_threshold(ramp, e=0.6, gap_m=1.3e-3, f_s_hz=96.0, zeta=0.0085,
    ...                     participation=1.2442, anchor_ms2=7.0)
    >>> bool(6.7 < m.mean_ms2 < 7.1)    # quasi-static saddle-node: 7.64 m/s^2
    True
    """
    check_positive(gap_m=gap_m, f_s_hz=f_s_hz, zeta=zeta, participation=participation)
    if not (math.isfinite(e) and 0.0 <= e <= 1.0):
        raise ParameterError(f"`e` must be in [0, 1], was {e}")
    if int(n_phases) != n_phases or n_phases < 1:
        raise ParameterError(f"`n_phases` must be an integer >= 1, was {n_phases}")
    if int(level_hold_periods) != level_hold_periods or level_hold_periods < 1:
        raise ParameterError(f"`level_hold_periods` must be an integer >= 1, was "
                             f"{level_hold_periods}")
    hold = int(level_hold_periods)
    omega_s = TWO_PI * f_s_hz
    # eq. 2.27, 2.31: F = q A / (omega_s^2 h); eq. 2.28: omega = f / f_s
    F_per_ms2 = participation / (omega_s**2 * gap_m)
    omega = ramp.freq_hz / f_s_hz
    tau_const_s = 1.0 / (zeta * omega_s)
    settle_tau = settle_time_constants / zeta
    lead_s = window_time_constants * tau_const_s
    t_w = 0.0
    if anchor_ms2 is not None and math.isfinite(anchor_ms2):
        t_anchor = ramp.time_s(anchor_ms2)
        if math.isfinite(t_anchor):
            # whole holds from the record's start, so that every replay has its piece grid
            t_w = math.floor(min(max(t_anchor - lead_s, 0.0), ramp.duration_s) * ramp.freq_hz
                             / hold) * hold / ramp.freq_hz
    kw = dict(F_per_ms2=F_per_ms2, omega_s=omega_s, omega=omega, zeta=zeta, e=e,
              settle_tau=settle_tau, quiet_s=lead_s, hold=hold, n_confirm=n_confirm,
              max_gap_cycles=max_gap_cycles, edge_cycles=edge_cycles)
    t_thr = np.full(int(n_phases), np.nan)
    for k in range(int(n_phases)):
        phase = TWO_PI * k / n_phases
        t = _replay(ramp, t_w, phase, **kw)  # type: ignore[arg-type]
        if t_w > 0.0 and not (t >= t_w + 0.5 * lead_s):
            t = _replay(ramp, 0.0, phase, **kw)  # type: ignore[arg-type]
        t_thr[k] = t
    values = ramp.level_start_ms2 + ramp.rate_ms2_s * t_thr
    ok = np.isfinite(values)
    mean = float(np.mean(values[ok])) if ok.any() else float("nan")
    std = float(np.std(values[ok])) if ok.any() else float("nan")
    return ModelThreshold(mean, std, values, t_thr)


def threshold_sigma_ms2(ramp: RampSpec, ramp_rms_ms2: float, level_hold_periods: int = 1
                        ) -> float:
    """Standard deviation of one measured threshold, m/s^2.

    ``sqrt((N step)^2 / 12 + rms^2)``: the uniform quantisation over one hold's level
    change (``step = |dA/dt| / f`` per forcing period, ``N = level_hold_periods``: impact
    comes once per cycle, the level changes once per hold) and the scatter of the measured
    envelope about its line (NaN counts as 0).

    Examples
    --------
    >>> bool(abs(threshold_sigma_ms2(RampSpec(100.0, "down", 50.0, 2.0, 6.0), 0.0)
    ...          - 0.08 / 12 ** 0.5) < 1e-12)
    True
    """
    rms = ramp_rms_ms2 if math.isfinite(ramp_rms_ms2) else 0.0
    return math.sqrt((level_hold_periods * ramp.step_ms2) ** 2 / 12.0 + rms**2)
