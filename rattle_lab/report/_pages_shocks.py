"""The pages of transient records: per run the shock found in each channel (onset, peak,
delay to the cause, clocks named) and the waveforms aligned on each channel's onset.

Draws :class:`._content_types.ShockContent`; nothing is computed here.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from ._common import landscape_figure
from ._content_types import ShockContent, ShockRun

_ROLE_COLOR = {"cause": "tab:red", "response": "tab:blue"}


def shock_pages(c: ShockContent) -> list[Figure]:
    """One page per transient run."""
    return [_shock_page(run) for run in c.runs]


def _shock_page(run: ShockRun) -> Figure:
    fig = landscape_figure()
    n_lines = len(run.lines)
    top = min(0.42, 0.05 + 0.026 * n_lines)  # the text block's share of the page
    text_fig, plot_fig = fig.subfigures(2, 1, height_ratios=(top, 1.0 - top))  # type: ignore[misc]
    text_fig.text(0.01, 0.97, f"Shock of transient run {run.input_key}/{run.run_id}: per "
                  "channel, the cause first", fontsize=12, weight="bold", va="top")
    y = 0.97 - 0.9 / max(n_lines + 1, 4)
    for line in run.lines:
        text_fig.text(0.01, y, line, fontsize=7.5, family="monospace", va="top")
        y -= 0.85 / max(n_lines + 1, 4)
    traces = run.traces
    axes = plot_fig.subplots(max(len(traces), 1), 1, sharex=True, squeeze=False)[:, 0]
    for ax, tr in zip(axes, traces):
        color = _ROLE_COLOR.get(tr.role, "0.2")
        ax.plot(tr.t_ms, tr.y, lw=0.8, color=color if tr.found else "0.6")
        if tr.found:
            ax.axvline(0.0, color="k", lw=0.9, ls="--")
            if tr.peak_t_ms is not None:
                ax.axvline(tr.peak_t_ms, color=color, lw=0.9, ls=":")
        state = "" if tr.found else ", no shock: around the cause's onset sample"
        ax.set_ylabel(f"({tr.units})", fontsize=8)
        ax.set_title(f"{tr.channel} ({tr.quantity}, {tr.role}, clock {tr.clock}, "
                     f"{tr.fs_hz:.6g} Hz){state}", fontsize=8, loc="left")
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
    axes[-1].set_xlabel("time from the channel's own onset (ms, on its own clock); dashed: "
                        "onset, dotted: peak")
    return fig
