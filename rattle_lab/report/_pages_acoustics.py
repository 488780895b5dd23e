"""The acoustics page: third-octave spectra, levels and loudness against impact velocity.

Draws :class:`._content_types.AcousticsContent`; nothing is computed here.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ._common import fmt, landscape_figure, table
from ._content_types import AcousticsContent


def acoustics_page(c: AcousticsContent) -> list[Figure]:
    """Third-octave spectra of rattle against background; level and loudness against velocity."""
    rows = list(c.rows)
    fig = landscape_figure()
    (ax_b, ax_l), (ax_n, ax_t) = fig.subplots(2, 2)
    # (a) band spectra: each run thin, energy mean over runs thick
    thin = {"rattle": "tab:red", "background": "0.45"}
    for what, f, db in c.band_traces:
        ax_b.plot(f, db, drawstyle="steps-mid", color=thin[what], lw=0.5, alpha=0.35)
    for what, color in (("rattle", "tab:red"), ("background", "0.2")):
        mean = c.band_means.get(what)
        if mean is not None:
            ax_b.plot(mean[0], mean[1], drawstyle="steps-mid", color=color, lw=1.8,
                      label=f"{what}: energy mean of {len(rows)} runs"
                      if what == "rattle" else f"{what} (no impacts): energy mean")
    ax_b.set_xscale("log")
    ax_b.set_xlabel("third-octave band centre frequency (Hz)")
    ax_b.set_ylabel("band level (dB re 20 uPa)")
    ax_b.set_title("Third-octave spectra (IEC 61260-1 class 1): rattle against background",
                   fontsize=9)
    ax_b.grid(alpha=0.3, which="both")
    if ax_b.get_legend_handles_labels()[0]:
        ax_b.legend(fontsize=7, loc="lower left")
    v, laeq, lafmax, n5, nmax = c.v_rms_m_s, c.laeq_db, c.lafmax_db, c.n5_sone, c.nmax_sone
    ok = np.isfinite(v) & (v > 0)
    # (b) levels against impact velocity, with the 20 dB/decade of a linear SPL law
    ax_l.plot(v[ok], laeq[ok], "o", color="tab:blue", label="LAeq of the run")
    ax_l.plot(v[ok], lafmax[ok], "^", color="tab:purple", label="LAFmax of the run")
    if c.level_guide is not None:
        ax_l.plot(*c.level_guide, "--", color="0.4",
                  label="20 dB per decade (p proportional to v, the SPL law)")
    ax_l.set_xscale("log")
    ax_l.set_xlabel("RMS impact velocity of the run (m/s)")
    ax_l.set_ylabel("A-weighted level (dB re 20 uPa)")
    ax_l.set_title("Level against impact velocity (IEC 61672-1)", fontsize=9)
    ax_l.grid(alpha=0.3, which="both")
    ax_l.legend(fontsize=7)
    # (c) loudness against impact velocity: is the SPL law a loudness law?
    ax_n.plot(v[ok], n5[ok], "o", color="tab:green", label="N5 (exceeded 5 % of the time)")
    ax_n.plot(v[ok], nmax[ok], "s", mfc="none", color="tab:green", label="Nmax")
    if c.loudness_guide is not None:
        ax_n.plot(*c.loudness_guide, "--", color="0.4",
                  label="N proportional to v^0.6 (SPL law with loudness doubling per 10 dB)")
    ax_n.set_xscale("log")
    ax_n.set_yscale("log")
    for axis in (ax_l.xaxis, ax_n.xaxis, ax_n.yaxis):
        _label_log_axis(axis)
    ax_n.set_xlabel("RMS impact velocity of the run (m/s)")
    ax_n.set_ylabel("ISO 532-1 loudness (sone)")
    ax_n.set_title(f"Loudness against impact velocity ({'/'.join(c.sound_fields)} field)",
                   fontsize=9)
    ax_n.grid(alpha=0.3, which="both")
    ax_n.legend(fontsize=7)
    # (d) the table
    ax_t.axis("off")
    cols = ["run", "LAeq", "LAFmax", "LCpeak", "N5", "Nmax", "S", "calibration"]
    table_rows = [[str(r["run_id"]), fmt(r["acoustics"].get("laeq_db"), ".1f"),
                   fmt(r["acoustics"].get("lafmax_db"), ".1f"),
                   fmt(r["acoustics"].get("lcpeak_db"), ".1f"),
                   fmt(r["acoustics"].get("loudness_n5_sone"), ".3g"),
                   fmt(r["acoustics"].get("loudness_max_sone"), ".3g"),
                   fmt(r["acoustics"].get("sharpness_acum"), ".2f"),
                   str((r.get("calibration") or {}).get("source", "declared"))]
                  for r in rows[:14]]
    table(ax_t, table_rows, cols, 7.0)
    psychoacoustics_inset(ax_t, rows)  # [issue 26] P, impacts/s, N above background vs v
    ax_t.set_title("Per run: levels in dB re 20 uPa, loudness in sone, sharpness (DIN 45692) "
                   "in acum", fontsize=9, loc="left")
    if len(rows) > 14:
        ax_t.text(0.0, 0.0, f"... and {len(rows) - 14} more runs", fontsize=7,
                  transform=ax_t.transAxes)
    from matplotlib.ticker import LogFormatterSciNotation, ScalarFormatter

    for ax in (ax_l, ax_n):  # log axes over less than a decade: plain numbers, no minor labels
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax_n.yaxis.set_major_formatter(ScalarFormatter())
    ax_n.yaxis.set_minor_formatter(NullFormatter())
    ax_b.xaxis.set_major_formatter(LogFormatterSciNotation())
    fig.suptitle("Sound levels, third-octave bands and loudness\n" + c.calibration_note,
                 fontsize=11)
    return [fig]


def _label_log_axis(axis: Any) -> None:
    """Numbers at 1, 2 and 5 per decade: a log axis inside one decade still has labels."""
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda value, _pos: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())


# [issue 26] psychoacoustic metrics against impact velocity: insets on the table's panel
def _psy_num(x: Any) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def psychoacoustics_inset(ax: Any, rows: list[dict[str, Any]]) -> None:
    """Three insets at the right of ``ax`` against each run's RMS impact velocity: impulse
    prominence and impacts per second; loudness above background and ECMA-418-2 loudness;
    ECMA-418-2 roughness and tonality.  Draws nothing when no run has the metrics."""
    v = np.array([_psy_num(r.get("v_rms_m_s")) for r in rows])
    ac = [r.get("acoustics") or {} for r in rows]
    col = {k: np.array([_psy_num(a.get(k)) for a in ac]) for k in (
        "impulse_prominence", "impacts_per_s", "loudness_above_background_sone",
        "loudness_ecma_sone", "roughness_asper", "tonality_tu")}
    ok = np.isfinite(v) & (v > 0)
    if not (ok & (np.isfinite(col["impulse_prominence"])
                  | np.isfinite(col["loudness_above_background_sone"]))).any():
        return
    from matplotlib.ticker import ScalarFormatter

    close = np.array(["background_too_close" in (a.get("psychoacoustic_flags") or [])
                      for a in ac])
    top = ax.inset_axes([0.76, 0.70, 0.2, 0.25])
    top.plot(v[ok], col["impulse_prominence"][ok], "o", ms=3, color="tab:red")
    top.axhline(5.0, color="0.5", lw=0.6, ls=":")   # K_I > 0 above P = 5
    top.set_ylabel("P (1)", fontsize=6, color="tab:red")
    rate = top.twinx()
    rate.plot(v[ok], col["impacts_per_s"][ok], "x", ms=3, color="tab:blue")
    rate.set_ylabel("impacts/s (1/s)", fontsize=6, color="tab:blue")
    top.set_title("impulse P (o; K_I > 0 above P = 5), impacts/s (x)", fontsize=5)
    mid = ax.inset_axes([0.76, 0.37, 0.2, 0.25], sharex=top)
    sel = ok & ~close
    mid.plot(v[sel], col["loudness_above_background_sone"][sel], "s", ms=3, color="tab:green")
    mid.plot(v[ok & close], col["loudness_above_background_sone"][ok & close], "s", ms=3,
             mfc="none", color="tab:green")
    mid.plot(v[ok], col["loudness_ecma_sone"][ok], "^", ms=3, color="tab:olive")
    mid.set_ylabel("loudness (sone)", fontsize=6)
    mid.set_title("N5 above bg. (s; hollow: too close), ECMA N (^)", fontsize=5)
    low = ax.inset_axes([0.76, 0.04, 0.2, 0.25], sharex=top)
    low.plot(v[ok], col["roughness_asper"][ok], "d", ms=3, color="tab:purple")
    low.plot(v[ok], col["tonality_tu"][ok], "v", ms=3, color="tab:brown")
    low.set_ylabel("R (asper_HMS), T (tu_HMS)", fontsize=5)
    low.set_title("ECMA-418-2 roughness (d), tonality (v)", fontsize=5)
    rate.patch.set_visible(False)   # (a figure-level twin: it must not hide the inset)
    low.set_xlabel("RMS impact velocity (m/s)", fontsize=6)
    for a in (top, rate, mid, low):
        a.tick_params(labelsize=5)
    top.set_xscale("log")
    for a in (top, mid):
        a.tick_params(labelbottom=False)
    low.xaxis.set_major_formatter(ScalarFormatter())
    low.xaxis.set_minor_formatter(NullFormatter())
