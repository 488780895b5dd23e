"""Free flight between impacts: evaluation, rigorous bounds, maxima and first contact.

Between impacts the nondimensional SDF oscillator moves as (thesis eq. 3.2)::

    x(t) = x_p(t) + y(t),   x_p(t) = c cos(omega t) + s sin(omega t)

with ``t`` the time since the flight started, ``x_p`` the forced (particular)
response and ``y`` a free damped oscillation, ``y'' + 2 zeta y' + y = 0``,
started from ``(y0, yd0)``.  Everything here is vectorised over flights.

Bounds used to bracket events without sampling luck
----------------------------------------------------
The free energy ``E = y^2 + y'^2`` never increases (``dE/dt = -4 zeta y'^2``),
and ``y''  = -(2 zeta y' + y)`` gives, by Cauchy-Schwarz,
``|y''| <= sqrt(1 + 4 zeta^2) sqrt(E(0))``.  ``y'`` is itself a free
oscillation, so in the same way ``|y'''| <= sqrt(1 + 4 zeta^2) sqrt(y'(0)^2 +
y''(0)^2)``.  With ``R = sqrt(c^2 + s^2)`` the amplitude of ``x_p``::

    |x''(t)|  <= M2 = omega^2 R + sqrt(1 + 4 zeta^2) sqrt(y0^2 + yd0^2)
    |x'''(t)| <= M3 = omega^3 R + sqrt(1 + 4 zeta^2) sqrt(yd0^2 + ydd0^2)

for every ``t >= 0`` (all ``zeta >= 0``, under- or over-damped).  On a cell
``[t_i, t_i + h]``:

* ``v`` has no zero if ``v_i``, ``v_{i+1}`` have one sign and
  ``|v_i| + |v_{i+1}| > M2 h`` (reaching zero and coming back needs that much);
* ``v`` is strictly monotone (at most one zero) if ``a_i``, ``a_{i+1}`` have one
  sign and ``|a_i| + |a_{i+1}| > M3 h``;
* ``x <= max(x_i, x_{i+1}, x_i + v_i s* + M2 s*^2 / 2)``, where ``s*`` is where
  the two Taylor upper bounds from the cell's ends meet (their difference is
  linear in ``s``), a bound within ``O(M2 h^2)`` of the true maximum.

Cells that none of these settles are split, so no local maximum and no contact
is missed for want of a fine enough grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab.model.sdf import homogeneous_transition, particular_coeffs

#: Grid cells per ``min(2 pi / omega, 2 pi)`` (the faster of forcing and free oscillation).
CELLS_PER_CYCLE = 16
#: How many times an undecided cell is split (by 8) before it is settled conservatively.
MAX_SPLITS = 10


@dataclass(frozen=True)
class Flights:
    """Coefficients of a batch of free flights (arrays of one shape; nondimensional).

    Attributes
    ----------
    omega, zeta : ndarray
        Forcing frequency and damping ratio.
    c, s : ndarray
        ``x_p(t) = c cos(omega t) + s sin(omega t)``; ``t`` counts from the flight's start.
    y0, yd0 : ndarray
        Free (homogeneous) part ``y = x - x_p`` and its rate at ``t = 0``.
    """

    omega: np.ndarray
    zeta: np.ndarray
    c: np.ndarray
    s: np.ndarray
    y0: np.ndarray
    yd0: np.ndarray

    def take(self, idx: np.ndarray) -> Flights:
        """The flights at indices ``idx`` of the flattened batch."""
        return Flights(*(np.ravel(getattr(self, f))[idx] for f in
                         ("omega", "zeta", "c", "s", "y0", "yd0")))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(M2, M3)``: bounds of ``|x''|`` and ``|x'''|`` over the whole flight."""
        k = np.sqrt(1.0 + 4.0 * self.zeta ** 2)
        amp = np.hypot(self.c, self.s)
        ydd0 = -2.0 * self.zeta * self.yd0 - self.y0
        m2 = self.omega ** 2 * amp + k * np.hypot(self.y0, self.yd0)
        m3 = self.omega ** 3 * amp + k * np.hypot(self.yd0, ydd0)
        return m2, m3


def flights(omega: ArrayLike, zeta: ArrayLike, c: ArrayLike, s: ArrayLike,
            y0: ArrayLike, yd0: ArrayLike) -> Flights:
    """Broadcast flight coefficients to one shape."""
    arrays = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (omega, zeta, c, s, y0, yd0)))
    return Flights(*(np.array(a) for a in arrays))


def flights_from_state(F: ArrayLike, omega: ArrayLike, zeta: ArrayLike, theta0: ArrayLike,
                       x0: ArrayLike, v0: ArrayLike) -> Flights:
    """Flights starting from ``(x0, v0)`` at forcing phase ``theta0``.

    The particular solution is ``A_c cos(theta) + A_s sin(theta)`` with
    ``theta = theta0 + omega t``; expanding gives ``c`` and ``s``.
    """
    A_c, A_s = particular_coeffs(F, omega, zeta)
    cos0, sin0 = np.cos(theta0), np.sin(theta0)
    c = A_c * cos0 + A_s * sin0
    s = A_s * cos0 - A_c * sin0
    w = np.asarray(omega, dtype=float)
    return flights(omega, zeta, c, s, np.asarray(x0, float) - c, np.asarray(v0, float) - w * s)


def evaluate(fl: Flights, t: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(x, v, a)`` at times ``t`` since the flight started (broadcast against the batch)."""
    t = np.asarray(t, dtype=float)
    w, z = fl.omega, fl.zeta
    cw, sw = np.cos(w * t), np.sin(w * t)
    xp = fl.c * cw + fl.s * sw
    vp = w * (fl.s * cw - fl.c * sw)
    Ec, Es = homogeneous_transition(z, t)
    y = (Ec + z * Es) * fl.y0 + Es * fl.yd0
    yd = -Es * fl.y0 + (Ec - z * Es) * fl.yd0
    ydd = -2.0 * z * yd - y
    return xp + y, vp + yd, -w * w * xp + ydd


def _cell_max_bound(x0: float, v0: float, x1: float, v1: float, h: float, m2: float) -> float:
    """Rigorous upper bound of ``x`` on a cell of width ``h`` from its end values (module docstring)."""
    denom = v0 - v1 + m2 * h
    s_star = (x1 - x0 - v1 * h + 0.5 * m2 * h * h) / denom if denom > 0.0 else 0.0
    s_star = min(max(s_star, 0.0), h)
    return max(x0, x1, x0 + v0 * s_star + 0.5 * m2 * s_star * s_star)


def _polish_maxima(fl: Flights, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Zero of ``v`` in ``[lo, hi]`` where ``v(lo) > 0 >= v(hi)`` (safeguarded Newton)."""
    t = 0.5 * (lo + hi)
    for _ in range(60):
        _, v, a = evaluate(fl, t)
        pos = v > 0.0
        lo = np.where(pos, t, lo)
        hi = np.where(pos, hi, t)
        with np.errstate(divide="ignore", invalid="ignore"):
            newton = t - v / a
        ok = np.isfinite(newton) & (newton > lo) & (newton < hi)
        t_new = np.where(ok, newton, 0.5 * (lo + hi))
        done = np.all(np.abs(t_new - t) <= 4e-16 * np.maximum(1.0, np.abs(t)))
        t = t_new
        if done:
            break
    return t


def interior_maxima(fl: Flights, T: ArrayLike, *, chunk: int = 2048) -> tuple[np.ndarray, np.ndarray]:
    """Highest interior local maximum of ``x`` on ``(0, T)`` for each flight.

    Local maxima are the zeros of ``v`` where it goes from positive to
    negative; they are bracketed on a grid whose cells are certified (module
    docstring) to hold no zero of ``v`` or exactly one, splitting undecided
    cells, then polished by safeguarded Newton.  A cell still undecided after
    :data:`MAX_SPLITS` splits (width ``< h 8**-10``; only at a degenerate
    critical point of ``x``) contributes its larger end value, which is within
    ``width * (|v| + M2 width)`` of its supremum.

    Parameters
    ----------
    fl : Flights
        The flights (any shape; flattened internally).
    T : array_like
        Flight durations, broadcast to the batch.

    Returns
    -------
    x_max, t_max : ndarray
        The highest local maximum and its time; ``-inf`` and NaN where ``x``
        has no interior local maximum.
    """
    shape = np.broadcast(fl.omega, np.asarray(T)).shape
    T = np.broadcast_to(np.asarray(T, dtype=float), shape).ravel()
    flat = fl.take(np.arange(int(np.prod(shape))))
    x_max = np.full(T.size, -np.inf)
    t_max = np.full(T.size, np.nan)
    for start in range(0, T.size, chunk):
        sl = slice(start, min(start + chunk, T.size))
        xm, tm = _interior_maxima_flat(flat.take(np.arange(sl.start, sl.stop)), T[sl])
        x_max[sl], t_max[sl] = xm, tm
    return x_max.reshape(shape), t_max.reshape(shape)


def _interior_maxima_flat(fl: Flights, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    nb = T.size
    x_max = np.full(nb, -np.inf)
    t_max = np.full(nb, np.nan)
    if nb == 0:
        return x_max, t_max
    m2, m3 = fl.bounds()
    cycle = np.minimum(2.0 * np.pi / fl.omega, 2.0 * np.pi)
    n_cells = int(np.ceil(np.nanmax(T / cycle) * CELLS_PER_CYCLE))
    n_cells = max(n_cells, 4)
    h = T / n_cells
    t = h[:, None] * np.arange(n_cells + 1)[None, :]
    x, v, a = evaluate(Flights(*(getattr(fl, f)[:, None] for f in
                                 ("omega", "zeta", "c", "s", "y0", "yd0"))), t)
    # Cells as flat arrays: owner, left time, width, end values.
    owner = np.repeat(np.arange(nb), n_cells)
    tl = t[:, :-1].ravel()
    hh = np.repeat(h, n_cells)
    xl, xr = x[:, :-1].ravel(), x[:, 1:].ravel()
    vl, vr = v[:, :-1].ravel(), v[:, 1:].ravel()
    al, ar = a[:, :-1].ravel(), a[:, 1:].ravel()
    bracket_owner: list[np.ndarray] = []
    bracket_lo: list[np.ndarray] = []
    bracket_hi: list[np.ndarray] = []
    for depth in range(MAX_SPLITS + 1):
        M2, M3 = m2[owner], m3[owner]
        no_zero = (vl * vr > 0.0) & (np.abs(vl) + np.abs(vr) > M2 * hh)
        monotone = (al * ar > 0.0) & (np.abs(al) + np.abs(ar) > M3 * hh)
        one_max = monotone & (vl > 0.0) & (vr <= 0.0)
        settled = no_zero | monotone
        bracket_owner.append(owner[one_max])
        bracket_lo.append(tl[one_max])
        bracket_hi.append(tl[one_max] + hh[one_max])
        keep = ~settled
        if not np.any(keep):
            break
        if depth == MAX_SPLITS:
            # Degenerate critical points only: take the larger end value (see docstring).
            o = owner[keep]
            cand = np.maximum(xl[keep], xr[keep])
            tc = np.where(xl[keep] >= xr[keep], tl[keep], tl[keep] + hh[keep])
            _update_max(x_max, t_max, o, cand, tc)
            break
        # Split the undecided cells in 8.
        owner, tl0, h0 = owner[keep], tl[keep], hh[keep]
        k = np.arange(9)[None, :]
        tt = tl0[:, None] + (h0[:, None] / 8.0) * k
        sub = fl.take(owner)
        xs, vs, as_ = evaluate(Flights(*(getattr(sub, f)[:, None] for f in
                                         ("omega", "zeta", "c", "s", "y0", "yd0"))), tt)
        owner = np.repeat(owner, 8)
        tl = tt[:, :-1].ravel()
        hh = np.repeat(h0 / 8.0, 8)
        xl, xr = xs[:, :-1].ravel(), xs[:, 1:].ravel()
        vl, vr = vs[:, :-1].ravel(), vs[:, 1:].ravel()
        al, ar = as_[:, :-1].ravel(), as_[:, 1:].ravel()
    bo = np.concatenate(bracket_owner)
    if bo.size:
        lo = np.concatenate(bracket_lo)
        hi = np.concatenate(bracket_hi)
        sub = fl.take(bo)
        tr = _polish_maxima(sub, lo, hi)
        xr_, _, _ = evaluate(sub, tr)
        _update_max(x_max, t_max, bo, xr_, tr)
    return x_max, t_max


def _update_max(x_max: np.ndarray, t_max: np.ndarray, owner: np.ndarray,
                cand: np.ndarray, tc: np.ndarray) -> None:
    """``x_max[owner] = max(x_max[owner], cand)`` with ``t_max`` following, for repeated owners."""
    if owner.size == 0:
        return
    order = np.lexsort((cand, owner))  # by owner, then ascending value: last one wins
    owner, cand, tc = owner[order], cand[order], tc[order]
    last = np.r_[owner[1:] != owner[:-1], True]
    o, c, t = owner[last], cand[last], tc[last]
    better = c > x_max[o]
    x_max[o[better]] = c[better]
    t_max[o[better]] = t[better]


def first_contact(fl: Flights, t_start: float, t_end: float) -> float | None:
    """First time in ``(t_start, t_end]`` where ``x`` reaches 1, for one flight.

    ``x(t_start) < 1`` is required.  Cells are certified contact-free by the
    upper bound of the module docstring; a cell that reaches 1 at its right
    end and in which ``x`` is certified monotone holds exactly the first
    crossing, which is then polished by safeguarded Newton to machine
    precision.  Undecided cells are split in halves (depth-first, left first,
    so the earliest contact wins) down to a width of ``1e-13``; a cell still
    undecided there is a tangency that does not cross (clearance below
    ``M2 * 1e-26``) and is treated as no contact.

    Returns
    -------
    float or None
        The contact time, or None when there is none before ``t_end``.
    """
    m2 = float(fl.bounds()[0])
    w = float(fl.omega)
    cycle = min(2.0 * math.pi / w, 2.0 * math.pi)
    h = cycle / CELLS_PER_CYCLE
    per_chunk = 2 * CELLS_PER_CYCLE
    t0 = t_start
    while t0 < t_end:
        t1 = min(t0 + per_chunk * h, t_end)
        n = max(1, int(math.ceil((t1 - t0) / h - 1e-9)))
        grid = np.linspace(t0, t1, n + 1)
        x, v, _ = evaluate(fl, grid)
        for i in range(n):
            hit = _cell_contact(fl, float(grid[i]), float(grid[i + 1]), float(x[i]), float(v[i]),
                                float(x[i + 1]), float(v[i + 1]), m2)
            if hit is not None:
                return hit
        t0 = t1
    return None


def _cell_contact(fl: Flights, ta: float, tb: float, xa: float, va: float, xb: float, vb: float,
                  m2: float) -> float | None:
    stack = [(ta, tb, xa, va, xb, vb)]
    while stack:
        ta, tb, xa, va, xb, vb = stack.pop()
        h = tb - ta
        if xb < 1.0:
            if _cell_max_bound(xa, va, xb, vb, h, m2) < 1.0:
                continue
        else:
            # x reaches 1 at the right end; if x is monotone here, the crossing is unique.
            if va * vb > 0.0 and abs(va) + abs(vb) > m2 * h:
                return _polish_contact(fl, ta, tb)
        if h < 1e-13:
            if xb >= 1.0:
                return tb
            continue
        tm = 0.5 * (ta + tb)
        xm, vm, _ = (float(q) for q in evaluate(fl, tm))
        stack.append((tm, tb, xm, vm, xb, vb))  # right half popped last
        stack.append((ta, tm, xa, va, xm, vm))
    return None


def _polish_contact(fl: Flights, lo: float, hi: float) -> float:
    """Root of ``x - 1`` in ``[lo, hi]`` with ``x(lo) < 1 <= x(hi)``, x monotone."""
    t = 0.5 * (lo + hi)
    for _ in range(100):
        x, v, _ = (float(q) for q in evaluate(fl, t))
        if x < 1.0:
            lo = t
        else:
            hi = t
        newton = t - (x - 1.0) / v if v != 0.0 else math.nan
        t_new = newton if lo < newton < hi else 0.5 * (lo + hi)
        if abs(t_new - t) <= 2e-16 * max(1.0, abs(t)):
            return t_new
        t = t_new
    return t
