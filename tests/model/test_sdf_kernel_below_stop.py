"""The search for the stop skips flights proven to stay below it (``below_stop_for_ever``).

``x = x_p + y`` with ``|x_p| <= R`` and ``|(y, y')|`` never growing, so a flight with
``R + |(y, y')| < 1`` (with a margin for rounding) cannot reach the stop: the kernel's
impact search returns "no impact" at once instead of examining the window chunk by
chunk (the steady motion of the Fig. 4-3 sweep's values without impact, issue 13).
Skipping must never change a result.  Checked here: (1) wherever the test holds, the
full chunked search (the kernel's own ``_search_chunk``, run over the window as
``first_reach`` did before) finds nothing, and an independent closed form of the flight
(written here with numpy, sampled densely) stays below the stop, for random flights in
all damping regimes, many of them within 1e-6 of the limit ``R + |(y, y')| = 1``;
(2) on the steady non-impacting motion it does hold, and no chunk is searched for the
stop; (3) flights that do reach the stop are never skipped.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rattle_lab.model.sdf import _kernel as K
from rattle_lab.model.sdf._kernel import _search


def _x_closed_form(F: float, w: float, z: float, th: float, y0: float, yd0: float,
                   s: np.ndarray) -> np.ndarray:
    """x(s) = x_p + y: particular part plus the homogeneous flow (own formulas)."""
    D = (1 - w * w) ** 2 + (2 * z * w) ** 2
    A, B = F * (1 - w * w) / D, F * 2 * z * w / D
    xp = A * np.cos(th + w * s) + B * np.sin(th + w * s)
    if z < 1:
        wd = math.sqrt(1 - z * z)
        y = np.exp(-z * s) * (y0 * np.cos(wd * s) + (yd0 + z * y0) / wd * np.sin(wd * s))
    elif z == 1:
        y = np.exp(-s) * (y0 + (yd0 + y0) * s)
    else:
        mu = math.sqrt(z * z - 1)
        r1, r2 = -z + mu, -z - mu
        c1 = (yd0 - r2 * y0) / (r1 - r2)
        c2 = (r1 * y0 - yd0) / (r1 - r2)
        y = c1 * np.exp(r1 * s) + c2 * np.exp(r2 * s)
    return xp + y


def _chunked_search(P: np.ndarray, S: np.ndarray, s_hi: float, hmax: float) -> float:
    """The window searched chunk by chunk, as ``first_reach`` does without the skip."""
    work = K.new_work()
    diag = np.zeros(2)
    va, vb = work[K.MAX_LEVEL + 4], work[K.MAX_LEVEL + 5]
    va[:5] = K.level_values(P, S, 0.0, 1.0, 1.0)
    sa = 0.0
    while sa < s_hi:
        sb = min(sa + hmax, s_hi)
        if s_hi - sb < 0.25 * hmax:
            sb = s_hi
        r = _search._search_chunk(P, S, 1.0, 1.0, sa, sb, va, vb, diag, work)
        if r >= 0.0:
            return r
        va[:5] = vb[:5]
        sa = sb
    return -1.0


def test_a_skipped_flight_has_no_impact_by_the_full_search_and_the_closed_form() -> None:
    rng = np.random.default_rng(13)
    n_skipped = n_close = 0
    for _ in range(600):
        z = float(rng.choice([0.0, 0.02, 0.3, 1.0, 1.7]))
        w = float(rng.uniform(0.3, 3.0))
        F = float(rng.uniform(0.01, 2.0))
        P = K.make_params(F, w, z, 0.6)
        if P[K.I_RES] != 0.0:
            continue
        R = P[K.I_R]
        if R >= 1.0:
            continue
        # a homogeneous state with R + rho near 1 (often within 1e-6 of it), either side
        gap = 1.0 - R
        rel = float(rng.choice([1e-6, 1e-3, 0.1, 0.5])) * rng.uniform(0.5, 1.0)
        rho = gap * (1.0 - rel if rng.uniform() < 0.7 else 1.0 + rel)
        ang = rng.uniform(0, 2 * math.pi)
        th = float(rng.uniform(0, 2 * math.pi))
        S = np.zeros(K.N_S)
        xp = P[K.I_AC] * math.cos(th) + P[K.I_AS] * math.sin(th)
        vp = w * (P[K.I_AS] * math.cos(th) - P[K.I_AC] * math.sin(th))
        x0, v0 = xp + rho * math.cos(ang), vp + rho * math.sin(ang)
        if x0 >= 1.0:
            continue
        K.start_segment(P, S, th, x0, v0, False)
        W = min(2 * math.pi, 2 * math.pi / w)
        if not K.below_stop_for_ever(P, S, S[K.J_Y], S[K.J_YD]):
            continue
        n_skipped += 1
        n_close += rho > gap * (1 - 2e-6)
        assert _chunked_search(P, S, W, W / K.CHUNKS_PER_WINDOW) == -1.0
        s = np.linspace(0.0, W, 4001)
        assert np.max(_x_closed_form(F, w, z, th, S[K.J_Y], S[K.J_YD], s)) < 1.0
    assert n_skipped > 150 and n_close > 20  # the test did exercise the skip, near its limit


@pytest.mark.parametrize("omega", [0.85, 1.25])
def test_the_steady_motion_without_impact_searches_no_chunk_for_the_stop(
        omega: float, monkeypatch: pytest.MonkeyPatch) -> None:
    # F = 0.2, zeta = 0.05: no impact at omega = 0.85 (R = 0.72) nor at 1.25 (R = 0.35)
    F, z, e = 0.2, 0.05, 0.6
    out = K.run(F, omega, z, e, 0.0, 0.0, 0.0, 0.0, False, 200 * 2 * math.pi / omega,
                False, False, 10**6)
    assert out[1] == 0
    t, x, v, th, stuck = out[10:15]
    searched: list[float] = []
    chunk = _search._search_chunk

    def counting_chunk(P, S, c, *args):  # type: ignore[no-untyped-def]
        if c == 1.0:
            searched.append(c)
        return chunk(P, S, c, *args)

    monkeypatch.setattr(_search, "_search_chunk", counting_chunk)
    out = K.run(F, omega, z, e, t, x, v, th, stuck, 20 * 2 * math.pi / omega, True, False,
                10**6)
    assert out[1] == 0 and out[7] == 20  # no impact; one upward crossing of 0 per period
    assert searched == []


def test_flights_that_reach_the_stop_are_not_skipped() -> None:
    # the 1/1 orbit (F = 0.2, omega = 1.1): every impact still found, as without the skip
    out = K.run(0.2, 1.1, 0.05, 0.6, 0.0, 0.0, 0.0, 0.0, False, 100 * 2 * math.pi / 1.1,
                False, False, 10**6)
    assert out[1] >= 95
    # a flight released just below the stop at rest is not skipped (R + rho >= 1)
    P = K.make_params(0.2, 1.1, 0.05, 0.6)
    S = np.zeros(K.N_S)
    K.start_segment(P, S, 0.0, 1.0 - 1e-9, 0.0, False)
    assert not K.below_stop_for_ever(P, S, S[K.J_Y], S[K.J_YD])
