"""The first use of the compiled kernels after an install: say so, and show the progress.

numba compiles the exact simulator's kernels on their first call and caches them on disk
(``cache=True``); a fresh ``pip install .`` has no cache, and the first ``rattle-lab
simulate`` would sit silent for about half a minute.  A wheel install runs no code of the
package, so the compile cannot happen at install time there (``make install`` and ``make
demo`` do run it: ``python -m rattle_lab._warmup``).  Instead the commands that
simulate check the cache first and, when a kernel is missing, say so on stderr and
compile the kernels one by one with a progress line each, in a child process.  The commands that detect impacts
(``fit``, ``run``, ``demo``) then do the same for the detection's kernels
(:func:`rattle_lab.detect.warm_cache`, about 15 s), which would otherwise compile silently
inside the first run's detection.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable

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
    and numba's cache lacks one: the simulator's, and (a command that detects impacts) the
    detection's.  Returns True when it compiled.

    The compiling runs in child processes (spawned, both side by side when both are cold),
    which write to the same stderr and fill numba's on-disk cache; this process then loads
    the kernels from it.  The compiler's memory goes with the children: a first ``fit`` of a
    small store peaked at 549 MiB compiling in-process against 295 MiB once compiled."""
    if command not in KERNEL_COMMANDS or (command == "model"
                                          and model_command in NO_KERNEL_MODEL_COMMANDS):
        return False
    from rattle_lab.model.sdf import cold_kernels

    targets: list[Callable[[], bool]] = []
    if cold_kernels():
        targets.append(_compile_simulator)
    if command in DETECT_COMMANDS:
        from rattle_lab.detect import kernels_cold

        if kernels_cold():
            targets.append(_compile_detection)
    return _run_children(targets) if targets else False


#: Exit status of a child that compiled (0: it found nothing to compile).
_COMPILED_STATUS = 3


def _exit_with(target: Callable[[], bool]) -> None:
    raise SystemExit(_COMPILED_STATUS if target() else 0)


def _run_children(targets: list[Callable[[], bool]]) -> bool:
    """Run each of ``targets`` in a spawned child process, side by side; True if one compiled.

    A child that cannot be started or fails is run here instead (the kernels then compile in
    this process, as they would on first use)."""
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    procs = []
    compiled = False
    try:
        for target in targets:
            try:
                proc = ctx.Process(target=_exit_with, args=(target,), daemon=True)
                proc.start()
            except OSError:
                compiled = target() or compiled
                continue
            procs.append((target, proc))
        for target, proc in procs:
            proc.join()
            if proc.exitcode == _COMPILED_STATUS:
                compiled = True
            elif proc.exitcode != 0:
                compiled = target() or compiled
    finally:
        for _, proc in procs:
            if proc.is_alive():
                proc.terminate()
                proc.join()
    return compiled


def _compile_detection() -> bool:
    from rattle_lab.detect import kernels_cold, warm_cache

    if not kernels_cold():
        return False
    print(DETECT_NOTICE, file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    warm_cache()
    print(f"rattle-lab: detection kernels compiled and cached in "
          f"{time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return True


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
