"""Runs of the protocol through the exact SDF simulator, in physical units.

Ramps and sweeps are simulated in pieces of ``piece_periods`` forcing periods with a
constant level and frequency each, carrying the simulator ``state`` (and with it the
forcing phase ``theta``) from piece to piece.  Nondimensional (thesis eq. 2.28-2.32):
``tau = omega_s t``, ``x = x_s / h``, ``F = participation A_e / (omega_s**2 h)``,
``omega = f / f_s``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rattle_lab.model import scaling
from rattle_lab.model.sdf import SDFParams, SDFState, particular_state, simulate
from ._counter import StageCounter
from ._scene import RunSpec

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Modal:
    """The modal model in physical units (what ``/truth`` holds)."""

    f_s_hz: float
    zeta: float
    participation: float
    gap_m: float
    e: float

    @property
    def omega_s_rad_s(self) -> float:
        """``2 pi f_s``, rad/s."""
        return TWO_PI * self.f_s_hz

    def F(self, level_m_s2: float) -> float:
        """Nondimensional forcing of a base-acceleration amplitude (eq. 2.27, 2.31)."""
        # F is linear in the level: convert 1 m/s^2 once (validated), then scale
        return level_m_s2 * self._F_per_m_s2

    @property
    def _F_per_m_s2(self) -> float:
        cached = self.__dict__.get("_F_unit")
        if cached is None:
            cached = float(scaling.F_from_accel(1.0, self.participation, self.omega_s_rad_s, self.gap_m))
            object.__setattr__(self, "_F_unit", cached)
        return cached


@dataclass(frozen=True)
class Piece:
    """A stretch of a run at constant level and frequency: ``t0_s <= t < t1_s``."""

    t0_s: float
    t1_s: float
    level_m_s2: float
    freq_hz: float


@dataclass(frozen=True)
class RunMotion:
    """The simulated motion of one run.

    Attributes
    ----------
    pieces : tuple of Piece
        The schedule simulated.
    impact_t_s, impact_v_in_m_s, impact_v_out_m_s : ndarray
        Impact times from the run start (s), incoming speed and outgoing speed (m/s, > 0):
        ``v = omega_s h v_nd`` (eq. 4.4).
    impact_level_m_s2 : ndarray
        Level of the piece in which each impact happened.
    piece_impacts : ndarray of int
        Number of impacts per piece.
    theta : ndarray or None
        Forcing phase at the samples (nondimensional), when sampled.
    level_m_s2, freq_hz : ndarray or None
        Level and frequency at the samples.
    v_rel_m_s, a_rel_m_s2 : ndarray or None
        Modal velocity and acceleration of the plate relative to the base at the samples:
        ``v_nd omega_s h`` and ``a_nd omega_s**2 h``; None when not asked for.
    """

    pieces: tuple[Piece, ...]
    impact_t_s: np.ndarray
    impact_v_in_m_s: np.ndarray
    impact_v_out_m_s: np.ndarray
    impact_level_m_s2: np.ndarray
    piece_impacts: np.ndarray
    theta: np.ndarray | None = None
    level_m_s2: np.ndarray | None = None
    freq_hz: np.ndarray | None = None
    v_rel_m_s: np.ndarray | None = None
    a_rel_m_s2: np.ndarray | None = None


def schedule(run: RunSpec, piece_periods: int) -> tuple[Piece, ...]:
    """Pieces of constant level and frequency covering ``[0, run.duration_s)``.

    Ramps and sweeps take the level or frequency of the continuous protocol at each
    piece's midpoint; stepped runs split the duration into equal steps.
    """
    T = run.duration_s
    if run.protocol == "sine_dwell":
        return (Piece(0.0, T, run.level_m_s2, run.freq_hz),)
    if run.protocol == "stepped_frequency":
        assert run.freq_end_hz is not None and run.freq_step_hz is not None
        n_steps = round(abs(run.freq_end_hz - run.freq_hz) / run.freq_step_hz) + 1
        sign = 1.0 if run.freq_end_hz >= run.freq_hz else -1.0
        edges = np.linspace(0.0, T, n_steps + 1)
        return tuple(Piece(float(edges[k]), float(edges[k + 1]), run.level_m_s2,
                           run.freq_hz + sign * k * run.freq_step_hz) for k in range(n_steps))
    pieces = []
    t0 = 0.0
    while t0 < T:
        if run.protocol == "swept_frequency":
            assert run.freq_end_hz is not None
            f_guess = run.freq_hz + (run.freq_end_hz - run.freq_hz) * t0 / T
            t1 = min(T, t0 + piece_periods / f_guess)
            f = run.freq_hz + (run.freq_end_hz - run.freq_hz) * 0.5 * (t0 + t1) / T
            level = run.level_m_s2
        else:
            assert run.level_end_m_s2 is not None
            t1 = min(T, t0 + piece_periods / run.freq_hz)
            f = run.freq_hz
            level = run.level_m_s2 + (run.level_end_m_s2 - run.level_m_s2) * 0.5 * (t0 + t1) / T
        if T - t1 < 1e-12 * T:
            t1 = T
        pieces.append(Piece(t0, t1, level, f))
        t0 = t1
    return tuple(pieces)


def initial_state(modal: Modal, piece: Piece, settle_time_constants: float) -> tuple[SDFState, float]:
    """State at the start of a run and the nondimensional time it is reached.

    Below grazing the run starts on the linear steady state (the shaker has been running
    at the start level); above grazing it starts from rest and settles for
    ``settle_time_constants / (zeta omega_s)`` seconds first.
    """
    params = SDFParams(F=modal.F(piece.level_m_s2), omega=piece.freq_hz / modal.f_s_hz,
                       zeta=modal.zeta, e=modal.e)
    xp, vp = particular_state(params.F, params.omega, params.zeta, 0.0)
    if float(np.hypot(xp, vp / params.omega)) < 1.0:
        return SDFState(t=0.0, x=float(xp), v=float(vp), theta=0.0), 0.0
    settle = settle_time_constants / max(modal.zeta, 1e-3)   # nondimensional (tau) time
    res = simulate(params, duration=settle)
    return res.state, res.state.t


def simulate_run(modal: Modal, run: RunSpec, *, piece_periods: int, settle_time_constants: float,
                 sample_rate_hz: float | None, want_v: bool = False, want_a: bool = False,
                 counter: StageCounter | None = None) -> RunMotion:
    """Simulate one run; sample the motion at ``sample_rate_hz`` when given (else impacts only)."""
    counter = counter if counter is not None else StageCounter()
    pieces = schedule(run, piece_periods)
    w_s = modal.omega_s_rad_s
    state, tau0 = initial_state(modal, pieces[0], settle_time_constants)
    sampled = sample_rate_hz is not None
    n = round(run.duration_s * sample_rate_hz) if sample_rate_hz is not None else 0
    t_samples = np.arange(n) / sample_rate_hz if sample_rate_hz is not None else np.empty(0)
    bounds = np.searchsorted(t_samples, [p.t0_s for p in pieces] + [run.duration_s], side="left")
    fields: tuple[Any, ...] = tuple(f for f, want in (("v", want_v), ("a", want_a)) if want)
    theta = np.empty(n) if sampled else None
    level = np.empty(n) if sampled else None
    freq = np.empty(n) if sampled else None
    v_rel = np.empty(n) if want_v and sampled else None
    a_rel = np.empty(n) if want_a and sampled else None
    imp_t: list[Any] = []
    imp_v: list[Any] = []
    imp_vo: list[Any] = []
    imp_lvl: list[Any] = []
    piece_impacts = np.zeros(len(pieces), dtype=np.int64)
    for k, piece in enumerate(pieces):
        params = SDFParams(F=modal.F(piece.level_m_s2), omega=piece.freq_hz / modal.f_s_hz,
                           zeta=modal.zeta, e=modal.e)
        # the piece ends exactly at tau0 + w_s t1 (no accumulated round-off across pieces)
        duration = tau0 + w_s * piece.t1_s - state.t
        dense_t = None
        lo, hi = int(bounds[k]), int(bounds[k + 1])
        if sampled and fields and hi > lo:
            dense_t = np.clip(tau0 + w_s * t_samples[lo:hi], state.t, state.t + duration)
        res = simulate(params, duration=duration, state=state, dense_t=dense_t,
                       dense_fields=fields or ("x",))
        counter.add("simulate")
        if sampled and hi > lo:
            tau = tau0 + w_s * t_samples[lo:hi]
            assert theta is not None and level is not None and freq is not None
            theta[lo:hi] = state.theta + params.omega * (tau - state.t)
            level[lo:hi] = piece.level_m_s2
            freq[lo:hi] = piece.freq_hz
            if dense_t is not None:
                counter.add("motion_dense")
                dense = res.dense
                assert dense is not None
                if v_rel is not None:
                    assert dense.v is not None
                    v_rel[lo:hi] = dense.v * w_s * modal.gap_m
                if a_rel is not None:
                    assert dense.a is not None
                    a_rel[lo:hi] = dense.a * w_s**2 * modal.gap_m
        m = len(res.impacts)
        piece_impacts[k] = m
        if m:
            imp_t.append((res.impacts.t - tau0) / w_s)
            imp_v.append(scaling.impact_velocity_ms(res.impacts.v_in, w_s, modal.gap_m))
            imp_vo.append(scaling.impact_velocity_ms(res.impacts.v_out, w_s, modal.gap_m))
            imp_lvl.append(np.full(m, piece.level_m_s2))
        state = res.state

    def cat(parts: list[np.ndarray]) -> np.ndarray:
        return np.concatenate(parts) if parts else np.empty(0)

    return RunMotion(pieces=pieces, impact_t_s=cat(imp_t), impact_v_in_m_s=cat(imp_v),
                     impact_v_out_m_s=cat(imp_vo), impact_level_m_s2=cat(imp_lvl),
                     piece_impacts=piece_impacts, theta=theta, level_m_s2=level, freq_hz=freq,
                     v_rel_m_s=v_rel, a_rel_m_s2=a_rel)


def true_thresholds(run: RunSpec, motion: RunMotion) -> tuple[float, float]:
    """``(onset, disappearance)`` levels, m/s^2, of a ramp run (NaN where not seen).

    Onset (ramp up): the level of the piece with the first impact; NaN if the run impacts
    from its first piece (the onset lies below the start) or never.  Disappearance (ramp
    down): the level of the piece with the last impact; NaN if impacts never stop or never occur.
    """
    onset = disappearance = math.nan
    hits = np.flatnonzero(motion.piece_impacts)
    if run.protocol == "amplitude_ramp_up" and hits.size and hits[0] > 0:
        onset = motion.pieces[int(hits[0])].level_m_s2
    if run.protocol == "amplitude_ramp_down" and hits.size and hits[-1] + 1 < len(motion.pieces):
        disappearance = motion.pieces[int(hits[-1])].level_m_s2
    return onset, disappearance
