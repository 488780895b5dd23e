"""Fill numba's on-disk cache with every compiled function, two processes at a time.

``python -m rattle_lab._warmup`` (``make install`` and ``make test`` run it after installing):
without it the first ``rattle-lab fit`` of a fresh install spends about 40 s compiling the
detection, flight-model and loudness kernels, and the first sweep or Lyapunov exponent
their own, in every process that gets there before the cache is written.  Each function is
compiled by calling what calls it, on small made-up inputs, so that numba compiles the
signatures the package uses (the dtypes of the arrays it passes).  Two groups run side by
side: the simulator's kernels and what is built on them (sweeps, the Lyapunov exponent), and
the rest (detection, the flight model and its ringing search, the channel checks, loudness,
the multi-mode model, the thesis's RK4).  A signature left out costs a compilation
on first use, nothing else.

:data:`COMPILED` lists the compiled functions by module; a test checks that it names every
function the package compiles with numba's cache.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable

#: The package's cached numba functions outside the simulator's kernel, by module (a test
#: checks that it names them all).  The kernel's (:mod:`rattle_lab.model.sdf._compiled`) are
#: compiled by :func:`~rattle_lab.model.sdf.warm_cache` and the sweep (``run_sweep``).
COMPILED: dict[str, tuple[str, ...]] = {
    "rattle_lab.model.sdf._rk4_thesis": ("_wrap_phase", "_rk4_slopes", "_rk4_increments",
                                          "_kernel", "_grow", "_acc"),
    "rattle_lab.model.analysis._periods": ("_classify", "_repeat_residuals", "_decays_to_zero",
                                            "_settled", "_classify_windows"),
    "rattle_lab.model.analysis.lyapunov": ("_tangent", "_phi"),
    "rattle_lab.model.modal._expsum": ("value", "start_exclusion", "first_touch", "bound",
                                        "_solve", "_envelope_max"),
    "rattle_lab.detect._flight_kernels": ("free_response", "free_sums", "residual_ss",
                                          "_sums_z", "_residual_z", "_solve2", "solve_flights",
                                          "added_sums", "eliminate_free", "sparse_cross",
                                          "tail_columns", "sparse_gram", "carried_gains",
                                          "solve_flights_rows", "_beta_gamma", "forced_rows",
                                          "tail_runs"),
    "rattle_lab.detect._jump_kernels": ("local_design", "local_lstsq", "local_eval", "_fit",
                                        "fit_value", "fits_at", "half_region", "pulse_peak",
                                        "_step_centroid",
                                        "_contact_pulse", "jump_fits_batch", "_refined",
                                        "sound_windows", "step_rows", "onsets",
                                        "lag_correlation"),
    "rattle_lab.records._scan": ("_n_equal", "flat_runs"),
    "rattle_lab.acoustics._iso532": ("_slopes", "_decay_frame", "_weight_frame", "_run",
                                     "_core_loudness"),
    "rattle_lab.acoustics._nl_decay": ("_decay_rows",),
    "rattle_lab.acoustics._filters": ("_band_power_sums", "_weighting_bins"),
}


def simulator() -> None:
    """The simulator's kernels, then the sweeps and the Lyapunov exponent."""
    import numpy as np

    from rattle_lab.model.analysis import (lyapunov_exponent, lyapunov_from_result, sweep,
                                           tangent_log_growth)
    from rattle_lab.model.sdf import SDFParams, simulate, warm_cache

    warm_cache()
    base = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)
    sweep("omega", [0.95, 1.0], base=base, cycles=20, discard=10, n_max=4, lyapunov="aperiodic",
          lyapunov_cycles=10.0, lyapunov_warmup=2.0)
    lyapunov_exponent(base, cycles=10.0, warmup_cycles=2.0)
    result = simulate(base, cycles=10.0)
    lyapunov_from_result(result, t_start=0.0, warmup=5.0)
    tangent_log_growth(base, result, np.array([10.0, 20.0]), t_start=0.0)


def pipeline() -> None:
    """Detection (local fits, the flight model, its ringing searches), the channel checks,
    the acoustics, the multi-mode model and the thesis's RK4."""
    import numpy as np

    from rattle_lab.detect import warm_cache
    from rattle_lab.model.modal import plate_system, simulate_modal
    from rattle_lab.model.sdf import SDFParams, simulate
    from rattle_lab.records import ChannelChecker

    for dtype in (np.float32, np.float64, np.int16, np.int32):
        ChannelChecker(np.dtype(dtype)).update(np.r_[np.zeros(40), np.arange(60)].astype(dtype))
    warm_cache()   # detection and the run's acoustics
    simulate_modal(plate_system(n_modes=2), cycles=3.0)
    # the thesis's RK4 (its own kernel, not the exact simulator's): here, where there is time
    simulate(SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6), cycles=5.0, method="rk4-thesis")


GROUPS: tuple[Callable[[], None], ...] = (simulator, pipeline)


def _timed(group: Callable[[], None]) -> float:
    t0 = time.perf_counter()
    group()
    return time.perf_counter() - t0


def main() -> int:
    """Run :data:`GROUPS`, side by side where there are two CPUs; print one line."""
    t0 = time.perf_counter()
    jobs = min(len(GROUPS), os.cpu_count() or 1)
    if jobs > 1:
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor

        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
            list(pool.map(_timed, GROUPS))
    else:
        for group in GROUPS:
            _timed(group)
    print(f"rattle_lab: numba kernels compiled and cached in {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":  # pragma: no cover - installation step
    sys.exit(main())
