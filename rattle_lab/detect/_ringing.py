"""The plate's higher modes in the vibrometer, found flight by flight and taken off.

Each impact excites the plate's higher modes as well as the fundamental; a vibrometer near
the contact sees them ring, on top of the fundamental, for as long as their damping lets
them (a mode with 2 % damping at 170 Hz rings for some 50 ms, five forcing periods).  The
velocity fits either side of an impact (:func:`~rattle_lab.detect._impacts.jump_velocities`)
then read the higher modes' velocity jump with the fundamental's, and ``e`` from their
ratio is that of the contact point, not of the mode the model describes (on the
independent generator of ``tests/independent_campaign.py``, whose modes take 22 % of each
jump, ``e`` came out 1.07 for 0.55).

Between two impacts, every mode moves freely: the fundamental as the local solution of a
mode forced near its resonance (:class:`~rattle_lab.detect._impacts._LocalFit`'s basis,
with an envelope of degree 2 over the flight), each higher mode as a damped sinusoid
``exp(-s tau) (b cos w tau + c sin w tau)`` with its own amplitude in each flight (what the
last impact gave it plus what is left of the earlier ones), at poles ``(w, s)`` that every
flight shares.  The poles are found by variable projection on the flights of the run
(the amplitudes eliminated exactly in each flight): a scan over frequency and damping,
Nelder-Mead on the new pole, one pole at a time while the Bayesian information criterion
falls.  Then every flight's modes are fitted, extrapolated across its contacts and taken
off the velocity, and the impacts' velocities are fitted again on what is left.

Only poles above :data:`MIN_RATIO` times the excitation frequency are searched: nearer
ones trade off against the fundamental's own free response within a flight.  The flight
model (:mod:`rattle_lab.detect._flights`) measures what such a mode adds to each jump.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

#: Lowest pole searched, times the excitation frequency.
MIN_RATIO = 1.3
#: Highest pole searched, times the excitation frequency (and below 0.4 of the sample rate).
MAX_RATIO = 30.0
#: Most poles taken off.
MAX_POLES = 4
#: Fewest samples of a flight's window.
MIN_FLIGHT_SAMPLES = 24
#: Fewest flights for a search.
MIN_FLIGHTS = 6
#: Flights the searches use (spread over the run); the last fit uses all.
SEARCH_FLIGHTS = 24
#: Flights of the first, cheap scan that decides whether anything rings.
SCAN_FLIGHTS = 12
#: Least relative fall of the residual, in that first scan, that counts as ringing.
MIN_SCAN_GAIN = 0.1
#: Damping ratios of the scan's poles.
SCAN_ZETA = (0.004, 0.02, 0.1)


@dataclass(frozen=True)
class Ringing:
    """Result of :func:`find_ringing`.

    Attributes
    ----------
    signal : ndarray
        The higher modes' velocity, m/s (zeros where nothing was found).
    poles : tuple of (f_hz, s_1_s)
        Their frequencies and decay rates.
    note : str
        What was done (empty when nothing rings).
    """

    signal: np.ndarray
    poles: tuple[tuple[float, float], ...] = ()
    note: str = ""


class _Flights:
    """Velocity samples between impacts; per flight: the fundamental's basis and the poles'."""

    def __init__(self, v: np.ndarray, fs_hz: float, f_hz: float, lo: np.ndarray,
                 hi: np.ndarray, ref: np.ndarray):
        lens = hi - lo + 1
        self.k = np.concatenate([np.arange(a, b + 1) for a, b in zip(lo, hi)])
        self.seg = np.repeat(np.arange(lo.size), lens)
        self.starts = np.concatenate([[0], np.cumsum(lens)[:-1]])
        self.tau = (self.k - ref[self.seg]) / fs_hz
        self.y = v[self.k]
        mid = 0.5 * (lo + hi)[self.seg]
        half = np.maximum(0.5 * (hi - lo), 1.0)[self.seg]
        u = (self.k - mid) / half
        w = 2.0 * np.pi * f_hz * self.tau
        c, s = np.cos(w), np.sin(w)
        self.z = np.column_stack([np.ones_like(u), c, s, u * c, u * s, u * u * c, u * u * s])
        # the fundamental's basis is eliminated once: each flight's projector onto its span
        gz = np.add.reduceat(self.z[:, :, None] * self.z[:, None, :], self.starts, axis=0)
        gz = gz + 1e-10 * np.trace(gz, axis1=1, axis2=2)[:, None, None] * np.eye(7)
        self.gz_inv = np.linalg.inv(gz)
        self.yp = self.project(self.y[:, None])[:, 0]
        self.yy = np.add.reduceat(self.yp * self.yp, self.starts)
        self.n = self.k.size
        self.n_flights = lo.size

    def project(self, x: np.ndarray) -> np.ndarray:
        """``x`` less its least-squares fit on each flight's fundamental basis."""
        zx = np.add.reduceat(self.z[:, :, None] * x[:, None, :], self.starts, axis=0)
        g = np.einsum("fpq,fqr->fpr", self.gz_inv, zx)
        return x - np.einsum("np,npr->nr", self.z, g[self.seg])

    def poles_columns(self, poles: list[tuple[float, float]]) -> np.ndarray:
        cols = []
        for f_hz, s in poles:
            env = np.exp(-s * self.tau)
            w = 2.0 * np.pi * f_hz * self.tau
            cols += [env * np.cos(w), env * np.sin(w)]
        return np.column_stack(cols)

    def solve(self, poles: list[tuple[float, float]]) -> tuple[float, np.ndarray]:
        """``(rss, amp)``: each flight's least squares on its basis and the poles' columns;
        ``amp`` the poles' amplitudes (flights x 2 per pole)."""
        if not poles:
            return float(np.sum(self.yy)), np.zeros((self.n_flights, 0))
        x = self.project(self.poles_columns(poles))
        p = x.shape[1]
        g = np.add.reduceat(x[:, :, None] * x[:, None, :], self.starts, axis=0)
        b = np.add.reduceat(x * self.yp[:, None], self.starts, axis=0)
        g = g + 1e-10 * np.trace(g, axis1=1, axis2=2)[:, None, None] * np.eye(p) \
            + 1e-300 * np.eye(p)
        amp = np.linalg.solve(g, b[:, :, None])[:, :, 0]
        rss = float(np.sum(np.maximum(self.yy - np.einsum("fp,fp->f", b, amp), 0.0)))
        return rss, amp


def _windows(n: int, k_imp: np.ndarray, pad: np.ndarray, max_len: int
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each impact's flight: from ``pad`` after it to ``pad`` before the next (``max_len`` at most)."""
    lo = np.ceil(k_imp + pad).astype(int)
    nxt = np.r_[np.floor(k_imp[1:] - pad[1:]), n - 1].astype(int)
    hi = np.minimum(np.minimum(nxt, lo + max_len - 1), n - 1)
    ok = hi - lo + 1 >= MIN_FLIGHT_SAMPLES
    return lo[ok], hi[ok], np.flatnonzero(ok)


def _pick(n: int, m: int) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(n, m)).round().astype(int))


def _search(fl: _Flights, f_lo: float, f_hi: float, s_max: float
            ) -> tuple[list[tuple[float, float]], float]:
    """Poles by variable projection, one at a time while the BIC falls; ``(poles, rss0)``."""
    rss0 = fl.solve([])[0]
    poles: list[tuple[float, float]] = []
    bic = fl.n * np.log(rss0)
    grid = np.geomspace(f_lo, f_hi, 48)
    for _ in range(MAX_POLES):
        scan = [(fl.solve(poles + [(f, z * 2 * np.pi * f)])[0], f, z * 2 * np.pi * f)
                for f in grid for z in SCAN_ZETA if z * 2 * np.pi * f <= s_max]
        _, f0, s0 = min(scan)

        def obj(p: np.ndarray, fixed: list[tuple[float, float]] = poles) -> float:
            f, s = float(p[0]), float(np.exp(p[1]))
            if not (f_lo <= f <= f_hi and 0.0 < s <= s_max):
                return np.inf
            return fl.solve(fixed + [(f, s)])[0]

        sol = minimize(obj, np.array([f0, np.log(s0)]), method="Nelder-Mead",
                       options={"maxfev": 60, "xatol": 1e-3, "fatol": 0.0,
                                "initial_simplex": [[f0, np.log(s0)], [f0 * 1.02, np.log(s0)],
                                                    [f0, np.log(s0) + 0.5]]})
        trial = poles + [(float(sol.x[0]), float(np.exp(sol.x[1])))]
        rss = float(sol.fun)
        # every flight's two amplitudes and the pole's two numbers are parameters
        bic_new = fl.n * np.log(rss) + (2 * fl.n_flights + 2) * len(trial) * np.log(fl.n)
        f_new, s_new = trial[-1]
        if (not bic_new < bic or any(abs(f_new / p[0] - 1) < 0.03 for p in poles)
                or f_new < 1.02 * f_lo or f_new > 0.98 * f_hi or s_new > 0.9 * s_max):
            break   # no gain, a pole found twice, or one on a bound of the search: unresolved
        poles, bic = trial, bic_new
    return poles, rss0


def find_ringing(v: np.ndarray, fs_hz: float, f_hz: float, k_imp: np.ndarray,
                 pad: np.ndarray) -> Ringing:
    """The higher modes' velocity in ``v`` between the impacts (see the module docstring).

    Parameters
    ----------
    v : ndarray
        The velocity channel, m/s.
    fs_hz, f_hz : float
        Sample rate and the (constant) excitation frequency, Hz.
    k_imp : ndarray
        Impact times, sample units (sorted).
    pad : ndarray
        Samples left out on each side of each impact (its contact and the band limit).

    Returns
    -------
    Ringing
        ``signal`` is zero everywhere when fewer than :data:`MIN_FLIGHTS` flights are
        long enough or the first scan finds nothing (``note`` says which).
    """
    v = np.asarray(v, dtype=float)
    zero = np.zeros(v.size)
    k_imp = np.asarray(k_imp, dtype=float)
    if k_imp.size < MIN_FLIGHTS:
        return Ringing(zero)
    period = fs_hz / f_hz
    lo, hi, imp = _windows(v.size, k_imp, np.asarray(pad, dtype=float), int(round(1.2 * period)))
    if lo.size < MIN_FLIGHTS:
        return Ringing(zero)
    f_lo, f_hi = MIN_RATIO * f_hz, min(MAX_RATIO * f_hz, 0.4 * fs_hz)
    if not f_hi > f_lo:
        return Ringing(zero)
    s_max = 0.25 * fs_hz

    def flights(sel: np.ndarray) -> _Flights:
        return _Flights(v, fs_hz, f_hz, lo[sel], hi[sel], k_imp[imp[sel]])

    # a cheap first look: does any pole take a tenth of the residual of a few flights?
    few = flights(_pick(lo.size, SCAN_FLIGHTS))
    rss0 = few.solve([])[0]
    best = min(few.solve([(f, z * 2 * np.pi * f)])[0]
               for f in np.geomspace(f_lo, f_hi, 32) for z in SCAN_ZETA[:2])
    if not best < (1.0 - MIN_SCAN_GAIN) * rss0:
        return Ringing(zero)
    poles, _ = _search(flights(_pick(lo.size, SEARCH_FLIGHTS)), f_lo, f_hi, s_max)
    if not poles:
        return Ringing(zero)
    every = flights(np.arange(lo.size))
    _, amp = every.solve(poles)
    # each flight's modes from its impact to the next impact's time, across both contacts
    signal = zero.copy()
    nxt = np.r_[k_imp[1:], np.inf]
    for f_i, i in enumerate(imp):
        a = int(np.ceil(k_imp[i]))
        b = int(min(np.floor(nxt[i]), hi[f_i] + period, v.size - 1))
        if b < a:
            continue
        tau = (np.arange(a, b + 1) - k_imp[i]) / fs_hz
        for j, (f_j, s_j) in enumerate(poles):
            env = np.exp(-s_j * tau)
            w = 2.0 * np.pi * f_j * tau
            signal[a:b + 1] += env * (amp[f_i, 2 * j] * np.cos(w) + amp[f_i, 2 * j + 1] * np.sin(w))
    return Ringing(signal, tuple(poles), "higher modes taken off the velocity: "
                   + ", ".join(f"{f:.0f} Hz (damping {s / (2 * np.pi * f):.3f})" for f, s in poles))


__all__ = ["Ringing", "find_ringing"]
