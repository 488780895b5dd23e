"""``make demo`` / ``rattle-lab demo``: the main job on the embedded default scene."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from .plots import plot_time_history
from .sdf import SDFParams, simulate


def run_demo(out_dir: str | Path, *, quiet: bool = False) -> int:
    """Run the demo into ``out_dir`` and print where its outputs are.

    Until the lab pipeline lands this simulates the thesis's Fig. 4-3 case
    (F = 0.2, zeta = 0.05, e = 0.6) at omega = 1, prints the impacts and writes
    a time-history plot.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    params = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)
    cycles = 30
    t = np.linspace(0.0, cycles * params.period, 200 * cycles + 1)
    res = simulate(params, cycles=cycles, dense_t=t,
                   dense_fields=("x", "v", "a", "forced", "transient", "excitation"))
    print(f"SDF impact oscillator F={params.F} omega={params.omega} zeta={params.zeta} "
          f"e={params.e}: {len(res.impacts)} impacts in {cycles} forcing cycles")
    for t_i, v_i in list(zip(res.impacts.t, res.impacts.v_in))[-5:]:
        print(f"  impact at t = {t_i:12.6f}  v_in = {v_i:.12f}")
    path = plot_time_history(res, out / "sdf_time_history.png")
    print(f"plot: {path.resolve()}", file=sys.stdout)
    return 0
