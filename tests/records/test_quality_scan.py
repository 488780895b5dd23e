"""The compiled flat-run scan against a brute-force enumeration of runs."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rattle_lab.records._scan import BLOCK, flat_runs


def _runs_brute(x: np.ndarray, min_len: int) -> list[tuple[int, int, float]]:
    """Maximal runs of identical samples with >= min_len samples, by a plain Python walk."""
    out = []
    i = 0
    values = x.tolist()
    while i < len(values):
        j = i
        while j + 1 < len(values) and values[j + 1] == values[i]:
            j += 1
        if j - i + 1 >= min_len:
            out.append((i, j - i + 1, float(values[i])))
        i = j + 1
    return out


def _runs_chunked(x: np.ndarray, min_len: int, chunk: int) -> list[tuple[int, int, float]]:
    """The same runs found chunk by chunk with the kernels, as ChannelChecker uses them."""
    out: list[tuple[int, int, float]] = []
    tail = x[:0].copy()
    open_start, open_len = 0, 0
    for start in range(0, x.size, chunk):
        part = x[start:start + chunk]
        cap = part.size // min_len + 2
        starts, lens = np.empty(cap, np.int64), np.empty(cap, np.int64)
        values = np.empty(cap, np.float64)
        k, open_start, open_len = flat_runs(part, tail, start, open_start, open_len, min_len,
                                            starts, lens, values)
        out += [(int(a), int(n), float(v)) for a, n, v in zip(starts[:k], lens[:k], values[:k])]
        tail = part[-1:].copy()
    if open_len >= min_len:
        out.append((open_start, open_len, float(tail[0])))
    return out


@settings(max_examples=200, deadline=None, derandomize=True)
@given(values=st.lists(st.integers(-2, 2), min_size=1, max_size=300),
       chunk=st.integers(1, 64), min_len=st.integers(2, 6),
       dtype=st.sampled_from([np.int16, np.int32, np.float32, np.float64]))
def test_chunked_scan_finds_exactly_the_brute_force_runs(values, chunk, min_len, dtype):
    x = np.asarray(values, dtype=dtype)  # values in -2..2 make long runs common
    assert _runs_chunked(x, min_len, chunk) == _runs_brute(x, min_len)


@settings(max_examples=100, deadline=None, derandomize=True)
@given(n=st.integers(1, 2000), chunk=st.integers(1, 2000), min_len=st.integers(2, 20),
       runs=st.lists(st.tuples(st.integers(0, 1999), st.integers(1, 300)), max_size=6))
def test_runs_in_a_live_signal_across_blocks(n, chunk, min_len, runs):
    # noise (no equal neighbours) with flat runs put in: most blocks are skipped whole
    x = np.random.default_rng(n).standard_normal(n)
    for start, length in runs:
        x[start:start + length] = x[min(start, n - 1)]
    assert _runs_chunked(x, min_len, chunk) == _runs_brute(x, min_len)


def test_nan_never_forms_a_run_and_runs_cross_chunks_and_blocks():
    x = np.array([np.nan, np.nan, np.nan, 1.0, 1.0, 1.0])
    assert _runs_chunked(x, 2, 2) == [(3, 3, 1.0)]
    # a run that spans block boundaries inside one chunk and then a chunk boundary
    y = np.arange(3 * BLOCK, dtype=np.float32)
    y[BLOCK - 5:2 * BLOCK + 7] = -1.0
    expected = [(BLOCK - 5, BLOCK + 12, -1.0)]
    assert _runs_brute(y, 3) == expected
    for chunk in (y.size, 2 * BLOCK, BLOCK + 3, 7):
        assert _runs_chunked(y, 3, chunk) == expected
