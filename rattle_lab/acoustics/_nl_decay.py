"""The nonlinear temporal decay of ISO 532-1 (time-varying loudness), compiled.

ISO 532-1:2017, 5.1.7 (method 1): the core loudness of each critical band passes a
network of two capacitors with the time constants ``t_short = 5 ms``, ``t_long = 15 ms``
and ``t_var = 75 ms``, charged instantly and discharged through one or both branches,
simulated on a virtual grid 24 times finer than the 2 kHz core-loudness rate.  MoSQITo
(the library that computes the rest of the chain here) runs this recursion as a Python
loop over every one of those sub-steps, which costs about 90 % of its time (5 s per
second of sound).  :func:`nonlinear_decay` is the same recursion, step for step and in
the same floating-point order, compiled with numba; ``tests/acoustics/test_acoustics.py`` checks
it against MoSQITo's own function to the last bit.
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: Sub-steps per core-loudness sample (the standard's virtual upsampling).
NL_ITER = 24
_CORE_RATE_HZ = 2000.0
_T_SHORT_S, _T_LONG_S, _T_VAR_S = 0.005, 0.015, 0.075


def _coefficients() -> np.ndarray:
    """The six recursion coefficients B0..B5 of the two-capacitor network."""
    dt = 1.0 / (_CORE_RATE_HZ * NL_ITER)
    p = (_T_VAR_S + _T_LONG_S) / (_T_VAR_S * _T_SHORT_S)
    q = 1.0 / (_T_SHORT_S * _T_VAR_S)
    l1 = -p / 2 + math.sqrt(p * p / 4 - q)
    l2 = -p / 2 - math.sqrt(p * p / 4 - q)
    den = _T_VAR_S * (l1 - l2)
    e1, e2 = math.exp(l1 * dt), math.exp(l2 * dt)
    return np.array([
        (e1 - e2) / den,
        ((_T_VAR_S * l2 + 1) * e1 - (_T_VAR_S * l1 + 1) * e2) / den,
        ((_T_VAR_S * l1 + 1) * e1 - (_T_VAR_S * l2 + 1) * e2) / den,
        (_T_VAR_S * l1 + 1) * (_T_VAR_S * l2 + 1) * (e1 - e2) / den,
        math.exp(-dt / _T_LONG_S),
        math.exp(-dt / _T_VAR_S),
    ])


@numba.njit(cache=True)
def _decay_rows(ui: np.ndarray, u2_first: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Run the capacitor network along each row of the sub-sampled input ``ui``."""
    rows, n = ui.shape
    uo = ui.copy()
    u2 = np.zeros_like(ui)
    for r in range(rows):
        u2[r, 0] = u2_first[r]
        for col in range(n):
            prev = col - 1 if col > 0 else n - 1  # the first step reads the last column
            uo_p, u2_p, x = uo[r, prev], u2[r, prev], ui[r, col]
            cand = uo_p * b[2] - u2_p * b[3]      # both capacitors discharge
            if uo_p > u2_p and cand >= x:
                uo[r, col] = cand
            cand = uo_p * b[4]                    # the long branch alone
            if uo_p <= u2_p and cand >= x:
                uo[r, col] = cand
            u2[r, col] = uo[r, col]
            cand = uo_p * b[0] - u2_p * b[1]
            if x < uo_p and uo_p > u2_p and cand <= uo[r, col]:
                u2[r, col] = cand
            cand = (u2_p - x) * b[5] + x
            if x >= uo_p and not (abs(x - uo_p) < 1e-5 and uo[r, col] <= u2_p):
                u2[r, col] = cand
    return uo


def nonlinear_decay(core_loudness: np.ndarray) -> np.ndarray:
    """ISO 532-1 nonlinear temporal decay of a (bands, time) core-loudness array at 2 kHz.

    Parameters
    ----------
    core_loudness : ndarray, shape (n_bands, n_times)
        Core loudness per critical band, sone per band, sampled at 2 kHz.

    Returns
    -------
    ndarray, same shape
        The loudness after the decay network.

    Examples
    --------
    >>> import numpy as np
    >>> out = nonlinear_decay(np.array([[0.0, 1.0, 0.0, 0.0, 0.0]]))
    >>> bool(out[0, 1] == 1.0 and 0.0 < out[0, 2] < 1.0)  # instant rise, gradual decay
    True
    """
    core = np.ascontiguousarray(core_loudness, dtype=float)
    step = np.roll(core, -1, axis=1)
    step[:, -1] = 0.0
    step = (step - core) / NL_ITER
    ui = np.empty((core.shape[0], core.shape[1], NL_ITER))
    ui[:, :, 0] = core
    for k in range(1, NL_ITER):  # the same running sum as the reference, for equal bits
        ui[:, :, k] = ui[:, :, k - 1] + step
    flat = ui.reshape(core.shape[0], core.shape[1] * NL_ITER)
    b = _coefficients()
    u2_first = np.where(core[:, 0] >= 1e-5, core[:, 0] * (1 - b[5]), 0.0)
    uo = _decay_rows(flat, u2_first, b)
    return uo.reshape(core.shape[0], core.shape[1], NL_ITER)[:, :, 0]


__all__ = ["NL_ITER", "nonlinear_decay"]
