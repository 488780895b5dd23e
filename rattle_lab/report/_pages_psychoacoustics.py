"""Issue 26's psychoacoustic metrics against impact velocity: two small insets on the acoustics page.

Self-contained: reads each row's ``acoustics`` dict (``fit --json``'s keys) and ``v_rms_m_s``
and draws into the lower right of the axes it is given; draws nothing when no run has
the metrics (a summary from an older version).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def _num(x: Any) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def psychoacoustics_inset(ax: Any, rows: list[dict[str, Any]]) -> None:
    """Impulse prominence and impacts per second (upper inset); loudness above background and
    the ECMA-418-2 values (lower inset), against each run's RMS impact velocity."""
    v = np.array([_num(r.get("v_rms_m_s")) for r in rows])
    ac = [r.get("acoustics") or {} for r in rows]
    col = {k: np.array([_num(a.get(k)) for a in ac]) for k in (
        "impulse_prominence", "impacts_per_s", "loudness_above_background_sone",
        "loudness_ecma_sone", "roughness_asper", "tonality_tu")}
    ok = np.isfinite(v) & (v > 0)
    if not (ok & (np.isfinite(col["impulse_prominence"])
                  | np.isfinite(col["loudness_above_background_sone"]))).any():
        return
    close = np.array(["background_too_close" in (a.get("psychoacoustic_flags") or [])
                      for a in ac])
    from matplotlib.ticker import NullFormatter, ScalarFormatter

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
    top.set_zorder(rate.get_zorder() + 1)   # the prominence above the rate
    top.patch.set_visible(False)
    low.set_xlabel("RMS impact velocity (m/s)", fontsize=6)
    for a in (top, rate, mid, low):
        a.tick_params(labelsize=5)
    top.set_xscale("log")
    for a in (top, mid):
        a.tick_params(labelbottom=False)
    low.xaxis.set_major_formatter(ScalarFormatter())
    low.xaxis.set_minor_formatter(NullFormatter())


__all__ = ["psychoacoustics_inset"]
