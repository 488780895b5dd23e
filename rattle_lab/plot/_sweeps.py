"""Parameter sweeps like thesis Fig. 4-3 (omega), 4-4 (gap) and 4-5 (e)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.analysis import Sweep

from ._figures import check_figure_path, save_figure

_AXIS_LABELS: dict[str, str] = {
    "omega": "forcing frequency omega (nondimensional)",
    "F": "forcing amplitude F (nondimensional)",
    "e": "coefficient of restitution e",
    "gap": "1/F (gap in units of F_es / omega_s^2, at fixed F_es)",
}


def plot_sweeps(sweeps: Sequence[Sweep], path: str | os.PathLike[str]) -> Path:
    """Plot sweeps like thesis Fig. 4-3 (omega), 4-4 (gap) and 4-5 (e); write atomically.

    One column per sweep (e.g. (a) up, (b) down), three rows: the impact
    velocities ``v_im``, the upward ``x = 0`` crossing velocities
    ``v_{x=0}^+`` and the average impact velocity per forcing cycle, against
    the swept parameter.  For a ``"gap"`` sweep the velocities are divided by
    ``F`` and plotted against ``1/F`` (eq. 4.5, Fig. 4-4).  The linear estimate
    of the impact velocity (eq. 4.11) is drawn as a line where it applies.
    Aperiodic values with a positive Lyapunov exponent are drawn in red.

    Parameters
    ----------
    sweeps : sequence of Sweep
        One to four sweeps of the same parameter.
    path : str or Path
        ``.png``, ``.pdf`` or ``.svg``.

    Returns
    -------
    Path

    Raises
    ------
    ParameterError
        If the sweeps are empty, mixed, or the suffix is not supported.
    OutputError
        If the directory does not exist.
    """
    from matplotlib.figure import Figure


    check_figure_path(path)
    sweeps = list(sweeps)
    if not 1 <= len(sweeps) <= 4 or len({s.param for s in sweeps}) != 1:
        raise ParameterError("`sweeps` must hold one to four sweeps of the same parameter")
    param = sweeps[0].param
    gap = param == "gap"
    fig = Figure(figsize=(5.0 * len(sweeps), 9.0), layout="constrained")
    axes = fig.subplots(3, len(sweeps), squeeze=False, sharex="col")
    # [issue 17] mathtext labels (was raw "v_{x=0}^+"), on two short lines so that the
    # three rows' labels do not run into each other
    names = ("$v_{im}\\,/\\,F$\n(nondim.)", "$v_{x=0}^{+}\\,/\\,F$\n(nondim.)",
             "mean $v_{im}\\,/\\,F$\nper cycle (nondim.)") if gap else \
        ("impact velocity $v_{im}$\n(nondim.)", "crossing velocity $v_{x=0}^{+}$\n(nondim.)",
         "mean $v_{im}$ per\nforcing cycle (nondim.)")
    for col, sw in enumerate(sweeps):
        xs = sw.values
        scale = np.array([p.params.F if gap else 1.0 for p in sw.points])
        chaotic = np.array([p.chaotic for p in sw.points])
        for row, attr in enumerate(("impact_velocities", "crossing_velocities")):
            ax = axes[row, col]
            for flag, color in ((False, "black"), (True, "tab:red")):
                pts = [(x, v / s) for x, s, c, p in zip(xs, scale, chaotic, sw.points)
                       if c == flag for v in getattr(p, attr)]
                if pts:
                    arr = np.array(pts)
                    ax.plot(arr[:, 0], arr[:, 1], ".", color=color, markersize=1.5,
                            label="aperiodic, lambda_1 > 0" if flag else None)
        lin = np.array([p.linear_impact_velocity for p in sw.points]) / scale
        if np.any(np.isfinite(lin)):
            # [issue 17] the y range follows the simulated data; the linear estimate (which
            # grows without bound near resonance) is drawn within it, not stretching it
            data_y = np.concatenate([np.asarray(p.impact_velocities, float) / s
                                     for p, s in zip(sw.points, scale)] or [np.zeros(0)])
            data_y = data_y[np.isfinite(data_y)]
            axes[0, col].plot(xs, lin, "-", color="tab:blue", linewidth=1.2,
                              label="linear estimate, eq. (4.11)")
            if data_y.size:
                lo, hi = float(data_y.min()), float(data_y.max())
                pad = 0.08 * (hi - lo) if hi > lo else 0.1 * max(abs(hi), 1e-12)
                axes[0, col].set_ylim(lo - pad, hi + pad)
        axes[2, col].plot(xs, sw.mean_impact_velocity / scale, ".-", color="black",
                          markersize=2, linewidth=0.6)
        for row in range(3):
            axes[row, col].set_ylabel(names[row])
            axes[row, col].grid(alpha=0.3)
        axes[2, col].set_xlabel(_AXIS_LABELS[param])
        b = sw.base
        fixed = {"omega": f"F = {b.F:g}", "F": f"omega = {b.omega:g}",
                 "e": f"F = {b.F:g}, omega = {b.omega:g}", "gap": f"omega = {b.omega:g}"}[param]
        rest = f"zeta = {b.zeta:g}" + ("" if param == "e" else f", e = {b.e:g}")
        axes[0, col].set_title(f"({chr(97 + col)}) {sw.direction}-sweep of "
                               f"{'1/F' if gap else param}\n{fixed}, {rest}", fontsize=10)
        handles, _ = axes[0, col].get_legend_handles_labels()
        if handles:
            axes[0, col].legend(fontsize=7, loc="best")
    fig.align_ylabels(axes[:, 0])
    save_figure(fig, path, dpi=150)
    return Path(path)
