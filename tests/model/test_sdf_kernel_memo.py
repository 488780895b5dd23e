"""The flight's memo of its last evaluations (``_kernel._flight.evaluate``): the same numbers.

``evaluate`` keeps the last ``N_MEMO`` evaluations of a flight in the flight's vector
``S`` and returns a repeated point from there; ``start_segment`` puts ``s = 0`` there
for a flight off the stop, computed from the cos and sin it already has, with the
transition at ``s = 0`` taken as exactly ``(1, 0)``.  A memo must never change a
number: here every memoised value is compared, bit for bit, with the same evaluation
made with the memo emptied, in both builds, in every regime of the homogeneous flow
(under-, critically and over-damped, undamped resonance) and on and off the stop.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.model.sdf._compiled import jit_kernel, python_kernel

#: (F, omega, zeta, e): zeta < 1, = 1, > 1, and the undamped resonance (secular part)
REGIMES = {
    "under-damped": (0.2, 1.1, 0.05, 0.6),
    "critically damped": (0.7, 0.9, 1.0, 0.5),
    "over-damped": (4.0, 0.7, 1.5, 0.4),
    "undamped resonance": (0.3, 1.0, 0.0, 0.8),
}
#: starts (phase, x, v, on the stop)
STARTS = [(0.0, 0.0, 0.0, False), (2.1, -0.4, 0.7, False), (5.9, 0.999, -1e-3, False),
          (1.3, 1.0, -0.5, True), (4.0, 1.0, -2e-7, True)]


def _fresh(K, S: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """A copy of ``S`` with the memo emptied (as for a flight never evaluated)."""
    S2 = S.copy()
    for i in range(K.N_MEMO):
        S2[K.J_MEMO + K.MEMO_WIDTH * i] = math.nan
    return S2


def _bits(values: tuple[float, ...]) -> bytes:
    return np.array(values, dtype=float).tobytes()


@pytest.mark.parametrize("K", [python_kernel, jit_kernel], ids=["python", "compiled"])
@pytest.mark.parametrize("regime", list(REGIMES))
@pytest.mark.parametrize("start", STARTS)
def test_memo_returns_the_numbers_a_fresh_evaluation_gives(K, regime: str,  # type: ignore[no-untyped-def]
                                                            start: tuple) -> None:
    P = K.make_params(*REGIMES[regime])
    S = np.zeros(K.N_S)
    th, x, v, on_stop = start
    K.start_segment(P, S, th, x, v, on_stop)
    if not on_stop:  # s = 0 was put in the memo by start_segment, not by evaluate
        assert S[K.J_MEMO] == 0.0
        assert _bits(K.evaluate(P, S, 0.0)) == _bits(K.evaluate(P, _fresh(K, S), 0.0))
    points = [0.0, 1e-9, 0.3, 1.7, 0.3, 4.2, 1e-9, 6.0, 1.7, 0.0]  # repeats, some evicted
    for s in points:
        memo = K.evaluate(P, S, s)
        fresh = K.evaluate(P, _fresh(K, S), s)
        assert _bits(memo) == _bits(fresh), (regime, start, s)
    # the memo keeps the last N_MEMO distinct points
    kept = {S[K.J_MEMO + K.MEMO_WIDTH * i] for i in range(K.N_MEMO)}
    assert len(kept) == K.N_MEMO and kept <= set(points)


@pytest.mark.parametrize("regime", list(REGIMES))
def test_a_new_flight_forgets_the_last_ones_evaluations(regime: str) -> None:
    K = python_kernel
    P = K.make_params(*REGIMES[regime])
    S = np.zeros(K.N_S)
    K.start_segment(P, S, 0.4, 0.2, 0.1, False)
    first = K.evaluate(P, S, 1.5)
    K.start_segment(P, S, 2.4, -0.3, 0.5, False)
    second = K.evaluate(P, S, 1.5)
    assert second != first
    assert _bits(second) == _bits(K.evaluate(P, _fresh(K, S), 1.5))
