"""Benchmark of the sweep and study layer (thesis 4.2-4.3): sweeps, bifurcation sets, maps.

Run ``python benchmarks/sweeps.py [--quick]``.  Times (wall clock, best of
``--repeat`` runs after an untimed warm-up that loads the compiled kernels):

1. the Fig. 4-3 slow sweep, up and down (451 values of omega in [0.85, 1.3]
   at F = 0.2, zeta = 0.05, e = 0.6, 100 forcing periods each, 70 discarded),
   with the largest Lyapunov exponent of every aperiodic value (a 300-period
   side run each) and without it;
2. the 1/n bifurcation sets n = 1..5 of Fig. 3-10 (default grid);
3. a regime map over (F, omega) in [0.02, 0.6] x [0.6, 1.5], 150 periods per
   point (200 x 200 points; 60 x 60 with ``--quick``), serially, on a local pool
   of 2 forked worker processes (``workers=2``, pool start-up included) and on a
   Dask ``LocalCluster`` of 2 worker processes through its scheduler address
   (cluster start-up timed apart); all results are checked to be identical, and
   the break-even serial time of each parallel path is printed: with overhead
   ``o = t_parallel - t_serial / w``, parallel pays for serial work longer than
   ``o w / (w - 1)``.  The bifurcation sets are also run with ``workers=2``.
   Parallel speed-ups mean something only on an otherwise idle machine with at
   least 2 free cores; the benchmark prints the load average next to them, and
   the CPU time of the serial and the pooled regime map (the pool's workers
   included): CPU seconds per wall second show how many cores each run actually
   got, and pool CPU / serial CPU the work the pool adds, neither of which the
   load changes.  No speed-up is extrapolated from them.

Target: the up+down sweep (with Lyapunov exponents) in well under one second
on one core, i.e. < 1 s; printed as PASS/FAIL.  Numbers also go to
``benchmarks/out/sweeps.json``.  All quantities are nondimensional.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:  # run from a checkout without installing
    sys.path.insert(0, str(ROOT))

from rattle_lab._atomic import atomic_write_text
from rattle_lab.model.analysis import bifurcation_sets, regime_map, sweep_up_down, sweep_values
from rattle_lab.model.sdf import SDFParams

OUT = Path(__file__).resolve().parent / "out"
SWEEP_TARGET_S = 1.0


def _best(func: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    best, result = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = func()
        best = min(best, time.perf_counter() - t0)
    return best, result


def _cpu_s() -> tuple[float, float]:
    """CPU seconds used so far by this process, and by its reaped child processes."""
    t = os.times()
    return t.user + t.system, t.children_user + t.children_system


def _timed_cpu(func: Callable[[], Any]) -> tuple[float, float, float, Any]:
    """One run: wall seconds, CPU seconds of this process and of its worker processes.

    The workers of a local pool are child processes, reaped when the pool closes, so
    their CPU time is in ``os.times().children_*`` once the call has returned.  (The
    workers of a Dask ``LocalCluster`` are not reaped by then; their CPU time is not
    counted.)  CPU time does not depend on how busy the machine is; the wall time does.
    """
    own0, kids0 = _cpu_s()
    t0 = time.perf_counter()
    out = func()
    wall = time.perf_counter() - t0
    own1, kids1 = _cpu_s()
    return wall, own1 - own0, kids1 - kids0, out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small map, one repeat (< 60 s)")
    ap.add_argument("--repeat", type=int, default=None, help="timed repeats (default 3; quick 1)")
    args = ap.parse_args(argv)
    repeat = args.repeat or (1 if args.quick else 3)
    n_map = 60 if args.quick else 200
    base = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)
    grid = sweep_values(0.85, 1.3, 0.001)
    rows: list[tuple[str, str, float]] = []

    t0 = time.perf_counter()
    sweep_up_down("omega", grid[:3], base=base)  # warm-up: numba cache load / compile
    warm = time.perf_counter() - t0

    t_sweep, (up, down) = _best(lambda: sweep_up_down("omega", grid, base=base), repeat)
    n_ap = sum(p.regime.kind == "aperiodic" for sw in (up, down) for p in sw.points)
    rows.append(("Fig. 4-3 sweep up+down, Lyapunov on aperiodic",
                 f"2 x 451 values x 100 periods, {n_ap} exponents", t_sweep))
    t_plain, _ = _best(lambda: sweep_up_down("omega", grid, base=base, lyapunov="none"), repeat)
    rows.append(("Fig. 4-3 sweep up+down, no Lyapunov", "2 x 451 values x 100 periods", t_plain))

    t_bif, bif = _best(lambda: bifurcation_sets([1, 2, 3, 4, 5]), repeat)
    rows.append(("1/n bifurcation sets n = 1..5", "241 x 121 grid, curves traced", t_bif))
    t_bif2, bif2 = _best(lambda: bifurcation_sets([1, 2, 3, 4, 5], workers=2), repeat)
    rows.append(("1/n bifurcation sets, workers=2", "same, pool start-up included", t_bif2))
    bif_same = (np.array_equal(bif.exists, bif2.exists) and np.array_equal(bif.stable, bif2.stable)
                and all(np.array_equal(a.F, b.F) and np.array_equal(a.omega, b.omega)
                        for a, b in zip(bif.curves, bif2.curves)))

    F = np.linspace(0.02, 0.6, n_map)
    omega = np.linspace(0.6, 1.5, n_map)
    regime_map(F[:2], omega[:2])  # warm-up
    load_before = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    t_serial, cpu_serial, _, serial = _timed_cpu(lambda: regime_map(F, omega))
    rows.append(("regime map, serial", f"{n_map} x {n_map} points x 150 periods", t_serial))
    t_pool, cpu_parent, cpu_workers, pool_map = _timed_cpu(lambda: regime_map(F, omega, workers=2))
    rows.append(("regime map, local pool 2 workers", "same, pool start-up included", t_pool))
    import logging

    from dask.distributed import LocalCluster

    t0 = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                      silence_logs=logging.ERROR) as cluster:
        t_start = time.perf_counter() - t0
        t_dask, dask_map = _best(lambda: regime_map(F, omega,
                                                    scheduler=cluster.scheduler_address), 1)
    rows.append(("Dask LocalCluster start, 2 workers", "", t_start))
    rows.append(("regime map, Dask scheduler 2 workers", "same, cluster already running", t_dask))

    def _same(a: Any, b: Any) -> bool:
        return all(np.array_equal(getattr(a, k), getattr(b, k), equal_nan=k in (
            "mean_impact_velocity", "max_impact_velocity", "lyapunov"))
            for k in ("code", "m", "n", "mean_impact_velocity", "max_impact_velocity", "lyapunov"))

    same = _same(serial, pool_map) and _same(serial, dask_map) and bif_same

    print("Sweep and study benchmark (rattle_lab.model.analysis), nondimensional units.")
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"python {platform.python_version()}; best of {repeat} after warm-up "
          f"(first call incl. numba cache load: {warm:.2f} s)")
    print()
    head = f"{'task':<46} {'size':<44} {'time / s':>9}"
    print(head)
    print("-" * len(head))
    for name, size, t in rows:
        print(f"{name:<46} {size:<44} {t:>9.3f}")
    print()
    w = 2
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"regime map: {n_map * n_map / t_serial:,.0f} points/s serial; results of every "
          f"parallel run identical to serial: {same}")
    print(f"load average {load:.1f} on {os.cpu_count()} cores (1-min average before the "
          f"map runs {load_before[0]:.1f}): the wall-clock speed-ups below are meaningful "
          f"only on an idle machine (goal >= 1.8x on 2 cores)")
    # What the machine gave each run, from CPU time (which load does not change): a run
    # that had a core to itself uses ~1 CPU second per wall second, a 2-worker run ~2.
    cores_serial = cpu_serial / t_serial
    cores_pool = (cpu_parent + cpu_workers) / t_pool
    print(f"  regime map CPU time: serial {cpu_serial:.2f} s in {t_serial:.2f} s wall "
          f"({cores_serial:.2f} cores); local pool {cpu_parent + cpu_workers:.2f} s "
          f"(parent {cpu_parent:.2f}, workers {cpu_workers:.2f}) in {t_pool:.2f} s wall "
          f"({cores_pool:.2f} cores)")
    print(f"  work added by the pool (CPU time pool / serial): "
          f"{(cpu_parent + cpu_workers) / cpu_serial:.2f}x; the wall-clock speed-up "
          f"{t_serial / t_pool:.2f}x was measured with {cores_pool:.2f} of {w} cores obtained "
          f"against {cores_serial:.2f} of 1 for the serial run")
    for name, t_par in (("local pool, 2 workers", t_pool),
                        ("Dask scheduler, 2 workers", t_dask),
                        ("Dask incl. cluster start", t_dask + t_start),
                        ("bifurcation sets, pool 2 workers", t_bif2)):
        t_ser = t_bif if name.startswith("bifurcation") else t_serial
        over = max(t_par - t_ser / w, 0.0)
        print(f"  {name:<34} {t_ser / t_par:5.2f}x over serial; overhead {over:6.2f} s, "
              f"break-even at {over * w / (w - 1):6.2f} s of serial work")
    ok = t_sweep < SWEEP_TARGET_S
    print(f"{'PASS' if ok else 'FAIL'}: Fig. 4-3 up+down sweep {t_sweep:.3f} s < "
          f"{SWEEP_TARGET_S:g} s on one core")
    OUT.mkdir(exist_ok=True)
    atomic_write_text(OUT / "sweeps.json", json.dumps({
        "quick": args.quick, "repeat": repeat, "warmup_s": warm,
        "rows": [{"task": n, "size": s, "time_s": t} for n, s, t in rows],
        "regime_map_cpu_s": {"serial": cpu_serial, "pool_parent": cpu_parent,
                             "pool_workers": cpu_workers},
        "load_average": list(load_before),
        "map_identical": same, "sweep_target_s": SWEEP_TARGET_S, "sweep_pass": ok,
    }, indent=2))
    return 0 if ok and same else 1


if __name__ == "__main__":
    sys.exit(main())
