"""Lightly damped ringing in the vibrometer: e from velocity ratios on a campaign we did not make.

The campaign comes from ``tests/independent_campaign.py`` (plain NumPy and h5py, its own exact
SDF flow and measurement chain; no rattle_lab code): a CFCF plate, f_s 96 Hz, e 0.55, four
ramps up and four down at 93-98 Hz and a dwell at 97 Hz, with the plate's higher modes at
171, 293 and 390 Hz, ``zeta_j`` of critical (default 2 %), 28 % of each velocity jump, in the
vibrometer.  Such modes ring on past the next impact: their tails sit in ``v_in`` as well as
in the jump, and no share of the jump undoes that.  Rows, each through
:func:`rattle_lab.workflow.fit_store` (what ``rattle-lab fit`` runs):

* ``local fits``: ``velocity_model = "local"`` (the detector's fits either side of each
  impact; what a user of a plain impact detector would get);
* ``campaign modes``: the default: the runs ring and no run's own flight model measures a
  share, so the modes are searched across the runs with each impact's ringing carried on
  (:func:`rattle_lab.detect.campaign_ring_modes`) and ``v_in``/``v_out`` come from the
  flight model with them;
* ``true modes``: the same with the generator's own modes given (``ring_modes``): what the
  flight model can do when the search is perfect.

Usage: ``python benchmarks/slow_ringing.py [--seeds 3] [--zeta-j 0.02]``.  Timings under load.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from independent_campaign import Chain, Plant, write_campaign  # noqa: E402

from rattle_lab.store import ingest  # noqa: E402
from rattle_lab.workflow import fit_store  # noqa: E402


def campaign(folder: Path, seed: int, zeta_j: float, ringing: bool = True
             ) -> tuple[Path, Chain]:
    """The campaign, ingested; ``ringing=False``: the vibrometer on a nodal line of the modes
    (``benchmarks/ringing_cost.py`` compares the two)."""
    plant = Plant()

    def grazing(f: float) -> float:
        w, r = 2 * math.pi * plant.f_s_hz, f / plant.f_s_hz
        return plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) \
            / plant.q

    runs = []
    for f in (93.0, 95.0, 97.0, 98.0):
        n = int(2.0 * f)
        runs.append({"run_id": f"up_{f:g}", "protocol": "amplitude_ramp_up", "freq_hz": f,
                     "levels": np.linspace(0.5 * grazing(f), 1.5 * grazing(f), n)})
        runs.append({"run_id": f"down_{f:g}", "protocol": "amplitude_ramp_down", "freq_hz": f,
                     "levels": np.linspace(1.5 * grazing(f), 0.3 * grazing(f), n)})
    runs.append({"run_id": "dwell_97", "protocol": "sine_dwell", "freq_hz": 97.0,
                 "levels": np.full(100, 1.3 * grazing(97.0))})
    chain = Chain(ring_zeta=(zeta_j,) * 3, ring_in_velocity=ringing)
    name = "ringing" if ringing else "quiet"
    write_campaign(folder / f"{name}.h5", plant, chain, runs, seed=seed)
    ingest([folder / f"{name}.h5"], folder / f"{name}_store.h5", quiet=True)
    return folder / f"{name}_store.h5", chain


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1, help="campaigns (seeds 3, 4, ...)")
    ap.add_argument("--zeta-j", type=float, default=0.02, help="the higher modes' damping ratio")
    args = ap.parse_args()
    e_true = Plant().e
    print(f"e from velocity ratios, independent campaign, higher modes at zeta_j = {args.zeta_j}"
          f" in the vibrometer (truth e = {e_true})")
    print(f"{'seed':>4}  {'method':<15} {'e':>8} {'error':>8} {'95 % covers':>11} "
          f"{'time s':>7}  modes found (Hz, decay 1/s)")
    for seed in range(3, 3 + args.seeds):
        with tempfile.TemporaryDirectory() as tmp:
            store, chain = campaign(Path(tmp), seed, args.zeta_j)
            true_modes = [[f, z * 2 * math.pi * f] for f, z in zip(chain.ring_hz,
                                                                   chain.ring_zeta)]
            for name, detect in (("local fits", {"velocity_model": "local"}),
                                 ("campaign modes", {}),
                                 ("true modes", {"ring_modes": true_modes})):
                t0 = time.perf_counter()
                res = fit_store(store, detect=detect, write=False)
                dt = time.perf_counter() - t0
                rr = res.summary.fits.restitution_ratio
                modes = sorted({m for r in res.runs if r.impacts is not None
                                for m in r.impacts.ring_modes})
                covers = abs(rr.value - e_true) <= 1.96 * rr.stderr
                print(f"{seed:>4}  {name:<15} {rr.value:>8.4f} {100 * (rr.value / e_true - 1):>+7.2f}%"
                      f" {'yes' if covers else 'no':>11} {dt:>7.0f}  "
                      + ", ".join(f"{f:.1f}/{s:.1f}" for f, s in modes), flush=True)


if __name__ == "__main__":
    main()
