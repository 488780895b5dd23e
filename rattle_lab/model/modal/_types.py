"""Result objects of the modal impact model."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._system import Contact, ModalSystem


def _ro(a: Any, dtype: Any = float) -> np.ndarray:
    arr = np.array(a, dtype=dtype)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True)
class ModalState:
    """State of the plate: time and mass-normalised modal coordinates.

    Attributes
    ----------
    t_s : float
        Time [s].
    p : numpy.ndarray
        ``p_k = sqrt(M_k) q_k`` [kg^1/2 m], shape (N,).
    v : numpy.ndarray
        ``p_k'`` [kg^1/2 m/s], shape (N,).
    r_m : float
        Local deflection of the omitted modes' element at the contact point [m] (0 when
        the system has none); the contact point is at ``beta . p - r``.
    """

    t_s: float
    p: np.ndarray
    v: np.ndarray
    r_m: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "t_s", float(self.t_s))
        object.__setattr__(self, "r_m", float(self.r_m))
        object.__setattr__(self, "p", _ro(self.p))
        object.__setattr__(self, "v", _ro(self.v))


@dataclass(frozen=True)
class ContactLog:
    """Every contact (rigid: each impulse; compliant: each interval of positive force).

    Attributes
    ----------
    t_start_s, t_end_s : numpy.ndarray
        Start and end [s] (equal for a rigid impulse).
    u_in_m_s : numpy.ndarray
        Contact-point velocity towards the striker at the start [m/s] (>= 0).
    u_out_m_s : numpy.ndarray
        Contact-point velocity away from the striker at the end [m/s].
    kind : numpy.ndarray of int
        0: impact (crossing), 1: grazing touch, 2: sticking interval (rigid contact).
    """

    t_start_s: np.ndarray
    t_end_s: np.ndarray
    u_in_m_s: np.ndarray
    u_out_m_s: np.ndarray
    kind: np.ndarray

    def __len__(self) -> int:
        return int(self.t_start_s.size)


@dataclass(frozen=True)
class EpisodeLog:
    """Impacts as contact episodes: first touch to final separation.

    Contacts closer than ``episode_gap_s`` (end of one to start of the next) form one
    episode: the micro-impact cluster of a rigid contact on a many-mode plate is one
    impact.

    Attributes
    ----------
    t_s, t_end_s : numpy.ndarray
        First touch and final separation [s].
    v_in_m_s : numpy.ndarray
        Contact-point velocity at first touch [m/s] (plate towards the striker, > 0).
    v_out_m_s : numpy.ndarray
        Contact-point velocity at final separation [m/s] (away from the striker, > 0).
    e_mode1 : numpy.ndarray
        Effective restitution of mode 1: ``-q_1'(after) / q_1'(before)`` (nondimensional).
    n_contacts : numpy.ndarray of int
        Contacts in the episode.
    mode_velocity_in, mode_velocity_out : numpy.ndarray
        Modal velocities ``q_k'`` [m/s] just before first touch and just after final
        separation, shape (n_episodes, N).
    """

    t_s: np.ndarray
    t_end_s: np.ndarray
    v_in_m_s: np.ndarray
    v_out_m_s: np.ndarray
    e_mode1: np.ndarray
    n_contacts: np.ndarray
    mode_velocity_in: np.ndarray
    mode_velocity_out: np.ndarray

    def __len__(self) -> int:
        return int(self.t_s.size)

    def to_dicts(self) -> list[dict[str, float]]:
        """One JSON-ready dict per episode (``t_s``, ``v_in_m_s``, ``v_out_m_s``, ``e_mode1``, ...)."""
        return [{"t_s": float(self.t_s[i]), "t_end_s": float(self.t_end_s[i]),
                 "v_in_m_s": float(self.v_in_m_s[i]), "v_out_m_s": float(self.v_out_m_s[i]),
                 "e_mode1": float(self.e_mode1[i]), "n_contacts": int(self.n_contacts[i])}
                for i in range(len(self))]


@dataclass(frozen=True, eq=False)
class ModalResult:
    """What :func:`rattle_lab.model.modal.simulate_modal` returns.

    Attributes
    ----------
    system : ModalSystem
        The system simulated.
    contact : Contact
        The contact law.
    contacts : ContactLog
        Every contact.
    impacts : EpisodeLog
        Contact episodes (what every output calls an impact).
    state : ModalState
        The final state (pass it as ``state=`` to continue).
    segments : tuple
        ``(t0_s, t1_s, evaluator)`` of every flow piece when ``dense=True``; the
        evaluator maps times to ``(p, v)``.
    n_events : int
        Events processed (touches, separations, releases, window restarts).
    """

    system: ModalSystem
    contact: Contact
    contacts: ContactLog
    impacts: EpisodeLog
    state: ModalState
    segments: tuple[Any, ...]
    n_events: int

    def modal_state(self, t_s: Any) -> tuple[np.ndarray, np.ndarray]:
        """Mass-normalised ``(p, v)`` at times ``t_s`` (needs ``dense=True``), shape (N, n_t)."""
        from rattle_lab.exceptions import ParameterError

        if not self.segments:
            raise ParameterError("the run kept no segments; simulate with `dense=True`")
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        starts = np.array([seg[0] for seg in self.segments])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.segments) - 1)
        n = self.system.n_modes
        p = np.empty((n, t.size))
        v = np.empty((n, t.size))
        for i in np.unique(idx):
            sel = idx == i
            t0, _, ev = self.segments[i]
            out = ev(t[sel] - t0)
            p[:, sel] = out[0]
            v[:, sel] = out[1]
        return p, v

    def residual_deflection_m(self, t_s: Any) -> np.ndarray:
        """Local deflection ``r(t)`` [m] of the omitted modes' element (zeros without one)."""
        from rattle_lab.exceptions import ParameterError

        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        if not self.system.corrected:
            return np.zeros(t.size)
        if not self.segments:
            raise ParameterError("the run kept no segments; simulate with `dense=True`")
        starts = np.array([seg[0] for seg in self.segments])
        idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(self.segments) - 1)
        r = np.empty(t.size)
        for i in np.unique(idx):
            sel = idx == i
            t0, _, ev = self.segments[i]
            r[sel] = ev(t[sel] - t0)[2]
        return r

    def modal_velocity_m_s(self, t_s: Any) -> np.ndarray:
        """Modal velocities ``q_k'(t)`` [m/s] (shapes' normalisation), shape (N, n_t)."""
        _, v = self.modal_state(t_s)
        return np.asarray(v / np.sqrt(self.system.modal_mass_kg)[:, None])

    def modal_energy_j(self, t_s: Any) -> np.ndarray:
        """Energy of each mode ``(p'**2 + omega**2 p**2) / 2`` [J], shape (N, n_t)."""
        p, v = self.modal_state(t_s)
        return np.asarray(0.5 * (v**2 + (self.system.omega_rad_s[:, None] * p) ** 2))
