"""The settled-match test and the sweep's classification, compiled: the same answers.

``periodic_label_settled`` (and ``classify_settled``) now run a numba function, and a
sweep classifies all its windows in one compiled call (``_periods._classify_windows``),
calling ``classify_settled`` only for a match that has not settled (issue 13: the
Python around the compiled sweep).  The reference here is the numpy code they replaced,
kept in this file: the same booleans on random impact sequences (settled orbits,
transients decaying to a shorter period, matches being left, NaN), and the same
(kind, m, n) and settled flag as ``classify_settled`` for every window of a real sweep.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.model.analysis._periods import (KIND_NAMES, _classify_windows,
                                                 classify_settled, periodic_label_settled)
from rattle_lab.model.analysis._sweep import sweep_values
from rattle_lab.model.sdf import SDFParams, SDFState
from rattle_lab.model.sdf._compiled import jit_kernel


def _residuals_ref(t: np.ndarray, v: np.ndarray, m: int, n: int, period: float,
                   vscale: float) -> np.ndarray:
    if t.size <= m:
        return np.empty(0)
    d = np.maximum(np.abs(t[m:] - t[:-m] - n * period) / period,
                   np.abs(v[m:] - v[:-m]) / vscale)
    groups = d.size // m
    return d[:groups * m].reshape(groups, m).max(axis=1)


def _decays_ref(d: np.ndarray) -> bool:
    if d.size < 3:
        return False
    h = (d.size - 1) // 2
    d1, d2, d3 = float(d[-1 - 2 * h]), float(d[-1 - h]), float(d[-1])
    if not d1 > d2 > d3:
        return False
    den = d1 + d3 - 2.0 * d2
    if den <= 0.0:
        return False
    return (d1 * d3 - d2 * d2) / den < 0.5 * d3


def _settled_ref(t: np.ndarray, v: np.ndarray, m: int, n: int, omega: float,
                 rtol: float = 1e-4) -> bool:
    """periodic_label_settled as it was (numpy)."""
    period = 2.0 * math.pi / float(omega)
    vscale = max(float(np.max(np.abs(v))) if v.size else 0.0, 1e-300)
    own = _residuals_ref(t, v, m, n, period, vscale)
    if own.size >= 2 and own[-1] > 4.0 * own[0] and own[-1] > 1e-3 * rtol:
        return False
    g = math.gcd(int(m), int(n))
    for k in range(2, g + 1):
        if g % k == 0 and _decays_ref(_residuals_ref(t, v, m // k, n // k, period, vscale)):
            return False
    return True


def test_settled_equals_the_numpy_reference_on_random_sequences() -> None:
    rng = np.random.default_rng(4)
    n_true = n_false = 0
    for _ in range(3000):
        m, n = int(rng.integers(1, 5)), int(rng.integers(1, 7))
        k = int(rng.integers(0, 40))
        omega = float(rng.uniform(0.5, 2.0))
        T = 2 * math.pi / omega
        mu = float(rng.choice([-0.9, 0.5, 0.97, 1.05, -1.0, 0.0]))
        j = np.arange(k)
        t = np.sort(j * (n * T / m) + 0.3 + rng.normal(0, 1e-6, k) * abs(mu) ** (j / 2))
        v = 0.5 + float(rng.choice([1e-2, 1e-5, 0.0])) * mu ** j + rng.normal(0, 1e-9, k)
        if k and rng.uniform() < 0.02:
            v[int(rng.integers(k))] = math.nan
        want = _settled_ref(t, v, m, n, omega)
        assert periodic_label_settled(t, v, m=m, n=n, omega=omega) == want, (m, n, mu, k)
        n_true += want
        n_false += not want
    assert n_true > 300 and n_false > 100  # both answers exercised


def test_the_batch_classification_equals_classify_settled_on_a_real_sweep() -> None:
    base = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)
    values = sweep_values(0.85, 1.3, 0.01)
    out = jit_kernel.run_sweep(np.full(values.size, 0.2), values, np.full(values.size, 0.6),
                               0.05, 0.0, 0.0, 0.0, 0.0, False, 70.0, 30.0)
    imp, _crs, off, ends, _info = out
    periods = np.array([base.replace(omega=float(w)).period for w in values])
    got = _classify_windows(np.ascontiguousarray(imp[:, 0]), np.ascontiguousarray(imp[:, 2]),
                            off[:, 0], ends[:, 0], ends[:, 1], periods, 12, 1e-4)
    kinds = set()
    for i, w in enumerate(values):
        p = base.replace(omega=float(w))
        sl = slice(off[i, 0], off[i + 1, 0])
        state = SDFState(t=ends[i, 1], x=ends[i, 2], v=ends[i, 3], theta=ends[i, 4],
                         stuck=bool(ends[i, 5]))
        regime, _ = classify_settled(p, imp[sl, 0], imp[sl, 2], t_start=ends[i, 0],
                                     end_state=state, n_max=12, settle_cycles=0)
        kind, m, n, settled = (int(x) for x in got[i])
        if settled:
            assert (KIND_NAMES[kind], m, n) == (regime.kind, regime.m, regime.n)
        else:
            assert kind == 1 and regime.kind == "unsettled"
            assert not _settled_ref(imp[sl, 0], imp[sl, 2], m, n, float(w))
        kinds.add(regime.kind)
    assert {"no-impact", "periodic"} <= kinds


def test_periodic_label_settled_rejects_bad_m_n() -> None:
    from rattle_lab.exceptions import ParameterError

    with pytest.raises(ParameterError, match="`m`"):
        periodic_label_settled([0.0, 1.0], [1.0, 1.0], m=0, n=1, omega=1.0)
    with pytest.raises(ParameterError, match="same length"):
        periodic_label_settled([0.0, 1.0], [1.0], m=1, n=1, omega=1.0)
