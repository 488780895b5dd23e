"""Do the reported 95 % intervals mean what they say?  Coverage over seeded campaigns.

For each of N seeds (default 50) a campaign is drawn from the detector's own generator
(``rattle_lab.rig._handbuilt.synthetic_campaign``: ramp thresholds that follow eq. 3.4
and the saddle-node exactly, with relative noise ``noise_rel`` on every channel), detected
and fitted as ``rattle-lab fit`` does; each parameter's reported 95 % interval is checked
against the truth.  Target: each covers the truth in >= 90 % of the campaigns.

Intervals: grazing fit (gap, f_s, zeta) of the crossing levels (half a forcing period
before each first impact, as ``rattle-lab fit``): lmfit profile 95 % interval; e from velocity
ratios: mean +- 1.96 standard errors, as ``rattle-lab fit`` reports it (``e_ratio``,
:func:`rattle_lab.fit.ratios_of_runs`: run-clustered, the runs' pooled ringing share taken
off with its error) and the one that treats every impact as independent (``e_ratio_iid``,
as before).  This generator's thresholds carry no ramp lag, so eq. (3.4)
is its exact model.

``--rig SCENE`` draws the campaigns from the synthetic rig instead (``default`` or a file in
``synthetic/``, e.g. ``realistic_lab.toml``): the scene as written with its ``seed`` replaced
by each campaign's, detected and fitted as ``benchmarks/accuracy.py`` does, with the rig's
participation passed in.  The rig's exact dynamics lag the ramp, so ``gap_m``, ``f_s_hz`` and
``zeta`` are the ramp-corrected grazing fit (``fit_grazing_ramp``: each threshold's lag
replayed through the simulator and removed, eq. (3.4) refitted; profile 95 % intervals);
``gap_qs``/``zeta_qs`` are eq. (3.4) on the raw crossing levels and ``zeta_ramp_qsgap`` the
replay of zeta alone at that gap (the fits before the correction), for comparison.  e from
velocity ratios as above; e from the downward thresholds by the ramp model at the corrected
gap, f_s and zeta: value -+ 1.96 stderr.  A rig campaign takes ~20 s under load, so use a
small ``--n`` there.

Usage: ``python benchmarks/interval_coverage.py [--n 50] [--noise 0.01] [--rig SCENE]``.
Timings under load.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

from rattle_lab.detect.thresholds import tabulate_thresholds
from rattle_lab.fit import (analyse_run, fit_grazing, fit_grazing_ramp, fit_restitution_down,
                            fit_zeta_ramp, ratios_of_runs, restitution_from_ratios,
                            ringing_corrected_ratios)
from rattle_lab.fit._store import _crossing_curve
from rattle_lab.rig import load_scene, synthesize
from rattle_lab.rig._handbuilt import synthetic_campaign

ROOT = Path(__file__).resolve().parents[1]
#: ``[detect]`` of the rig scenes (``--velocity-model``).
DETECT: dict[str, str] = {}


def one_rig(seed: int, scene_name: str) -> dict[str, tuple[float, float, float]]:
    """Intervals of one rig campaign: the scene with its seed replaced by ``seed``."""
    scene = load_scene(ROOT / "synthetic" / scene_name if scene_name != "default" else "default")
    scene = dataclasses.replace(scene, seed=int(scene.seed) + 1000 * (seed + 1))
    record = synthesize(scene).record
    truth = record.truth
    runs = [analyse_run("rig", run, detect=DETECT, fit={},
                        mic_distance_m=record.rig.mic_distance_m)
            for run in record.runs]
    ths = [r.threshold for r in runs if r.threshold is not None]
    q = truth.participation
    hold = scene.simulation.piece_periods
    # eq. (3.4) fitted to the thresholds with each ramp's lag replayed and removed
    rg = fit_grazing_ramp(ths, participation=q, level_hold_periods=hold)
    assert rg.quasi_static is not None
    g, qs = rg.params, rg.quasi_static.params
    out = {name: (truth_v, g[name].ci_low, g[name].ci_high)
           for name, truth_v in (("gap_m", truth.gap_m), ("f_s_hz", truth.f_s_hz),
                                 ("zeta", truth.zeta))}
    # the uncorrected eq. (3.4) fit, and the replay of zeta alone at its gap, for comparison
    out["gap_qs"] = (truth.gap_m, qs["gap_m"].ci_low, qs["gap_m"].ci_high)
    out["zeta_qs"] = (truth.zeta, qs["zeta"].ci_low, qs["zeta"].ci_high)
    zf = fit_zeta_ramp(ths, gap_m=qs["gap_m"].value, f_s_hz=qs["f_s_hz"].value,
                       zeta0=qs["zeta"].value, participation=q, level_hold_periods=hold)
    out["zeta_ramp_qsgap"] = (truth.zeta, zf.ci_low, zf.ci_high)
    ok = [r for r in runs if r.impacts]
    # as rattle-lab fit: the runs' ringing shares pooled and taken off every ratio
    rs = ratios_of_runs([r.impacts for r in ok])
    e_mean, e_se = rs.float_value, rs.stderr if rs.stderr is not None else float("nan")
    out["e_ratio"] = (truth.e, e_mean - 1.96 * e_se, e_mean + 1.96 * e_se)
    ratios = (np.concatenate([ringing_corrected_ratios(r.impacts.v_in_m_s, r.impacts.v_out_m_s,
                                                       rs.ringing_share) for r in ok])
              if rs.ringing_runs and rs.ringing_share is not None
              else np.concatenate([r.impacts.e for r in ok]))
    st = restitution_from_ratios(ratios)
    out["e_ratio_iid"] = (truth.e, st.mean - 1.96 * st.stderr, st.mean + 1.96 * st.stderr)
    ed = fit_restitution_down(ths, gap_m=g["gap_m"].value, f_s_hz=g["f_s_hz"].value,
                              zeta=g["zeta"].value, zeta_stderr=g["zeta"].stderr,
                              participation=q, level_hold_periods=hold)
    out["e_down"] = (truth.e, ed.value - 1.96 * ed.stderr, ed.value + 1.96 * ed.stderr)
    return out


def one(seed: int, noise_rel: float) -> dict[str, tuple[float, float, float]]:
    record, truth = synthetic_campaign(noise_rel=noise_rel, seed=seed, extra_runs=False,
                                       up_freq_hz=(85.0, 93.0, 95.0, 96.0, 97.0, 99.0, 106.0),
                                       down_freq_hz=(106.0, 112.0), duration_s=0.6)
    runs = [analyse_run("s", run, detect={}, fit={"n_confirm": 3},
                        mic_distance_m=record.rig.mic_distance_m) for run in record.runs]
    curve = tabulate_thresholds([r.threshold for r in runs if r.threshold is not None])
    up = _crossing_curve([r.threshold for r in runs if r.threshold is not None], curve.freq_hz)
    g = fit_grazing(curve.freq_hz, up, participation=truth.participation).params
    out = {name: (truth_v, g[name].ci_low, g[name].ci_high)
           for name, truth_v in (("gap_m", truth.gap_m), ("f_s_hz", truth.f_s_hz),
                                 ("zeta", truth.zeta))}
    ok = [r for r in runs if r.impacts]
    rs = ratios_of_runs([r.impacts for r in ok])     # (this generator rings in no run)
    e_mean, e_se = rs.float_value, rs.stderr if rs.stderr is not None else float("nan")
    out["e_ratio"] = (truth.e, e_mean - 1.96 * e_se, e_mean + 1.96 * e_se)
    st = restitution_from_ratios(np.concatenate([r.impacts.e for r in ok]))
    out["e_ratio_iid"] = (truth.e, st.mean - 1.96 * st.stderr, st.mean + 1.96 * st.stderr)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50, help="seeded campaigns (default 50)")
    ap.add_argument("--noise", type=float, default=0.01, help="relative noise (default 0.01)")
    ap.add_argument("--rig", metavar="SCENE", help="rig campaigns of this scene ('default' or a "
                    "file in synthetic/) instead of the detector's generator")
    ap.add_argument("--velocity-model", choices=("auto", "local", "flights"), default="auto",
                    help="the detector's ringing share on rig scenes (ImpactParams.velocity_model): "
                    "auto (default: the flight model where ringing shows), local (none) or "
                    "flights (every run)")
    args = ap.parse_args()
    DETECT["velocity_model"] = args.velocity_model
    t0 = time.perf_counter()
    hits: dict[str, list[bool]] = {}
    width: dict[str, list[float]] = {}
    for seed in range(args.n):
        res = one_rig(seed, args.rig) if args.rig else one(seed, args.noise)
        for name, (truth, lo, hi) in res.items():
            hits.setdefault(name, []).append(bool(lo <= truth <= hi))
            width.setdefault(name, []).append((hi - lo) / 2 / truth)
        print(f"campaign {seed + 1}/{args.n}: " + " ".join(
            f"{name}={'in' if h[-1] else 'OUT'}" for name, h in hits.items()),
            file=sys.stderr, flush=True)
    dt = time.perf_counter() - t0
    what = f"rig scene {args.rig}" if args.rig else f"noise_rel {args.noise:g}"
    print(f"coverage of the reported 95 % intervals over {args.n} seeded campaigns "
          f"({what}); {dt:.0f} s under load ({dt / args.n:.2f} s per campaign)")
    print(f"{'parameter':<10}  {'coverage':>8}  {'median half-width':>17}  target")
    for name in hits:
        cov = float(np.mean(hits[name]))
        print(f"{name:<10}  {cov:>8.2f}  {100 * float(np.nanmedian(width[name])):>16.2f}%  "
              f">=0.90 {'PASS' if cov >= 0.90 else 'FAIL'}")


if __name__ == "__main__":
    main()
