"""Work the exact kernel does per impact: counted closed-form evaluations, no clocks.

The impact root finder (``_kernel._search._root``) used to bisect the whole bracket from its
far end once Newton had converged onto the other end from one side: up to 53
evaluations for one impact where the root was already known to rounding (issue 13;
the chatter cases of ``benchmarks/work_precision.py`` spent most of their time
there).  These tests count the calls of ``level_values`` (one closed-form evaluation
each) made by the pure-Python build of the kernel, which runs the same source as the
compiled one, on the mpmath reference cases and the two chatter cases of the
benchmark.  Bounds: at most 12 evaluations for any one impact (now at most 9 on these
cases; a safeguarded Newton/Halley iteration from a bracket converges to rounding in
~5, plus a probe or two to close the bracket), and at most 7 on average.  The
accuracy of the impacts found is checked against mpmath in ``test_sdf_simulate.py``;
here each root is also checked to satisfy the kernel's contract: ``x >= 1`` at the
returned time and ``x < 1`` a few rounding units before it.
"""

from __future__ import annotations

import math

import pytest

from rattle_lab.model.sdf import _kernel
from rattle_lab.model.sdf._kernel import _search

CASES = {
    "1/1 orbit": (0.2, 1.0, 0.05, 0.6, 0.0, 0.0, 0.0, 40.0),
    "below resonance": (0.2, 0.93, 0.05, 0.6, 0.0, 0.0, 0.0, 40.0),
    "undamped, F>1": (1.3, 0.8, 0.0, 0.5, 0.0, 0.0, 0.0, 30.0),
    "over-damped": (4.0, 0.7, 1.5, 0.4, 0.0, 0.0, 0.0, 20.0),
    "chatter (work_precision iv)": (2.0, 0.5, 0.1, 0.5, 0.0, 0.0, 0.0, 10.0),
    "chatter + sticking (work_precision v)": (3.0, 0.5, 0.1, 0.5, 0.0, 0.0, 0.0, 10.0),
}


@pytest.mark.parametrize("name", list(CASES))
def test_impact_roots_take_few_evaluations(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    F, w, z, e, x0, v0, th0, cycles = CASES[name]
    level_values = _search.level_values
    root = _search._root
    depth: list[int] = []
    per_root: list[int] = []
    contract: list[tuple[float, float, float]] = []

    def counting_level_values(*args):  # type: ignore[no-untyped-def]
        if depth:
            depth[-1] += 1
        return level_values(*args)

    def counting_root(P, S, c, sig, which, lo, hi, *ends):  # type: ignore[no-untyped-def]
        depth.append(0)
        try:
            s = root(P, S, c, sig, which, lo, hi, *ends)
        finally:
            per_root.append(depth.pop())
        if which == 0 and c == 1.0:  # an impact: g = sig (x - 1)
            before = max(lo, s - 8.0 * _kernel.EPS * max(abs(s), 1e-300))
            g_at = level_values(P, S, s, c, sig)[0]
            g_before = level_values(P, S, before, c, sig)[0] if before > lo else -1.0
            contract.append((s, g_at, g_before))
        return s

    # replaced where the search looks them up: the globals of _search_chunk and _root
    monkeypatch.setattr(_search, "level_values", counting_level_values)
    monkeypatch.setattr(_search, "_root", counting_root)
    out = _kernel.run(F, w, z, e, 0.0, x0, v0, th0, False, cycles * 2.0 * math.pi / w,
                      False, False, 10**6)
    n_imp = out[1]
    assert n_imp > 5 and per_root, "the case must have impacts found by the root finder"
    assert max(per_root) <= 12, f"{name}: {max(per_root)} evaluations for one root"
    assert sum(per_root) / len(per_root) <= 7.0
    for s, g_at, g_before in contract:
        assert g_at >= 0.0, f"root at s={s!r} has x < 1"
        # g is negative 8 ulp before the root, up to its rounding noise (a few ulp of 1)
        assert g_before < 8.0 * _kernel.EPS, f"x > 1 before the root at s={s!r}"
