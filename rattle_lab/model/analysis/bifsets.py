"""Bifurcation sets of the 1/n orbits in the (omega, F) plane (thesis 3.3, Fig. 3-7, 3-9, 3-10).

For each ``n`` the 1/n orbits form a two-parameter family, fixed by the
frequency ``omega`` and the impact velocity ``v = v_im`` alone; the forcing
that carries an orbit is explicit, ``F(omega, v) = sqrt(D) hypot(1 - p1 v, q v)``
(see :mod:`rattle_lab.model.analysis._one_over_n`).  The boundaries of the regions
where the orbits exist and are stable are therefore traced as zero curves in
the ``(omega, v)`` plane and mapped to ``(omega, F)``:

``grazing``
    ``v = 0``: the orbit is born from the impact-free response, on
    ``F = sqrt(D)`` (eq. 3.4); kept where the orbits with small ``v > 0`` exist.
``saddle-node``
    the two roots of eq. (3.5) merge, ``F_sn(omega)`` explicitly (eq. 3.11),
    where ``v_sn > 0`` and that orbit exists; a multiplier is +1 there.
``period-doubling``
    ``1 + tr + det = 0`` (a multiplier -1), where the orbit exists.
``secondary-grazing``
    an interior maximum of ``x`` touches the stop (zero clearance).

Zero curves are found by marching squares (contourpy) on a grid in
``(omega, s)`` with ``v = s v_top(omega)`` (``v_top``: the impact velocity at
the largest ``F`` of the domain), and every vertex is then refined by
bisection along its grid edge to ``2**-32`` of the edge, so the curves are
exact to far better than plotting accuracy.  Regions are additionally
evaluated pixel by pixel on an ``(omega, F)`` grid for filling.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, cast

import numpy as np

from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError

from . import _one_over_n as _on
from ._dask import check_execution, run_chunks

BoundaryKind = Literal["grazing", "saddle-node", "period-doubling", "secondary-grazing"]
KINDS: tuple[BoundaryKind, ...] = ("grazing", "saddle-node", "period-doubling", "secondary-grazing")

__all__ = ["BoundaryCurve", "BifurcationSets", "bifurcation_sets"]


@dataclass(frozen=True)
class BoundaryCurve:
    """One boundary curve of the 1/n regions (nondimensional).

    Attributes
    ----------
    n : int
        Orbit type 1/n (0 for the overall grazing curve, eq. 3.4).
    kind : {"grazing", "saddle-node", "period-doubling", "secondary-grazing"}
        The boundary condition (see the module docstring).
    omega, F : ndarray
        The curve, ordered along it.
    v_im : ndarray
        Impact velocity of the orbit on the curve.
    """

    n: int
    kind: BoundaryKind
    omega: np.ndarray
    F: np.ndarray
    v_im: np.ndarray

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary."""
        return {"n": self.n, "kind": self.kind, "omega": self.omega.tolist(),
                "F": self.F.tolist(), "v_im": self.v_im.tolist()}


@dataclass(frozen=True)
class BifurcationSets:
    """Regions of existence and stability of 1/n orbits and their boundary curves.

    Attributes
    ----------
    ns : tuple of int
        The orbit types computed.
    zeta, e : float
        Damping ratio and coefficient of restitution.
    omega : ndarray, shape (n_omega,)
        Frequency grid of the region arrays (nondimensional).
    F : ndarray, shape (n_F,)
        Forcing-amplitude grid of the region arrays (nondimensional).
    exists : ndarray of bool, shape (len(ns), n_F, n_omega)
        Some 1/n orbit exists (``v_im > 0``, no intermediate contact).
    stable : ndarray of bool, shape (len(ns), n_F, n_omega)
        Some existing 1/n orbit is stable (multipliers inside the unit circle).
    curves : tuple of BoundaryCurve
        Traced boundaries, per ``n`` and kind, each a connected piece.
    grazing : BoundaryCurve
        Eq. (3.4) over the whole frequency range (``n = 0``).
    provenance : dict
        What made this: package version, function and arguments.
    """

    ns: tuple[int, ...]
    zeta: float
    e: float
    omega: np.ndarray
    F: np.ndarray
    exists: np.ndarray
    stable: np.ndarray
    curves: tuple[BoundaryCurve, ...]
    grazing: BoundaryCurve
    provenance: dict[str, object] = field(default_factory=dict)

    def curves_of(self, n: int, kind: BoundaryKind | None = None) -> tuple[BoundaryCurve, ...]:
        """The curves of orbit type 1/n, optionally of one kind."""
        return tuple(c for c in self.curves if c.n == n and (kind is None or c.kind == kind))

    def to_dict(self, *, include_regions: bool = False) -> dict[str, object]:
        """JSON-ready dictionary; the region grids only on request (they are large)."""
        out: dict[str, object] = {
            "ns": list(self.ns), "zeta": self.zeta, "e": self.e,
            "omega_range": [float(self.omega[0]), float(self.omega[-1])],
            "F_range": [float(self.F[0]), float(self.F[-1])],
            "grid": {"n_omega": int(self.omega.size), "n_F": int(self.F.size)},
            "area_fraction": {str(n): {"exists": float(self.exists[i].mean()),
                                       "stable": float(self.stable[i].mean())}
                              for i, n in enumerate(self.ns)},
            "grazing": self.grazing.to_dict(),
            "curves": [c.to_dict() for c in self.curves],
            "provenance": self.provenance,
        }
        if include_regions:
            out["omega"] = self.omega.tolist()
            out["F"] = self.F.tolist()
            out["exists"] = self.exists.astype(int).tolist()
            out["stable"] = self.stable.astype(int).tolist()
        return out


# ---------------------------------------------------------------------------
# Computation
# ---------------------------------------------------------------------------

def _validate(ns: Sequence[int], omega_range: tuple[float, float], F_range: tuple[float, float],
              zeta: float, e: float, n_omega: int, n_F: int, n_v: int) -> tuple[int, ...]:
    ns_t = tuple(ns)
    if not ns_t:
        raise ParameterError("`ns` must name at least one n, was empty")
    for n in ns_t:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ParameterError(f"`ns` must hold integers >= 1, was {n!r}")
    w0, w1 = (float(x) for x in omega_range)
    if not (math.isfinite(w0) and math.isfinite(w1) and 0.0 < w0 < w1):
        raise ParameterError(f"`omega_range` must satisfy 0 < lo < hi, was {omega_range}")
    f0, f1 = (float(x) for x in F_range)
    if not (math.isfinite(f0) and math.isfinite(f1) and 0.0 <= f0 < f1):
        raise ParameterError(f"`F_range` must satisfy 0 <= lo < hi, was {F_range}")
    if not (math.isfinite(zeta) and zeta > 0.0):
        raise ParameterError(f"`zeta` must be > 0 for bifurcation sets, was {zeta}")
    if not (math.isfinite(e) and 0.0 < e <= 1.0):
        raise ParameterError(f"`e` must be in (0, 1], was {e}")
    for name, val in (("n_omega", n_omega), ("n_F", n_F), ("n_v", n_v)):
        if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or val < 8:
            raise ParameterError(f"`{name}` must be an integer >= 8, was {val!r}")
    return tuple(int(n) for n in ns_t)


def _regions(n: int, omega: np.ndarray, F: np.ndarray, zeta: float, e: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """``exists`` and ``stable`` of the 1/n orbits on the ``(F, omega)`` grid."""
    fam = _on.family(n, omega[None, :], zeta, e)
    lo, hi = _on.roots(fam, F[:, None])
    exists = np.zeros(lo.shape, dtype=bool)
    stable = np.zeros(lo.shape, dtype=bool)
    for v in (lo, hi):
        vv = np.where(v > 0.0, v, np.nan)
        clear, _ = _on.clearance(fam, vv)
        tr, det = _on.trace_det(fam, vv)
        ex = clear > 0.0  # NaN compares False
        st = ex & (1.0 - tr + det > 0.0) & (1.0 + tr + det > 0.0)
        exists |= ex
        stable |= st
    return exists, stable


def _edge_refine(func: Callable[[np.ndarray, np.ndarray], np.ndarray], line: np.ndarray,
                 wg: np.ndarray, sg: np.ndarray, Z: np.ndarray) -> np.ndarray:
    """Move each contour vertex onto the exact zero of ``func`` along its grid edge."""
    w, s = line[:, 0].copy(), line[:, 1].copy()
    i = np.clip(np.searchsorted(wg, w, side="right") - 1, 0, wg.size - 2)
    j = np.clip(np.searchsorted(sg, s, side="right") - 1, 0, sg.size - 2)
    tol_w = 1e-9 * (wg[-1] - wg[0])
    tol_s = 1e-9 * (sg[-1] - sg[0])
    on_w_node = np.isclose(w, wg[i], rtol=0, atol=tol_w) | np.isclose(w, wg[i + 1], rtol=0, atol=tol_w)
    on_s_node = np.isclose(s, sg[j], rtol=0, atol=tol_s) | np.isclose(s, sg[j + 1], rtol=0, atol=tol_s)
    # Vertical edge (fixed omega, s varies) or horizontal edge (fixed s, omega varies).
    iw = np.where(np.isclose(w, wg[i + 1], rtol=0, atol=tol_w), i + 1, i)
    js = np.where(np.isclose(s, sg[j + 1], rtol=0, atol=tol_s), j + 1, j)
    vertical = on_w_node & ~on_s_node
    horizontal = on_s_node & ~on_w_node
    w0 = np.where(vertical, wg[iw], np.where(horizontal, wg[i], w))
    w1 = np.where(vertical, wg[iw], np.where(horizontal, wg[i + 1], w))
    s0 = np.where(vertical, sg[j], np.where(horizontal, sg[js], s))
    s1 = np.where(vertical, sg[j + 1], np.where(horizontal, sg[js], s))
    z0 = np.where(vertical, Z[j, iw], np.where(horizontal, Z[js, i], np.nan))
    z1 = np.where(vertical, Z[j + 1, iw], np.where(horizontal, Z[js, i + 1], np.nan))
    todo = (vertical | horizontal) & (np.sign(z0) * np.sign(z1) < 0)
    if not np.any(todo):
        return line
    a, b = np.zeros(todo.sum()), np.ones(todo.sum())
    w0t, w1t, s0t, s1t, z0t = w0[todo], w1[todo], s0[todo], s1[todo], z0[todo]
    for _ in range(32):
        m = 0.5 * (a + b)
        fm = func(w0t + m * (w1t - w0t), s0t + m * (s1t - s0t))
        same = np.sign(fm) == np.sign(z0t)
        a = np.where(same, m, a)
        b = np.where(same, b, m)
    m = 0.5 * (a + b)
    w[todo] = w0t + m * (w1t - w0t)
    s[todo] = s0t + m * (s1t - s0t)
    return np.column_stack([w, s])


def _zero_curves(func: Callable[[np.ndarray, np.ndarray], np.ndarray], wg: np.ndarray,
                 sg: np.ndarray, Z: np.ndarray) -> list[np.ndarray]:
    """Polished zero curves of ``func`` sampled as ``Z`` on the grid (rows: s, columns: omega)."""
    import contourpy

    zm = np.ma.masked_invalid(Z)
    if zm.count() == 0:
        return []
    gen = contourpy.contour_generator(wg, sg, zm, line_type="Separate")
    lines = cast("list[np.ndarray]", gen.lines(0.0))
    return [_edge_refine(func, ln, wg, sg, Z) for ln in lines if len(ln) >= 2]


def _segments(keep: np.ndarray) -> list[slice]:
    """Runs of True of length >= 2."""
    out, start = [], None
    for k, flag in enumerate(np.r_[keep, False]):
        if flag and start is None:
            start = k
        elif not flag and start is not None:
            if k - start >= 2:
                out.append(slice(start, k))
            start = None
    return out


def _curves_for_n(n: int, wg: np.ndarray, F_range: tuple[float, float], zeta: float, e: float,
                  n_v: int) -> list[BoundaryCurve]:
    f_lo, f_hi = F_range
    curves: list[BoundaryCurve] = []

    def add(kind: BoundaryKind, w: np.ndarray, v: np.ndarray, keep: np.ndarray) -> None:
        fam = _on.family(n, w, zeta, e)
        F, _ = _on.forcing(fam, v)
        keep = keep & np.isfinite(F) & (F >= f_lo) & (F <= f_hi)
        for sl in _segments(keep):
            curves.append(BoundaryCurve(n=n, kind=kind, omega=w[sl].copy(), F=F[sl].copy(),
                                        v_im=v[sl].copy()))

    # Primary grazing: v -> 0+ on F = sqrt(D); kept where those orbits exist.
    v_eps = 1e-5
    fam = _on.family(n, wg, zeta, e)
    clear_eps, _ = _on.clearance(fam, np.full(wg.shape, v_eps))
    add("grazing", wg, np.zeros_like(wg), clear_eps > 0.0)

    # Saddle-node: explicit (eq. 3.11, 3.13).
    A = fam.p1 ** 2 + fam.q ** 2
    v_sn = fam.p1 / A
    clear_sn, _ = _on.clearance(fam, np.where(v_sn > 0.0, v_sn, np.nan))
    add("saddle-node", wg, v_sn, (v_sn > 0.0) & (clear_sn > 0.0))

    # Period doubling and secondary grazing: zero curves in (omega, s), v = s v_top(omega).
    def v_top(w: np.ndarray) -> np.ndarray:
        _, hi = _on.roots(_on.family(n, w, zeta, e), 1.02 * f_hi)
        return np.where(hi > 0.0, hi, np.nan)

    def p_minus(w: np.ndarray, s: np.ndarray) -> np.ndarray:
        tr, det = _on.trace_det(_on.family(n, w, zeta, e), s * v_top(w))
        return 1.0 + tr + det

    def clearance(w: np.ndarray, s: np.ndarray) -> np.ndarray:
        c, _ = _on.clearance(_on.family(n, w, zeta, e), s * v_top(w))
        return np.where(np.isposinf(c), 1.0, c)

    sg = np.linspace(1e-3, 1.0, n_v)
    W, S = np.meshgrid(wg, sg)
    for kind, func in (("period-doubling", p_minus), ("secondary-grazing", clearance)):
        Z = func(W, S)
        for line in _zero_curves(func, wg, sg, Z):
            w, s = line[:, 0], line[:, 1]
            v = s * v_top(w)
            if kind == "period-doubling":
                c, _ = _on.clearance(_on.family(n, w, zeta, e), v)
                keep = c > 0.0
            else:
                keep = np.isfinite(v)
            add(kind, w, v, keep)  # type: ignore[arg-type]
    return curves


def _part_for_n(job: tuple[str, int, np.ndarray, np.ndarray, tuple[float, float], float, float,
                           int]) -> Any:
    """One chunk of :func:`bifurcation_sets`: the regions or the boundary curves of one 1/n."""
    part, n, wg, Fg, F_lim, zeta, e, n_v = job
    if part == "regions":
        return _regions(n, wg, Fg, zeta, e)
    return list(_curves_for_n(n, wg, F_lim, zeta, e, n_v))


def bifurcation_sets(ns: Sequence[int] = (1, 2, 3, 4), *,
                     omega_range: tuple[float, float] = (0.6, 1.5),
                     F_range: tuple[float, float] = (0.0, 0.6),
                     zeta: float = 0.05, e: float = 0.6,
                     n_omega: int = 241, n_F: int = 121, n_v: int = 81, workers: int = 1,
                     scheduler: str | None = None) -> BifurcationSets:
    """Regions of existence and stability of 1/n orbits in the (omega, F) plane.

    The thesis's Fig. 3-7, 3-9 and 3-10 (``zeta = 0.05``, ``e = 0.6``,
    ``omega`` in [0.6, 1.5], ``F`` in [0, 0.6]).

    Parameters
    ----------
    ns : sequence of int
        Orbit types 1/n to compute (each >= 1).
    omega_range, F_range : (float, float)
        The domain (nondimensional), ``0 < omega_lo < omega_hi``,
        ``0 <= F_lo < F_hi``.
    zeta : float
        Damping ratio, > 0.
    e : float
        Coefficient of restitution, in (0, 1].
    n_omega, n_F : int
        Grid of the filled regions (and ``n_omega`` also of the curve tracing).
    n_v : int
        Impact-velocity grid of the curve tracing.
    workers : int
        Local worker processes over the orbit types ``ns`` (1: serial); the result is
        the same, bit for bit (:mod:`rattle_lab.model.analysis._dask`).
    scheduler : str, optional
        Address of a running ``dask.distributed`` scheduler to run them on instead.

    Returns
    -------
    BifurcationSets

    Raises
    ------
    ParameterError
        On an invalid argument (named in the message).

    Examples
    --------
    >>> sets = bifurcation_sets([1], omega_range=(1.1, 1.3), F_range=(0.0, 0.3),
    ...                         n_omega=41, n_F=31, n_v=41)
    >>> sn = sets.curves_of(1, "saddle-node")[0]
    >>> import numpy as np
    >>> bool(np.isclose(np.interp(0.2, sn.F, sn.omega), 1.2296, atol=2e-3))
    True
    """
    ns_t = _validate(ns, omega_range, F_range, zeta, e, n_omega, n_F, n_v)
    workers_i, sched = check_execution(workers, scheduler)
    wg = np.linspace(float(omega_range[0]), float(omega_range[1]), int(n_omega))
    Fg = np.linspace(float(F_range[0]), float(F_range[1]), int(n_F))
    exists = np.zeros((len(ns_t), Fg.size, wg.size), dtype=bool)
    stable = np.zeros_like(exists)
    curves: list[BoundaryCurve] = []
    F_lim = (float(F_range[0]), float(F_range[1]))
    # Regions and curves of each 1/n are independent chunks, largest first (the cost grows
    # with n; tracing costs about twice the regions): a pool of workers stays busy to the end.
    jobs = sorted(((part, n, wg, Fg, F_lim, float(zeta), float(e), int(n_v))
                   for n in ns_t for part in ("curves", "regions")),
                  key=lambda job: (-job[1], job[0]))
    parts = dict(zip(((job[0], job[1]) for job in jobs),
                     run_chunks(_part_for_n, jobs, workers=workers_i, scheduler=sched,
                                desc="bifurcation sets")))
    for k, n in enumerate(ns_t):
        exists[k], stable[k] = parts["regions", n]
        curves.extend(parts["curves", n])
    wf = np.linspace(wg[0], wg[-1], 4 * wg.size)
    Fgr = np.sqrt(((1.0 - wf) * (1.0 + wf)) ** 2 + (2.0 * zeta * wf) ** 2)
    inside = (Fgr >= Fg[0]) & (Fgr <= Fg[-1])
    grazing = BoundaryCurve(n=0, kind="grazing", omega=wf[inside], F=Fgr[inside],
                            v_im=np.zeros(int(inside.sum())))
    provenance: dict[str, object] = {
        "package": "rattle_lab", "version": __version__,
        "function": "rattle_lab.model.analysis.bifurcation_sets",
        "arguments": {"ns": list(ns_t), "omega_range": [float(x) for x in omega_range],
                      "F_range": [float(x) for x in F_range], "zeta": float(zeta), "e": float(e),
                      "n_omega": int(n_omega), "n_F": int(n_F), "n_v": int(n_v)},
    }
    return BifurcationSets(ns=ns_t, zeta=float(zeta), e=float(e), omega=wg, F=Fg,
                           exists=exists, stable=stable, curves=tuple(curves), grazing=grazing,
                           provenance=provenance)


# ---------------------------------------------------------------------------
# Plot
# ---------------------------------------------------------------------------

