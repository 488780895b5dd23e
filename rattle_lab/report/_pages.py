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
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from rattle_lab.fit import Estimate, FitSummary, Fits, GrazingSummary, RatioRestitution
from ._data import ReportData

PAGE_SIZE_IN = (8.27, 11.69)  # A4 portrait
LANDSCAPE_IN = (11.69, 8.27)


class Missing(Exception):
    """A section cannot be drawn; the message says why (shown on the summary page)."""


def landscape_figure() -> Figure:
    """An A4 landscape figure, constrained layout, with the bottom 2.5 % kept for the footer."""
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    fig.get_layout_engine().set(rect=(0.0, 0.025, 1.0, 0.975))  # type: ignore[union-attr, call-arg]
    return fig


def _fmt(x: Any, digits: str = ".4g") -> str:
    if x is None:
        return "-"
    try:
        xf = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "-" if not math.isfinite(xf) else format(xf, digits)


def _fits(data: ReportData) -> Fits:
    return data.summary.fits if data.summary is not None else Fits()


def _grazing(data: ReportData) -> GrazingSummary | None:
    return _fits(data).grazing


def _pval(g: GrazingSummary, name: str, default: float = float("nan")) -> float:
    value = g.parameters()[name].value
    return default if value is None else value


# --- summary -------------------------------------------------------------------------------

#: Characters per line of the monospaced text pages (7.5 pt DejaVu Sans Mono on A4 portrait).
TEXT_WIDTH = 112
_COLS = (("quantity", 34), ("value", 11), ("std. error", 11), ("95 % CI", 25), ("unit", 0))


def _t_ci(value: Any, stderr: Any, dof: int) -> tuple[float | None, float | None]:
    """Student-t 95 % interval ``value +/- t(0.975, dof) stderr`` (None where undefined)."""
    from scipy import stats

    try:
        v, e = float(value), float(stderr)
    except (TypeError, ValueError):
        return None, None
    if dof < 1 or not (math.isfinite(v) and math.isfinite(e)):
        return None, None
    half = float(stats.t.ppf(0.975, dof)) * e
    return v - half, v + half


def _row(quantity: str, value: Any = None, stderr: Any = None,
         ci: tuple[Any, Any] | None = None, unit: str = "", note: str = "",
         scale: float = 1.0) -> list[str]:
    """One aligned row of the parameter table (and its note, wrapped, below it)."""
    def sc(x: Any) -> Any:
        return None if x is None else float(x) * scale

    ci_txt = "-" if ci is None or None in ci else f"[{_fmt(sc(ci[0]))}, {_fmt(sc(ci[1]))}]"
    err_txt = stderr if isinstance(stderr, str) else _fmt(sc(stderr))
    cells = (quantity, _fmt(sc(value), ".5g"), err_txt, ci_txt, unit)
    line = "  " + " ".join(c.ljust(w) if w else c for c, (_, w) in zip(cells, _COLS))
    out = [line.rstrip()]
    if note:
        out.extend(textwrap.wrap(note, TEXT_WIDTH, initial_indent="      ",
                                 subsequent_indent="      "))
    return out


def _fit_summary(data: ReportData) -> FitSummary:
    """The typed summary of a report with results (gather sets both or neither)."""
    if data.summary is None:
        raise Missing(data.missing.get("results", "no results"))
    return data.summary


def _not_fitted(data: ReportData, key: str) -> str:
    if data.summary is None:
        return data.missing.get("results", "no results")
    return " ".join(data.summary.not_fitted.get(key, "not fitted").split())


def parameter_lines(data: ReportData) -> list[str]:
    """The table of fitted parameters: value, standard error, 95 % interval, unit."""
    header = "  " + " ".join(n.ljust(w) if w else n for n, w in _COLS)
    lines = [header, "  " + "-" * (len(header) - 2)]
    fits = _fits(data)
    g = _grazing(data)
    names = {"gap_m": ("gap h", 1e3, "mm"), "f_s_hz": ("f_s (modal frequency)", 1.0, "Hz"),
             "zeta": ("zeta (damping ratio)", 1.0, "1"),
             "participation": ("participation Q1/Q2", 1.0, "1")}
    if g is not None:
        for key, (label, scale, unit) in names.items():
            p = g.parameters()[key]
            if not p.vary:
                lines += _row(label, p.value, "fixed", None, unit, scale=scale)
                continue
            lines += _row(label, p.value, p.stderr, (p.ci_low, p.ci_high), unit, scale=scale)
        notes = list(g.unidentifiable)
        if g.outliers_hz:
            notes.append("thresholds left out as outliers at " + ", ".join(
                f"{_fmt(f)} Hz" for f in g.outliers_hz))
        for note in notes:
            lines += textwrap.wrap("note: " + note, TEXT_WIDTH, initial_indent="      ",
                                   subsequent_indent="      ")
    else:
        lines += _row("gap h, f_s, zeta", note="not fitted: " + _not_fitted(data, "grazing"))
    not_fitted = data.summary.not_fitted if data.summary is not None else {}
    for key, label, what in (("damping_ramp", "zeta (ramp model)", "upward ramps"),
                             ("restitution_ratio", "e (velocity ratios)", "impacts"),
                             ("restitution_down", "e (disappearance thresholds)", "thresholds")):
        est: Estimate | None = getattr(fits, key)
        if est is None:
            if key != "damping_ramp" or key in not_fitted:  # an optional fit: only if tried
                lines += _row(label, note="not fitted: " + _not_fitted(data, key))
            continue
        n = int(getattr(est, "n", 0))
        method = getattr(est, "method", "")
        note = f"from {n} {what}" + (f" ({method})" if method else "")
        if isinstance(est, RatioRestitution) and est.median is not None:
            note += f"; median {_fmt(est.median)}, scatter (std) {_fmt(est.std)}"
        err = est.stderr
        if err is not None and est.value is not None and err > abs(est.value):
            note += "; NOT IDENTIFIED: the standard error exceeds the value"
        for extra in est.notes:
            note += f"; {extra}"
        ci: tuple[float | None, float | None] = (est.ci_low, est.ci_high)
        if None in ci:
            ci = _t_ci(est.value, err, n - 1)
        lines += _row(label, est.value, err, ci, "1", note)
    for name, label in (("first", "first peak"), ("max", "maximum peak"),
                        ("rms", "RMS per impact")):
        law = fits.spl_law(name)
        if law is None:
            lines += _row(f"SPL law, {label}",
                          note="not fitted: " + _not_fitted(data, f"spl_law_{name}"))
            continue
        lin, db = law.linear, law.db
        lines += _row(f"SPL {label}: slope", lin.slope, None,
                      (lin.slope_ci_low, lin.slope_ci_high), "Pa/(m/s)",
                      f"p = slope * |v_in| + intercept, r2 = {_fmt(lin.r2, '.3f')}, "
                      f"{lin.n} impacts")
        lines += _row(f"SPL {label}: intercept", lin.intercept, None,
                      (lin.intercept_ci_low, lin.intercept_ci_high), "Pa")
        lines += _row(f"SPL {label}: C", db.c_db, None,
                      (db.c_ci_low, db.c_ci_high), "dB re 20 uPa at 1 m/s",
                      f"L = 20 log10(|v_in| / (1 m/s)) + C; free-slope check k = "
                      f"{_fmt(db.k_db_per_decade, '.3g')} dB/decade (20 for a linear law)")
    return lines


def wrapped(line: str) -> list[str]:
    """``line`` wrapped to :data:`TEXT_WIDTH` characters, continuation lines indented."""
    if len(line) <= TEXT_WIDTH:
        return [line]
    indent = " " * (len(line) - len(line.lstrip()) + 4)
    return textwrap.wrap(line, TEXT_WIDTH, subsequent_indent=indent, break_long_words=True)


def summary_lines(data: ReportData, version: str) -> list[str]:
    """Text lines of the summary page (fitted values, flags, provenance), <= TEXT_WIDTH wide."""
    lines = [f"store: {data.store.name}"]
    if data.summary is not None:
        summ = data.summary
        n_imp = sum(r.n_impacts for r in summ.runs)
        lines.append(f"runs: {summ.n_runs} ({summ.n_ok} analysed, "
                     f"{len(summ.skipped)} skipped), {n_imp} impacts detected")
    lines += ["", "Fitted parameters (95 % CI: as the fit gives it, e.g. profile likelihood for "
              "eq. (3.4); else Student t from the standard error; OLS t for the SPL laws)"]
    lines += parameter_lines(data)
    lines += ["", "Data-quality flags (catalogue)"]
    cat = data.catalogue
    flagged = cat[cat["flags"].astype(str) != ""]
    negative = negative_hysteresis(data)
    if len(flagged) == 0 and not negative:
        lines.append("  none")
    for f_hz, h in negative:
        lines.append(f"  thresholds: NEGATIVE hysteresis at {f_hz:g} Hz ({h:.3g} m/s^2): the "
                     "disappearance lies above the onset")
    for _, row in flagged.head(12).iterrows():
        lines.append(f"  {row['input_key']}/{row['run_id']}/{row['channel']}: {row['flags']}")
    if len(flagged) > 12:
        lines.append(f"  ... and {len(flagged) - 12} more flagged channels")
    if data.summary is not None:  # issue 15: the fit's own flags (e.g. participation_assumed)
        part = data.summary.participation
        for flag in data.summary.data_quality:
            lines.append(f"  fit: {flag} (participation {part.value if part else None} from "
                         f"{part.source if part else '?'})" if flag.startswith("participation")
                         else f"  fit: {flag}")
    skipped = data.summary.skipped if data.summary is not None else ()
    for item in skipped[:6]:
        lines.append(f"  run skipped by the fit: {item.input_key}/{item.run_id}: "
                     f"{item.reason}")
    lines += ["", "Provenance", f"  report: rattle_lab {version} (rattle_lab.report.write_report)"]
    if data.results is not None:
        prov = data.results.provenance
        via = f" via {prov['via']} ({prov.get('pipeline', '')})" if prov.get("via") else ""
        lines.append(f"  results: {prov.get('function', '?')}{via}, rattle_lab "
                     f"{prov.get('rattle_lab_version', data.results.rattle_lab_version)}, "
                     f"written {data.results.created_iso}")
        params = prov.get("parameters") or {}
        for table in ("detect", "fit"):
            if isinstance(params.get(table), Mapping):
                text = ", ".join(f"{k} = {v}" for k, v in sorted(params[table].items()))
                lines.append(f"  [{table}] {text or '(defaults)'}")
    versions = sorted({str(e.get("rattle_lab_version", "?")) for e in data.provenance_log})
    lines.append(f"  ingest: {len(data.provenance_log)} logged call(s), rattle_lab "
                 f"{', '.join(versions) or '?'}")
    inputs = cat.drop_duplicates("input_key")
    hash_col = "file_hash" if "file_hash" in cat.columns else "file_sha256"
    for _, row in inputs.head(10).iterrows():
        lines.append(f"  input {row['input_key']}: {row['file']} ({row['campaign_id']}, "
                     f"{row['source']}), {row[hash_col]}")
    if len(inputs) > 10:
        lines.append(f"  ... and {len(inputs) - 10} more inputs")
    return [w for line in lines for w in wrapped(line)]


def text_pages(title: str, lines: list[str]) -> list[Figure]:
    """Pages of monospaced text (continued on further pages when long)."""
    per_page = 56
    chunks = [lines[i:i + per_page] for i in range(0, max(len(lines), 1), per_page)] or [[]]
    figs = []
    for k, chunk in enumerate(chunks):
        fig = Figure(figsize=PAGE_SIZE_IN)
        fig.text(0.06, 0.96, title + (" (continued)" if k else ""), fontsize=14,
                 weight="bold", va="top")
        y = 0.925
        for line in chunk:
            fig.text(0.06, y, line, fontsize=7.5, family="monospace", va="top")
            y -= 0.0155
        figs.append(fig)
    return figs


def text_page(title: str, lines: list[str]) -> Figure:
    """A page of monospaced text (the first page of :func:`text_pages`)."""
    return text_pages(title, lines)[0]


# --- rig and calibration ---------------------------------------------------------------------

_RIG_UNITS = {"plate_length_m": "m", "plate_width_m": "m", "plate_thickness_m": "m",
              "striker_x_m": "m", "striker_y_m": "m", "gap_m": "m", "mic_distance_m": "m"}


def _table(ax: Any, rows: list[list[str]], cols: list[str], fontsize: float) -> None:
    table = ax.table(cellText=rows, colLabels=cols, loc="upper left", cellLoc="left",
                     colLoc="left")
    table.auto_set_font_size(False)
    table.set_fontsize(fontsize)
    table.auto_set_column_width(list(range(len(cols))))
    table.scale(1.0, 1.35)
    for (r, _), cell in table.get_celld().items():
        if r == 0:
            cell.set_text_props(weight="bold")
            cell.set_facecolor("0.92")


def rig_page(data: ReportData) -> list[Figure]:
    """Rig facts and the calibration table of the channels."""
    if not data.records:
        raise Missing("no readable record in the store")
    fig = Figure(figsize=LANDSCAPE_IN)
    fig.text(0.03, 0.96, "Rig and calibration", fontsize=15, weight="bold", va="top")
    recs = data.records[:3]
    fact_rows = []
    for key in recs[0].rig:
        label = key[:-2] + " (m)" if key in _RIG_UNITS else key
        vals = [(_fmt(r.rig.get(key)) if isinstance(r.rig.get(key), float)
                 else str(r.rig.get(key) or "-")) for r in recs]
        fact_rows.append([label.replace("_", " "), *vals])
    ax_rig = fig.add_axes((0.03, 0.62, 0.94, 0.3))
    ax_rig.axis("off")
    _table(ax_rig, fact_rows, ["rig", *[f"{r.input_key} ({r.campaign_id}, {r.source})"
                                        for r in recs]], 7.5)
    if len(data.records) > 3:
        fig.text(0.03, 0.6, f"... and {len(data.records) - 3} more records (not shown)",
                 fontsize=7)
    cols = ["input", "channel", "quantity", "SI unit", "source unit", "scale to SI",
            "sensitivity", "rate (Hz)", "sensor", "serial", "calibrated", "range (SI unit)",
            "position (m)"]
    rows = [[c.input_key[-8:], c.name, c.quantity, c.units, c.source_units or "-",
             _fmt(c.scale_to_si), c.sensitivity or "-", _fmt(c.sample_rate_hz, '.6g'),
             c.sensor_model or "-", c.sensor_serial or "-", c.calibration_date or "-",
             c.range_si or "-", c.position_m or "-"]
            for rec in data.records for c in rec.channels]
    n_rows = len(rows)
    rows = rows[:24]
    fig.text(0.03, 0.575, "Channels and calibration", fontsize=11, weight="bold", va="top")
    ax = fig.add_axes((0.03, 0.06, 0.94, 0.49))
    ax.axis("off")
    _table(ax, rows, cols, 7.0)
    if n_rows > len(rows):
        fig.text(0.03, 0.045, f"... and {n_rows - len(rows)} more channels (not shown)",
                 fontsize=7)
    return [fig]


# --- thresholds (Fig. 6-2, 6-3) ------------------------------------------------------------

def band_quantile(g: GrazingSummary) -> tuple[float, int | None]:
    """The 97.5 % quantile for the 95 % band of the eq. (3.4) fit, and its degrees of freedom.

    Student t with ``n - p`` degrees of freedom (``n`` thresholds fitted, the
    outliers left out; ``p`` varied parameters), as the profile intervals of the
    fit are; 1.96 (normal, ``None``) when the fit does not say how many points it used
    (no residuals).
    ``nan`` when ``n <= p``: an exactly determined fit has no band.
    """
    from scipy import stats

    if not g.residuals_ms2:
        return 1.96, None
    n = sum(1 for r in g.residuals_ms2 if r is not None)
    n -= len(g.outliers_hz)
    dof = n - len(g.correlation_names)
    return (float(stats.t.ppf(0.975, dof)) if dof >= 1 else float("nan")), dof


def grazing_band_ms2(freq_hz: np.ndarray, g: GrazingSummary) -> tuple[np.ndarray, np.ndarray]:
    """Eq. (3.4) at the fitted parameters and the half-width of its 95 % band, m/s^2.

    Delta method: the covariance is ``stderr_i stderr_j corr_ij`` of the varied
    parameters (as stored by the fit), the gradient is by central differences,
    and the quantile is :func:`band_quantile` (Student t with the fit's degrees
    of freedom).

    Parameters
    ----------
    freq_hz : ndarray
        Excitation frequencies, Hz.
    g : GrazingSummary
        The grazing fit of the fit summary.

    Returns
    -------
    (ndarray, ndarray)
        The threshold and the half-width of the band, m/s^2 (NaN without a covariance).
    """
    from rattle_lab.model.linear import threshold_accel_ms2

    names = ("gap_m", "f_s_hz", "zeta", "participation")
    p0 = {n: _pval(g, n, 1.0 if n == "participation" else float("nan")) for n in names}

    def model(p: Mapping[str, float]) -> np.ndarray:
        return np.asarray(threshold_accel_ms2(freq_hz, p["gap_m"], p["f_s_hz"], abs(p["zeta"]),
                                              p["participation"]), dtype=float)

    y = model(p0)
    varied = list(g.correlation_names)
    matrix = np.array([[np.nan if c is None else c for c in row] for row in g.correlation],
                      dtype=float).reshape(len(g.correlation), -1)
    err = np.array([g.parameters()[n].stderr or np.nan for n in varied]) if varied \
        else np.zeros(0)
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
    return y, band_quantile(g)[0] * np.sqrt(np.maximum(var, 0.0))


def negative_hysteresis(data: ReportData) -> list[tuple[float, float]]:
    """``(freq_hz, onset - disappearance)`` where the disappearance lies above the onset."""
    if data.results is None:
        return []
    f, up, down = _threshold_arrays(data)
    h = up - down
    return [(float(a), float(b)) for a, b in zip(f, h) if math.isfinite(b) and b < 0]


def _threshold_arrays(data: ReportData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``freq_hz, up_ms2, down_ms2`` as ``/results/thresholds`` holds them (NaN: not measured)."""
    th = data.results.thresholds
    f = np.asarray(th.get("freq_hz", []), dtype=float)
    up = np.asarray(th.get("up_ms2", np.full(f.size, np.nan)), dtype=float)
    down = np.asarray(th.get("down_ms2", np.full(f.size, np.nan)), dtype=float)
    return f, up, down


def threshold_page(data: ReportData) -> list[Figure]:
    """Onset/disappearance thresholds against frequency, eq. 3.4 fit and band, hysteresis."""
    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    f, up, down = _threshold_arrays(data)
    if f.size == 0 or not (np.isfinite(up).any() or np.isfinite(down).any()):
        raise Missing("no ramp thresholds in /results/thresholds (needs amplitude_ramp_up/down "
                      "runs with a base accelerometer)")
    fig = landscape_figure()
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
            _, dof = band_quantile(g)
            how = f"Student t, {dof} dof" if dof is not None else "normal"
            ax.fill_between(grid, y - half, y + half, color="0.6", alpha=0.35,
                            label=f"95 % confidence band (delta method, {how})")
        out = np.array([np.nan if x is None else x for x in g.outliers_hz], dtype=float)
        if out.size:
            sel = np.isin(f, out)
            ax.plot(f[sel], up[sel], "o", ms=11, mfc="none", color="k",
                    label="left out of the fit (outlier)")
    ok = np.isfinite(up) & np.isfinite(down)
    if ok.any():
        ax.fill_between(f[ok], down[ok], up[ok], where=(up[ok] >= down[ok]), interpolate=True,
                        color="tab:orange", alpha=0.25, label="hysteresis (onset - disappearance)")
    ax.plot(f, up, "^", color="tab:red", label="onset (ramp up)")
    ax.plot(f, down, "v", color="tab:blue", label="disappearance (ramp down)")
    ax.set_xlabel("excitation frequency (Hz)")
    ax.set_ylabel("base acceleration amplitude at threshold (m/s^2)")
    ax.set_title("Impact thresholds (thesis Fig. 6-2, 6-3 a)")
    ax.legend(fontsize=8, loc="upper center")
    ax.grid(alpha=0.3)
    hyst = up - down
    neg = np.isfinite(hyst) & (hyst < 0)
    width = 0.6 * (np.min(np.diff(f)) if f.size > 1 else 1.0)
    ax_h.bar(f[~neg], hyst[~neg], width=width, color="tab:orange", label="onset above "
             "disappearance (expected)")
    if neg.any():  # a negative hysteresis is not physical for this oscillator: flag it
        ax_h.bar(f[neg], hyst[neg], width=width, color="tab:red", hatch="//", edgecolor="k",
                 label="NEGATIVE: disappearance above onset (check the ramps)")
        for fx, h in zip(f[neg], hyst[neg]):
            ax_h.annotate(f"negative\n{h:.3g} m/s^2", (fx, h), xytext=(0, -28),
                          textcoords="offset points", ha="center", fontsize=8, color="tab:red",
                          weight="bold")
        ax_h.legend(fontsize=7, loc="upper left")
    ax_h.axhline(0.0, color="k", lw=0.8)
    ax_h.set_xlabel("excitation frequency (Hz)")
    ax_h.set_ylabel("hysteresis, onset - disappearance (m/s^2)")
    ax_h.set_title("Hysteresis")
    ax_h.grid(alpha=0.3)
    if g is None:
        data.missing["eq. 3.4 fit curve"] = _fit_summary(data).not_fitted.get(
            "grazing", "grazing fit absent")
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
    pts: list[tuple[float, float, int, float]] = []
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
        protocol = str(r.get("protocol", ""))
        shift = {"amplitude_ramp_up": -0.12, "amplitude_ramp_down": 0.12}.get(protocol, 0.0)
        units.add(info.get("level_units") or "?")
        dwell = float(lvl_end is None or lvl_end == lvl)
        pts.extend((f + shift, lv, int(c), dwell) for lv, c in zip(levels, counts))
    if not pts:
        raise Missing("no analysed run with an excitation frequency and level")
    arr = np.array(pts, dtype=float).reshape(-1, 4)
    fig = landscape_figure()
    ax = fig.add_subplot()
    classes = ((0, "no impact", "0.8"), (1, "1 impact per cycle", "tab:blue"),
               (2, "2 impacts per cycle", "tab:orange"), (3, ">= 3 impacts per cycle", "tab:red"))
    diamonds: list[tuple[float, float, float, str]] = []
    for n, label, color in classes:
        sel = arr[:, 2] == n if n < 3 else arr[:, 2] >= 3
        ramp, dwell = sel & (arr[:, 3] == 0), sel & (arr[:, 3] == 1)
        if ramp.any():  # the rarer (more impacts) classes above and larger: never hidden
            ax.scatter(arr[ramp, 0], arr[ramp, 1], s=6 + 5 * n, color=color, label=label,
                       zorder=2 + n, linewidths=0)
        if dwell.any():  # one marker per dwell: the share of its cycles in this class
            for fx, lv in sorted({(a, b) for a, b in arr[dwell, :2]}):
                share = float(np.mean(arr[(arr[:, 0] == fx) & (arr[:, 1] == lv)][:, 2]
                                      .clip(max=3) == n))
                diamonds.append((fx, lv, share, color))
    # the largest diamonds first, so that a small share is drawn on top of a large one
    for fx, lv, share, color in sorted(diamonds, key=lambda d: -d[2]):
        ax.scatter([fx], [lv], s=40 + 120 * share, marker="D", color=color, edgecolor="k",
                   linewidth=0.6, zorder=10)
    if (arr[:, 3] == 1).any():
        ax.scatter([], [], s=60, marker="D", color="w", edgecolor="k",
                   label="sine dwell (size: share of its cycles)")
    ax.set_xlabel("excitation frequency (Hz); ramps: up left, down right of each frequency")
    ax.set_ylabel(f"nominal base-acceleration amplitude ({', '.join(sorted(units))})")
    ax.set_title("Impact patterns per forcing cycle (thesis Fig. 6-5)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return [fig]


# --- waveforms (Fig. 6-4, 6-6) -------------------------------------------------------------

def waveform_page(data: ReportData, *, n_examples: int = 2, n_cycles: int = 5) -> list[Figure]:
    """Short windows of plate acceleration, velocity and sound pressure with events marked."""
    from rattle_lab.store import open_stored_record

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
    fig = landscape_figure()
    axes = fig.subplots(3, len(chosen), squeeze=False, sharex="col")
    for col, ((key, run_id), r) in enumerate(chosen):
        f = float(r["freq_hz"])
        t_imp = np.asarray(r.get("t_s", []), dtype=float)
        t_mid = float(np.median(t_imp))
        with open_stored_record(data.store, key) as record:
            run = record.run(run_id)
            by_q: dict[str, Any] = {}
            for channel in run.channels:
                by_q.setdefault(channel.quantity, channel)
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
                    for i, ti in enumerate(t_imp[win]):
                        ax.axvline(ti, color="tab:red", lw=0.6, alpha=0.6,
                                   label="detected impact" if i == 0 else None)
                    ax.legend(fontsize=7, loc="upper right")
                elif quantity == "sound_pressure" and "t_first_s" in r:
                    # marked on the recorded trace at the detected times (the peak heights
                    # in /results are of the pressure less the forced-mode part)
                    for tk, mk, color, lab in (("t_first_s", "o", "tab:blue", "first peak"),
                                               ("t_max_s", "x", "tab:orange", "maximum peak")):
                        tt = np.asarray(r[tk], dtype=float)
                        sel = np.isfinite(tt) & (tt >= t[0]) & (tt <= t[-1]) if t.size else tt < 0
                        ax.plot(tt[sel], np.interp(tt[sel], t, x), mk, ms=7, mew=1.3,
                                mfc="none", color=color, label=lab)
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
    laws = {n: fits.spl_law(n) for n in ("first", "max", "rms")}
    if all(v is None for v in laws.values()):
        why = _fit_summary(data).not_fitted.get("spl_law_first", "not fitted")
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
    fig = landscape_figure()
    ax = fig.add_subplot()
    colors = {"first": "tab:blue", "max": "tab:red", "rms": "tab:green"}
    names = {"first": "first peak", "max": "maximum peak", "rms": "RMS per impact"}
    for n in ("rms", "max", "first"):  # the first-peak law (the thesis's) drawn on top
        law = laws[n]
        if law is None or not v_all[n]:
            continue
        v, p = np.concatenate(v_all[n]), np.concatenate(p_all[n])
        ok = np.isfinite(v) & np.isfinite(p) & (v > 0) & (p > 0)
        v, p = v[ok], p[ok]
        ax.plot(v, p, ".", ms=2.5, alpha=0.5, color=colors[n], label=f"{names[n]}, measured")
        lin = law.linear
        slope, icpt = _num(lin.slope), _num(lin.intercept)
        grid = np.linspace(0.0, float(v.max()) * 1.05 if v.size else 1.0, 100)
        ax.plot(grid, slope * grid + icpt, color=colors[n], lw=1.3,
                label=f"{names[n]}: p = {slope:.3g} Pa/(m/s) |v_in| + {icpt:.3g} Pa (r2 "
                      f"{_num(lin.r2):.3f})")
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
    handles, labels = ax.get_legend_handles_labels()
    ax.legend(handles[::-1], labels[::-1], fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    return [fig]


# --- model predictions ---------------------------------------------------------------------

def _nondim(g: GrazingSummary, f_hz: np.ndarray, a_ms2: np.ndarray) -> tuple[np.ndarray,
                                                                                np.ndarray]:
    # Eq. (2.28) omega = f / f_s and eq. (2.31) F = (Q1/Q2) A / (omega_s^2 h)
    f_s, gap = _pval(g, "f_s_hz"), _pval(g, "gap_m")
    q = _pval(g, "participation", 1.0)
    w_s = 2 * np.pi * f_s
    return f_hz / f_s, q * a_ms2 / (w_s**2 * gap)


def smooth_region(omega: np.ndarray, F: np.ndarray, mask: np.ndarray,
                  factor: int = 6) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A boolean region on a grid as a smooth field on a finer grid (for contourf at 0.5).

    The 0/1 field is blurred by a Gaussian of one cell and interpolated cubically
    onto a grid ``factor`` times finer: the 0.5 contour then runs smoothly, within a
    cell of the computed boundary, instead of in grid-cell steps.
    """
    from scipy import ndimage

    z = ndimage.gaussian_filter(np.asarray(mask, dtype=float), sigma=1.0, mode="nearest")
    z = ndimage.zoom(z, factor, order=3, mode="nearest", grid_mode=False)
    w = np.linspace(omega[0], omega[-1], z.shape[1])
    f = np.linspace(F[0], F[-1], z.shape[0])
    return w, f, z


def model_pages(data: ReportData, *, n_sweep: int = 40, max_freqs: int = 6,
                quiet: bool = True) -> list[Figure]:
    """Bifurcation sets and F sweeps of the SDF model at the fitted parameters (coarse grids).

    Page 1: the 1/1 and 1/2 existence and stability regions (:func:`bifurcation_sets`)
    in the (omega, F) plane with the measured thresholds converted by eq. (2.28),
    (2.31).  Page 2: at each measured frequency (up to ``max_freqs``), a slow F
    sweep up and back down (:func:`sweep_up_down`, ``n_sweep`` amplitudes, 60
    forcing periods each): the model's onset and disappearance against the measured
    ones, each with the sweep step as its resolution.  ``quiet``: no progress bar.
    """
    from rattle_lab.model.analysis import bifurcation_sets, sweep_up_down
    from rattle_lab.model.sdf import SDFParams

    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    g = _grazing(data)
    if g is None:
        raise Missing("needs the grazing fit (gap, f_s, zeta): "
                      + _fit_summary(data).not_fitted.get("grazing", "absent"))
    fits = _fits(data)
    e_fit = fits.restitution_ratio
    if e_fit is None or e_fit.value is None:
        raise Missing("needs a fitted coefficient of restitution e")
    # zeta from replaying the ramps when the fit made it (free of the ramp lag), else eq. (3.4)'s
    ramp = fits.damping_ramp
    ramp_zeta = ramp.value if ramp is not None and ramp.value else None
    zeta = ramp_zeta if ramp_zeta is not None else abs(_pval(g, "zeta"))
    zeta_src = "ramp model" if ramp_zeta is not None else "eq. (3.4) fit"
    e = e_fit.value
    if not 0.0 <= e <= 1.0:
        raise Missing(f"fitted e = {e:.4g} is outside [0, 1]")
    if not (math.isfinite(zeta) and zeta > 0 and math.isfinite(_pval(g, "gap_m"))):
        raise Missing(f"fitted zeta {zeta} or gap unusable for the model")
    f, up, down = _threshold_arrays(data)
    w_up, F_up = _nondim(g, f, up)
    w_dn, F_dn = _nondim(g, f, down)
    finite_w = w_up[np.isfinite(w_up)]
    w_lo = float(finite_w.min() - 0.05) if finite_w.size else 0.8
    w_hi = float(max(1.2, finite_w.max() + 0.05)) if finite_w.size else 1.2
    F_all = np.concatenate([F_up[np.isfinite(F_up)], F_dn[np.isfinite(F_dn)]])
    F_hi = float(max(1.6 * F_all.max(), 4 * zeta)) if F_all.size else 0.2
    sets = bifurcation_sets((1, 2), omega_range=(max(w_lo, 0.05), w_hi), F_range=(0.0, F_hi),
                            zeta=zeta, e=e, n_omega=61, n_F=41, n_v=31)
    import matplotlib
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from rattle_lab.plot._bifsets import _LINESTYLES  # the same styles as `model bifsets`' plot

    fig = landscape_figure()
    ax = fig.add_subplot()
    handles: list[Any] = []
    tab10 = matplotlib.colormaps["tab10"].colors  # type: ignore[attr-defined]
    for k, n in enumerate(sets.ns):
        color = tab10[k % len(tab10)]
        if sets.exists[k].any():
            ax.contourf(*smooth_region(sets.omega, sets.F, sets.exists[k]), levels=[0.5, 1.5],
                        colors=[color], alpha=0.15)
        if sets.stable[k].any():
            ax.contourf(*smooth_region(sets.omega, sets.F, sets.stable[k]), levels=[0.5, 1.5],
                        colors=[color], alpha=0.45)
        for c in sets.curves_of(n):
            if c.kind != "grazing":
                ax.plot(c.omega, c.F, color=color, lw=1.3, ls=_LINESTYLES[c.kind])
        handles += [Patch(facecolor=color, alpha=0.15, label=f"1/{n} orbit exists"),
                    Patch(facecolor=color, alpha=0.45, label=f"1/{n} orbit exists and is stable")]
    if len(sets.ns) >= 2:
        both = sets.exists[0] & sets.exists[1]
        if both.any():  # where the two shadings blend: named in the legend, hatched
            ax.contourf(*smooth_region(sets.omega, sets.F, both), levels=[0.5, 1.5],
                        colors="none", hatches=["xx"])
            handles.append(Patch(facecolor="none", edgecolor="0.3", hatch="xx",
                                 label=f"1/{sets.ns[0]} and 1/{sets.ns[1]} both exist "
                                       "(overlap of the shadings: coexisting orbits)"))
    for kind in ("saddle-node", "period-doubling", "secondary-grazing"):
        if any(c.kind == kind for n in sets.ns for c in sets.curves_of(n)):
            handles.append(Line2D([], [], color="0.3", ls=_LINESTYLES[kind], label=kind))
    (graze,) = ax.plot(sets.grazing.omega, sets.grazing.F, color="k", lw=1.4,
                       label="grazing, eq. (3.4)")
    (on,) = ax.plot(w_up, F_up, "^", color="tab:red", ms=7, label="measured onset")
    (off,) = ax.plot(w_dn, F_dn, "v", color="tab:blue", ms=7, label="measured disappearance")
    ax.set_xlim(sets.omega[0], sets.omega[-1])
    ax.set_ylim(sets.F[0], sets.F[-1])
    ax.set_xlabel("forcing frequency omega = f / f_s (nondimensional)")
    ax.set_ylabel("forcing amplitude F = Q A / (omega_s^2 h) (nondimensional)")
    ax.set_title(f"Model bifurcation sets at the fitted zeta = {zeta:.3g} ({zeta_src}), "
                 f"e = {e:.3g}, with the measured thresholds\n(region edges smoothed within "
                 f"one cell of the {sets.omega.size} x {sets.F.size} grid)")
    ax.legend(handles=[*handles, graze, on, off], fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    figs = [fig]
    # F sweeps up and down at each measured frequency: model onset/disappearance
    sel = np.flatnonzero(np.isfinite(w_up) | np.isfinite(w_dn))[:max_freqs]
    if sel.size:
        from rattle_lab._progress import progress

        grid = np.linspace(F_hi / n_sweep, F_hi, n_sweep)
        step = float(grid[1] - grid[0]) if grid.size > 1 else float(grid[0])
        on_F, off_F = np.full(sel.size, np.nan), np.full(sel.size, np.nan)
        for i, j in enumerate(progress(sel, total=sel.size, desc="model sweeps", quiet=quiet,
                                       unit="freq")):
            s_up, s_dn = sweep_up_down("F", grid, base=SDFParams(F=grid[0], omega=float(
                f[j] / _pval(g, "f_s_hz")), zeta=zeta, e=e), cycles=60, discard=40, n_max=6,
                lyapunov="none", quiet=True)
            hit_up = [p.value for p in s_up.points if p.impact_velocities.size]
            hit_dn = [p.value for p in s_dn.points if p.impact_velocities.size]
            # the threshold lies within one step below the first amplitude with impacts
            on_F[i] = min(hit_up) - step / 2 if hit_up else np.nan
            off_F[i] = min(hit_dn) - step / 2 if hit_dn else np.nan
        w_s = 2 * np.pi * _pval(g, "f_s_hz")
        scale = w_s**2 * _pval(g, "gap_m") / _pval(g, "participation", 1.0)
        fig2 = landscape_figure()
        ax2 = fig2.add_subplot()
        half = step / 2 * scale
        ax2.errorbar(f[sel] - 0.04, on_F * scale, yerr=half, fmt="s-", color="tab:red",
                     mfc="none", capsize=3, label="model onset (F sweep up)")
        ax2.errorbar(f[sel] + 0.04, off_F * scale, yerr=half, fmt="s--", color="tab:blue",
                     mfc="none", capsize=3, label="model disappearance (F sweep back down)")
        ax2.plot(f, up, "^", color="tab:red", ms=8, label="measured onset")
        ax2.plot(f, down, "v", color="tab:blue", ms=8, label="measured disappearance")
        ax2.set_xlabel("excitation frequency (Hz)")
        ax2.set_ylabel("base acceleration amplitude at threshold (m/s^2)")
        ax2.set_title(f"Model at the fitted parameters against the measured thresholds: F "
                      f"swept over {n_sweep} amplitudes up to {F_hi * scale:.3g} m/s^2\n(60 "
                      f"forcing periods each; bars: the sweep step, {2 * half:.3g} m/s^2)")
        ax2.legend(fontsize=8, loc="upper left")
        ax2.grid(alpha=0.3)
        figs.append(fig2)
    return figs


# --- acoustics: levels, bands, loudness (issue 17) -----------------------------------------

def _acoustic_rows(data: ReportData) -> list[dict[str, Any]]:
    """Summary rows of the runs with an ``acoustics`` object, with their impact velocity."""
    if data.results is None:
        return []
    out = []
    for run in _fit_summary(data).runs:
        if run.acoustics is None:
            continue
        row = run.to_dict()
        r = data.results.runs.get((run.input_key, run.run_id), {})
        v = np.abs(np.asarray(r.get("v_in_m_s", []), dtype=float))
        v = v[np.isfinite(v)]
        out.append({**row, "v_rms_m_s": float(np.sqrt(np.mean(v**2))) if v.size else np.nan})
    return out


def _num(x: Any) -> float:
    return float("nan") if x is None else float(x)


def _band_arrays(bands: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    items = sorted((float(k), _num(v)) for k, v in bands.items())
    if not items:
        return np.zeros(0), np.zeros(0)
    f, db = np.array(items).T
    return f, db


def calibration_note(rows: list[dict[str, Any]]) -> str:
    """One line saying how the microphones were calibrated (calibrator or declared)."""
    sources = sorted({str((r.get("calibration") or {}).get("source", "declared")) for r in rows})
    flags = sorted({f for r in rows for f in (r.get("calibration") or {}).get("flags", [])})
    if sources == ["calibrator"]:
        text = "microphone sensitivity from the campaign's calibrator records"
    elif "calibrator" in sources:
        text = "microphone sensitivity from calibrator records for some runs, declared for others"
    elif sources == ["none"]:
        text = "microphone UNCALIBRATED (full-scale units): levels are not in dB re 20 uPa"
    else:
        text = "no calibrator record: the declared microphone sensitivity is used"
    if flags:
        text += "; FLAGGED: " + ", ".join(flags) + " (pre/post calibration differ by > 0.5 dB)"
    return text


def acoustics_page(data: ReportData) -> list[Figure]:
    """Third-octave spectra of rattle against background; level and loudness against velocity."""
    if data.results is None:
        raise Missing(data.missing.get("results", "no results"))
    rows = _acoustic_rows(data)
    if not rows:
        raise Missing("no run with a microphone has acoustic results (fit with this version)")
    fig = landscape_figure()
    (ax_b, ax_l), (ax_n, ax_t) = fig.subplots(2, 2)
    # (a) band spectra: each run thin, energy mean over runs thick
    pooled: dict[str, dict[float, list[float]]] = {"rattle": {}, "background": {}}
    for r in rows:
        ac = r["acoustics"]
        for what, key, color in (("rattle", "rattle_third_octave_db", "tab:red"),
                                 ("background", "background_third_octave_db", "0.45")):
            f, db = _band_arrays(ac.get(key) or {})
            if f.size:
                ax_b.plot(f, db, drawstyle="steps-mid", color=color, lw=0.5, alpha=0.35)
                for fk, dk in zip(f, db):
                    pooled[what].setdefault(fk, []).append(dk)
    for what, color in (("rattle", "tab:red"), ("background", "0.2")):
        if pooled[what]:
            f = np.array(sorted(pooled[what]))
            db = np.array([10 * np.log10(np.mean(10 ** (np.array(pooled[what][k]) / 10)))
                           for k in f])
            ax_b.plot(f, db, drawstyle="steps-mid", color=color, lw=1.8,
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
    v = np.array([r["v_rms_m_s"] for r in rows])
    laeq = np.array([_num(r["acoustics"].get("laeq_db")) for r in rows])
    lafmax = np.array([_num(r["acoustics"].get("lafmax_db")) for r in rows])
    n5 = np.array([_num(r["acoustics"].get("loudness_n5_sone")) for r in rows])
    nmax = np.array([_num(r["acoustics"].get("loudness_max_sone")) for r in rows])
    ok = np.isfinite(v) & (v > 0)
    # (b) levels against impact velocity, with the 20 dB/decade of a linear SPL law
    ax_l.plot(v[ok], laeq[ok], "o", color="tab:blue", label="LAeq of the run")
    ax_l.plot(v[ok], lafmax[ok], "^", color="tab:purple", label="LAFmax of the run")
    if ok.sum() >= 1 and np.isfinite(laeq[ok]).any():
        grid = np.geomspace(v[ok].min() / 1.2, v[ok].max() * 1.2, 50)
        v_mid, l_mid = np.exp(np.nanmedian(np.log(v[ok]))), np.nanmedian(laeq[ok])
        ax_l.plot(grid, l_mid + 20 * np.log10(grid / v_mid), "--", color="0.4",
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
    sel = ok & np.isfinite(n5) & (n5 > 0)
    if sel.any():
        grid = np.geomspace(v[sel].min() / 1.2, v[sel].max() * 1.2, 50)
        v_mid, n_mid = np.exp(np.median(np.log(v[sel]))), np.exp(np.median(np.log(n5[sel])))
        ax_n.plot(grid, n_mid * (grid / v_mid) ** 0.602, "--", color="0.4",
                  label="N proportional to v^0.6 (SPL law with loudness doubling per 10 dB)")
    ax_n.set_xscale("log")
    ax_n.set_yscale("log")
    for axis in (ax_l.xaxis, ax_n.xaxis, ax_n.yaxis):
        _label_log_axis(axis)
    ax_n.set_xlabel("RMS impact velocity of the run (m/s)")
    ax_n.set_ylabel("ISO 532-1 loudness (sone)")
    field = sorted({str(r["acoustics"].get("sound_field") or "free") for r in rows})
    ax_n.set_title(f"Loudness against impact velocity ({'/'.join(field)} field)", fontsize=9)
    ax_n.grid(alpha=0.3, which="both")
    ax_n.legend(fontsize=7)
    # (d) the table
    ax_t.axis("off")
    cols = ["run", "LAeq", "LAFmax", "LCpeak", "N5", "Nmax", "S", "calibration"]
    table_rows = [[str(r["run_id"]), _fmt(r["acoustics"].get("laeq_db"), ".1f"),
                   _fmt(r["acoustics"].get("lafmax_db"), ".1f"),
                   _fmt(r["acoustics"].get("lcpeak_db"), ".1f"),
                   _fmt(r["acoustics"].get("loudness_n5_sone"), ".3g"),
                   _fmt(r["acoustics"].get("loudness_max_sone"), ".3g"),
                   _fmt(r["acoustics"].get("sharpness_acum"), ".2f"),
                   str((r.get("calibration") or {}).get("source", "declared"))]
                  for r in rows[:14]]
    _table(ax_t, table_rows, cols, 7.0)
    ax_t.set_title("Per run: levels in dB re 20 uPa, loudness in sone, sharpness (DIN 45692) "
                   "in acum", fontsize=9, loc="left")
    if len(rows) > 14:
        ax_t.text(0.0, 0.0, f"... and {len(rows) - 14} more runs", fontsize=7,
                  transform=ax_t.transAxes)
    from matplotlib.ticker import LogFormatterSciNotation, NullFormatter, ScalarFormatter

    for ax in (ax_l, ax_n):  # log axes over less than a decade: plain numbers, no minor labels
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.xaxis.set_minor_formatter(NullFormatter())
    ax_n.yaxis.set_major_formatter(ScalarFormatter())
    ax_n.yaxis.set_minor_formatter(NullFormatter())
    ax_b.xaxis.set_major_formatter(LogFormatterSciNotation())
    fig.suptitle("Sound levels, third-octave bands and loudness\n" + calibration_note(rows),
                 fontsize=11)
    return [fig]


def _label_log_axis(axis: Any) -> None:
    """Numbers at 1, 2 and 5 per decade: a log axis inside one decade still has labels."""
    axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(FuncFormatter(lambda value, _pos: f"{value:g}"))
    axis.set_minor_formatter(NullFormatter())
