"""Scale-out through Dask gives results identical to serial execution.

A real ``dask.distributed.LocalCluster`` with two worker processes (one thread
each) runs the same studies as the serial path; every array must be equal bit
for bit (NaN in the same places), because each point is computed by the same
deterministic code whatever runs it.  The workers load the compiled kernels
from numba's on-disk cache.
"""

from __future__ import annotations

import math
import os
import platform
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from rattle_lab.model.analysis import _dask
from rattle_lab.model.analysis._dask import chunk_rows, run_chunks
from rattle_lab.model.analysis import AttractorMap, disturbance_map, regime_map
from rattle_lab.exceptions import ParameterError

F = np.linspace(0.1, 0.4, 4)
OMEGA = np.linspace(0.9, 1.2, 5)


def _assert_same_map(a: AttractorMap, b: AttractorMap) -> None:
    for name in ("code", "m", "n", "mean_impact_velocity", "max_impact_velocity", "lyapunov",
                 "sticking"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.fixture(scope="module")
def cluster():  # type: ignore[no-untyped-def]
    import logging

    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                      dashboard_address=":0", silence_logs=logging.ERROR) as lc:
        yield lc


def test_regime_map_through_scheduler_equals_serial(cluster) -> None:  # type: ignore[no-untyped-def]
    serial = regime_map(F, OMEGA, cycles=100, discard=70, chunk_size=3)
    remote = regime_map(F, OMEGA, cycles=100, discard=70, chunk_size=3,
                        scheduler=cluster.scheduler_address)
    _assert_same_map(serial, remote)
    assert (serial.code == 2).any() and (serial.code == 1).any()  # a non-trivial map


def test_local_workers_equal_serial() -> None:
    # workers > 1: the package starts (and stops) its own pool of forked worker processes
    kw = dict(kick_tol=0.05, cycles=120, check_cycles=10, chunk_size=2)
    serial = disturbance_map([0.12, 0.2], [1.1, 1.2], **kw)  # type: ignore[arg-type]
    local = disturbance_map([0.12, 0.2], [1.1, 1.2], workers=2, **kw)  # type: ignore[arg-type]
    np.testing.assert_array_equal(serial.threshold, local.threshold)
    assert np.isfinite(serial.threshold).any()


def test_regime_map_on_a_local_pool_equals_serial() -> None:
    """Chunks spread over 2 forked worker processes, results reassembled in order."""
    serial = regime_map(F, OMEGA, cycles=100, discard=70, chunk_size=3)
    pooled = regime_map(F, OMEGA, cycles=100, discard=70, chunk_size=3, workers=2)
    _assert_same_map(serial, pooled)
    assert (serial.code == 2).any() and (serial.code == 1).any()


def test_pool_keeps_order_and_raises_the_workers_error() -> None:
    rows = np.arange(10.0).reshape(5, 2)
    assert run_chunks(np.sum, chunk_rows(rows, 1), workers=2) == [1.0, 5.0, 9.0, 13.0, 17.0]
    with pytest.raises(ValueError, match="math domain error"):
        run_chunks(math.sqrt, [4.0, -1.0, 9.0], workers=2)


def test_run_chunks_keeps_order_and_validates() -> None:
    rows = np.arange(10.0).reshape(5, 2)
    chunks = chunk_rows(rows, 2)
    assert [c.shape[0] for c in chunks] == [2, 2, 1]
    assert run_chunks(np.sum, chunks) == [6.0, 22.0, 17.0]
    with pytest.raises(ParameterError, match="`chunk_size` must be an integer >= 1, was 0"):
        chunk_rows(rows, 0)
    with pytest.raises(ParameterError, match="`workers` must be an integer >= 1, was -2"):
        run_chunks(np.sum, chunks, workers=-2)


def test_unreachable_scheduler_is_a_parameter_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(_dask, "CONNECT_TIMEOUT_S", 1)
    with pytest.raises(ParameterError, match="`scheduler` 'tcp://127.0.0.1:9': cannot connect"):
        run_chunks(np.sum, [np.ones(2)], scheduler="tcp://127.0.0.1:9")


# --- issue 29: `fit` and `run` on a cluster ---------------------------------------------------

def _small_campaign(tmp_path, n_runs: int = 4):  # type: ignore[no-untyped-def]
    """A campaign from the independent generator (tests/independent_campaign.py), ingested."""
    from independent_campaign import Chain, Plant, write_campaign

    from rattle_lab.store import ingest

    plant = Plant()
    w = 2 * math.pi * plant.f_s_hz
    runs = []
    for k, f in enumerate((93.0, 99.0, 95.0, 97.0)[:n_runs]):
        r = f / plant.f_s_hz
        graze = plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) \
            / plant.q
        runs.append({"run_id": f"dwell_{k}", "protocol": "sine_dwell", "freq_hz": f,
                     "levels": np.full(40, 1.5 * graze)})
    write_campaign(tmp_path / "c.h5", plant, Chain(fs_hz=12800.0), runs, seed=5)
    store = tmp_path / "s.h5"
    ingest([tmp_path / "c.h5"], store, quiet=True)
    return store


def _summary_json(result) -> str:  # type: ignore[no-untyped-def]
    import json

    return json.dumps(result.summary.to_dict(), sort_keys=True, default=str)


@pytest.fixture(scope="module")
def campaign_store(tmp_path_factory):  # type: ignore[no-untyped-def]
    """The 4-run campaign's store, shared by the tests that read it (``fit_store(...,
    write=False)``); a test that hands it to the CLI copies it first."""
    return _small_campaign(tmp_path_factory.mktemp("dask_campaign"))


@pytest.fixture(scope="module")
def serial_fit(campaign_store):  # type: ignore[no-untyped-def]
    """The serial fit of :func:`campaign_store`, the reference of the scale-out tests."""
    from rattle_lab.workflow import fit_store

    return fit_store(campaign_store, write=False)


def test_fit_store_on_local_cluster_equals_serial(cluster, campaign_store, serial_fit  # type: ignore[no-untyped-def]
                                                  ) -> None:
    # Tasks open the store themselves on the worker processes; every fitted number and
    # every run's result must equal the serial run's (the same code on the same bytes).
    from rattle_lab.workflow import fit_store

    serial = serial_fit
    remote = fit_store(campaign_store, write=False, scheduler=cluster.scheduler_address)
    assert serial.summary.n_ok == 4
    assert _summary_json(remote) == _summary_json(serial)


def test_a_long_run_is_a_task_per_segment_equal_to_serial_and_to_the_api(cluster, tmp_path
                                                                         ) -> None:  # type: ignore[no-untyped-def]
    """A run cut into segments (``segment_samples``, issue 29): one task per segment for
    its impacts, then one per segment for its sound.  On the cluster the run's result equals
    the serial one bit for bit; its impact times, sound and acoustics equal
    :func:`~rattle_lab.detect.analyse_run`'s in one process."""
    import json

    from independent_campaign import Chain, Plant, write_campaign

    from rattle_lab.detect import analyse_run
    from rattle_lab.store import ingest, open_stored_record, read_catalogue
    from rattle_lab.workflow.pipeline import _segment_counts, detect_runs

    plant = Plant()
    w, r = 2 * math.pi * plant.f_s_hz, 95.0 / plant.f_s_hz
    graze = plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) \
        / plant.q
    write_campaign(tmp_path / "c.h5", plant, Chain(fs_hz=12800.0), [
        {"run_id": "long", "protocol": "sine_dwell", "freq_hz": 95.0,
         "levels": np.full(8 * 95, 1.5 * graze)}], seed=9)
    store = tmp_path / "s.h5"
    ingest([tmp_path / "c.h5"], store, quiet=True)
    detect = {"segment_samples": 16384}
    from rattle_lab.detect import DetectParams

    key = str(read_catalogue(store, level="runs")["input_key"][0])
    assert _segment_counts([(str(store), key, "long")], DetectParams.from_mapping(detect)) == [6]
    serial = detect_runs(store, detect, {})[0]
    remote = detect_runs(store, detect, {}, scheduler=cluster.scheduler_address)[0]
    with open_stored_record(store, key) as record:
        api = analyse_run(key, record.run("long"), detect=detect, fit={},
                          mic_distance_m=record.rig.mic_distance_m)
    assert serial.impacts.n_impacts > 200
    for name in ("t_s", "v_in_m_s", "v_out_m_s", "e"):
        np.testing.assert_array_equal(getattr(remote.impacts, name),
                                      getattr(serial.impacts, name), err_msg=name)
    assert remote.chain_flags == serial.chain_flags
    # analyse_run alone has no campaign ringing search (detect_runs' later passes may carry
    # ringing modes into the velocities): the same impacts, sound and acoustics
    for other in (remote, api):
        np.testing.assert_array_equal(other.impacts.t_s, serial.impacts.t_s)
        np.testing.assert_array_equal(other.peaks.p_first_pa, serial.peaks.p_first_pa)
        assert (json.dumps(other.acoustics.summary(), sort_keys=True, default=str)
                == json.dumps(serial.acoustics.summary(), sort_keys=True, default=str))
        assert (other.spl_rms_db, other.pattern) == (serial.spl_rms_db, serial.pattern)


def test_a_worker_killed_mid_task_is_retried_nothing_lost_or_doubled(  # type: ignore[no-untyped-def]
        campaign_store, serial_fit) -> None:
    # A worker process is killed (SIGKILL) while it runs a detection task: the nanny starts
    # a new one, the scheduler runs the lost task again, and the result holds every run once,
    # equal to the serial result.
    import logging
    import os
    import signal
    import threading
    import time

    from dask.distributed import Client, LocalCluster

    from rattle_lab.workflow import fit_store

    store, serial = campaign_store, serial_fit
    killed: list[int] = []
    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0",
                      silence_logs=logging.CRITICAL) as lc, Client(lc) as client:
        pids = client.run(os.getpid)

        def kill_one_busy_worker() -> None:
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline and not killed:
                busy = [addr for addr, keys in client.processing().items()
                        if any("detect_task" in str(k) for k in keys)]
                if busy and busy[0] in pids:
                    time.sleep(0.2)          # well inside the task (seconds long)
                    os.kill(pids[busy[0]], signal.SIGKILL)
                    killed.append(pids[busy[0]])
                time.sleep(0.02)

        killer = threading.Thread(target=kill_one_busy_worker, daemon=True)
        killer.start()
        remote = fit_store(store, write=False, scheduler=client)
        killer.join(timeout=5)
        after = client.run(os.getpid)
    assert killed, "no worker was seen running a detection task"
    assert killed[0] not in after.values()           # that process is gone, replaced
    assert remote.summary.n_ok == serial.summary.n_ok == 4
    assert _summary_json(remote) == _summary_json(serial)


def test_cli_fit_with_a_scheduler_that_does_not_answer_is_one_line_exit_2(  # type: ignore[no-untyped-def]
        campaign_store, tmp_path) -> None:
    import shutil

    from record_factory import run_cli

    # the connection is tried before any run is detected: any store serves, a copy of the
    # shared one (the command must not write to it, but a failure here should not spoil it)
    store = tmp_path / "s.h5"
    shutil.copyfile(campaign_store, store)
    proc = run_cli("fit", str(store), "--scheduler", "tcp://127.0.0.1:9", "--quiet")
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr
    assert "`scheduler` 'tcp://127.0.0.1:9': cannot connect" in lines[0]
    # refused at the first try (nothing listens on port 9), not after the client's timeout
    assert "connection refused" in lines[0]


def test_cli_fit_and_run_accept_a_scheduler(cluster, tmp_path) -> None:  # type: ignore[no-untyped-def]
    import json

    from record_factory import run_cli

    store = _small_campaign(tmp_path, n_runs=2)
    proc = run_cli("fit", str(store), "--json", "--quiet", "--scheduler",
                   cluster.scheduler_address)
    assert proc.returncode == 0, proc.stderr
    on_cluster = json.loads(proc.stdout)
    proc = run_cli("fit", str(store), "--json", "--quiet")
    assert proc.returncode == 0, proc.stderr
    serial = json.loads(proc.stdout)
    for d in (on_cluster, serial):   # provenance: when and where it ran
        d.pop("provenance", None)
    assert on_cluster == serial


def test_cli_fit_on_a_local_cluster_it_starts_itself(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``--scheduler local:2``: a LocalCluster of 2 worker processes started for the command
    and closed after; the output equals the serial one.  ``local:x`` is one line, exit 2."""
    import json

    from record_factory import run_cli

    store = _small_campaign(tmp_path, n_runs=2)
    proc = run_cli("fit", str(store), "--json", "--quiet", "--scheduler", "local:2")
    assert proc.returncode == 0, proc.stderr
    local = json.loads(proc.stdout)
    proc = run_cli("fit", str(store), "--json", "--quiet")
    serial = json.loads(proc.stdout)
    for d in (local, serial):
        d.pop("provenance", None)
    assert local == serial
    proc = run_cli("fit", str(store), "--quiet", "--scheduler", "local:x")
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "local:N" in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr


def test_progress_shows_samples_per_second_and_time_left(monkeypatch, capsys) -> None:
    # Long work (the detect stage) counts channel samples: the bar shows the rate in
    # samples/s and the time left.
    import time

    from rattle_lab import _progress
    from rattle_lab.workflow.pipeline import map_tasks

    monkeypatch.setattr(_progress, "progress_enabled", lambda quiet=False: not quiet)
    out = map_tasks(time.sleep, [(0.15,), (0.15,), (0.15,)], quiet=False, desc="detect",
                    weights=[2_000_000, 2_000_000, 2_000_000])
    assert out == [None, None, None]
    err = capsys.readouterr().err
    import re

    assert re.search(r"detect: .*M/6\.00M \[\d\d:\d\d<\d\d:\d\d, +[\d.]+Msample/s\]", err), err


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's mallopt")
def test_a_dask_worker_gets_glibc_thresholds_back():
    # a Dask nanny starts workers with MALLOC_TRIM_THRESHOLD_=65536, which turns off glibc's
    # dynamic mmap threshold: every large temporary is mapped and faulted in again (a
    # detection task took 1.8-2.0 s instead of 0.9-1.2 s).  The task wrapper restores the
    # thresholds; counted here as page faults of 50 allocations of 4 MiB (each array 1024
    # pages: hundreds of faults each time before, none once the heap holds one)
    code = textwrap.dedent("""
        import resource
        import numpy as np
        from rattle_lab.workflow.pipeline import _glibc_thresholds

        def faults():
            before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
            for _ in range(50):
                a = np.ones(2**19)
                del a
            return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

        untuned = faults()
        _glibc_thresholds()
        faults()           # the heap takes the first array's pages once
        print(untuned, faults())
    """)
    env = dict(os.environ, MALLOC_TRIM_THRESHOLD_="65536")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True, timeout=120)
    untuned, tuned = map(int, out.stdout.split())
    assert untuned >= 50 * 100
    assert tuned * 10 < untuned
