"""Content of the pages drawn from single runs: example waveforms and acoustics.

Like :mod:`._content`, this only reads and calls: the stored channels (windows
around the detected impacts), :func:`rattle_lab.acoustics.energy_mean_db` and the
guide lines of :mod:`rattle_lab.plot`; the report's pages draw what it returns.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from rattle_lab.acoustics import energy_mean_db
from rattle_lab.plot import db_slope_guide, power_law_guide
from rattle_lab.report import (WAVEFORM_QUANTITIES, AcousticsContent, ListenerMetrics, Trace,
                               WaveformColumn, WaveformContent)
from ._content import Missing, require_results
from ._gather import ReportData

# --- waveforms -------------------------------------------------------------------------------

def _window(ch: Any, t_mid: float, f: float, n_cycles: int) -> tuple[np.ndarray, np.ndarray]:
    fs = float(ch.sample_rate_hz)
    t0 = float(ch.start_time_s or 0.0)
    i0 = max(0, int(round((t_mid - t0 - n_cycles / (2 * f)) * fs)))
    i1 = min(ch.n_samples, i0 + int(round(n_cycles / f * fs)))
    return t0 + np.arange(i0, i1) / fs, np.asarray(ch.read(i0, i1))


def _trace(quantity: str, t: np.ndarray, x: np.ndarray, t_imp: np.ndarray,
           r: Mapping[str, Any]) -> Trace:
    win = (t_imp >= t[0]) & (t_imp <= t[-1]) if t.size else t_imp < 0
    t_win = t_imp[win]
    y_win = np.interp(t_win, t, x) if quantity == "plate_velocity" and win.any() \
        else np.zeros(0)
    peaks: list[tuple[str, np.ndarray, np.ndarray]] = []
    if quantity == "sound_pressure" and "t_first_s" in r:
        # marked on the recorded trace at the detected times (the peak heights in /results
        # are of the pressure less the forced-mode part)
        for which, key in (("first", "t_first_s"), ("max", "t_max_s")):
            tt = np.asarray(r[key], dtype=float)
            sel = np.isfinite(tt) & (tt >= t[0]) & (tt <= t[-1]) if t.size else tt < 0
            peaks.append((which, tt[sel], np.interp(tt[sel], t, x)))
    return Trace(t, x, t_win, y_win, tuple(peaks))


def waveform_content(data: ReportData, *, n_examples: int = 2, n_cycles: int = 5
                     ) -> WaveformContent:
    """Windows of ``n_cycles`` forcing periods centred on the middle impact of up to
    ``n_examples`` runs with impacts (read from the store)."""
    from rattle_lab.store import open_stored_record

    require_results(data)
    candidates = [(k, r) for k, r in sorted(data.results.runs.items())
                  if r.get("status") == "ok" and int(r.get("n_impacts", 0)) > 0
                  and math.isfinite(float(r.get("freq_hz", np.nan)))]
    # steady runs first (thesis Fig. 6-4 shows dwells), then the rest
    candidates.sort(key=lambda kr: (kr[1].get("protocol") != "sine_dwell", kr[0]))
    chosen = candidates[:n_examples]
    if not chosen:
        raise Missing("no analysed run with impacts")
    columns = []
    for (key, run_id), r in chosen:
        f = float(r["freq_hz"])
        t_imp = np.asarray(r.get("t_s", []), dtype=float)
        # centred on the impact nearest the run's middle: a window of n_cycles periods then
        # ends half a period from the impacts of a 1/1 pattern, never on one
        t_mid = float(t_imp[np.argmin(np.abs(t_imp - np.median(t_imp)))])
        traces: list[Trace | None] = []
        with open_stored_record(data.store, key) as record:
            by_q: dict[str, Any] = {}
            for channel in record.run(run_id).channels:
                by_q.setdefault(channel.quantity, channel)
            for quantity, _ in WAVEFORM_QUANTITIES:
                ch = by_q.get(quantity)
                if ch is None or not ch.sample_rate_hz:
                    traces.append(None)
                    continue
                t, x = _window(ch, t_mid, f, n_cycles)
                traces.append(_trace(quantity, t, x, t_imp, r))
        columns.append(WaveformColumn(run_id, str(r.get("protocol", "")), f,
                                      str(r.get("pattern") or "-"), tuple(traces)))
    return WaveformContent(tuple(columns))


# --- acoustics -------------------------------------------------------------------------------

def _num(x: Any) -> float:
    return float("nan") if x is None else float(x)


def _band_arrays(bands: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    items = sorted((float(k), _num(v)) for k, v in bands.items())
    if not items:
        return np.zeros(0), np.zeros(0)
    f, db = np.array(items).T
    return f, db


def acoustic_rows(data: ReportData) -> list[dict[str, Any]]:
    """Summary rows of the runs with an ``acoustics`` object, with their RMS impact velocity."""
    if data.results is None or data.summary is None:
        return []
    out = []
    for run in data.summary.runs:
        if run.acoustics is None:
            continue
        row = run.to_dict()
        r = data.results.runs.get((run.input_key, run.run_id), {})
        v = np.abs(np.asarray(r.get("v_in_m_s", []), dtype=float))
        v = v[np.isfinite(v)]
        out.append({**row, "v_rms_m_s": float(np.sqrt(np.mean(v**2))) if v.size else np.nan})
    return out


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



def acoustics_content(data: ReportData) -> AcousticsContent:
    """The acoustics page's content."""
    require_results(data)
    rows = acoustic_rows(data)
    if not rows:
        raise Missing("no run with a microphone has acoustic results (fit with this version)")
    traces: list[tuple[str, np.ndarray, np.ndarray]] = []
    pooled: dict[str, dict[float, list[float]]] = {"rattle": {}, "background": {}}
    for r in rows:
        ac = r["acoustics"]
        for what, key in (("rattle", "rattle_third_octave_db"),
                          ("background", "background_third_octave_db")):
            f, db = _band_arrays(ac.get(key) or {})
            if f.size:
                traces.append((what, f, db))
                for fk, dk in zip(f, db):
                    pooled[what].setdefault(fk, []).append(dk)
    means: dict[str, tuple[np.ndarray, np.ndarray] | None] = {}
    for what in ("rattle", "background"):
        means[what] = None
        if pooled[what]:
            f = np.array(sorted(pooled[what]))
            means[what] = (f, np.array([energy_mean_db(pooled[what][k]) for k in f]))
    v = np.array([r["v_rms_m_s"] for r in rows])
    laeq = np.array([_num(r["acoustics"].get("laeq_db")) for r in rows])
    lafmax = np.array([_num(r["acoustics"].get("lafmax_db")) for r in rows])
    n5 = np.array([_num(r["acoustics"].get("loudness_n5_sone")) for r in rows])
    nmax = np.array([_num(r["acoustics"].get("loudness_max_sone")) for r in rows])
    ok = np.isfinite(v) & (v > 0)
    level_guide = (db_slope_guide(v[ok], laeq[ok], 20.0)
                   if ok.sum() >= 1 and np.isfinite(laeq[ok]).any() else None)
    sel = ok & np.isfinite(n5) & (n5 > 0)
    loudness_guide = power_law_guide(v[sel], n5[sel], 0.602) if sel.any() else None
    fields = tuple(sorted({str(r["acoustics"].get("sound_field") or "free") for r in rows}))
    return AcousticsContent(tuple(rows), tuple(traces), means, v, laeq, lafmax, n5, nmax,
                            level_guide, loudness_guide, calibration_note(rows), fields,
                            listener_metrics(rows))


def listener_metrics(rows: list[dict[str, Any]]) -> ListenerMetrics:
    """Impulsiveness, impact rate, loudness above the background and the ECMA-418-2 metrics
    of each run (issue 26), for the acoustics section's second page."""
    def col(key: str) -> np.ndarray:
        return np.array([_num(r["acoustics"].get(key)) for r in rows])

    flags = tuple(dict.fromkeys(str(f) for r in rows
                                for f in r["acoustics"].get("psychoacoustic_flags") or []))
    ecma = col("loudness_ecma_sone")
    if np.isfinite(ecma).any():
        note = ""
    elif "ecma418_unavailable" in flags:
        note = ("ECMA-418-2 loudness, tonality and roughness: not computed, the optional "
                "package sottek-hearing-model is not installed")
    elif any("uncalibrated" in f for f in flags):
        note = "ECMA-418-2 loudness, tonality and roughness: not computed, microphone uncalibrated"
    else:
        note = ("ECMA-418-2 loudness, tonality and roughness: not computed ([fit] ecma418_s = 0, "
                "the default; give the seconds of rattle per run to rate)")
    return ListenerMetrics(col("impulse_prominence"), col("impulse_penalty_db"),
                           col("impacts_per_s"), col("loudness_above_background_sone"),
                           col("background_loudness_spread_sone"), ecma, col("tonality_tu"),
                           col("roughness_asper"), note, flags)
