"""benchmarks/ecma418_floor.py: the steps it times are the standard's, computed right.

Its rows are a floor under any ECMA-418-2 implementation only if its filter bank is the
53 band filters and its ACFs are the blocks' autocorrelations; both are checked here against
independent computations (scipy.signal.lfilter; a direct sum over lags).  No timing is
asserted.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from bench_module import benchmark_module


@pytest.fixture(scope="module")
def floor():
    with benchmark_module("ecma418_floor") as module:
        yield module


def test_filter_bank_is_each_bands_recursive_filter(floor):
    # The compiled direct-form recursion against lfilter's transposed form with the same
    # coefficients.  A 5-fold pole at d e^(i w) amplifies a rounding by up to about
    # 1 / (1 - d)^5 (3e9 for the lowest band, d = 0.988; 4e2 for the highest): the
    # tolerance is 20 eps / (1 - d)^5 of the output's scale (measured: 0.7 of the bound
    # for the lowest band, 2 for the highest, whose bound is a few eps).
    x = np.random.default_rng(1).normal(0.0, 1.0, 3000)
    b, a = floor.coefficients()
    got = floor.filter_bank(x, b, a)
    assert got.shape == (x.size, 53)
    for j in (0, 17, 30, 52):
        d = abs(a[j, 1]) / 5.0                     # a_1 = -5 d e^(i w)
        ref = 2.0 * np.real(signal.lfilter(b[j], a[j], x))
        tol = 20 * np.finfo(float).eps / (1 - d) ** 5 * np.max(np.abs(ref))
        np.testing.assert_allclose(got[:, j], ref, rtol=0, atol=tol)


def test_band_filters_have_unit_gain_at_their_centres(floor):
    # ECMA-418-2 normalises each band filter to 0 dB at its centre F(z): |H| = 1 within 2 %
    # (the numerator's e_i weights are the standard's; a wrong one is off by a factor).
    b, a = floor.coefficients()
    f_c = 81.9289 / 0.1618 * np.sinh(0.1618 * np.arange(0.5, 27.0, 0.5))
    for j in range(53):
        _, h = signal.freqz(b[j], a[j], worN=[f_c[j]], fs=floor.FS)
        assert abs(abs(h[0]) - 1.0) < 0.02, (j, abs(h[0]))


def test_acf_blocks_are_the_blocks_autocorrelations(floor, monkeypatch):
    # One band of 1024-sample blocks: the FFT route's lag-0 sum equals the blocks' energy
    # summed (np.dot per block, double), relative 1e-5 (single precision: 6e-8 per
    # rounding, over the transforms' 11 stages and 2048-term sums of positive terms).
    monkeypatch.setattr(floor, "BLOCKS", (1024,))
    x = np.random.default_rng(2).normal(0.0, 1.0, 5 * 1024)
    total = floor.acf_blocks(x[:, None])
    hop = 256
    n_blocks = (x.size - 1024) // hop + 1
    ref = sum(float(np.dot(x[k * hop:k * hop + 1024], x[k * hop:k * hop + 1024]))
              for k in range(n_blocks))
    assert total == pytest.approx(ref, rel=1e-5)
