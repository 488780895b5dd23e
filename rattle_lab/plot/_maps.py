"""Regime maps, basins and disturbance maps like thesis Fig. 4-6 and 4-7."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.analysis import DisturbanceMap
from rattle_lab.model.analysis.maps import AttractorMap

from ._figures import check_figure_path, save_figure


def _boundary_curves(ax: Any, omega: np.ndarray, zeta: float, e: float, F_lim: tuple[float, float]
                     ) -> None:
    from rattle_lab.model.analysis.orbits import saddle_node_forcing

    w = np.linspace(float(omega.min()), float(omega.max()), 400)
    F_g = np.hypot((1.0 - w) * (1.0 + w), 2.0 * zeta * w)
    ax.plot(w, F_g, color="black", linewidth=1.5, label="grazing, eq. (3.4)")
    F_sn, v_sn = saddle_node_forcing(1, w, zeta, e)
    F_sn = np.where((w > 1.0) & (v_sn > 0.0), F_sn, np.nan)
    if np.any(np.isfinite(F_sn)):
        ax.plot(w, F_sn, color="black", linestyle="-.", linewidth=1.2,
                label="1/1 saddle-node, eq. (3.11)")
    ax.set_ylim(*F_lim)


def plot_attractor_map(amap: AttractorMap, path: str | Path, *, max_labels: int = 12) -> Path:
    """Plot a regime map or basins (one colour per regime label) and write it atomically.

    The ``max_labels - 1`` most frequent labels get their own colour, the rest
    share one (``"other"``).  A regime map also shows the grazing curve
    (eq. 3.4) and the 1/1 saddle-node (eq. 3.11).

    Parameters
    ----------
    amap : AttractorMap
        What :func:`regime_map` or :func:`basin_map` returned.
    path : str or Path
        ``.png``, ``.pdf`` or ``.svg``.
    max_labels : int
        Colours in the legend.

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        If the suffix is not supported.
    OutputError
        If the directory does not exist.
    """
    import matplotlib
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch


    check_figure_path(path)
    labels = amap.labels().astype(str)
    ranked = list(amap.counts())
    fixed_colors = {"no impact": "#ffffff", "aperiodic": "#222222", "unsettled": "#bbbbbb"}
    shown = ranked[:max_labels - 1] if len(ranked) > max_labels else ranked
    palette = list(matplotlib.colormaps["tab20"].colors)  # type: ignore[attr-defined]
    colors: list[Any] = []
    k = 0
    for lab in shown:
        if lab in fixed_colors:
            colors.append(fixed_colors[lab])
        else:
            colors.append(palette[k % len(palette)])
            k += 1
    index = {lab: i for i, lab in enumerate(shown)}
    other = len(shown)
    idx = np.vectorize(lambda s: index.get(s, other))(labels).astype(float)
    if len(shown) < len(ranked):
        colors.append("#999999")
    fig = Figure(figsize=(9.0, 6.0), layout="constrained")
    ax = fig.add_subplot()
    ax.pcolormesh(amap.x, amap.y, idx, cmap=ListedColormap(colors), vmin=-0.5,
                  vmax=len(colors) - 0.5, shading="nearest")
    handles: list[Any] = [Patch(facecolor=c, edgecolor="0.5", label=lab)
                          for lab, c in zip(shown + (["other"] if len(shown) < len(ranked)
                                                     else []), colors)]
    if amap.kind == "regime":
        _boundary_curves(ax, amap.x, amap.fixed["zeta"], amap.fixed["e"],
                         (float(amap.y.min()), float(amap.y.max())))
        ax.set_xlim(float(amap.x.min()), float(amap.x.max()))
        ax.set_xlabel("forcing frequency omega (nondimensional)")
        ax.set_ylabel("forcing amplitude F (nondimensional)")
        ax.set_title(f"Regime map (zeta = {amap.fixed['zeta']:g}, e = {amap.fixed['e']:g}; "
                     f"{amap.cycles} periods, last {amap.cycles - amap.discard} classified)")
        handles.extend(ax.get_legend_handles_labels()[0])
    else:
        f = amap.fixed
        ax.set_xlabel("initial displacement x0 (nondimensional)")
        ax.set_ylabel("initial velocity v0 (nondimensional)")
        ax.set_title(f"Basins of attraction (F = {f['F']:g}, omega = {f['omega']:g}, "
                     f"zeta = {f['zeta']:g}, e = {f['e']:g}, theta0 = {f['theta0']:g})")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
              borderaxespad=0.0)
    return save_figure(fig, path, dpi=150)


def plot_disturbance_map(dmap: DisturbanceMap, path: str | Path, *,
                         levels: tuple[float, ...] = (0.1, 0.2, 0.4)) -> Path:
    """Plot the demarcation curves of thesis Fig. 4-7 and write the figure atomically.

    The threshold is shown in colour over the grid; the level curves
    ``threshold = V`` for each ``V`` in ``levels`` are the demarcation curves
    (a kick ``V`` sustains impact above the curve).  The grazing curve and the
    1/1 saddle-node bound the hysteresis region.

    Parameters
    ----------
    dmap : DisturbanceMap
        What :func:`disturbance_map` returned.
    path : str or Path
        ``.png``, ``.pdf`` or ``.svg``.
    levels : tuple of float
        Disturbance velocities of the demarcation curves (nondimensional).

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        If the suffix is not supported or ``levels`` are not positive.
    OutputError
        If the directory does not exist.
    """
    from matplotlib.figure import Figure


    check_figure_path(path)
    lv = sorted(float(v) for v in levels)
    if not lv or any(not (math.isfinite(v) and v > 0) for v in lv):
        raise ParameterError(f"`levels` must be positive numbers, was {levels!r}")
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    fig = Figure(figsize=(9.5, 6.0), layout="constrained")
    ax = fig.add_subplot()
    th = dmap.threshold
    # above grazing (NaN): impact without any disturbance; inf: none up to kick_max
    cat = np.where(np.isnan(th), 0.0, np.where(np.isinf(th), 1.0, np.nan))
    ax.pcolormesh(dmap.omega, dmap.F, cat, cmap=ListedColormap(["#d9d9d9", "#ffffff"]),
                  vmin=-0.5, vmax=1.5, shading="nearest")
    mesh = ax.pcolormesh(dmap.omega, dmap.F, np.where(np.isfinite(th), th, np.nan),
                         cmap="viridis", shading="nearest", vmin=0.0, vmax=dmap.kick_max)
    fig.colorbar(mesh, ax=ax, label="threshold kick (nondimensional velocity)")
    if dmap.F.size > 1 and dmap.omega.size > 1:
        # for the level curves: above grazing every kick (even 0) gives impact; where no
        # kick up to kick_max does, the threshold is unknown (masked: no curve drawn there)
        filled = np.ma.masked_invalid(np.where(np.isnan(th), 0.0, np.where(np.isinf(th),
                                                                           np.nan, th)))
        cs = ax.contour(dmap.omega, dmap.F, filled, levels=lv, colors="red", linewidths=1.4)
        ax.clabel(cs, fmt=lambda v: f"V = {v:g}", fontsize=8)
    _boundary_curves(ax, dmap.omega, dmap.zeta, dmap.e, (float(dmap.F.min()), float(dmap.F.max())))
    ax.set_xlim(float(dmap.omega.min()), float(dmap.omega.max()))
    ax.set_xlabel("forcing frequency omega (nondimensional)")
    ax.set_ylabel("forcing amplitude F (nondimensional)")
    ax.set_title(f"Disturbance demarcation curves (zeta = {dmap.zeta:g}, e = {dmap.e:g})\n"
                 "a kick V at the upward x = 0 crossing sustains impact above the curve V",
                 fontsize=10)
    handles = ax.get_legend_handles_labels()[0] + [
        Patch(facecolor="#d9d9d9", edgecolor="0.5", label="above grazing: impact without kick"),
        Patch(facecolor="#ffffff", edgecolor="0.5",
              label=f"no sustained impact up to kick {dmap.kick_max:g}")]
    ax.legend(handles=handles, loc="lower right", fontsize=8)
    return save_figure(fig, path, dpi=150)
