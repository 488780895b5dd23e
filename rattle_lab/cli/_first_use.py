"""The first use of the compiled kernels after an install: say so, and show the progress.

numba compiles the exact simulator's kernels on their first call and caches them on disk
(``cache=True``); a fresh ``pip install .`` has no cache, and the first ``rattle-lab
simulate`` would sit silent for about half a minute.  A wheel install runs no code of the
package, so the compile cannot happen at install time there (``make install`` and ``make
demo`` do run it: ``python -m rattle_lab._warmup``).  Instead the commands that
simulate check the cache first and, when a kernel is missing, say so on stderr and
compile the kernels one by one with a progress line each.  The commands that detect impacts
(``fit``, ``run``, ``demo``) then do the same for the detection's kernels
(:func:`rattle_lab.detect.warm_cache`, about 15 s), which would otherwise compile silently
inside the first run's detection.
"""

from __future__ import annotations

import sys
import time

#: Commands that run the compiled kernels (simulate, fit's ramp replays, the model).
KERNEL_COMMANDS = frozenset({"simulate", "demo", "model", "fit", "run", "report", "explore"})
#: ``model`` sub-commands that do not simulate (the plate and modal models).
NO_KERNEL_MODEL_COMMANDS = frozenset({"plate", "modal", None})

NOTICE = ("rattle-lab: compiling the exact kernels once, about 30 s (numba; later runs load "
          "them from its cache)")
#: Commands that detect impacts (and rate a run's sound): the detection's kernels.
DETECT_COMMANDS = frozenset({"fit", "run", "demo"})
DETECT_NOTICE = ("rattle-lab: compiling the detection's kernels once, about 15 s (numba; later "
                 "runs load them from its cache)")


def compile_if_cold(command: str | None, model_command: str | None = None) -> bool:
    """Compile the kernels, with a notice and progress on stderr, if ``command`` needs them
    and numba's cache lacks one: the simulator's, then (a command that detects impacts) the
    detection's.  Returns True when it compiled."""
    if command not in KERNEL_COMMANDS or (command == "model"
                                          and model_command in NO_KERNEL_MODEL_COMMANDS):
        return False
    compiled = _compile_simulator()
    if command in DETECT_COMMANDS:
        from rattle_lab.detect import kernels_cold, warm_cache

        if kernels_cold():
            print(DETECT_NOTICE, file=sys.stderr, flush=True)
            t0 = time.perf_counter()
            warm_cache()
            print(f"rattle-lab: detection kernels compiled and cached in "
                  f"{time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
            compiled = True
    return compiled


def _compile_simulator() -> bool:
    from rattle_lab.model.sdf import KERNELS, cold_kernels, warm_cache

    if not cold_kernels():
        return False
    print(NOTICE, file=sys.stderr, flush=True)
    t0 = time.perf_counter()

    def line(i: int, name: str) -> None:
        print(f"rattle-lab: compiling kernel {i + 1} of {len(KERNELS)} ({name}), "
              f"{time.perf_counter() - t0:.0f} s so far", file=sys.stderr, flush=True)

    seconds = warm_cache(on_kernel=line)
    print(f"rattle-lab: kernels compiled and cached in {seconds:.0f} s", file=sys.stderr,
          flush=True)
    return True
