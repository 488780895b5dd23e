"""Accuracy of detection and fitting against known truth, with the run time of each stage.

Scenes: ``rattle_lab.detect._synthetic.synthetic_campaign`` -- hand-built
signals around chosen impacts, ramps whose thresholds follow eq. (3.4) and the
1/1 saddle-node (the physical synthetic rig, ``rattle_lab.rig``, did not exist
when this was written; swap it in when it does).  Noise levels are relative
(``noise_rel``: 1 % is the "realistic" level the targets refer to).

Prints, per noise level: detection precision / recall / F1, impact-time error,
impact-velocity error, threshold error, fitted gap, zeta, f_s and e errors,
SPL-law slope error, each with PASS/FAIL against the targets at the realistic
level; then the real-record results (../shared/realdata) when present.

Usage: ``python benchmarks/accuracy.py [--quick] [--json FILE]``
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

from rattle_lab.detect import ImpactParams, cross_correlation_delay, detect_impacts, sound_peaks
from rattle_lab.detect._synthetic import synthetic_campaign
from rattle_lab.fit import (analyse_run, fit_grazing, fit_linear_law, fit_restitution_down,
                            restitution_from_ratios)
from rattle_lab.thresholds import tabulate_thresholds

ROOT = Path(__file__).resolve().parents[1]
REALDATA = (ROOT / ".." / "shared" / "realdata").resolve()
REALISTIC = 0.01
TARGETS = {"f1": (">=", 0.99), "v_err_rel": ("<=", 0.02), "gap_err_rel": ("<=", 0.02),
           "f_s_err_rel": ("<=", 0.005), "zeta_err_rel": ("<=", 0.10), "spl_slope_err_rel": ("<=", 0.03)}


def _match(t_true: np.ndarray, t_det: np.ndarray, tol_s: float) -> tuple[int, np.ndarray, np.ndarray]:
    """Greedy one-to-one matching within ``tol_s``: (n matched, true idx, det idx)."""
    if t_true.size == 0 or t_det.size == 0:
        return 0, np.zeros(0, int), np.zeros(0, int)
    k = np.clip(np.searchsorted(t_det, t_true), 1, t_det.size - 1) if t_det.size > 1 else np.zeros(t_true.size, int)
    cand = np.where(np.abs(t_det[k - 1 if t_det.size > 1 else k] - t_true) < np.abs(t_det[k] - t_true),
                    k - 1 if t_det.size > 1 else k, k)
    ok = np.abs(t_det[cand] - t_true) <= tol_s
    ti, di = np.flatnonzero(ok), cand[ok]
    _, first = np.unique(di, return_index=True)
    return int(first.size), ti[first], di[first]


def run_scene(noise_rel: float, quick: bool, seed: int = 0) -> dict[str, float]:
    times: dict[str, float] = {}
    t0 = time.perf_counter()
    kw = dict(up_freq_hz=(85.0, 93.0, 95.0, 96.0, 97.0, 99.0, 106.0),
              down_freq_hz=(106.0, 112.0), duration_s=0.6) if quick else {}
    record, truth = synthetic_campaign(noise_rel=noise_rel, seed=seed, extra_runs=True, **kw)
    times["generate_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    runs = [analyse_run("synthetic", run, detect={}, fit={"n_confirm": 3},
                        mic_distance_m=record.rig.mic_distance_m) for run in record.runs]
    times["detect_s"] = time.perf_counter() - t0
    tp = fp = fn = 0
    dt, dv, v_true_all, p_max_all = [], [], [], []
    for r in runs:
        if r.impacts is None:
            continue
        t_true, v_true = truth.impacts[r.run_id]
        n, ti, di = _match(t_true, r.impacts.t_s, 0.5e-3)
        tp, fp, fn = tp + n, fp + r.impacts.n_impacts - n, fn + t_true.size - n
        dt.extend(np.abs(r.impacts.t_s[di] - t_true[ti]))
        dv.extend(np.abs(r.impacts.v_in_m_s[di] / v_true[ti] - 1))
        if r.peaks is not None:
            v_true_all.extend(np.abs(r.impacts.v_in_m_s[di]))
            p_max_all.extend(r.peaks.p_max_pa[di])
    t0 = time.perf_counter()
    curve = tabulate_thresholds([r.threshold for r in runs if r.threshold is not None])
    times["thresholds_s"] = time.perf_counter() - t0
    up_true = dict(zip(truth.up_freq_hz, truth.up_ms2))
    thr_err = [abs(a / up_true[f] - 1) for f, a in zip(curve.freq_hz, curve.up_ms2)
               if f in up_true and np.isfinite(a)]
    t0 = time.perf_counter()
    g = fit_grazing(curve.freq_hz, curve.up_ms2, participation=truth.participation)
    times["grazing_fit_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    e_ratio = restitution_from_ratios(np.concatenate([r.impacts.e for r in runs if r.impacts is not None]))
    p = g.params
    e_down = fit_restitution_down(curve.freq_hz, curve.down_ms2, gap_m=p["gap_m"].value,
                                  f_s_hz=p["f_s_hz"].value, zeta=p["zeta"].value,
                                  participation=truth.participation)
    times["restitution_fit_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    law = fit_linear_law(v_true_all, p_max_all)
    times["spl_fit_s"] = time.perf_counter() - t0
    slope_true = truth.acoustics.gain_pa_per_m_s * truth.acoustics.peaks()[1]
    precision = tp / (tp + fp) if tp + fp else 1.0
    recall = tp / (tp + fn) if tp + fn else 1.0
    return {
        "noise_rel": noise_rel, "precision": precision, "recall": recall,
        "f1": 2 * precision * recall / (precision + recall) if precision + recall else 0.0,
        "t_err_med_us": 1e6 * float(np.median(dt)), "t_err_max_us": 1e6 * float(np.max(dt)),
        "v_err_rel": float(np.median(dv)), "v_err_p95_rel": float(np.percentile(dv, 95)),
        "thr_err_rel": float(np.median(thr_err)),
        "gap_err_rel": abs(p["gap_m"].value / truth.gap_m - 1),
        "f_s_err_rel": abs(p["f_s_hz"].value / truth.f_s_hz - 1),
        "zeta_err_rel": abs(p["zeta"].value / truth.zeta - 1),
        "e_ratio_err": abs(e_ratio.mean - truth.e), "e_down_err": abs(e_down.e.value - truth.e),
        "spl_slope_err_rel": abs(law.slope / slope_true - 1), **times,
    }


def real_records() -> dict[str, object]:
    if not REALDATA.is_dir():
        return {"skipped": f"{REALDATA} absent"}
    from rattle_lab.records import read

    out: dict[str, object] = {}
    shock = ImpactParams(on=100.0, off=10.0, min_separation_s=0.5)
    maps = ROOT / "data_schema" / "mappings"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = read(REALDATA / "droptable" / "Test_001.lvm", mapping=maps / "droptable_lvm.toml")
        run = rec.runs[0]
        for name in ("table", "board"):
            ch = run.channel(name)
            log = detect_impacts(ch.sample_rate_hz, accel_ms2=ch.read(), params=shock)
            out[f"droptable_{name}"] = f"{log.n_impacts} event(s), onset {log.onset_s[0]:.5f} s"
        out["droptable_delay_ms"] = round(1e3 * cross_correlation_delay(
            run.channel("table").read(), run.channel("board").read(), 51200.0, max_lag_s=0.01), 4)
        rec = read(REALDATA / "hammer" / "measurements_1.npy", mapping=maps / "hammer_npy.toml")
        run = rec.runs[0]
        t = run.timestamps["t"].read(0, run.channel("force").n_samples)
        fs = 1.0 / float(np.median(np.diff(t)))
        log = detect_impacts(fs, accel_ms2=run.channel("force").read(), params=shock)
        pk = sound_peaks(run.channel("response").read(), fs, log.t_s, window_s=0.05)
        out["hammer"] = (f"{log.n_impacts} hit at {1e3 * log.t_s[0]:.3f} ms; response first peak "
                         f"+{1e3 * pk.delay_first_s[0]:.3f} ms, max +{1e3 * pk.delay_max_s[0]:.3f} ms")
        rec = read(REALDATA / "clap" / "rir_clap.wav", mapping=maps / "clap_wav.toml")
        ch = rec.runs[0].channels[0]
        log = detect_impacts(ch.sample_rate_hz, accel_ms2=ch.read(), params=shock)
        pk = sound_peaks(ch.read(), ch.sample_rate_hz, log.onset_s, window_s=0.05)
        out["clap"] = (f"{log.n_impacts} event, onset {1e3 * log.onset_s[0]:.3f} ms, first peak "
                       f"{1e3 * pk.t_first_s[0]:.3f} ms ({pk.p_first_pa[0]:.3f} FS), max "
                       f"{1e3 * pk.t_max_s[0]:.3f} ms ({pk.p_max_pa[0]:.3f} FS)")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer, shorter runs (< 60 s)")
    ap.add_argument("--json", metavar="FILE", help="also write the results as JSON")
    args = ap.parse_args()
    levels = (0.0, REALISTIC, 0.03) if not args.quick else (0.0, REALISTIC)
    rows = [run_scene(level, args.quick) for level in levels]
    keys = [k for k in rows[0] if k != "noise_rel"]
    print("generator: rattle_lab.detect._synthetic (own; rattle_lab.rig not used)")
    print(f"{'metric':<20}" + "".join(f"  noise={r['noise_rel']:<8g}" for r in rows) + "  target@1%")
    for k in keys:
        line = f"{k:<20}" + "".join(f"  {r[k]:<14.4g}" for r in rows)
        if k in TARGETS:
            op, lim = TARGETS[k]
            val = next(r[k] for r in rows if r["noise_rel"] == REALISTIC)
            ok = val >= lim if op == ">=" else val <= lim
            line += f"  {op}{lim:g} {'PASS' if ok else 'FAIL'}"
        print(line)
    real = real_records()
    print("\nreal records (../shared/realdata):")
    for k, v in real.items():
        print(f"  {k}: {v}")
    if args.json:
        Path(args.json).write_text(json.dumps({"synthetic": rows, "real": real}, indent=2))


if __name__ == "__main__":
    main()
