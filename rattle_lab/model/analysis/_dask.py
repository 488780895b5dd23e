"""Scale-out of embarrassingly parallel studies (regime maps, basins, disturbance maps).

A study is cut into chunks of independent points; a chunk is a picklable
argument of a module-level function that returns a numpy array.  The chunks
run

* in this process, one after the other (``workers=1``, no scheduler: the
  default; Dask is not even imported);
* on a pool of ``workers`` processes on this machine (``workers > 1``), forked
  from this one after its compiled kernels are loaded (where the platform can
  fork; elsewhere spawned), so that a worker starts in milliseconds instead of
  the seconds of a fresh interpreter that imports the package and loads numba's
  cache.  This is what a Dask ``LocalCluster`` cost before (0.11x serial on a
  regime map: cluster start-up, a fresh interpreter per worker, scheduling);
* on a running ``dask.distributed`` cluster (``scheduler="tcp://host:8786"``),
  whose workers must have ``rattle_lab`` installed: for more cores than this
  machine has.  It pays once the serial work exceeds the cluster's overheads
  (connection, the first chunk's kernel load on each worker, one round trip per
  chunk) times ``w / (w - 1)`` for ``w`` workers; ``benchmarks/sweeps.py``
  measures both and prints the break-even.

Every point is computed by the same deterministic code whatever runs it, so
the results are identical to serial execution, bit for bit (tested).  The
compiled kernels are cached on disk by numba (``cache=True``), so worker
processes load them instead of compiling; a fresh worker on another machine
compiles once (a few seconds).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np

from rattle_lab._progress import progress
from rattle_lab.exceptions import ParameterError

T = TypeVar("T")

__all__ = ["run_chunks", "check_execution", "chunk_rows"]

#: Seconds to wait for a scheduler given by address.
CONNECT_TIMEOUT_S = 10


def check_execution(workers: object, scheduler: object) -> tuple[int, str | None]:
    """Validate the ``workers`` / ``scheduler`` pair; return them normalised.

    Raises
    ------
    ParameterError
        If ``workers`` is not an integer >= 1 or ``scheduler`` not a non-empty string.
    """
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or int(workers) < 1:
        raise ParameterError(f"`workers` must be an integer >= 1, was {workers!r}")
    if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
        raise ParameterError(f"`scheduler` must be an address like 'tcp://host:8786', was {scheduler!r}")
    return int(workers), (scheduler.strip() if isinstance(scheduler, str) else None)


def chunk_rows(rows: np.ndarray, chunk_size: int) -> list[np.ndarray]:
    """Split ``rows`` (first axis) into consecutive chunks of at most ``chunk_size``.

    Raises
    ------
    ParameterError
        If ``chunk_size`` is not an integer >= 1.
    """
    if isinstance(chunk_size, bool) or not isinstance(chunk_size, (int, np.integer)) or chunk_size < 1:
        raise ParameterError(f"`chunk_size` must be an integer >= 1, was {chunk_size!r}")
    return [rows[i:i + int(chunk_size)] for i in range(0, rows.shape[0], int(chunk_size))]


def run_chunks(func: Callable[[T], Any], chunks: Sequence[T], *, workers: int = 1,
               scheduler: str | None = None, desc: str = "", quiet: bool = True) -> list[Any]:
    """Apply ``func`` to every chunk, locally or through Dask; results in chunk order.

    Parameters
    ----------
    func : callable
        A module-level (picklable) function of one chunk.
    chunks : sequence
        The chunks (picklable).
    workers : int
        1: run here, serially.  More: a local pool of that many processes, forked
        from this one (ignored when ``scheduler`` is given).
    scheduler : str, optional
        Address of a running ``dask.distributed`` scheduler.
    desc : str
        Progress-bar label.
    quiet : bool
        No progress bar.

    Returns
    -------
    list
        ``[func(c) for c in chunks]``.

    Raises
    ------
    ParameterError
        On invalid ``workers`` / ``scheduler``, or if the scheduler cannot be reached.
    """
    workers, scheduler = check_execution(workers, scheduler)
    if scheduler is None and (workers == 1 or len(chunks) <= 1):
        return [func(c) for c in progress(chunks, total=len(chunks), desc=desc, quiet=quiet,
                                           unit="chunk")]
    if scheduler is None:
        return _run_pool(func, chunks, workers, desc, quiet)
    from dask.distributed import Client, as_completed

    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError, ValueError) as exc:
        raise ParameterError(f"`scheduler` {scheduler!r}: cannot connect ({exc})") from None
    try:
        futures = client.map(func, list(chunks), pure=False)
        position = {f.key: i for i, f in enumerate(futures)}
        results: list[Any] = [None] * len(futures)
        for fut in progress(as_completed(futures), total=len(futures), desc=desc, quiet=quiet,
                            unit="chunk"):
            results[position[fut.key]] = fut.result()
        return results
    finally:
        client.close()


def _run_pool(func: Callable[[T], Any], chunks: Sequence[T], workers: int, desc: str,
              quiet: bool) -> list[Any]:
    """``[func(c) for c in chunks]`` on a local pool of ``workers`` processes."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor, as_completed

    from rattle_lab.model.sdf import warm_cache

    warm_cache()  # load the compiled kernels here, so that forked workers inherit them
    method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
    pool = ProcessPoolExecutor(max_workers=min(workers, len(chunks)),
                               mp_context=mp.get_context(method), initializer=_worker_signals)
    try:
        futures = {pool.submit(func, c): i for i, c in enumerate(chunks)}
        results: list[Any] = [None] * len(chunks)
        for fut in progress(as_completed(futures), total=len(futures), desc=desc, quiet=quiet,
                            unit="chunk"):
            results[futures[fut]] = fut.result()
    except BaseException:
        # Ctrl-C, SIGTERM or a failed chunk: drop the pending chunks and stop the workers
        # now (they hold no output; a chunk is pure computation) instead of waiting for
        # every queued chunk to finish, as leaving the pool's `with` block would.
        _stop_pool(pool)
        raise
    pool.shutdown(wait=True)
    return results


def _worker_signals() -> None:
    """In a pool worker: Ctrl-C is the parent's to handle (it stops the pool); SIGTERM ends it."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _stop_pool(pool: Any) -> None:
    """Cancel a pool's pending work and end its worker processes at once."""
    processes = list(getattr(pool, "_processes", {}).values())  # CPython's executor
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=1.0)
        if proc.is_alive():
            proc.kill()
            proc.join(timeout=1.0)
