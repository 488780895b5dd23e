"""Scale-out through Dask gives results identical to serial execution.

A real ``dask.distributed.LocalCluster`` with two worker processes (one thread
each) runs the same studies as the serial path; every array must be equal bit
for bit (NaN in the same places), because each point is computed by the same
deterministic code whatever runs it.  The workers load the compiled kernels
from numba's on-disk cache.
"""

from __future__ import annotations

import math

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
