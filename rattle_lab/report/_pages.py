"""One function per report section: each returns figures, or raises :class:`Missing`.

Figures are bare :class:`matplotlib.figure.Figure` objects (Agg, no pyplot
state).  Every axis carries its unit.  Plot-only arithmetic lives here (the
eq. 3.4 band by the delta method, the OLS band of the SPL law, impacts per
forcing cycle); every fitted number comes from ``/results``.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ._data import ReportData

PAGE_SIZE_IN = (8.27, 11.69)  # A4 portrait
LANDSCAPE_IN = (11.69, 8.27)


class Missing(Exception):
    """A section cannot be drawn; the message says why (shown on the summary page)."""


def _fmt(x: Any, digits: str = ".4g") -> str:
    if x is None:
        return "-"
    try:
        xf = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "-" if not math.isfinite(xf) else format(xf, digits)


def _fits(data: ReportData) -> dict[str, Any]:
    if data.results is None:
        return {}
    return dict(data.results.summary.get("fits", {}))


def _grazing(data: ReportData) -> dict[str, Any] | None:
    g = _fits(data).get("grazing")
    if not isinstance(g, Mapping):
        return None
    if not all(isinstance(g.get(k), Mapping) for k in ("gap_m", "f_s_hz", "zeta")):
        return None
    return dict(g)


def _pval(g: Mapping[str, Any], name: str, default: float = float("nan")) -> float:
    p = g.get(name)
    if not isinstance(p, Mapping) or p.get("value") is None:
        return default
    return float(p["value"])


# --- summary -------------------------------------------------------------------------------

def summary_lines(data: ReportData, version: str) -> list[str]:
    """Text lines of the summary page (fitted values, flags, provenance)."""
    lines = [f"store: {data.store.name}", ""]
    fits = _fits(data)
    lines.append("Fitted parameters (value +/- standard error [95 % confidence interval], unit)")
    g = _grazing(data)
    names = {"gap_m": ("gap", 1e3, "mm"), "f_s_hz": ("f_s (modal frequency)", 1.0, "Hz"),
             "zeta": ("zeta (damping ratio)", 1.0, "1"),
             "participation": ("participation Q1/Q2", 1.0, "1")}
    if g is not None:
        for key, (label, scale, unit) in names.items():
            p = g.get(key)
            if not isinstance(p, Mapping):
                continue
            ci = p.get("ci") or [None, None]
            ci_txt = (f" [{_fmt(ci[0] * scale if ci[0] is not None else None)}, "
                      f"{_fmt(ci[1] * scale if ci[1] is not None else None)}]")
            fixed = "" if p.get("vary", True) else " (fixed)"
            val = None if p.get("value") is None else p["value"] * scale
            err = None if p.get("stderr") is None else p["stderr"] * scale
            lines.append(f"  {label} = {_fmt(val)} +/- {_fmt(err)}{ci_txt} {unit}{fixed}")
        for note in g.get("unidentifiable", []) or []:
            lines.append(f"  note: {note}")
    else:
        lines.append("  gap, f_s, zeta: not fitted ("
                     + str(data.results.summary.get("not_fitted", {}).get("grazing", "no results")
                           if data.results is not None else "no results") + ")")
    for key, label in (("restitution_ratio", "e (velocity ratios)"),
                       ("restitution_down", "e (disappearance thresholds)")):
        p = fits.get(key)
        if isinstance(p, Mapping):
            lines.append(f"  {label} = {_fmt(p.get('value'))} +/- {_fmt(p.get('stderr'))} 1")
        else:
            why = (data.results.summary.get("not_fitted", {}).get(key, "not fitted")
                   if data.results is not None else "no results")
            lines.append(f"  {label}: not fitted ({why})")
    for name in ("first", "max", "rms"):
        law = fits.get(f"spl_law_{name}")
        if not isinstance(law, Mapping):
            continue
        lin, db = law.get("linear", {}), law.get("db", {})
        sci = lin.get("slope_ci") or [None, None]
        cci = db.get("c_ci") or [None, None]
        label = {"first": "first peak", "max": "maximum peak", "rms": "RMS per impact"}[name]
        lines.append(f"  SPL law ({label}): p = {_fmt(lin.get('slope'))} [{_fmt(sci[0])}, "
                     f"{_fmt(sci[1])}] Pa/(m/s) * v + {_fmt(lin.get('intercept'))} Pa, "
                     f"r2 = {_fmt(lin.get('r2'), '.3f')}; L = 20 log10(v) + "
                     f"{_fmt(db.get('c_db'))} [{_fmt(cci[0])}, {_fmt(cci[1])}] dB re 20 uPa")
    lines.append("")
    lines.append("Data-quality flags (catalogue)")
    cat = data.catalogue
    flagged = cat[cat["flags"].astype(str) != ""]
    if len(flagged) == 0:
        lines.append("  none")
    for _, row in flagged.head(12).iterrows():
        lines.append(f"  {row['input_key']}/{row['run_id']}/{row['channel']}: {row['flags']}")
    if len(flagged) > 12:
        lines.append(f"  ... and {len(flagged) - 12} more flagged channels")
    lines.append("")
    lines.append("Provenance")
    lines.append(f"  report: rattle_lab {version}")
    if data.results is not None:
        prov = data.results.provenance
        lines.append(f"  results: {prov.get('function', '?')}, rattle_lab "
                     f"{prov.get('rattle_lab_version', data.results.rattle_lab_version)}, "
                     f"written {data.results.created_iso}")
    versions = sorted({str(e.get("rattle_lab_version", "?")) for e in data.provenance_log})
    lines.append(f"  ingest: {len(data.provenance_log)} logged call(s), rattle_lab "
                 f"{', '.join(versions) or '?'}")
    inputs = cat.drop_duplicates("input_key")
    for _, row in inputs.head(10).iterrows():
        lines.append(f"  input {row['input_key']}: {row['campaign_id']} ({row['source']}), "
                     f"sha256 {str(row['file_sha256'])[:32]}...")
    if len(inputs) > 10:
        lines.append(f"  ... and {len(inputs) - 10} more inputs")
    return lines


def text_page(title: str, lines: list[str]) -> Figure:
    """A page of monospaced text."""
    fig = Figure(figsize=PAGE_SIZE_IN)
    fig.text(0.06, 0.96, title, fontsize=15, weight="bold", va="top")
    y = 0.92
    for line in lines:
        fig.text(0.06, y, line, fontsize=7.5, family="monospace", va="top")
        y -= 0.0165
        if y < 0.05:
            fig.text(0.06, y, "... (truncated)", fontsize=7.5, family="monospace", va="top")
            break
    return fig


# --- rig and calibration ---------------------------------------------------------------------

def rig_page(data: ReportData) -> list[Figure]:
    """Rig facts and the calibration table of the channels."""
    if not data.records:
        raise Missing("no readable record in the store")
    fig = Figure(figsize=LANDSCAPE_IN)
    fig.text(0.04, 0.96, "Rig and calibration", fontsize=15, weight="bold", va="top")
    rig_units = {"plate_length_m": "m", "plate_width_m": "m", "plate_thickness_m": "m",
                 "striker_x_m": "m", "striker_y_m": "m", "gap_m": "m", "mic_distance_m": "m"}
    y = 0.91
    for rec in data.records[:3]:
        facts = ", ".join(f"{k} = {_fmt(v) if isinstance(v, float) else (v or '-')}"
                          f"{' ' + rig_units[k] if k in rig_units and v is not None else ''}"
                          for k, v in rec.rig.items())
        text = textwrap.fill(f"{rec.input_key} ({rec.campaign_id}, {rec.source}): {facts}", 200)
        fig.text(0.04, y, text, fontsize=7, va="top")
        y -= 0.025 * (text.count("\n") + 1) + 0.01
    cols = ["input", "channel", "quantity", "SI unit", "source unit", "scale to SI",
            "sensitivity", "rate (Hz)", "sensor", "serial", "calibrated", "range (SI)",
            "position (m)"]
    rows = [[c.input_key[-8:], c.name, c.quantity, c.units, c.source_units, _fmt(c.scale_to_si),
             c.sensitivity or "-", _fmt(c.sample_rate_hz, '.6g'), c.sensor_model or "-",
             c.sensor_serial or "-", c.calibration_date or "-", c.range_si or "-",
             c.position_m or "-"] for rec in data.records for c in rec.channels][:30]
    ax = fig.add_axes((0.02, 0.05, 0.96, y - 0.08))
    ax.axis("off")
    table = ax.table(cellText=rows, colLabels=cols, loc="upper center", cellLoc="left")
    table.auto_set_font_size(False)
    table.set_fontsize(6.5)
    table.scale(1.0, 1.3)
    return [fig]


# --- thresholds (Fig. 6-2, 6-3) ------------------------------------------------------------

def grazing_band_ms2(freq_hz: np.ndarray, g: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (3.4) at the fitted parameters and its 95 % band (delta method), m/s^2.

    The covariance is ``stderr_i stderr_j corr_ij`` of the varied parameters
    (as stored by the fit); the gradient is by central differences.
    """
    from ..linear import threshold_accel_ms2

    names = ("gap_m", "f_s_hz", "zeta", "participation")
    p0 = {n: _pval(g, n, 1.0 if n == "participation" else float("nan")) for n in names}

    def model(p: Mapping[str, float]) -> np.ndarray:
        return np.asarray(threshold_accel_ms2(freq_hz, p["gap_m"], p["f_s_hz"], abs(p["zeta"]),
                                              p["participation"]), dtype=float)

    y = model(p0)
    corr = g.get("correlation") or {}
    varied = list(corr.get("names") or [])
    matrix = np.asarray(corr.get("matrix") or np.zeros((0, 0)), dtype=float)
    err = np.array([float(g[n].get("stderr") or np.nan) for n in varied]) if varied else np.zeros(0)
    if not varied or matrix.shape != (len(varied), len(varied)) or not np.isfinite(err).all():
        return y, np.full_like(y, np.nan)
    cov = matrix * np.outer(err, err)
    jac = np.empty((len(varied), y.size))
    for i, n in enumerate(varied):
        h = 1e-6 * max(abs(p0[n]), 1e-12)
        hi, lo = dict(p0), dict(p0)
        hi[n] += h
        lo[n] -= h
        jac[i] = (model(hi) - model(lo)) / (2 * h)
    var = np.einsum("ik,ij,jk->k", jac, cov, jac)
    return y, 1.96 * np.sqrt(np.maximum(var, 0.0))


def threshold_page(data: ReportData) -> list[Figure]:
    """Onset/disappearance thresholds against frequency, eq. 3.4 fit and band, hysteresis."""
    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    th = data.results.thresholds
    f = np.asarray(th.get("freq_hz", []), dtype=float)
    up = np.asarray(th.get("up_ms2", np.full(f.size, np.nan)), dtype=float)
    down = np.asarray(th.get("down_ms2", np.full(f.size, np.nan)), dtype=float)
    if f.size == 0 or not (np.isfinite(up).any() or np.isfinite(down).any()):
        raise Missing("no ramp thresholds in /results/thresholds (needs amplitude_ramp_up/down "
                      "runs with a base accelerometer)")
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    ax, ax_h = fig.subplots(1, 2, width_ratios=(2, 1))
    g = _grazing(data)
    if g is not None:
        lo_f = min(f.min(), _pval(g, "f_s_hz", f.min())) - 2.0
        hi_f = max(f.max(), _pval(g, "f_s_hz", f.max())) + 2.0
        grid = np.linspace(max(lo_f, 0.1), hi_f, 200)
        y, half = grazing_band_ms2(grid, g)
        ax.plot(grid, y, color="k", lw=1.2,
                label=f"eq. (3.4) fit: gap {1e3 * _pval(g, 'gap_m'):.3g} mm, f_s "
                      f"{_pval(g, 'f_s_hz'):.4g} Hz, zeta {_pval(g, 'zeta'):.3g}")
        if np.isfinite(half).any():
            ax.fill_between(grid, y - half, y + half, color="0.6", alpha=0.35,
                            label="95 % confidence band (delta method)")
    ok = np.isfinite(up) & np.isfinite(down)
    if ok.any():
        ax.fill_between(f[ok], down[ok], up[ok], color="tab:orange", alpha=0.25,
                        label="hysteresis (onset - disappearance)")
    ax.plot(f, up, "^", color="tab:red", label="onset (ramp up)")
    ax.plot(f, down, "v", color="tab:blue", label="disappearance (ramp down)")
    ax.set_xlabel("excitation frequency (Hz)")
    ax.set_ylabel("base acceleration amplitude at threshold (m/s^2)")
    ax.set_title("Impact thresholds (thesis Fig. 6-2, 6-3 a)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    ax_h.bar(f, up - down, width=0.6 * (np.min(np.diff(f)) if f.size > 1 else 1.0),
             color="tab:orange")
    ax_h.set_xlabel("excitation frequency (Hz)")
    ax_h.set_ylabel("hysteresis, onset - disappearance (m/s^2)")
    ax_h.set_title("Hysteresis")
    ax_h.grid(alpha=0.3)
    if g is None:
        data.missing["eq. 3.4 fit curve"] = (data.results.summary.get("not_fitted", {})
                                             .get("grazing", "grazing fit absent"))
    return [fig]


# --- impact patterns (Fig. 6-5) ------------------------------------------------------------

def _run_info(data: ReportData, key: str, run_id: str) -> dict[str, Any]:
    for rec in data.records:
        if rec.input_key == key:
            return rec.runs.get(run_id, {})
    return {}


def _cycle_counts(t_s: np.ndarray, freq_hz: float, t0: float, duration_s: float) -> np.ndarray:
    n_cycles = int(math.floor(duration_s * freq_hz))
    k = np.floor((np.asarray(t_s, dtype=float) - t0) * freq_hz).astype(int)
    k = k[(k >= 0) & (k < n_cycles)]
    return np.bincount(k, minlength=n_cycles)


def pattern_page(data: ReportData) -> list[Figure]:
    """Impacts per forcing cycle over frequency and base-acceleration amplitude."""
    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    cat = data.catalogue
    pts: list[tuple[float, float, int]] = []
    units = set()
    for (key, run_id), r in sorted(data.results.runs.items()):
        if r.get("status") != "ok" or "t_s" not in r:
            continue
        info = _run_info(data, key, run_id)
        f = float(r.get("freq_hz", np.nan))
        lvl = info.get("level")
        if not (math.isfinite(f) and f > 0) or lvl is None:
            continue
        rows = cat[(cat["input_key"] == key) & (cat["run_id"] == run_id)]
        if len(rows) == 0:
            continue
        t0 = float(np.nan_to_num(rows["start_time_s"].iloc[0]))
        duration = float(rows["duration_s"].max())
        counts = _cycle_counts(r["t_s"], f, t0, duration)
        if counts.size == 0:
            continue
        lvl_end = info.get("level_end")
        levels = np.linspace(float(lvl), float(lvl if lvl_end is None else lvl_end), counts.size)
        shift = {"amplitude_ramp_up": -0.12, "amplitude_ramp_down": 0.12}.get(
            str(r.get("protocol", "")), 0.0)
        units.add(info.get("level_units") or "?")
        pts.extend((f + shift, lv, int(c)) for lv, c in zip(levels, counts))
    if not pts:
        raise Missing("no analysed run with an excitation frequency and level")
    arr = np.array(pts, dtype=float)
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    ax = fig.add_subplot()
    classes = ((0, "no impact", "0.8"), (1, "1 impact per cycle", "tab:blue"),
               (2, "2 impacts per cycle", "tab:orange"), (3, ">= 3 impacts per cycle", "tab:red"))
    for n, label, color in classes:
        sel = arr[:, 2] == n if n < 3 else arr[:, 2] >= 3
        if sel.any():
            ax.scatter(arr[sel, 0], arr[sel, 1], s=6, color=color, label=label)
    ax.set_xlabel("excitation frequency (Hz) (ramp up left, ramp down right of each frequency)")
    ax.set_ylabel(f"nominal base-acceleration amplitude ({', '.join(sorted(units))})")
    ax.set_title("Impact patterns per forcing cycle (thesis Fig. 6-5)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return [fig]


# --- waveforms (Fig. 6-4, 6-6) -------------------------------------------------------------

def waveform_page(data: ReportData, *, n_examples: int = 2, n_cycles: int = 5) -> list[Figure]:
    """Short windows of plate acceleration, velocity and sound pressure with events marked."""
    from ..ingest import open_stored_record

    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    candidates = [(k, r) for k, r in sorted(data.results.runs.items())
                  if r.get("status") == "ok" and int(r.get("n_impacts", 0)) > 0
                  and math.isfinite(float(r.get("freq_hz", np.nan)))]
    # steady runs first (thesis Fig. 6-4 shows dwells), then the rest
    candidates.sort(key=lambda kr: (kr[1].get("protocol") != "sine_dwell", kr[0]))
    chosen = candidates[:n_examples]
    if not chosen:
        raise Missing("no analysed run with impacts")
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    axes = fig.subplots(3, len(chosen), squeeze=False, sharex="col")
    for col, ((key, run_id), r) in enumerate(chosen):
        f = float(r["freq_hz"])
        t_imp = np.asarray(r.get("t_s", []), dtype=float)
        t_mid = float(np.median(t_imp))
        with open_stored_record(data.store, key) as record:
            run = record.run(run_id)
            by_q: dict[str, Any] = {}
            for ch in run.channels:
                by_q.setdefault(ch.quantity, ch)
            rows = (("plate_acceleration", "plate acceleration (m/s^2)"),
                    ("plate_velocity", "plate velocity (m/s)"),
                    ("sound_pressure", "sound pressure (Pa)"))
            for row, (quantity, label) in enumerate(rows):
                ax = axes[row, col]
                ch = by_q.get(quantity)
                ax.set_ylabel(label)
                ax.grid(alpha=0.3)
                if ch is None or not ch.sample_rate_hz:
                    ax.text(0.5, 0.5, f"no {quantity} channel", ha="center",
                            transform=ax.transAxes)
                    continue
                fs = float(ch.sample_rate_hz)
                t0 = float(ch.start_time_s or 0.0)
                i0 = max(0, int(round((t_mid - t0 - n_cycles / (2 * f)) * fs)))
                i1 = min(ch.n_samples, i0 + int(round(n_cycles / f * fs)))
                x = ch.read(i0, i1)
                t = t0 + np.arange(i0, i1) / fs
                ax.plot(t, x, lw=0.7, color="0.2")
                win = (t_imp >= t[0]) & (t_imp <= t[-1]) if t.size else t_imp < 0
                if quantity == "plate_velocity" and win.any():
                    ax.plot(t_imp[win], np.interp(t_imp[win], t, x), "o", mfc="none",
                            color="tab:red", label="detected impact")
                    ax.legend(fontsize=7, loc="upper right")
                elif quantity == "plate_acceleration" and win.any():
                    for ti in t_imp[win]:
                        ax.axvline(ti, color="tab:red", lw=0.6, alpha=0.6)
                elif quantity == "sound_pressure" and "t_first_s" in r:
                    for tk, pk, mk, lab in (("t_first_s", "p_first_pa", "o", "first peak"),
                                            ("t_max_s", "p_max_pa", "x", "maximum peak")):
                        tt = np.asarray(r[tk], dtype=float)
                        pp = np.asarray(r[pk], dtype=float)
                        sel = np.isfinite(tt) & (tt >= t[0]) & (tt <= t[-1]) if t.size else tt < 0
                        ax.plot(tt[sel], pp[sel], mk, mfc="none", label=lab)
                    ax.legend(fontsize=7, loc="upper right")
        axes[0, col].set_title(f"{run_id} ({r.get('protocol', '')}, {f:g} Hz, pattern "
                               f"{r.get('pattern') or '-'})", fontsize=9)
        axes[2, col].set_xlabel("time (s)")
    fig.suptitle("Example waveforms with detected impacts and sound peaks "
                 "(thesis Fig. 6-4, 6-6)")
    return [fig]


# --- SPL law (Fig. 6-7) --------------------------------------------------------------------

def spl_page(data: ReportData) -> list[Figure]:
    """Sound pressure against impact velocity with the fitted linear laws and 95 % bands."""
    from scipy import stats

    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    fits = _fits(data)
    laws = {n: fits.get(f"spl_law_{n}") for n in ("first", "max", "rms")}
    if not any(isinstance(v, Mapping) for v in laws.values()):
        why = data.results.summary.get("not_fitted", {}).get("spl_law_first", "not fitted")
        raise Missing(f"no SPL law in /results ({why})")
    v_all: dict[str, list[np.ndarray]] = {"first": [], "max": [], "rms": []}
    p_all: dict[str, list[np.ndarray]] = {"first": [], "max": [], "rms": []}
    for r in data.results.runs.values():
        if r.get("status") != "ok" or "v_in_m_s" not in r or "p_first_pa" not in r:
            continue
        v = np.abs(np.asarray(r["v_in_m_s"], dtype=float))
        for n, key in (("first", "p_first_pa"), ("max", "p_max_pa"), ("rms", "p_rms_pa")):
            if key in r and np.asarray(r[key]).shape == v.shape:
                v_all[n].append(v)
                p_all[n].append(np.abs(np.asarray(r[key], dtype=float)))
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    ax = fig.add_subplot()
    colors = {"first": "tab:blue", "max": "tab:red", "rms": "tab:green"}
    for n, law in laws.items():
        if not isinstance(law, Mapping) or not v_all[n]:
            continue
        v, p = np.concatenate(v_all[n]), np.concatenate(p_all[n])
        ok = np.isfinite(v) & np.isfinite(p) & (v > 0) & (p > 0)
        v, p = v[ok], p[ok]
        ax.plot(v, p, ".", ms=2.5, alpha=0.5, color=colors[n], label=f"{n}, measured")
        lin = law.get("linear", {})
        slope, icpt = float(lin.get("slope", np.nan)), float(lin.get("intercept", np.nan))
        grid = np.linspace(0.0, float(v.max()) * 1.05 if v.size else 1.0, 100)
        ax.plot(grid, slope * grid + icpt, color=colors[n], lw=1.3,
                label=f"{n}: p = {slope:.3g} Pa/(m/s) v + {icpt:.3g} Pa (r2 "
                      f"{float(lin.get('r2', np.nan)):.3f})")
        if v.size > 2:  # 95 % band of the mean (OLS), for the plot only
            resid = p - (slope * v + icpt)
            s = math.sqrt(float(np.sum(resid**2)) / (v.size - 2))
            sxx = float(np.sum((v - v.mean()) ** 2))
            if sxx > 0:
                half = stats.t.ppf(0.975, v.size - 2) * s * np.sqrt(
                    1.0 / v.size + (grid - v.mean()) ** 2 / sxx)
                ax.fill_between(grid, slope * grid + icpt - half, slope * grid + icpt + half,
                                color=colors[n], alpha=0.2)
    ax.set_xlabel("impact velocity |v_in| (m/s)")
    ax.set_ylabel("sound pressure (Pa)")
    ax.set_title("Sound pressure against impact velocity, fitted laws with 95 % bands "
                 "(thesis Fig. 6-7)")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    return [fig]


# --- model predictions ---------------------------------------------------------------------

def _nondim(g: Mapping[str, Any], f_hz: np.ndarray, a_ms2: np.ndarray) -> tuple[np.ndarray,
                                                                                np.ndarray]:
    # Eq. (2.28) omega = f / f_s and eq. (2.31) F = (Q1/Q2) A / (omega_s^2 h)
    f_s, gap = _pval(g, "f_s_hz"), _pval(g, "gap_m")
    q = _pval(g, "participation", 1.0)
    w_s = 2 * np.pi * f_s
    return f_hz / f_s, q * a_ms2 / (w_s**2 * gap)


def model_pages(data: ReportData, *, n_sweep: int = 24, max_freqs: int = 6) -> list[Figure]:
    """Bifurcation sets and F sweeps of the SDF model at the fitted parameters (coarse grids)."""
    from ..analysis import bifurcation_sets, sweep_up_down
    from ..sdf import SDFParams

    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    g = _grazing(data)
    if g is None:
        raise Missing("needs the grazing fit (gap, f_s, zeta): "
                      + str(data.results.summary.get("not_fitted", {}).get("grazing", "absent")))
    fits = _fits(data)
    e_fit = fits.get("restitution_ratio")
    if not isinstance(e_fit, Mapping) or e_fit.get("value") is None:
        raise Missing("needs a fitted coefficient of restitution e")
    zeta = abs(_pval(g, "zeta"))
    e = min(max(float(e_fit["value"]), 0.0), 1.0)
    if not (math.isfinite(zeta) and zeta > 0 and math.isfinite(_pval(g, "gap_m"))):
        raise Missing(f"fitted zeta {zeta} or gap unusable for the model")
    th = data.results.thresholds
    f = np.asarray(th.get("freq_hz", []), dtype=float)
    up = np.asarray(th.get("up_ms2", np.full(f.size, np.nan)), dtype=float)
    down = np.asarray(th.get("down_ms2", np.full(f.size, np.nan)), dtype=float)
    w_up, F_up = _nondim(g, f, up)
    w_dn, F_dn = _nondim(g, f, down)
    finite_w = w_up[np.isfinite(w_up)]
    w_lo = float(min(0.8, finite_w.min() - 0.05)) if finite_w.size else 0.8
    w_hi = float(max(1.2, finite_w.max() + 0.05)) if finite_w.size else 1.2
    F_all = np.concatenate([F_up[np.isfinite(F_up)], F_dn[np.isfinite(F_dn)]])
    F_hi = float(max(2.0 * F_all.max(), 4 * zeta)) if F_all.size else 0.2
    sets = bifurcation_sets((1, 2), omega_range=(max(w_lo, 0.05), w_hi), F_range=(0.0, F_hi),
                            zeta=zeta, e=e, n_omega=61, n_F=41, n_v=31)
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    ax = fig.add_subplot()
    for k, (n, color) in enumerate(zip(sets.ns, ("tab:blue", "tab:orange"))):
        if sets.exists[k].any():
            ax.contourf(sets.omega, sets.F, sets.exists[k].astype(float), levels=[0.5, 1.5],
                        colors=[color], alpha=0.15)
        if sets.stable[k].any():
            ax.contourf(sets.omega, sets.F, sets.stable[k].astype(float), levels=[0.5, 1.5],
                        colors=[color], alpha=0.4)
        for c in sets.curves_of(n):
            if c.kind != "grazing":
                ax.plot(c.omega, c.F, color=color, lw=1.0,
                        ls={"saddle-node": "--", "period-doubling": ":"}.get(c.kind, "-."))
        ax.plot([], [], color=color, lw=6, alpha=0.4, label=f"1/{n} stable (light: exists)")
    ax.plot(sets.grazing.omega, sets.grazing.F, color="k", lw=1.4, label="grazing, eq. (3.4)")
    ax.plot(w_up, F_up, "^", color="tab:red", label="measured onset")
    ax.plot(w_dn, F_dn, "v", color="tab:blue", label="measured disappearance")
    ax.set_xlim(sets.omega[0], sets.omega[-1])
    ax.set_ylim(sets.F[0], sets.F[-1])
    ax.set_xlabel("forcing frequency omega = f / f_s (nondimensional)")
    ax.set_ylabel("forcing amplitude F = Q A / (omega_s^2 h) (nondimensional)")
    ax.set_title(f"Model bifurcation sets at the fitted zeta = {zeta:.3g}, e = {e:.3g}, with\n"
                 "the measured operating points (dashed: saddle-node, dotted: period-doubling)")
    ax.legend(fontsize=7, loc="upper left")
    figs = [fig]
    # F sweeps up and down at each measured frequency: model onset/disappearance
    sel = np.flatnonzero(np.isfinite(w_up) | np.isfinite(w_dn))[:max_freqs]
    if sel.size:
        grid = np.linspace(F_hi / n_sweep, F_hi, n_sweep)
        on, off = np.full(sel.size, np.nan), np.full(sel.size, np.nan)
        for i, j in enumerate(sel):
            s_up, s_dn = sweep_up_down("F", grid, base=SDFParams(F=grid[0], omega=float(
                f[j] / _pval(g, "f_s_hz")), zeta=zeta, e=e), cycles=60, discard=40, n_max=6,
                lyapunov="none")
            hit_up = [p.value for p in s_up.points if p.impact_velocities.size]
            hit_dn = [p.value for p in s_dn.points if p.impact_velocities.size]
            on[i] = min(hit_up) if hit_up else np.nan
            off[i] = min(hit_dn) if hit_dn else np.nan
        w_s = 2 * np.pi * _pval(g, "f_s_hz")
        scale = w_s**2 * _pval(g, "gap_m") / _pval(g, "participation", 1.0)
        fig2 = Figure(figsize=LANDSCAPE_IN, layout="constrained")
        ax2 = fig2.add_subplot()
        ax2.plot(f[sel], on * scale, "s-", color="tab:red", mfc="none",
                 label="model onset (F sweep up)")
        ax2.plot(f[sel], off * scale, "s--", color="tab:blue", mfc="none",
                 label="model disappearance (F sweep down)")
        ax2.plot(f, up, "^", color="tab:red", label="measured onset")
        ax2.plot(f, down, "v", color="tab:blue", label="measured disappearance")
        ax2.set_xlabel("excitation frequency (Hz)")
        ax2.set_ylabel("base acceleration amplitude at threshold (m/s^2)")
        ax2.set_title(f"Model sweeps ({n_sweep} amplitudes up to {F_hi * scale:.3g} m/s^2, "
                      "60 cycles each) against the measured thresholds")
        ax2.legend(fontsize=8)
        ax2.grid(alpha=0.3)
        figs.append(fig2)
    return figs
