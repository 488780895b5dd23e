"""Bifurcation sets like thesis Fig. 3-10."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rattle_lab.model.analysis.bifsets import BifurcationSets

from ._figures import check_figure_path, save_figure

BIFURCATION_LINESTYLES: dict[str, Any] = {"grazing": "-", "saddle-node": "-.", "period-doubling": "--",
                               "secondary-grazing": ":"}


def plot_bifurcation_sets(sets: BifurcationSets, path: str | Path, *, dpi: int = 150) -> Path:
    """Plot the bifurcation sets like thesis Fig. 3-10 and write it atomically.

    Existence regions are lightly shaded and stability regions shaded darker,
    one colour per ``n``; the boundary curves are drawn in that colour with a
    line style per kind, and the grazing curve (eq. 3.4) in black.

    Parameters
    ----------
    sets : BifurcationSets
        What :func:`bifurcation_sets` returned.
    path : str or Path
        Output file; the format follows the suffix (``.png``, ``.pdf``, ``.svg``).
    dpi : int
        Resolution of raster output.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ParameterError
        If the suffix is not a supported format.
    OutputError
        If the output directory does not exist.
    """
    # A bare Figure (no pyplot): no global backend state is touched, and it renders with Agg.
    import matplotlib
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    path = check_figure_path(path)
    colors = matplotlib.colormaps["tab10"].colors  # type: ignore[attr-defined]
    fig = Figure(figsize=(10.0, 6.0), layout="constrained")
    ax = fig.add_subplot()
    handles: list[object] = []
    for k, n in enumerate(sets.ns):
        col = colors[k % len(colors)]
        if sets.exists[k].any():
            ax.contourf(sets.omega, sets.F, sets.exists[k].astype(float), levels=[0.5, 1.5],
                        colors=[col], alpha=0.15)
        if sets.stable[k].any():
            ax.contourf(sets.omega, sets.F, sets.stable[k].astype(float), levels=[0.5, 1.5],
                        colors=[col], alpha=0.45)
        for c in sets.curves_of(n):
            if c.kind == "grazing":
                continue  # drawn once, in black
            ax.plot(c.omega, c.F, color=col, linestyle=BIFURCATION_LINESTYLES[c.kind], linewidth=1.3)
        handles.append(Patch(facecolor=col, alpha=0.15, label=f"1/{n} exists"))
        handles.append(Patch(facecolor=col, alpha=0.45, label=f"1/{n} stable"))
    ax.plot(sets.grazing.omega, sets.grazing.F, color="black", linewidth=1.6)
    handles.append(Line2D([], [], color="black", linewidth=1.6, label="grazing, eq. (3.4)"))
    for kind in ("saddle-node", "period-doubling", "secondary-grazing"):
        handles.append(Line2D([], [], color="0.3", linestyle=BIFURCATION_LINESTYLES[kind], label=kind))
    ax.set_xlim(sets.omega[0], sets.omega[-1])
    ax.set_ylim(sets.F[0], sets.F[-1])
    ax.set_xlabel("forcing frequency omega (nondimensional)")
    ax.set_ylabel("forcing amplitude F (nondimensional)")
    ax.set_title(f"Bifurcation sets of 1/n orbits (zeta = {sets.zeta:g}, e = {sets.e:g})")
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8,
              borderaxespad=0.0)
    return save_figure(fig, path, dpi=dpi)


def smooth_region(omega: np.ndarray, F: np.ndarray, mask: np.ndarray,
                  factor: int = 6) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A boolean region on a grid as a smooth field on a finer grid (for contourf at 0.5).

    The 0/1 field is blurred by a Gaussian of one cell and interpolated cubically
    onto a grid ``factor`` times finer: the 0.5 contour then runs smoothly, within a
    cell of the computed boundary, instead of in grid-cell steps.

    Parameters
    ----------
    omega, F : ndarray
        The grid's axes (``mask`` is ``(F.size, omega.size)``).
    mask : ndarray of bool
        The region.
    factor : int
        Refinement of the grid.

    Returns
    -------
    (ndarray, ndarray, ndarray)
        The finer axes and the smoothed field (``contourf(w, f, z, levels=[0.5, 1.5])``).
    """
    from scipy import ndimage

    z = ndimage.gaussian_filter(np.asarray(mask, dtype=float), sigma=1.0, mode="nearest")
    z = ndimage.zoom(z, factor, order=3, mode="nearest", grid_mode=False)
    w = np.linspace(omega[0], omega[-1], z.shape[1])
    f = np.linspace(F[0], F[-1], z.shape[0])
    return w, f, z
