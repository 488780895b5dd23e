"""Throughput of issue 26's psychoacoustic metrics for one 51.2 kHz microphone channel.

Each metric's CPU time (``time.process_time``, one thread: BLAS/FFT threads pinned to 1) on a
signal of rattle-like clicks in noise, as a multiple of real time (seconds of sound per
second of CPU: the goal is >= 50x per core).  ECMA-418-2 (sottek-hearing-model, optional) on
a shorter stretch: it is slow; beside it, the floor of any implementation of the standard
(``ecma418_floor.py``: its filter bank compiled and its tonality's ACFs by FFT).  The number
of repeats keeps each row under a few seconds.

Run: ``python benchmarks/psychoacoustics.py [seconds_of_sound]``
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from threadpoolctl import threadpool_limits

import numpy as np

from rattle_lab.acoustics import (ecma418, ecma418_available, find_onsets, loudness,
                                  rattle_episodes, run_acoustics)
from rattle_lab.acoustics._episodes import episode_psychoacoustics

FS = 51200.0


def clicks(dur: float, rate_hz: float = 20.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    x = rng.normal(0.0, 2e-3, round(dur * FS))
    t_imp = np.arange(0.5, dur - 0.5, 1.0 / rate_hz)
    k = np.arange(round(0.012 * FS))
    click = 0.5 * np.exp(-k / FS / 0.002) * np.sin(2 * np.pi * 2000 * k / FS)
    for ti in t_imp:
        i = round(ti * FS)
        x[i:i + k.size] += click[:x.size - i]
    return x, t_imp


def cpu(fn, repeats: int = 1) -> float:
    fn()  # warm (imports, numba, caches)
    t0 = time.process_time()
    for _ in range(repeats):
        fn()
    return (time.process_time() - t0) / repeats


def measure(dur: float = 10.0, ecma_floor_s: float = 2.0) -> list[tuple[str, float, float]]:
    """(metric, seconds of sound, CPU s) of each metric, one thread; ECMA-418-2 on 2 s when
    sottek-hearing-model is installed, and the floor of any implementation of it
    (``ecma418_floor.py``) on ``ecma_floor_s`` s."""
    from ecma418_floor import floor_rows

    x, t_imp = clicks(dur)
    eps = rattle_episodes(t_imp, start_time_s=0.0, duration_s=dur)
    rows = []
    with threadpool_limits(1):
        rows.append(("impulse prominence P, K_I (ISO/PAS 1996-3)", dur,
                     cpu(lambda: find_onsets(x, FS), 3)))
        rows.append(("impacts per second + P per episode (no loudness)", dur,
                     cpu(lambda: episode_psychoacoustics(x, FS, t_imp, eps, [],
                                                         with_loudness=False), 3)))
        rows.append(("ISO 532-1 loudness (rattle_lab.acoustics.loudness)", dur,
                     cpu(lambda: loudness(x, FS))))
        rows.append(("run_acoustics: levels, bands, loudness of run + episodes", dur,
                     cpu(lambda: run_acoustics(x, FS, t_imp), 3)))
        if ecma418_available():
            short = x[:round(2.0 * FS)]
            rows.append(("ECMA-418-2 tonality+loudness+roughness (sottek-hm)", 2.0,
                         cpu(lambda: ecma418(short, FS))))
        else:
            rows.append(("ECMA-418-2 (sottek-hearing-model not installed)", float("nan"),
                         float("nan")))
    rows.extend(floor_rows(ecma_floor_s))
    return rows


def main() -> None:
    dur = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    rows = measure(dur)
    print(f"{'metric':62s} {'sound s':>8s} {'CPU s':>8s} {'x real time':>12s} {'>= 50x':>7s}")
    for name, sound, t in rows:
        ratio = sound / t if t > 0 else float("nan")
        ok = "yes" if ratio >= 50 else "NO"
        print(f"{name:62s} {sound:8.1f} {t:8.3f} {ratio:12.1f} {ok:>7s}")


if __name__ == "__main__":
    main()
