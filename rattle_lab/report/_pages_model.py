"""The model pages: bifurcation sets with the measured thresholds, and the model's sweeps.

Draws :class:`._content_types.ModelContent`; the sets, smoothed regions and sweeps
were computed before (by :mod:`rattle_lab.workflow`).
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure

from rattle_lab.plot import BIFURCATION_LINESTYLES  # the same styles as `model bifsets`' plot
from ._common import landscape_figure
from ._content_types import ModelContent, SweepComparison


def model_pages(c: ModelContent) -> list[Figure]:
    """Page 1: the 1/1 and 1/2 regions in (omega, F) with the measured thresholds; page 2 (when
    a frequency was swept): the model's onset and disappearance against the measured ones."""
    figs = [_bifurcation_page(c)]
    if c.sweeps is not None:
        figs.append(_sweep_page(c.sweeps))
    return figs


def _bifurcation_page(c: ModelContent) -> Figure:
    import matplotlib
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    sets = c.sets
    fig = landscape_figure()
    # the plot and, right of it, a column of fixed width for the legend (outside the plot, so
    # that the regions, the hatched coexistence first, stay visible); the legend is left out
    # of the layout, so the plot's width does not follow the glyphs of the legend's font
    grid = fig.add_gridspec(1, 2, width_ratios=[2.6, 1.0])
    ax = fig.add_subplot(grid[0, 0])
    legend_ax = fig.add_subplot(grid[0, 1])
    legend_ax.set_axis_off()
    handles: list[Any] = []
    tab10 = matplotlib.colormaps["tab10"].colors  # type: ignore[attr-defined]
    for k, n in enumerate(sets.ns):
        color = tab10[k % len(tab10)]
        exists, stable = c.exists_fields[k], c.stable_fields[k]
        if exists is not None:
            ax.contourf(*exists, levels=[0.5, 1.5], colors=[color], alpha=0.15)
        if stable is not None:
            ax.contourf(*stable, levels=[0.5, 1.5], colors=[color], alpha=0.45)
        for curve in sets.curves_of(n):
            if curve.kind != "grazing":
                ax.plot(curve.omega, curve.F, color=color, lw=1.3, ls=BIFURCATION_LINESTYLES[curve.kind])
        handles += [Patch(facecolor=color, alpha=0.15, label=f"1/{n} orbit exists"),
                    Patch(facecolor=color, alpha=0.45, label=f"1/{n} orbit exists and is stable")]
    if c.both_field is not None:  # where the two shadings blend: named in the legend, hatched
        ax.contourf(*c.both_field, levels=[0.5, 1.5], colors="none", hatches=["xx"])
        handles.append(Patch(facecolor="none", edgecolor="0.3", hatch="xx",
                             label=f"1/{sets.ns[0]} and 1/{sets.ns[1]} both exist\n"
                                   "(overlap of the shadings: coexisting orbits)"))
    for kind in ("saddle-node", "period-doubling", "secondary-grazing"):
        if any(curve.kind == kind for n in sets.ns for curve in sets.curves_of(n)):
            handles.append(Line2D([], [], color="0.3", ls=BIFURCATION_LINESTYLES[kind], label=kind))
    (graze,) = ax.plot(sets.grazing.omega, sets.grazing.F, color="k", lw=1.4,
                       label="grazing, eq. (3.4)")
    (on,) = ax.plot(c.omega_up, c.F_up, "^", color="tab:red", ms=7, label="measured onset")
    (off,) = ax.plot(c.omega_down, c.F_down, "v", color="tab:blue", ms=7,
                     label="measured disappearance")
    ax.set_xlim(sets.omega[0], sets.omega[-1])
    ax.set_ylim(sets.F[0], sets.F[-1])
    ax.set_xlabel("forcing frequency omega = f / f_s (nondimensional)")
    ax.set_ylabel("forcing amplitude F = Q A / (omega_s^2 h) (nondimensional)")
    ax.set_title(f"Model bifurcation sets at the fitted zeta = {c.zeta:.3g} ({c.zeta_source}), "
                 f"e = {c.e:.3g}, with the measured thresholds\n(region edges smoothed within "
                 f"one cell of the {sets.omega.size} x {sets.F.size} grid)")
    legend = legend_ax.legend(handles=[*handles, graze, on, off], fontsize=8.5,
                              loc="upper left", borderaxespad=0.0)
    legend.set_in_layout(False)
    ax.grid(alpha=0.3)
    return fig


def _sweep_page(s: SweepComparison) -> Figure:
    fig = landscape_figure()
    ax = fig.add_subplot()
    half = s.half_step_ms2
    ax.errorbar(s.freq_hz - 0.04, s.onset_ms2, yerr=half, fmt="s-", color="tab:red",
                mfc="none", capsize=3, label="model onset (F sweep up)")
    ax.errorbar(s.freq_hz + 0.04, s.disappearance_ms2, yerr=half, fmt="s--", color="tab:blue",
                mfc="none", capsize=3, label="model disappearance (F sweep back down)")
    ax.plot(s.measured_freq_hz, s.measured_up_ms2, "^", color="tab:red", ms=8,
            label="measured onset")
    ax.plot(s.measured_freq_hz, s.measured_down_ms2, "v", color="tab:blue", ms=8,
            label="measured disappearance")
    ax.set_xlabel("excitation frequency (Hz)")
    ax.set_ylabel("base acceleration amplitude at threshold (m/s^2)")
    ax.set_title(f"Model at the fitted parameters against the measured thresholds: F "
                 f"swept over {s.n_sweep} amplitudes up to {s.F_max_ms2:.3g} m/s^2\n(60 "
                 f"forcing periods each; bars: the sweep step, {2 * half:.3g} m/s^2)")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    return fig
