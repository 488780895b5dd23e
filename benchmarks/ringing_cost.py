"""Issue 29, item 3: what the expensive models (flight model, campaign ringing search) cost.

The goal: a record without ringing pays nothing for them; one with ringing at most twice the
base cost.  The base cost is the fit with ``velocity_model = "local"`` (detection, the local
fits either side of each impact, thresholds, fits, levels and loudness: no flight model, no
ringing search); the default (``velocity_model = "auto"``) adds the flight model and, where
the runs ring, the campaign's mode search.

Two campaigns from ``tests/independent_campaign.py`` (plain NumPy and h5py, no rattle_lab
code; the ramps and dwell of ``benchmarks/slow_ringing.py``), the same seed: the plate's
higher modes (171, 293, 390 Hz, 2 % of critical) in the vibrometer, and the vibrometer at a
nodal line of those modes (no ringing).  Each fit through
:func:`rattle_lab.workflow.fit_store` (what ``rattle-lab fit`` runs), nothing written; the
time is the best of ``--repeats`` wall-clock runs in this process (imports and numba's cache
loads are paid before the first).

Usage: ``python benchmarks/ringing_cost.py [--repeats 2] [--seed 3]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from slow_ringing import campaign  # noqa: E402
from throughput import machine  # noqa: E402

from rattle_lab.workflow import fit_store  # noqa: E402


def best_of(store: Path, detect: dict[str, object], repeats: int) -> tuple[float, object]:
    best, res = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = fit_store(store, detect=detect, write=False, quiet=True)
        best = min(best, time.perf_counter() - t0)
    return best, res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=2, help="fits per row (the best is shown)")
    ap.add_argument("--seed", type=int, default=3)
    args = ap.parse_args()
    print(f"# {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        stores = {ringing: campaign(Path(tmp), args.seed, 0.02, ringing)[0]
                  for ringing in (False, True)}
        for detect in ({"velocity_model": "local"}, {}):     # imports, numba cache loads
            fit_store(stores[False], detect=detect, write=False, quiet=True)
        print(f"{'campaign':<34} {'base (local) s':>14} {'default s':>10} {'ratio':>6} "
              f"{'goal':>6}  modes searched (Hz)")
        for ringing, store in stores.items():
            base, res0 = best_of(store, {"velocity_model": "local"}, args.repeats)
            full, res = best_of(store, {}, args.repeats)
            # a fair ratio needs the same fits made: a fit the base refused costs it nothing
            skipped = sorted(set(res0.summary.not_fitted) - set(res.summary.not_fitted))
            if skipped:
                print(f"  (the base did not make {', '.join(skipped)}: the ratio is high)")
            modes = sorted({round(m[0], 1) for r in res.runs if r.impacts is not None
                            for m in r.impacts.ring_modes})
            what = ("higher modes ring in the vibrometer" if ringing
                    else "no ringing (vibrometer on a nodal line)")
            goal = "<= 2" if ringing else "~ 1"
            print(f"{what:<34} {base:>14.1f} {full:>10.1f} {full / base:>6.2f} {goal:>6}  "
                  + (", ".join(f"{f:g}" for f in modes) or "-"), flush=True)


if __name__ == "__main__":
    main()
