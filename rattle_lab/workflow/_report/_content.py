"""What each report page shows, computed once, before anything is drawn.

:func:`build_content` turns the gathered :class:`ReportData` into a frozen
:class:`rattle_lab.report.ReportContent`: per section the arrays and values the page
draws (band curves, thresholds, impacts per cycle, SPL points and bands, acoustic rows,
waveform windows, the model's bifurcation sets and sweeps) or the reason the section is
left out.  The builders here only call the functions that own each computation
(:mod:`rattle_lab.fit` for bands and intervals, :mod:`rattle_lab.detect` for impacts per
cycle, :mod:`rattle_lab.model` for conversions and simulations) and store their results
in the report's content types; the report's page modules only draw.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from rattle_lab.detect import impacts_per_cycle
from rattle_lab.fit import (Fits, GrazingSummary, SplLawSummary, band_quantile, grazing_band_ms2,
                            linear_law_band, threshold_hysteresis)
from rattle_lab.report import (GrazingCurve, PatternContent, ReportContent,
                               RigContent, SplContent, SplCurve,
                               ThresholdContent)
from ._gather import ReportData
from ._summary import report_negative_hysteresis, summary_lines, threshold_arrays


class Missing(Exception):
    """A section cannot be drawn; the message says why (shown on the summary page)."""


def fits_of(data: ReportData) -> Fits:
    """The typed fits of the summary (empty without results)."""
    return data.summary.fits if data.summary is not None else Fits()


def pval(g: GrazingSummary, name: str, default: float = float("nan")) -> float:
    """A fitted grazing parameter's value (``default`` where the fit has none)."""
    value = g.params[name].value
    return default if value is None else value


def require_results(data: ReportData) -> None:
    """Raise :class:`Missing` (with the gathering's reason) when the store has no results."""
    if data.results is None or data.summary is None:
        raise Missing(data.missing.get("results", "no results"))


def not_fitted(data: ReportData, key: str, default: str) -> str:
    """Why the fit ``key`` is absent, as the summary says."""
    return data.summary.not_fitted.get(key, default) if data.summary is not None else default


# --- rig -------------------------------------------------------------------------------------

def rig_content(data: ReportData) -> RigContent:
    """The rig page's content (raises :class:`Missing` without a readable record)."""
    if not data.records:
        raise Missing("no readable record in the store")
    return RigContent(data.records)


# --- thresholds ------------------------------------------------------------------------------

def threshold_content(data: ReportData) -> ThresholdContent:
    """The threshold page's content (raises :class:`Missing` without ramp thresholds)."""
    require_results(data)
    f, up, down = threshold_arrays(data)
    if f.size == 0 or not (np.isfinite(up).any() or np.isfinite(down).any()):
        raise Missing("no ramp thresholds in /results/thresholds (needs amplitude_ramp_up/down "
                      "runs with a base accelerometer)")
    fits = fits_of(data)
    g = fits.grazing
    curve: GrazingCurve | None = None
    corrected: GrazingCurve | None = None
    missing: tuple[tuple[str, str], ...] = ()
    if g is not None:
        lo_f = min(f.min(), pval(g, "f_s_hz", f.min())) - 2.0
        hi_f = max(f.max(), pval(g, "f_s_hz", f.max())) + 2.0
        grid = np.linspace(max(lo_f, 0.1), hi_f, 200)
        y, half = grazing_band_ms2(grid, g)
        out = np.array([np.nan if x is None else x for x in g.outliers_hz], dtype=float)
        sel = np.isin(f, out)
        band = (y - half, y + half) if np.isfinite(half).any() else None
        at_f = grazing_band_ms2(f, g)[0]
        curve = GrazingCurve(grid, y, band, band_quantile(g)[1], pval(g, "gap_m"),
                             pval(g, "f_s_hz"), pval(g, "zeta"),
                             f[sel] if out.size else None, up[sel] if out.size else None,
                             residual_freq_hz=f, residual_ms2=up - at_f)
        corrected = _corrected_curve(fits, g, grid, f, at_f)
    else:
        missing = (("eq. 3.4 fit curve", not_fitted(data, "grazing", "grazing fit absent")),)
    hyst = threshold_hysteresis(up, down)
    width = 0.6 * (float(np.min(np.diff(f))) if f.size > 1 else 1.0)
    both = np.isfinite(up) & np.isfinite(down)
    negative = np.isin(f, [fx for fx, _ in report_negative_hysteresis(data)])
    return ThresholdContent(f, up, down, hyst, negative, both, width,
                            curve, missing, corrected, hysteresis_segments(f, both))


def hysteresis_segments(freq_hz: np.ndarray, both: np.ndarray) -> tuple[tuple[int, int], ...]:
    """Runs of neighbouring frequencies (on the measured grid) where both thresholds exist.

    Index ranges ``(i, j)`` into ``freq_hz[both]`` (``j`` exclusive).  Two measured
    frequencies are neighbours when no frequency of the grid lies between them and their
    spacing is at most 1.5 times the grid's smallest step: a frequency without a run, or
    without one of the two thresholds, breaks the shading.

    >>> f = np.array([95.0, 96.0, 97.0, 98.0, 100.0])
    >>> hysteresis_segments(f, np.ones(5, bool))
    ((0, 4), (4, 5))
    >>> hysteresis_segments(f, np.array([True, True, False, True, True]))
    ((0, 2), (2, 3), (3, 4))
    """
    f_all = np.unique(freq_hz[np.isfinite(freq_hz)])
    step = float(np.min(np.diff(f_all))) if f_all.size > 1 else np.inf
    idx = np.flatnonzero(both)
    segments: list[tuple[int, int]] = []
    start = 0
    for k in range(1, idx.size + 1):
        if k < idx.size:
            a, b = freq_hz[idx[k - 1]], freq_hz[idx[k]]
            between = (f_all > a) & (f_all < b)
            if b - a <= 1.5 * step and not between.any() and idx[k] == idx[k - 1] + 1:
                continue
        segments.append((start, k))
        start = k
    return tuple(segments)


def _corrected_curve(fits: Fits, g: GrazingSummary, grid: np.ndarray, f: np.ndarray,
                     at_f: np.ndarray) -> GrazingCurve | None:
    """Eq. (3.4) at the ramp-corrected gap, f_s and zeta (the quasi-static grazing onset)."""
    import dataclasses

    rg = fits.grazing_ramp
    if rg is None or any(getattr(rg, n).value is None for n in ("gap_m", "f_s_hz", "zeta")):
        return None
    params = {n: dataclasses.replace(getattr(g, n), value=getattr(rg, n).value, stderr=None)
              for n in ("gap_m", "f_s_hz", "zeta")}
    gc = dataclasses.replace(g, **params)
    y = grazing_band_ms2(grid, gc)[0]
    y_f = grazing_band_ms2(f, gc)[0]
    gap, f_s, zeta = (float(getattr(rg, n).value or np.nan) for n in ("gap_m", "f_s_hz", "zeta"))
    return GrazingCurve(grid, y, None, None, gap, f_s, zeta, None, None, residual_freq_hz=f,
                        residual_ms2=y_f - at_f,
                        label="eq. (3.4) at the ramp-corrected gap, f_s, zeta (quasi-static "
                              "onset; the ramps' onsets lag it)")


# --- impact patterns -------------------------------------------------------------------------

def _run_info(data: ReportData, key: str, run_id: str) -> dict[str, Any]:
    for rec in data.records:
        if rec.input_key == key:
            return rec.runs.get(run_id, {})
    return {}


def pattern_content(data: ReportData) -> PatternContent:
    """The impact-pattern page's content (cycle counts by :func:`impacts_per_cycle`)."""
    require_results(data)
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
        counts = impacts_per_cycle(r["t_s"], f, t0, duration)
        if counts.size == 0:
            continue
        lvl_end = info.get("level_end")
        # the nominal level of each cycle: a ramp goes linearly from level to level_end
        levels = np.linspace(float(lvl), float(lvl if lvl_end is None else lvl_end), counts.size)
        protocol = str(r.get("protocol", ""))
        shift = {"amplitude_ramp_up": -0.12, "amplitude_ramp_down": 0.12}.get(protocol, 0.0)
        units.add(info.get("level_units") or "?")
        dwell = float(lvl_end is None or lvl_end == lvl)
        pts.extend((f + shift, lv, int(c), dwell) for lv, c in zip(levels, counts))
    if not pts:
        raise Missing("no analysed run with an excitation frequency and level")
    arr = np.array(pts, dtype=float).reshape(-1, 4)
    shares: list[tuple[int, float, float, float]] = []
    for n in range(4):
        sel = arr[:, 2] == n if n < 3 else arr[:, 2] >= 3
        dwell = sel & (arr[:, 3] == 1)
        for fx, lv in sorted({(a, b) for a, b in arr[dwell, :2]}):
            share = float(np.mean(arr[(arr[:, 0] == fx) & (arr[:, 1] == lv)][:, 2]
                                  .clip(max=3) == n))
            shares.append((n, float(fx), float(lv), share))
    return PatternContent(arr, tuple(sorted(units)), tuple(shares))


# --- SPL law ---------------------------------------------------------------------------------

def _num(x: Any) -> float:
    return float("nan") if x is None else float(x)


def spl_content(data: ReportData) -> SplContent:
    """The SPL-law page's content (band by :func:`rattle_lab.fit.linear_law_band`)."""
    require_results(data)
    fits = fits_of(data)
    laws: dict[str, SplLawSummary | None] = {n: fits.spl_law(n) for n in ("first", "max", "rms")}
    if all(v is None for v in laws.values()):
        raise Missing(f"no SPL law in /results "
                      f"({not_fitted(data, 'spl_law_first', 'not fitted')})")
    v_all: dict[str, list[np.ndarray]] = {"first": [], "max": [], "rms": []}
    p_all: dict[str, list[np.ndarray]] = {"first": [], "max": [], "rms": []}
    l_all: dict[str, list[np.ndarray]] = {"first": [], "max": [], "rms": []}
    for r in data.results.runs.values():
        if r.get("status") != "ok" or "v_in_m_s" not in r or "p_first_pa" not in r:
            continue
        v = np.abs(np.asarray(r["v_in_m_s"], dtype=float))
        later = _later_max(r, v.shape)
        for n, key in (("first", "p_first_pa"), ("max", "p_max_pa"), ("rms", "p_rms_pa")):
            if key in r and np.asarray(r[key]).shape == v.shape:
                v_all[n].append(v)
                p_all[n].append(np.abs(np.asarray(r[key], dtype=float)))
                l_all[n].append(later)
    curves = []
    for n in ("rms", "max", "first"):  # the first-peak law (the thesis's) drawn on top
        law = laws[n]
        if law is None or not v_all[n]:
            continue
        v, p = np.concatenate(v_all[n]), np.concatenate(p_all[n])
        later = np.concatenate(l_all[n])
        ok = np.isfinite(v) & np.isfinite(p) & (v > 0) & (p > 0)
        v, p, later = v[ok], p[ok], later[ok]
        slope, icpt = _num(law.linear.slope), _num(law.linear.intercept)
        grid = np.linspace(0.0, float(v.max()) * 1.05 if v.size else 1.0, 100)
        line = slope * grid + icpt
        half = linear_law_band(v, p, slope, icpt, grid)
        curves.append(SplCurve(n, v, p, slope, icpt, _num(law.linear.r2), grid, line,
                               None if half is None else (line - half, line + half),
                               later_max=later))
    return SplContent(tuple(curves))


def _later_max(r: Any, shape: tuple[int, ...]) -> np.ndarray:
    """Per impact: True where the largest sound peak comes after the first one."""
    if "t_first_s" not in r or "t_max_s" not in r:
        return np.zeros(shape, dtype=bool)
    t1 = np.asarray(r["t_first_s"], dtype=float)
    tm = np.asarray(r["t_max_s"], dtype=float)
    if t1.shape != shape or tm.shape != shape:
        return np.zeros(shape, dtype=bool)
    with np.errstate(invalid="ignore"):
        return np.isfinite(t1) & np.isfinite(tm) & (tm > t1)


# --- the whole report ------------------------------------------------------------------------

def build_content(data: ReportData, builders: tuple[tuple[str, Callable[..., Any]], ...], *,
                  model: bool = True, quiet: bool = True, version: str = "") -> ReportContent:
    """Compute every page's content; a section whose builder raises :class:`Missing` is left out.

    Parameters
    ----------
    data : ReportData
        From :func:`gather` (not modified).
    builders : tuple of (str, callable)
        Section name and content builder, in page order; the ``"model predictions"``
        builder also takes ``quiet``.
    model : bool
        Build the model predictions (else recorded as not requested).
    quiet : bool
        No progress bar.
    version : str
        The rattle_lab version named on the summary page.
    """
    missing = dict(data.missing)
    sections: list[tuple[str, Any]] = []
    shocks_only = data.summary is not None and data.summary.shocks_only
    transients = bool(data.summary is not None and data.summary.transients)
    if shocks_only:
        missing["rattle sections"] = ("transient records only (single shocks): the thresholds, "
                                      "impact patterns, waveforms, SPL law, acoustics and model "
                                      "need shaker runs")
    for name, build in builders:
        if shocks_only and name not in ("rig and calibration", "shocks"):
            continue
        if name == "shocks" and not transients:
            continue  # no transient run: nothing to say
        if name == "model predictions" and not model:
            missing[name] = "not requested (model=False)"
            continue
        try:
            content = build(data, quiet=quiet) if name == "model predictions" else build(data)
        except Missing as exc:
            missing[name] = " ".join(str(exc).split())
            continue
        sections.append((name, content))
        missing.update(getattr(content, "missing", ()))
    title = ("rattle_lab report: transient records (shocks)" if shocks_only
             else "rattle_lab report: fitted gap, zeta, f_s, e and SPL law")
    return ReportContent(data.store.name, tuple(summary_lines(data, version)),
                         tuple(sections), missing, title)


__all__ = ["Missing", "build_content", "report_negative_hysteresis"]
