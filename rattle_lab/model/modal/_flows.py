"""Closed-form flows between events: free modes, and coupled linear systems.

Free flight (no contact): each mass-normalised mode is a damped oscillator under
the harmonic load, ``p'' + 2 zeta omega p' + omega**2 p = phi cos(theta0 + Omega s)``::

    p(s) = Re(C exp(lam s)) + Re(P exp(i (theta0 + Omega s))),
    lam = -zeta omega + i omega_d,   omega_d = omega sqrt(1 - zeta**2),
    P = phi / (omega**2 - Omega**2 + 2 i zeta omega Omega),
    C = y0 - i (y0' + zeta omega y0) / omega_d     (y0, y0' the homogeneous start).

Coupled linear flow (Kelvin-Voigt contact, or sticking on the striker): the
first-order system ``z' = A z + f0 + Re(phi exp(i theta))`` with
``A = [[0, I], [-K, -C]]`` is solved exactly by the eigen-decomposition
``A = V diag(Lambda) V^-1`` (homogeneous part) plus the constant and harmonic
particular solutions ``z_c = [K^-1 f0, 0]``, ``Z = [P, i Omega P]`` with
``(K - Omega**2 I + i Omega C) P = phi``.  Any linear functional of the state is
then an exponential sum (:mod:`rattle_lab.model.modal._expsum`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from rattle_lab.exceptions import ParameterError


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``A @ x`` by numpy's own loops: multi-threaded BLAS costs milliseconds per call on
    small matrices when its threads must wake up (measured: 20 ms for 64 x 64 on a busy
    2-core machine, against 20 us here)."""
    return np.einsum("ij,j...->i...", A, x, optimize=False)


def _decay(x: np.ndarray) -> np.ndarray:
    """``exp(x)`` with terms below 1e-280 set to zero: subnormal numbers would make the
    following matrix products ~1000 times slower, and such terms are below rounding."""
    return np.where(x.real < -645.0, 0.0, np.exp(np.maximum(x.real, -645.0) + 1j * x.imag))


class FreeModes:
    """Constants of the uncoupled modal flow (one per system)."""

    def __init__(self, omega: np.ndarray, zeta: np.ndarray, phi: np.ndarray, Omega: float) -> None:
        self.omega = omega
        self.zeta = zeta
        self.Omega = Omega
        self.wd = omega * np.sqrt((1.0 - zeta) * (1.0 + zeta))
        self.lam = (-zeta * omega) + 1j * self.wd
        denom = (omega - Omega) * (omega + Omega) + 2j * zeta * omega * Omega
        self.P = phi / denom  # x_p = Re(P e^{i theta})

    def start(self, p: np.ndarray, v: np.ndarray, theta0: float) -> tuple[np.ndarray, np.ndarray]:
        """``(C, Pt)``: homogeneous amplitudes and the phase-folded particular amplitudes."""
        Pt = self.P * np.exp(1j * theta0)
        y0 = p - Pt.real
        yd0 = v - (1j * self.Omega * Pt).real
        C = y0 - 1j * (yd0 + self.zeta * self.omega * y0) / self.wd
        return C, Pt

    def state(self, C: np.ndarray, Pt: np.ndarray, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """``(p, v)`` at local times ``s``: shape (N,) for a scalar s, (N, n_s) otherwise."""
        s_arr = np.asarray(s, dtype=float)
        if s_arr.ndim == 0:
            eh = C * np.exp(self.lam * float(s_arr))
            ef = Pt * np.exp(1j * self.Omega * float(s_arr))
            return eh.real + ef.real, (self.lam * eh).real + (1j * self.Omega * ef).real
        eh = C[:, None] * np.exp(np.outer(self.lam, s_arr))
        ef = Pt[:, None] * np.exp(1j * self.Omega * s_arr)[None, :]
        return eh.real + ef.real, (self.lam[:, None] * eh).real + (1j * self.Omega * ef).real

    def functional(self, C: np.ndarray, Pt: np.ndarray, alpha: np.ndarray, beta: np.ndarray | None,
                   c0: float) -> tuple[np.ndarray, np.ndarray, float]:
        """Exponential sum of ``sum_k alpha_k p_k + beta_k p_k' + c0``."""
        coef = alpha.astype(complex) if beta is None else alpha + beta * self.lam
        coef_f = alpha.astype(complex) if beta is None else alpha + beta * (1j * self.Omega)
        a = np.concatenate([coef * C, [np.sum(coef_f * Pt)]])
        lam = np.concatenate([self.lam, [1j * self.Omega]])
        return a, lam, float(c0)


class LinearFlow:
    """Exact flow of ``p'' + C p' + K p = f0 + phi cos(theta)`` (n coordinates, n may be 0)."""

    def __init__(self, K: np.ndarray, C: np.ndarray, f0: np.ndarray, phi: np.ndarray, Omega: float) -> None:
        n = K.shape[0]
        self.n = n
        self.Omega = Omega
        if n == 0:
            self.Lam = np.zeros(0, dtype=complex)
            self.V = np.zeros((0, 0), dtype=complex)
            self.Vinv = np.zeros((0, 0), dtype=complex)
            self.zc = np.zeros(0)
            self.Z = np.zeros(0, dtype=complex)
            return
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -K
        A[n:, n:] = -C
        Lam, V = scipy.linalg.eig(A)
        if np.any(Lam.real > 1e-9 * np.max(np.abs(Lam))):
            raise ParameterError("the coupled contact system is unstable (an eigenvalue has Re > 0)")
        cond = np.linalg.cond(V)
        if not np.isfinite(cond) or cond > 1e10:
            raise ParameterError(f"the contact system's eigenvectors are ill-conditioned (cond {cond:.2e}); "
                                 "a repeated eigenvalue, e.g. critical damping, is not supported")
        self.Lam = np.minimum(Lam.real, 0.0) + 1j * Lam.imag
        self.V = V
        self.Vinv = np.linalg.inv(V)
        pc = np.linalg.solve(K, f0)
        self.zc = np.concatenate([pc, np.zeros(n)])
        P = np.linalg.solve(K - Omega**2 * np.eye(n) + 1j * Omega * C, phi.astype(complex))
        self.Z = np.concatenate([P, 1j * Omega * P])

    def start(self, z0: np.ndarray, theta0: float) -> tuple[np.ndarray, np.ndarray]:
        """``(gamma, Zt)``: modal coefficients of the homogeneous start and the phased harmonic part."""
        if self.n == 0:
            return np.zeros(0, dtype=complex), np.zeros(0, dtype=complex)
        Zt = self.Z * np.exp(1j * theta0)
        zh = z0 - self.zc - Zt.real
        gamma = _mv(self.Vinv, zh.astype(complex))
        return gamma, Zt

    def state(self, gamma: np.ndarray, Zt: np.ndarray, s: np.ndarray | float) -> np.ndarray:
        """``z = (p, p')`` at local times ``s``: shape (2n,) or (2n, n_s)."""
        s_arr = np.asarray(s, dtype=float)
        if s_arr.ndim == 0:
            zh = _mv(self.V, gamma * _decay(self.Lam * float(s_arr))).real
            return zh + self.zc + (Zt * np.exp(1j * self.Omega * float(s_arr))).real
        zh = _mv(self.V, gamma[:, None] * _decay(np.outer(self.Lam, s_arr))).real
        return zh + self.zc[:, None] + (Zt[:, None] * np.exp(1j * self.Omega * s_arr)[None, :]).real

    def functional(self, gamma: np.ndarray, Zt: np.ndarray, w: np.ndarray, c0: float,
                   w_forcing: complex = 0.0) -> tuple[np.ndarray, np.ndarray, float]:
        """Exponential sum of ``w . z + c0 + Re(w_forcing e^{i Omega s})`` (``w_forcing`` already phased)."""
        a = _mv(self.V.T, w.astype(complex)) * gamma if self.n else np.zeros(0, dtype=complex)
        harm = (np.dot(w, Zt) if self.n else 0.0) + w_forcing
        a = np.concatenate([a, [harm]])
        lam = np.concatenate([self.Lam, [1j * self.Omega]])
        return a, lam, float(c0 + (np.dot(w, self.zc) if self.n else 0.0))


class AffineFlow(LinearFlow):
    """Exact flow of the first-order system ``z' = A z + f0 + phi cos(theta)`` (any size m).

    Used where the state is not ``(p, p')`` alone: the modes plus the omitted modes'
    local deflection ``r`` (Kelvin-Voigt contact with the contact-point element).
    """

    def __init__(self, A: np.ndarray, f0: np.ndarray, phi: np.ndarray, Omega: float) -> None:
        m = A.shape[0]
        self.n = m
        self.Omega = Omega
        Lam, V = scipy.linalg.eig(A)
        if np.any(Lam.real > 1e-9 * np.max(np.abs(Lam))):
            raise ParameterError("the coupled contact system is unstable (an eigenvalue has Re > 0)")
        cond = np.linalg.cond(V)
        if not np.isfinite(cond) or cond > 1e10:
            raise ParameterError(f"the contact system's eigenvectors are ill-conditioned (cond {cond:.2e}); "
                                 "a repeated eigenvalue, e.g. critical damping, is not supported")
        self.Lam = np.minimum(Lam.real, 0.0) + 1j * Lam.imag
        self.V = V
        self.Vinv = np.linalg.inv(V)
        self.zc = -np.linalg.solve(A, f0)
        self.Z = np.linalg.solve(1j * Omega * np.eye(m) - A, phi.astype(complex))
