"""Event-driven simulation of the modal plate-striker model: :func:`simulate_modal`.

Between contacts every mode flows in closed form (:class:`~rattle_lab.model.modal._flows.FreeModes`);
the contact onset is the earliest zero of the contact-point gap, an exponential sum
located by :func:`~rattle_lab.model.modal._expsum.first_touch` (rigorous derivative bounds,
so no grazing contact is missed, then a bracketed Newton iteration to adjacent floats).

Contact laws
    *rigid*: an impulse at the contact point, ``u+ = -e u-``, distributed through the
    modal masses (``dp' = -J beta``, ``J = (1 + e) u- / |beta|**2``).  When the next
    flight would be lower than ``H_RES`` (rounding of the gap) while the load pushes
    into the striker, the chatter has accumulated: the plate sticks (the contact
    velocity is removed) and moves on the constraint ``beta . p = gap`` (an exact
    linear flow of the other N - 1 directions) until the contact force, an
    exponential sum, reaches zero.
    *kelvin-voigt*: ``f_c = k delta + c delta'``; during contact the coupled system is
    linear and solved exactly (:class:`~rattle_lab.model.modal._flows.LinearFlow`); the
    contact ends when ``f_c`` reaches zero (to rounding).  After a separation with
    ``delta > 0`` (c > 0) the contact resumes where ``f_c`` turns positive again.
    *omitted modes* (``system.corrected``): the contact point is ``beta . p - r`` with
    ``k_r r + Z r' = f_c`` (:mod:`~rattle_lab.model.modal._system`); in free flight ``r``
    relaxes as ``exp(-s k_r / Z)``, one more real term of the exponential sums, and the
    Kelvin-Voigt contact is the exact linear flow of ``(p, p', r)``.  The rigid contact
    is not defined with the element (a rigid striker against a dashpot has no impulse):
    use a compliant one.
    *hertz*: ``f_c = k_H delta**1.5``, integrated by DOP853 (``scipy.integrate.solve_ivp``,
    rtol ``hertz_rtol``, atol ``hertz_rtol`` times the gap's scale) with the separation
    ``delta = 0`` located by its event finder on the dense output.

Each flow is restarted at least once per window ``min(1/f, 2 pi/omega_1)`` so that
local times stay small.  An *impact* is a contact episode: contacts closer than
``episode_gap_s`` (default a quarter period of mode 1) are one impact.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg

from rattle_lab.exceptions import ParameterError, SimulationError
from . import _expsum as ex
from ._flows import AffineFlow, FreeModes, LinearFlow, _mv
from ._system import Contact, HertzContact, KelvinVoigtContact, ModalSystem, RigidContact
from ._types import ContactLog, EpisodeLog, ModalResult, ModalState

EPS = np.finfo(float).eps
#: A rigid-contact flight lower than H_RES_REL * gap is below the rounding of the gap
#: function: the chatter has accumulated and the plate sticks.
H_RES_REL = 256.0 * EPS
TOL_REL = 4.0 * EPS

FREE, KV, STICK, HERTZ = 0, 1, 2, 3


class _Engine:
    def __init__(self, system: ModalSystem, contact: Contact, dense: bool, hertz_rtol: float) -> None:
        self.sys = system
        self.contact = contact
        self.dense = dense
        self.hertz_rtol = hertz_rtol
        self.omega = system.omega_rad_s
        self.zeta = system.zeta
        self.phi = system.phi
        self.beta = system.beta
        self.nb2 = float(self.beta @ self.beta)
        self.gap = system.gap_m
        self.Omega = system.Omega_rad_s
        self.fm = FreeModes(self.omega, self.zeta, self.phi, self.Omega)
        self.corr = system.corrected
        self.Zl = system.local_impedance_n_s_m
        self.Gr = system.residual_compliance_m_n
        self.rate = 1.0 / (self.Gr * self.Zl) if self.corr else 0.0
        self.r = 0.0
        if self.corr and isinstance(contact, RigidContact):
            raise ParameterError("the rigid contact is not defined with the omitted modes' element (a rigid "
                                 "striker against the plate's local impedance has no impulse); use a "
                                 "kelvin-voigt or hertz contact, or a system without the element")
        self.window = min(1.0 / system.freq_hz, 2.0 * math.pi / float(np.min(self.omega)))
        self.tol_d = TOL_REL * self.gap
        n = system.n_modes
        K0 = np.diag(self.omega**2)
        C0 = np.diag(2.0 * self.zeta * self.omega)
        self.K0, self.C0 = K0, C0
        if isinstance(contact, KelvinVoigtContact):
            k, c = contact.stiffness_n_m, contact.damping_n_s_m
            bb = np.outer(self.beta, self.beta)
            if self.corr:
                self._kv_corrected(k, c)
            else:
                self.kv = LinearFlow(K0 + k * bb, C0 + c * bb, k * self.gap * self.beta, self.phi, self.Omega)
            self.tol_f = TOL_REL * k * self.gap
        if isinstance(contact, RigidContact):
            T = scipy.linalg.null_space(self.beta[None, :]) if n > 1 else np.zeros((1, 0))
            self.T = T
            self.p0 = self.gap * self.beta / self.nb2
            Kr = T.T @ K0 @ T
            Cr = T.T @ C0 @ T
            self.stick = LinearFlow(Kr, Cr, -T.T @ (K0 @ self.p0), T.T @ self.phi, self.Omega)
            # contact force lambda_c = w . (r, r') + c + Re(f e^{i theta}) while stuck
            self.w_lam = -np.concatenate([self.beta @ K0 @ T, self.beta @ C0 @ T]) / self.nb2
            self.c_lam = -float(self.beta @ K0 @ self.p0) / self.nb2
            self.f_lam = float(self.beta @ self.phi) / self.nb2
            self.tol_l = TOL_REL * (abs(self.c_lam) + abs(self.f_lam))
        self.contacts: list[tuple[float, float, float, float, int, np.ndarray, np.ndarray]] = []
        self.segments: list[tuple[float, float, Any]] = []

    def _kv_corrected(self, k: float, c: float) -> None:
        """Kelvin-Voigt contact through the element: the linear flow of ``z = (p, p', r)``."""
        n = self.sys.n_modes
        b, Zl, Gr = self.beta, self.Zl, self.Gr
        # r' = g . z + g0 (from Z r' + r / G = k delta + c delta', delta = beta . p - r - gap)
        g = np.concatenate([k * b, c * b, [-(k + 1.0 / Gr)]]) / (Zl + c)
        g0 = -k * self.gap / (Zl + c)
        # f_c = f_row . z + f_c0
        f_row = np.concatenate([k * b, c * b, [-k]]) - c * g
        f_c0 = -k * self.gap - c * g0
        A = np.zeros((2 * n + 1, 2 * n + 1))
        A[:n, n:2 * n] = np.eye(n)
        A[n:2 * n, :n] = -self.K0
        A[n:2 * n, n:2 * n] = -self.C0
        A[n:2 * n, :] -= np.outer(b, f_row)
        A[2 * n, :] = g
        f0 = np.concatenate([np.zeros(n), -b * f_c0, [g0]])
        ph = np.concatenate([np.zeros(n), self.phi, [0.0]])
        self.kv = AffineFlow(A, f0, ph, self.Omega)
        self.kv_g, self.kv_g0, self.kv_frow, self.kv_f0 = g, g0, f_row, f_c0

    # ------------------------------------------------------------------ helpers
    def theta(self, t: float) -> float:
        return self.Omega * t + self.sys.phase_rad

    def contact_accel(self, p: np.ndarray, v: np.ndarray, t: float) -> float:
        """``beta . p''`` with no contact force (> 0: the load pushes into the striker)."""
        acc = self.phi * math.cos(self.theta(t)) - 2.0 * self.zeta * self.omega * v - self.omega**2 * p
        return float(self.beta @ acc)

    def record(self, t0: float, t1: float, ev: Any) -> None:
        if self.dense:
            self.segments.append((t0, t1, ev))

    # ------------------------------------------------------------------ run
    def run(self, t: float, p: np.ndarray, v: np.ndarray, t_end: float,
            max_events: int, in_contact: bool = False) -> tuple[float, np.ndarray, np.ndarray, int]:
        mode = FREE
        on_stop = False
        n_events = 0
        c_start: tuple[float, float, np.ndarray] | None = None  # (t, u_in, v before) of an open contact
        if in_contact:  # a compliant contact going on at the start (e.g. across a ramp's pieces)
            mode = KV if isinstance(self.contact, KelvinVoigtContact) else HERTZ
            c_start = (t, max(float(self.beta @ v) + self.rate * self.r, 0.0), v.copy())
        while t < t_end:
            n_events += 1
            if n_events > max_events:
                raise SimulationError(f"event budget of {max_events} exhausted at t = {t:.17g} s; "
                                      "raise `max_events` or shorten the run")
            win = min(self.window, t_end - t)
            if win <= 4 * EPS * max(abs(t), 1.0):
                break
            th = self.theta(t)
            if mode == FREE:
                C, Pt = self.fm.start(p, v, th)
                a, lam, c0 = self.fm.functional(C, Pt, self.beta, None, -self.gap)
                fm = self.fm
                r0 = self.r
                if self.corr:
                    a = np.append(a, -r0 + 0j)
                    lam = np.append(lam, -self.rate + 0j)
                    ev: Any = (lambda s, C=C, Pt=Pt, fm=fm, r0=r0:
                               (*fm.state(C, Pt, s), r0 * np.exp(-self.rate * s)))
                else:
                    ev = (lambda s, C=C, Pt=Pt, fm=fm: fm.state(C, Pt, s))
                d0 = ex.value(a, lam, c0, 0.0, 0)
                if isinstance(self.contact, KelvinVoigtContact) and d0 > self.tol_d:
                    s_hit, kind, to_contact = self._free_inside(C, Pt, a, lam, c0, win, r0)
                else:
                    s_lo = 0.0
                    if on_stop or d0 > -self.tol_d:
                        s_lo = ex.start_exclusion(a, lam, c0, 0.0, win)
                    if s_lo == 0.0 and d0 > -self.tol_d:
                        kind, s_hit = ex.GRAZE, 0.0
                    else:
                        kind, s_hit, _ = ex.first_touch(a, lam, c0, s_lo, win, self.tol_d)
                    to_contact = kind != ex.NONE
                if not to_contact:
                    s_adv = s_hit if kind != ex.NONE else win
                    p, v = fm.state(C, Pt, s_adv)
                    self.r = r0 * math.exp(-self.rate * s_adv)
                    self.record(t, t + s_adv, ev)
                    t += s_adv
                    on_stop = kind != ex.NONE  # left the stop region (delta = 0 going down)
                    continue
                p, v = fm.state(C, Pt, s_hit)
                self.r = r0 * math.exp(-self.rate * s_hit)
                self.record(t, t + s_hit, ev)
                t += s_hit
                on_stop = False
                mode, p, v, c_start = self._touch(t, p, v, kind)
                if mode == FREE:
                    on_stop = True
                continue
            if mode == KV:
                mode, t, p, v, c_start, on_stop = self._kv_step(t, p, v, th, win, c_start)
                continue
            if mode == STICK:
                mode, t, p, v, c_start, on_stop = self._stick_step(t, p, v, th, win, c_start)
                continue
            if mode == HERTZ:
                mode, t, p, v, c_start, on_stop = self._hertz_step(t, p, v, th, win, c_start)
                continue
        self.open_contact = c_start
        return t, p, v, n_events

    # ------------------------------------------------------------------ free flight from inside (KV, c > 0)
    def _free_inside(self, C: np.ndarray, Pt: np.ndarray, a: np.ndarray, lam: np.ndarray, c0: float,
                     win: float, r0: float) -> tuple[float, int, bool]:
        """Free flight that starts with delta > 0 after a Kelvin-Voigt release at f_c = 0."""
        assert isinstance(self.contact, KelvinVoigtContact)
        k, c = self.contact.stiffness_n_m, self.contact.damping_n_s_m
        af, lamf, cf = self.fm.functional(C, Pt, k * self.beta, c * self.beta, -k * self.gap)
        if self.corr:  # f_c = k (.. - r) + c (.. - r'), r' = -rate r
            af = np.append(af, (-k + c * self.rate) * r0 + 0j)
            lamf = np.append(lamf, -self.rate + 0j)
        s_lo = ex.start_exclusion(af, lamf, cf, 0.0, win)
        if s_lo == 0.0:
            return 0.0, ex.GRAZE, True
        k1, s1, _ = ex.first_touch(af, lamf, cf, s_lo, win, self.tol_f)
        k2, s2, _ = ex.first_touch(-a, lam, -c0, 0.0, win, self.tol_d)
        if k1 != ex.NONE and (k2 == ex.NONE or s1 <= s2):
            return s1, k1, True
        if k2 != ex.NONE:
            return s2, k2, False
        return win, ex.NONE, False

    # ------------------------------------------------------------------ contact onset
    def _touch(self, t: float, p: np.ndarray, v: np.ndarray, kind: int) -> tuple[int, np.ndarray, np.ndarray, Any]:
        u = max(float(self.beta @ v) + self.rate * self.r, 0.0)
        v_before = v.copy()
        if isinstance(self.contact, RigidContact):
            e = self.contact.e
            # p is left where the crossing was located (the first float with delta >= 0):
            # projecting it onto delta = 0 would add a systematic energy error of ~eps per impact.
            v = v - self.beta * ((1.0 + e) * float(self.beta @ v) / self.nb2) if u > 0 else v.copy()
            a_c = self.contact_accel(p, v, t)
            u_out = -float(self.beta @ v)
            if a_c > 0.0 and max(u_out, 0.0) ** 2 <= 2.0 * a_c * H_RES_REL * self.gap:
                if u > 0:  # the last micro-impact is a contact of its own
                    self.contacts.append((t, t, u, u_out, 0 if kind == ex.CROSSING else 1, v_before, v.copy()))
                v = v - self.beta * (float(self.beta @ v) / self.nb2)
                # The unresolved flights form a geometric series (ratio e, each 2 u / a_c
                # long): sticking is reported from their accumulation point.
                tail = 2.0 * max(u_out, 0.0) / (a_c * (1.0 - e)) if e < 1.0 else 0.0
                return STICK, p, v, (t + tail, 0.0, v.copy())
            self.contacts.append((t, t, u, u_out, 0 if kind == ex.CROSSING else 1, v_before, v.copy()))
            return FREE, p, v, None
        if isinstance(self.contact, KelvinVoigtContact):
            return KV, p, v, (t, u, v_before)
        return HERTZ, p, v, (t, u, v_before)

    def _close(self, c_start: Any, t: float, v: np.ndarray, kind: int, u_out: float | None = None) -> None:
        t0, u, v_before = c_start
        uo = -float(self.beta @ v) if u_out is None else u_out
        self.contacts.append((t0, t, u, uo, kind, v_before, v.copy()))

    # ------------------------------------------------------------------ Kelvin-Voigt contact
    def _kv_step(self, t: float, p: np.ndarray, v: np.ndarray, th: float, win: float, c_start: Any) -> tuple:
        assert isinstance(self.contact, KelvinVoigtContact)
        k, c = self.contact.stiffness_n_m, self.contact.damping_n_s_m
        kv = self.kv
        n = self.sys.n_modes
        if self.corr:
            gamma, Zt = kv.start(np.concatenate([p, v, [self.r]]), th)
            a, lam, c0 = kv.functional(gamma, Zt, -self.kv_frow, -self.kv_f0)
            ev: Any = (lambda s, g=gamma, Z=Zt: _split3(kv.state(g, Z, s), n))
        else:
            gamma, Zt = kv.start(np.concatenate([p, v]), th)
            w = -np.concatenate([k * self.beta, c * self.beta])
            a, lam, c0 = kv.functional(gamma, Zt, w, k * self.gap)
            ev = (lambda s, g=gamma, Z=Zt: _split(kv.state(g, Z, s), n))
        h0 = ex.value(a, lam, c0, 0.0, 0)
        s_lo = 0.0
        if h0 > -self.tol_f:
            s_lo = ex.start_exclusion(a, lam, c0, 0.0, win)
            if s_lo == 0.0:  # grazing touch: the force never becomes positive
                self._close(c_start, t, v, 1, -float(self.beta @ v) - self.rate * self.r if self.corr else None)
                return FREE, t, p, v, None, True
        kind, s, _ = ex.first_touch(a, lam, c0, s_lo, win, self.tol_f)
        z = kv.state(gamma, Zt, s)
        self.record(t, t + s, ev)
        t += s
        p, v = z[:n].copy(), z[n:2 * n].copy()
        u_out = None
        if self.corr:
            self.r = float(z[2 * n])
            u_out = -(float(self.beta @ v) - float(self.kv_g @ z + self.kv_g0))
        if kind == ex.NONE:
            return KV, t, p, v, c_start, False
        self._close(c_start, t, v, 0, u_out)
        return FREE, t, p, v, None, True

    # ------------------------------------------------------------------ rigid contact: sticking
    def _stick_step(self, t: float, p: np.ndarray, v: np.ndarray, th: float, win: float, c_start: Any) -> tuple:
        T, st = self.T, self.stick
        z0 = np.concatenate([_mv(T.T, p - self.p0), _mv(T.T, v)])
        gamma, Zt = st.start(z0, th)
        a, lam, c0 = st.functional(gamma, Zt, -self.w_lam, -self.c_lam, -self.f_lam * np.exp(1j * th))

        def to_pv(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            m = T.shape[1]
            if z.ndim == 1:
                return self.p0 + _mv(T, z[:m]), _mv(T, z[m:])
            return self.p0[:, None] + _mv(T, z[:m]), _mv(T, z[m:])

        ev = (lambda s, g=gamma, Z=Zt: to_pv(st.state(g, Z, s)) if st.n else _pinned(self.p0, s))
        h0 = ex.value(a, lam, c0, 0.0, 0)
        if h0 >= -self.tol_l:  # the force does not push: no sticking after all
            self._close(c_start, t, v, 1)
            return FREE, t, p, v, None, True
        kind, s, _ = ex.first_touch(a, lam, c0, 0.0, win, self.tol_l)
        p, v = ev(s)
        p, v = np.array(p, dtype=float), np.array(v, dtype=float)
        self.record(t, t + s, ev)
        t += s
        if kind == ex.NONE:
            return STICK, t, p, v, c_start, False
        self._close(c_start, t, v, 2)
        return FREE, t, p, v, None, True

    # ------------------------------------------------------------------ Hertz contact (numerical)
    def _hertz_step(self, t: float, p: np.ndarray, v: np.ndarray, th: float, win: float, c_start: Any) -> tuple:
        from scipy.integrate import solve_ivp

        assert isinstance(self.contact, HertzContact)
        kh = self.contact.stiffness_n_m15
        n = self.sys.n_modes
        beta, phi, Om, gap = self.beta, self.phi, self.Omega, self.gap
        c1 = 2.0 * self.zeta * self.omega
        w2 = self.omega**2

        corr, Zl, Gr = self.corr, self.Zl, self.Gr

        def rhs(s: float, y: np.ndarray) -> np.ndarray:
            d = float(beta @ y[:n]) - gap - (y[2 * n] if corr else 0.0)
            f = kh * d * math.sqrt(d) if d > 0 else 0.0
            dv = phi * math.cos(th + Om * s) - c1 * y[n:2 * n] - w2 * y[:n] - beta * f
            if corr:
                return np.concatenate([y[n:2 * n], dv, [(f - y[2 * n] / Gr) / Zl]])
            return np.concatenate([y[n:], dv])

        def sep(s: float, y: np.ndarray) -> float:
            return float(beta @ y[:n]) - gap - (y[2 * n] if corr else 0.0)
        sep.terminal = True  # type: ignore[attr-defined]
        sep.direction = -1  # type: ignore[attr-defined]
        p_scale = gap / math.sqrt(self.nb2)
        atol = np.concatenate([np.full(n, p_scale), np.full(n, p_scale * float(np.max(self.omega)))]
                              + ([[gap]] if corr else []))
        y0 = np.concatenate([p, v] + ([[self.r]] if corr else []))
        sol = solve_ivp(rhs, (0.0, win), y0, method="DOP853", rtol=self.hertz_rtol,
                        atol=self.hertz_rtol * atol, events=sep, dense_output=self.dense)
        if not sol.success:
            raise SimulationError(f"Hertz contact integration failed at t = {t:.17g} s: {sol.message}")
        if sol.t_events[0].size:
            s = float(sol.t_events[0][0])
            y = sol.y_events[0][0]
        else:
            s = float(sol.t[-1])
            y = sol.y[:, -1]
        if self.dense:
            so = sol.sol
            self.record(t, t + s, (lambda x, so=so: _split3(so(x), n)) if corr else (lambda x, so=so: _split(so(x), n)))
        t += s
        p, v = y[:n].copy(), y[n:2 * n].copy()
        if corr:
            self.r = float(y[2 * n])
        if not sol.t_events[0].size:
            return HERTZ, t, p, v, c_start, False
        p = p + beta * ((gap + self.r - float(beta @ p)) / self.nb2)  # on the stop to rounding
        self._close(c_start, t, v, 0, -float(beta @ v) - self.rate * self.r if corr else None)
        return FREE, t, p, v, None, True


def _split(z: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    return z[:n], z[n:]


def _split3(z: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, Any]:
    return z[:n], z[n:2 * n], z[2 * n]


def _pinned(p0: np.ndarray, s: Any) -> tuple[np.ndarray, np.ndarray]:
    s_arr = np.asarray(s, dtype=float)
    if s_arr.ndim == 0:
        return p0.copy(), np.zeros_like(p0)
    return np.repeat(p0[:, None], s_arr.size, axis=1), np.zeros((p0.size, s_arr.size))


def _episodes(contacts: list[tuple], gap_s: float, n_modes: int) -> EpisodeLog:
    groups: list[list[tuple]] = []
    for c in contacts:
        if groups and c[0] - groups[-1][-1][1] <= gap_s:
            groups[-1].append(c)
        else:
            groups.append([c])
    t0 = np.array([g[0][0] for g in groups])
    t1 = np.array([g[-1][1] for g in groups])
    u_in = np.array([g[0][2] for g in groups])
    u_out = np.array([g[-1][3] for g in groups])
    v_in = np.array([g[0][5] for g in groups]).reshape(-1, n_modes)
    v_out = np.array([g[-1][6] for g in groups]).reshape(-1, n_modes)
    with np.errstate(divide="ignore", invalid="ignore"):
        e1 = np.where(v_in[:, 0] != 0, -v_out[:, 0] / v_in[:, 0], np.nan)
    return EpisodeLog(t_s=t0, t_end_s=t1, v_in_m_s=u_in, v_out_m_s=u_out, e_mode1=e1,
                      n_contacts=np.array([len(g) for g in groups], dtype=int),
                      mode_velocity_in=v_in, mode_velocity_out=v_out)


def simulate_modal(system: ModalSystem, contact: Contact | None = None, *, cycles: float | None = None,
                   duration_s: float | None = None, state: ModalState | None = None,
                   episode_gap_s: float | None = None, dense: bool = False, max_events: int | None = None,
                   hertz_rtol: float = 1e-10) -> ModalResult:
    """Simulate the N-mode plate against the striker.

    Parameters
    ----------
    system : ModalSystem
        Modes, damping, forcing, striker and gap (see :func:`plate_system`).
    contact : RigidContact, KelvinVoigtContact or HertzContact, optional
        Contact law; default :class:`KelvinVoigtContact` with the thesis striker's stiffness.
    cycles, duration_s : float
        Run length, in forcing periods or seconds (exactly one).
    state : ModalState, optional
        Start (default: at rest at t = 0); it may start inside a compliant contact (the
        end state of a run whose contact was going on), not inside a rigid one.
    episode_gap_s : float, optional
        Contacts closer than this are one impact (default ``0.25 * 2 pi / omega_1``).
        Episodes that may still go on at the end of the run are left out of ``impacts``
        (their contacts stay in ``contacts``).
    dense : bool
        Keep the flow pieces for :meth:`ModalResult.modal_state` (sound, figures).
    max_events : int, optional
        Event budget (default ``10**6 + 2000 * cycles``).
    hertz_rtol : float
        Relative tolerance of the Hertz integration (DOP853).

    Returns
    -------
    ModalResult

    Raises
    ------
    ParameterError
        On invalid arguments.
    SimulationError
        If the event budget runs out.

    Examples
    --------
    >>> import numpy as np
    >>> from rattle_lab.model.modal import plate_system, simulate_modal, RigidContact
    >>> sys1 = plate_system(n_modes=1, pressure_pa=285.0, freq_hz=99.8)
    >>> res = simulate_modal(sys1, RigidContact(e=0.6), cycles=30)
    >>> bool(len(res.impacts) > 0 and np.allclose(res.impacts.e_mode1, 0.6))
    True
    """
    if not isinstance(system, ModalSystem):
        raise ParameterError(f"`system` must be a ModalSystem, was {type(system).__name__}")
    contact = KelvinVoigtContact() if contact is None else contact
    if not isinstance(contact, RigidContact | KelvinVoigtContact | HertzContact):
        raise ParameterError(f"`contact` must be a RigidContact, KelvinVoigtContact or HertzContact, was {contact!r}")
    if (cycles is None) == (duration_s is None):
        raise ParameterError("give exactly one of `cycles` and `duration_s`")
    dur = float(cycles) / system.freq_hz if cycles is not None else float(duration_s)  # type: ignore[arg-type]
    if not (math.isfinite(dur) and dur >= 0):
        raise ParameterError(f"the run length must be finite and >= 0, was cycles={cycles}, duration_s={duration_s}")
    if not (0 < hertz_rtol < 1e-3):
        raise ParameterError(f"`hertz_rtol` must lie in (0, 1e-3), was {hertz_rtol}")
    n = system.n_modes
    if state is None:
        state = ModalState(t_s=0.0, p=np.zeros(n), v=np.zeros(n))
    if state.p.size != n or state.v.size != n:
        raise ParameterError(f"`state` must have {n} modal coordinates, had {state.p.size}")
    in_contact = float(system.beta @ state.p) - state.r_m > system.gap_m * (1 + 1e-12)
    if in_contact and isinstance(contact, RigidContact):
        raise ParameterError("`state` penetrates the striker (beta . p - r > gap)")
    if state.r_m != 0.0 and not system.corrected:
        raise ParameterError("`state` has a local deflection r but the system has no omitted-modes element")
    gap_s = 0.25 * 2.0 * math.pi / float(system.omega_rad_s[0]) if episode_gap_s is None else float(episode_gap_s)
    if not (gap_s >= 0 and math.isfinite(gap_s)):
        raise ParameterError(f"`episode_gap_s` must be finite and >= 0, was {episode_gap_s}")
    budget = max_events if max_events is not None else 10**6 + int(2000 * dur * system.freq_hz)
    eng = _Engine(system, contact, dense, hertz_rtol)
    eng.r = state.r_m
    t, p, v, n_events = eng.run(state.t_s, state.p.copy(), state.v.copy(), state.t_s + dur, budget, in_contact)
    cs = eng.contacts
    log = ContactLog(t_start_s=np.array([c[0] for c in cs]), t_end_s=np.array([c[1] for c in cs]),
                     u_in_m_s=np.array([c[2] for c in cs]), u_out_m_s=np.array([c[3] for c in cs]),
                     kind=np.array([c[4] for c in cs], dtype=int))
    # An episode whose last contact ends within episode_gap_s of the end of the run (or
    # that is still open) may go on: it is left out of the impacts, not cut short.
    t_stop = state.t_s + dur
    starts = [c[0] for c in cs] + ([eng.open_contact[0]] if eng.open_contact is not None else [])
    n_done = sum(1 for c in cs if c[1] < t_stop - gap_s)
    while 0 < n_done < len(starts) and starts[n_done] - cs[n_done - 1][1] <= gap_s:
        n_done -= 1
    eps_log = _episodes(cs[:n_done], gap_s, n)
    sq = np.sqrt(system.modal_mass_kg)
    eps_log = EpisodeLog(t_s=eps_log.t_s, t_end_s=eps_log.t_end_s, v_in_m_s=eps_log.v_in_m_s,
                         v_out_m_s=eps_log.v_out_m_s, e_mode1=eps_log.e_mode1, n_contacts=eps_log.n_contacts,
                         mode_velocity_in=eps_log.mode_velocity_in / sq,
                         mode_velocity_out=eps_log.mode_velocity_out / sq)
    return ModalResult(system=system, contact=contact, contacts=log, impacts=eps_log,
                       state=ModalState(t_s=t, p=p, v=v, r_m=eng.r), segments=tuple(eng.segments), n_events=n_events)
