"""Pages drawn from the content of one section each: rig, thresholds, patterns, waveforms, SPL.

Each function takes the section's content (:mod:`._content_types`)
and returns figures; nothing is computed or read here.  Figures are bare
:class:`matplotlib.figure.Figure` objects (Agg, no pyplot state); every axis carries
its unit.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ._common import PAGE_SIZE_IN, fmt, landscape_figure, table
from ._content_types import (WAVEFORM_QUANTITIES, PatternContent, RigContent, SplContent,
                             ThresholdContent, WaveformContent)

_RIG_UNITS = {"plate_length_m": "m", "plate_width_m": "m", "plate_thickness_m": "m",
              "striker_x_m": "m", "striker_y_m": "m", "gap_m": "m", "mic_distance_m": "m"}


def rig_page(content: RigContent) -> list[Figure]:
    """Rig facts and the calibration table of the channels (portrait, like the summary)."""
    records = content.records
    fig = Figure(figsize=PAGE_SIZE_IN)
    fig.text(0.06, 0.96, "Rig and calibration", fontsize=14, weight="bold", va="top")
    recs = records[:2]
    fact_rows = []
    for key in recs[0].rig:
        label = key[:-2] + " (m)" if key in _RIG_UNITS else key
        vals = [(fmt(r.rig.get(key)) if isinstance(r.rig.get(key), float)
                 else str(r.rig.get(key) or "-")) for r in recs]
        fact_rows.append([label.replace("_", " "), *vals])
    ax_rig = fig.add_axes((0.06, 0.62, 0.88, 0.3))
    ax_rig.axis("off")
    table(ax_rig, fact_rows, ["rig", *[f"{r.input_key} ({r.campaign_id}, {r.source})"
                                       for r in recs]], 8.5, fill_width=True)
    if len(records) > 2:
        fig.text(0.06, 0.605, f"... and {len(records) - 2} more records (not shown)",
                 fontsize=8)
    channels = [(rec, c) for rec in records for c in rec.channels]
    n_rows = len(channels)
    channels = channels[:20]
    cols = ["input", "channel", "quantity", "SI unit", "source unit", "scale to SI",
            "sensitivity", "rate (Hz)"]
    rows = [[c.input_key[-8:], c.name, c.quantity, c.units, c.source_units or "-",
             fmt(c.scale_to_si), c.sensitivity or "-", fmt(c.sample_rate_hz, '.6g')]
            for _, c in channels]
    fig.text(0.06, 0.585, "Channels", fontsize=11, weight="bold", va="top")
    ax = fig.add_axes((0.06, 0.36, 0.88, 0.21))
    ax.axis("off")
    table(ax, rows, cols, 8.0, fill_width=True)
    cols2 = ["channel", "sensor", "serial", "calibrated", "range (SI unit)", "position (m)"]
    rows2 = [[c.name, c.sensor_model or "-", c.sensor_serial or "-",
              c.calibration_date or "-", c.range_si or "-", c.position_m or "-"]
             for _, c in channels]
    fig.text(0.06, 0.335, "Sensors and calibration", fontsize=11, weight="bold", va="top")
    ax2 = fig.add_axes((0.06, 0.06, 0.88, 0.26))
    ax2.axis("off")
    table(ax2, rows2, cols2, 8.0, fill_width=True)
    if n_rows > len(channels):
        fig.text(0.06, 0.045, f"... and {n_rows - len(channels)} more channels (not shown)",
                 fontsize=8)
    return [fig]


# --- thresholds (Fig. 6-2, 6-3) ------------------------------------------------------------

def threshold_page(c: ThresholdContent) -> list[Figure]:
    """Onset/disappearance thresholds against frequency, eq. 3.4 fit and band, hysteresis.

    Left: the thresholds with the eq. (3.4) fit and, where fitted, eq. (3.4) at the
    ramp-corrected parameters; below it the measured onsets less the fit with the fit's
    95 % band (the band is far narrower than the thresholds' range: only there is it seen).
    Right: the hysteresis per frequency.
    """
    f, up, down = c.freq_hz, c.up_ms2, c.down_ms2
    fig = landscape_figure()
    grid = fig.add_gridspec(2, 2, width_ratios=(2, 1), height_ratios=(3, 1))
    ax = fig.add_subplot(grid[0, 0])
    ax_r = fig.add_subplot(grid[1, 0], sharex=ax)
    ax_h = fig.add_subplot(grid[:, 1])
    curve = c.curve
    if curve is not None:
        ax.plot(curve.grid_hz, curve.accel_ms2, color="k", lw=1.4,
                label=f"{curve.label}: gap {1e3 * curve.gap_m:.4g} mm, f_s "
                      f"{curve.f_s_hz:.4g} Hz, zeta {curve.zeta:.3g}")
        if curve.outlier_freq_hz is not None and curve.outlier_up_ms2 is not None:
            ax.plot(curve.outlier_freq_hz, curve.outlier_up_ms2, "o", ms=11, mfc="none",
                    color="k", label="left out of the fit (outlier)")
    if c.corrected is not None:
        k = c.corrected
        ax.plot(k.grid_hz, k.accel_ms2, color="tab:green", lw=1.6, ls="--",
                label=f"{k.label}:\n    gap {1e3 * k.gap_m:.4g} mm, f_s {k.f_s_hz:.4g} Hz, "
                      f"zeta {k.zeta:.3g}")
    ok = c.both
    fo, do, uo = f[ok], down[ok], up[ok]
    for n, (i, j) in enumerate(c.hysteresis_segments):
        label = "hysteresis (onset - disappearance)" if n == 0 else "_nolegend_"
        if j - i > 1:
            ax.fill_between(fo[i:j], do[i:j], uo[i:j], where=(uo[i:j] >= do[i:j]),
                            interpolate=True, color="tab:orange", alpha=0.3, label=label)
        else:  # a frequency without measured neighbours: a bar, not a shading across a gap
            ax.vlines(fo[i], do[i], uo[i], color="tab:orange", lw=6, alpha=0.4, label=label)
    ax.plot(f, up, "^", color="tab:red", ms=8, label="onset (ramp up)", zorder=5)
    ax.plot(f, down, "v", color="tab:blue", ms=8, label="disappearance (ramp down)", zorder=5)
    ax.set_ylabel("base acceleration amplitude at threshold (m/s^2)")
    ax.set_title("Impact thresholds (thesis Fig. 6-2, 6-3 a)")
    ax.legend(fontsize=9, loc="upper left")
    ax.grid(alpha=0.3)
    ax.tick_params(labelbottom=False)
    # the residuals, where the 95 % band can be seen
    ax_r.axhline(0.0, color="k", lw=1.0)
    if curve is not None:
        if curve.band_ms2 is not None:
            how = f"Student t, {curve.dof} dof" if curve.dof is not None else "normal"
            ax_r.fill_between(curve.grid_hz, curve.band_ms2[0] - curve.accel_ms2,
                              curve.band_ms2[1] - curve.accel_ms2, color="0.45", alpha=0.45,
                              label=f"95 % confidence band of the fit (delta method, {how})")
        if curve.residual_ms2 is not None and curve.residual_freq_hz is not None:
            ax_r.plot(curve.residual_freq_hz, curve.residual_ms2, "^", color="tab:red", ms=7,
                      label="onset less the fit")
    if c.corrected is not None and c.corrected.residual_ms2 is not None \
            and c.corrected.residual_freq_hz is not None:
        ax_r.plot(c.corrected.residual_freq_hz, c.corrected.residual_ms2, "s", mfc="none",
                  color="tab:green", ms=6, label="ramp-corrected curve less the fit")
    ax_r.set_xlabel("excitation frequency (Hz)")
    ax_r.set_ylabel("less the fit (m/s^2)")
    ax_r.grid(alpha=0.3)
    if ax_r.get_legend_handles_labels()[0]:
        ax_r.legend(fontsize=8, loc="best")
    hyst, neg = c.hysteresis_ms2, c.negative
    ax_h.bar(f[~neg], hyst[~neg], width=c.bar_width_hz, color="tab:orange", label="onset above "
             "disappearance (expected)")
    if neg.any():  # a negative hysteresis is not physical for this oscillator: flag it
        ax_h.bar(f[neg], hyst[neg], width=c.bar_width_hz, color="tab:red", hatch="//",
                 edgecolor="k", label="NEGATIVE: disappearance above onset (check the ramps)")
        for fx, h in zip(f[neg], hyst[neg]):
            ax_h.annotate(f"negative\n{h:.3g} m/s^2", (fx, h), xytext=(0, -28),
                          textcoords="offset points", ha="center", fontsize=8, color="tab:red",
                          weight="bold")
        ax_h.legend(fontsize=8, loc="upper left")
    ax_h.axhline(0.0, color="k", lw=0.8)
    ax_h.set_xlabel("excitation frequency (Hz)")
    ax_h.set_ylabel("hysteresis, onset - disappearance (m/s^2)")
    ax_h.set_title("Hysteresis")
    ax_h.grid(alpha=0.3)
    return [fig]


# --- impact patterns (Fig. 6-5) ------------------------------------------------------------

_CLASSES = ((0, "no impact", "0.8"), (1, "1 impact per cycle", "tab:blue"),
            (2, "2 impacts per cycle", "tab:orange"), (3, ">= 3 impacts per cycle", "tab:red"))


def pattern_page(c: PatternContent) -> list[Figure]:
    """Impacts per forcing cycle over frequency and base-acceleration amplitude."""
    arr = c.points
    fig = landscape_figure()
    ax = fig.add_subplot()
    color_of = {n: color for n, _, color in _CLASSES}
    for n, label, color in _CLASSES:
        sel = arr[:, 2] == n if n < 3 else arr[:, 2] >= 3
        ramp = sel & (arr[:, 3] == 0)
        if ramp.any():  # the rarer (more impacts) classes above and larger: never hidden
            ax.scatter(arr[ramp, 0], arr[ramp, 1], s=6 + 5 * n, color=color, label=label,
                       zorder=2 + n, linewidths=0)
    # one marker per dwell and class (size: the share of its cycles in the class); the
    # largest first, so that a small share is drawn on top of a large one
    for n, fx, lv, share in sorted(c.dwell_shares, key=lambda d: -d[3]):
        ax.scatter([fx], [lv], s=40 + 120 * share, marker="D", color=color_of[n],
                   edgecolor="k", linewidth=0.6, zorder=10)
    if (arr[:, 3] == 1).any():
        ax.scatter([], [], s=60, marker="D", color="w", edgecolor="k",
                   label="sine dwell (size: share of its cycles)")
    ax.set_xlabel("excitation frequency (Hz); ramps: up left, down right of each frequency")
    ax.set_ylabel(f"nominal base-acceleration amplitude ({', '.join(c.level_units)})")
    ax.set_title("Impact patterns per forcing cycle (thesis Fig. 6-5)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return [fig]


# --- waveforms (Fig. 6-4, 6-6) -------------------------------------------------------------

_PEAK_STYLE = {"first": ("o", "tab:blue", "first peak"), "max": ("x", "tab:orange",
                                                                 "maximum peak")}


def waveform_page(c: WaveformContent) -> list[Figure]:
    """Short windows of plate acceleration, velocity and sound pressure with events marked."""
    fig = landscape_figure()
    axes = fig.subplots(3, len(c.columns), squeeze=False, sharex="col")
    for col, column in enumerate(c.columns):
        for row, ((quantity, label), trace) in enumerate(zip(WAVEFORM_QUANTITIES,
                                                             column.traces)):
            ax = axes[row, col]
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
            if trace is None:
                ax.text(0.5, 0.5, f"no {quantity} channel", ha="center", transform=ax.transAxes)
                continue
            ax.plot(trace.t_s, trace.y, lw=0.7, color="0.2")
            ax.margins(x=0.0, y=0.14)  # room for the markers at the extremes, inside the frame
            if trace.t_s.size > 1:
                ax.set_xlim(trace.t_s[0], trace.t_s[-1])
            has_impacts = trace.impact_t_s.size > 0
            if quantity == "plate_velocity" and has_impacts:
                ax.plot(trace.impact_t_s, trace.impact_y, "o", mfc="none", color="tab:red",
                        label="detected impact")
                ax.legend(fontsize=7, loc="best")
            elif quantity == "plate_acceleration" and has_impacts:
                for i, ti in enumerate(trace.impact_t_s):
                    ax.axvline(ti, color="tab:red", lw=0.6, alpha=0.6,
                               label="detected impact" if i == 0 else None)
                ax.legend(fontsize=7, loc="best")
            elif quantity == "sound_pressure" and trace.peaks:
                for which, tt, yy in trace.peaks:
                    mk, color, lab = _PEAK_STYLE[which]
                    ax.plot(tt, yy, mk, ms=7, mew=1.3, mfc="none", color=color, label=lab,
                            clip_on=False, zorder=4)
                ax.legend(fontsize=7, loc="best")
        axes[0, col].set_title(f"{column.run_id} ({column.protocol}, {column.freq_hz:g} Hz, "
                               f"pattern {column.pattern})", fontsize=9)
        axes[2, col].set_xlabel("time (s)")
    fig.suptitle("Example waveforms with detected impacts and sound peaks "
                 "(thesis Fig. 6-4, 6-6)")
    return [fig]


# --- SPL law (Fig. 6-7) --------------------------------------------------------------------

_SPL_COLORS = {"first": "tab:blue", "max": "tab:red", "rms": "tab:green"}
_SPL_NAMES = {"first": "first peak", "max": "maximum peak", "rms": "RMS per impact"}


def spl_page(c: SplContent) -> list[Figure]:
    """Sound pressure against impact velocity with the fitted linear laws and 95 % bands.

    The first-peak points (small dots) are drawn first, the maximum-peak and RMS points
    over them; where the content knows it, the maximum-peak and RMS points of impacts
    whose largest peak is a later one (not the first) get their own marker: the upper
    branch of those clouds, through which the one fitted line also runs.
    """
    fig = landscape_figure()
    ax = fig.add_subplot()
    points, lines = [], []
    for curve in c.curves:
        color, name = _SPL_COLORS[curve.name], _SPL_NAMES[curve.name]
        slope, icpt, grid = curve.slope, curve.intercept, curve.grid_m_s
        split = curve.later_max is not None and curve.name != "first" and curve.later_max.any()
        if split:
            later = np.asarray(curve.later_max, dtype=bool)
            points.append(ax.plot(curve.v_m_s[~later], curve.p_pa[~later], "o", ms=3.5,
                                  mfc="none", mew=0.6, alpha=0.7, color=color,
                                  zorder=3, label=f"{name}: the first peak is the largest "
                                  f"({int((~later).sum())})")[0])
            points.append(ax.plot(curve.v_m_s[later], curve.p_pa[later], "x", ms=4, mew=0.8,
                                  color=color, zorder=3,
                                  label=f"{name}: a later peak is larger than the first "
                                        f"({int(later.sum())}, the upper branch)")[0])
        else:
            points.append(ax.plot(curve.v_m_s, curve.p_pa, ".", ms=3, alpha=0.6, color=color,
                                  zorder=2, label=f"{name}, measured ({curve.v_m_s.size})")[0])
        both = " (one line through both branches)" if split else ""
        lines.append(ax.plot(grid, curve.line_pa, color=color, lw=1.5, zorder=4,
                             label=f"{name}: p = {slope:.3g} Pa/(m/s) |v_in| + {icpt:.3g} Pa "
                                   f"(r2 {curve.r2:.3f}){both}")[0])
        if curve.band_pa is not None:  # 95 % band of the mean (OLS)
            ax.fill_between(grid, *curve.band_pa, color=color, alpha=0.25, zorder=1)
    ax.set_xlabel("impact velocity |v_in| (m/s)")
    ax.set_ylabel("sound pressure (Pa)")
    ax.set_title("Sound pressure against impact velocity, fitted laws with 95 % bands "
                 "(thesis Fig. 6-7)")
    ax.legend(handles=lines[::-1] + points[::-1], fontsize=8.5, loc="upper left")
    ax.grid(alpha=0.3)
    return [fig]
