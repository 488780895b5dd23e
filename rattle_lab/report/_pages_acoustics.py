"""The acoustics page: third-octave spectra, levels and loudness against impact velocity.

Draws :class:`._content_types.AcousticsContent`; nothing is computed here.
"""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ._common import fmt, landscape_figure, table
from ._content_types import AcousticsContent, ListenerMetrics


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
    ax_l.set_xlabel("RMS impact velocity of the run (m/s)")
    ax_l.set_ylabel("A-weighted level (dB re 20 uPa)")
    ax_l.set_title("Level against impact velocity (IEC 61672-1)", fontsize=9)
    # (c) loudness against impact velocity: is the SPL law a loudness law?
    ax_n.plot(v[ok], n5[ok], "o", color="tab:green", label="N5 (exceeded 5 % of the time)")
    ax_n.plot(v[ok], nmax[ok], "s", mfc="none", color="tab:green", label="Nmax")
    if c.loudness_guide is not None:
        ax_n.plot(*c.loudness_guide, "--", color="0.4",
                  label="N proportional to v^0.6 (SPL law with loudness doubling per 10 dB)")
    ax_n.set_xlabel("RMS impact velocity of the run (m/s)")
    ax_n.set_ylabel("ISO 532-1 loudness (sone)")
    ax_n.set_title(f"Loudness against impact velocity ({'/'.join(c.sound_fields)} field)",
                   fontsize=9)
    finite_n = np.concatenate([n5[ok], nmax[ok]])
    finite_n = finite_n[np.isfinite(finite_n) & (finite_n > 0)]
    # log axes need data: a campaign where no run has an impact velocity (no impact found,
    # a campaign below the rattle onset) gets a note instead
    _log_axes(ax_l, v[ok] if np.isfinite(np.concatenate([laeq[ok], lafmax[ok]])).any()
              else v[:0], None)
    _log_axes(ax_n, v[ok] if finite_n.size else v[:0], finite_n)
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
    table(ax_t, table_rows, cols, 8.0, fill_width=True, row_scale=1.5)
    ax_t.set_title("Per run: levels in dB re 20 uPa, loudness in sone, sharpness (DIN 45692) "
                   "in acum", fontsize=9, loc="left")
    if len(rows) > 14:
        ax_t.text(0.0, 0.0, f"... and {len(rows) - 14} more runs", fontsize=7,
                  transform=ax_t.transAxes)
    from matplotlib.ticker import LogFormatterSciNotation

    ax_b.xaxis.set_major_formatter(LogFormatterSciNotation())
    fig.suptitle("Sound levels, third-octave bands and loudness\n" + c.calibration_note,
                 fontsize=11)
    if c.listener is None:
        return [fig]
    return [fig, listener_page(c.v_rms_m_s, c.listener)]


def listener_page(v: np.ndarray, m: ListenerMetrics) -> Figure:
    """Impulsiveness, loudness above the background, impact rate and the ECMA-418-2 metrics
    of each run against its RMS impact velocity."""
    fig = landscape_figure()
    (ax_i, ax_b), (ax_r, ax_e) = fig.subplots(2, 2)
    ok = np.isfinite(v) & (v > 0)
    # (a) impulsiveness: the level adjustment K_I (dB) and the prominence P
    ax_i.plot(v[ok], m.impulse_penalty_db[ok], "o", color="tab:red",
              label="K_I, level adjustment (dB)")
    ax_i.plot(v[ok], m.impulse_prominence[ok], "s", mfc="none", color="tab:orange",
              label="P, impulse prominence")
    ax_i.set_ylabel("K_I (dB); P (nondimensional)")
    ax_i.set_title("Impulsiveness (ISO/PAS 1996-3:2022, NT ACOU 112)", fontsize=9)
    # (b) the rattle's loudness above the background, bars: the background's spread
    ax_b.errorbar(v[ok], m.above_background_sone[ok],
                  yerr=np.where(np.isfinite(m.background_spread_sone[ok]),
                                m.background_spread_sone[ok], 0.0),
                  fmt="o", color="tab:green", capsize=2,
                  label="N5 rattle - N5 background (bar: background spread)")
    ax_b.axhline(0.0, color="0.4", lw=0.8)
    ax_b.set_ylabel("loudness above background (sone)")
    ax_b.set_title("Rattle loudness above the background (ISO 532-1 N5)", fontsize=9)
    # (c) impacts per second of the rattle episodes
    ax_r.plot(v[ok], m.impacts_per_s[ok], "D", color="tab:blue",
              label="impacts per second of rattle")
    ax_r.set_ylabel("impact rate (1/s)")
    ax_r.set_title("Impact rate in the rattle episodes", fontsize=9)
    for ax, shown in ((ax_i, (m.impulse_penalty_db, m.impulse_prominence)),
                      (ax_b, (m.above_background_sone,)), (ax_r, (m.impacts_per_s,))):
        _velocity_axis(ax, v, ok, shown)
    # (d) ECMA-418-2, where computed
    if m.ecma_note:
        ax_e.axis("off")
        ax_e.text(0.0, 0.6, "\n".join(textwrap.wrap(m.ecma_note, 60)), fontsize=9,
                  transform=ax_e.transAxes, va="top")
    else:
        for values, marker, label in ((m.loudness_ecma_sone, "o", "loudness (sone_HMS)"),
                                      (m.tonality_tu, "^", "tonality (tu_HMS)"),
                                      (m.roughness_asper, "s", "roughness (asper_HMS)")):
            ax_e.plot(v[ok], values[ok], marker, label=label)
        ax_e.set_ylabel("ECMA-418-2 value (unit in legend)")
        ax_e.set_title("ECMA-418-2 (hearing model of Sottek)", fontsize=9)
        _velocity_axis(ax_e, v, ok, (m.loudness_ecma_sone, m.tonality_tu, m.roughness_asper))
    flags = ("flags: " + ", ".join(m.flags)) if m.flags else "no psychoacoustic flag"
    fig.suptitle("Rattle as a listener hears it: impulsiveness, loudness above the background, "
                 "impact rate\n" + flags, fontsize=11)
    return fig


def _log_axes(ax: Any, v: np.ndarray, y: np.ndarray | None,
              note: str = "no run has an impact velocity and this value\n"
                          "(no impacts detected: see the summary's flags)") -> None:
    """Log velocity axis (and log ``y`` axis where ``y`` is given) labelled for reading;
    ``note`` instead where there is no point to draw (a log axis without data cannot draw)."""
    if not v.size:
        ax.text(0.5, 0.5, note, ha="center", va="center", fontsize=8, transform=ax.transAxes)
        ax.set_xticks([])
        ax.set_yticks([])
        return
    ax.set_xscale("log")
    _label_log_axis(ax.xaxis, v)
    if y is not None:
        ax.set_yscale("log")
        _label_log_axis(ax.yaxis, y)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)


def _velocity_axis(ax: Any, v: np.ndarray, ok: np.ndarray,
                   values: tuple[np.ndarray, ...]) -> None:
    """A log impact-velocity axis under ``values``; a note instead where no run has both a
    velocity and a value (a log axis cannot be drawn without data)."""
    ax.set_xlabel("RMS impact velocity of the run (m/s)")
    drawn = ok & np.any([np.isfinite(y) for y in values], axis=0)
    _log_axes(ax, v[drawn], None, note="no run has both an impact velocity and this value\n"
                                       "(see the flags above)")


def _label_log_axis(axis: Any, values: np.ndarray) -> None:
    """Plain numbers on a log axis, dense enough to read: 1, 2, 5 per decade over more
    than a decade of data, every integer multiple (20, 30, 40, 50) inside one."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values) & (values > 0)]
    decades = float(np.log10(values.max() / values.min())) if values.size > 1 else 0.0
    subs = (1.0, 2.0, 5.0) if decades > 1.0 else tuple(float(k) for k in range(1, 10))
    axis.set_major_locator(LogLocator(subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda value, _pos: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())

