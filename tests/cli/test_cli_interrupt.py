"""Ctrl-C and SIGTERM on a parallel ``rattle-lab model map`` (issue 27 item 6).

A terminal sends Ctrl-C as SIGINT to the whole process group: the command and its worker
processes.  The command must cancel the chunks not yet run, stop its workers and exit at
once (130, or 143 for SIGTERM), not after the whole job.  Run through the installed entry
point, in a process group of its own, with a job of minutes (a 41 x 41 regime map of
100000 forcing periods per point); the bound on the exit, 5 s, is what cancelling costs
at most (terminating two workers and joining them, about 0.1 s, plus the interpreter's
exit), an upper bound and not a timing benchmark.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time

import psutil
import pytest
from conftest import RATTLE_LAB

#: Seconds the command may take to exit after the signal (see the module docstring).
EXIT_BOUND_S = 5.0

JOB = ("model", "map", "--kind", "regime", "--F", "0.05:0.5", "--omega", "0.8:1.3",
       "--n-F", "41", "--n-omega", "41", "--cycles", "100000", "--discard", "100",
       "--no-lyapunov", "--chunk-size", "2", "--workers", "2", "--quiet")


def _start() -> tuple[subprocess.Popen[str], list[psutil.Process]]:
    # the child gets the default SIGINT action, as a command typed at a terminal has: a test
    # run started in the background by a shell inherits SIGINT ignored, and Python then
    # leaves it ignored (the map would run on for minutes)
    proc = subprocess.Popen([str(RATTLE_LAB), *JOB], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    parent = psutil.Process(proc.pid)
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline:  # the pool's two workers are running chunks
        workers = [p for p in parent.children(recursive=True) if p.is_running()]
        if len(workers) >= 2 and all(p.cpu_times().user > 0.2 for p in workers[:2]):
            return proc, workers
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.2)
    proc.kill()
    raise AssertionError("the map's workers did not start")


@pytest.mark.parametrize("sig, status, word", [(signal.SIGINT, 130, "interrupted"),
                                               (signal.SIGTERM, 143, "terminated")])
def test_map_with_workers_stops_at_once_on_a_signal(sig: int, status: int, word: str) -> None:
    proc, workers = _start()
    t0 = time.monotonic()
    os.killpg(proc.pid, sig)  # as a terminal sends it: the whole process group
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        raise
    elapsed = time.monotonic() - t0
    assert proc.returncode == status, err[-2000:]
    assert err.strip().splitlines()[-1] == f"rattle-lab: {word}", err[-2000:]
    assert "Traceback" not in err
    assert elapsed <= EXIT_BOUND_S, elapsed
    time.sleep(0.5)
    assert not [w for w in workers if w.is_running() and w.status() != psutil.STATUS_ZOMBIE]
