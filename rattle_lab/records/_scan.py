"""Compiled inner loop of the streaming data-quality checks (numba, GIL released).

A long record is checked chunk by chunk.  The check that costs most is the
search for flat runs (identical consecutive samples: clipping and dropouts).
:func:`flat_runs` walks the chunk in blocks: a block in which no sample equals
its neighbour, the common case for a live signal, costs one branch-free count
that the compiler vectorises; only the other blocks are walked sample by
sample.  The run that touches the end of a chunk is carried over to the next.

Samples are compared in their stored dtype, as ``numpy.equal`` does: NaN is
never equal to itself, so NaN samples never form a flat run (they are counted
by the NaN check instead).
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def _n_equal(x: np.ndarray, lo: int, hi: int) -> int:
    """Number of ``i`` in ``lo:hi`` (``lo >= 1``) with ``x[i] == x[i-1]``.

    The loop runs over a view from index 1, so the compiler can see that no index is
    negative (no wrap-around check) and vectorises it.
    """
    y = x[lo - 1:hi]
    n = 0
    for i in range(1, y.shape[0]):
        n += y[i] == y[i - 1]
    return n


#: Samples per block of :func:`flat_runs`: a block without equal neighbours costs one
#: vectorised pass; only blocks with some are walked sample by sample.
BLOCK = 256


@numba.njit(cache=True, nogil=True)
def flat_runs(x: np.ndarray, tail: np.ndarray, offset: int, open_start: int, open_len: int,
              min_len: int, starts: np.ndarray, lens: np.ndarray,
              values: np.ndarray) -> tuple[int, int, int]:
    """Runs of identical samples that end in this chunk and are at least ``min_len`` long.

    The run in progress when the previous chunk ended (``open_start``,
    ``open_len`` samples of the value ``tail[0]``; ``open_len = 0`` for none)
    continues while the samples equal it.  Runs that end inside the chunk and
    have ``>= min_len`` samples are written to ``starts``, ``lens`` and
    ``values`` (absolute sample index, length, value as float64); the run that
    reaches the end of the chunk is returned as the new open run.  Blocks of
    :data:`BLOCK` samples in which no sample equals its neighbour are passed
    over after one vectorised count.

    Parameters
    ----------
    x : ndarray
        The chunk (1-D).
    tail : ndarray
        Previous chunk's last sample (length 1), or empty.
    offset : int
        Absolute index of ``x[0]``.
    open_start, open_len : int
        The open run from the previous chunk.
    min_len : int
        Shortest run reported.
    starts, lens, values : ndarray
        Output buffers; ``len(x) // min_len + 2`` entries always suffice.

    Returns
    -------
    (n_runs, open_start, open_len)
        Runs written, and the run left open at the end of the chunk.
    """
    n = x.shape[0]
    k = 0
    if n == 0:
        return 0, open_start, open_len
    run_start = open_start
    run_len = open_len
    if tail.shape[0] == 0 or run_len == 0 or not (x[0] == tail[0]):
        if run_len >= min_len:
            starts[k] = run_start
            lens[k] = run_len
            values[k] = tail[0]
            k += 1
        run_start = offset
        run_len = 1
    else:
        run_len += 1
    for b in range(1, n, BLOCK):
        e = min(n, b + BLOCK)
        if _n_equal(x, b, e) == 0:
            # every sample of the block differs from the one before: the run in progress
            # ends at b - 1, and the block's last sample begins the next one
            if run_len >= min_len:
                starts[k] = run_start
                lens[k] = run_len
                values[k] = x[b - 1]
                k += 1
            run_start = offset + e - 1
            run_len = 1
            continue
        for i in range(b, e):
            if x[i] == x[i - 1]:
                run_len += 1
            else:
                if run_len >= min_len:
                    starts[k] = run_start
                    lens[k] = run_len
                    values[k] = x[i - 1]
                    k += 1
                run_start = offset + i
                run_len = 1
    return k, run_start, run_len


__all__ = ["flat_runs"]
