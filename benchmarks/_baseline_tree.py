"""Child process of ``speed_goals.py``: time an earlier source tree's code, with its own API.

Run as ``PYTHONPATH=TREE python benchmarks/_baseline_tree.py`` with one JSON object on
stdin; prints one JSON object on stdout.  It imports ``rattle_lab`` from ``TREE`` (checked:
the installed, current package must not answer instead) and nothing from the current
checkout, so the code timed is the tree's code as it was.  The inputs are plain numbers,
so both versions see exactly the same problem.

Tasks (``"task"`` in the input):

``"ramp_fit"``
    ``fit_restitution_down(method="ramp")`` of the tree on the given thresholds and modal
    model.  One untimed ``model_threshold`` call first (numba's cache load or compile), then
    the best of ``repeat`` timed fits, each after clearing the module's memo caches (so no
    run profits from the one before).  Returns the seconds (wall and CPU of this process,
    each the best), the fitted ``e`` and its stderr.
``"sweep"``
    The pure-Python exact event-driven reference of the Fig. 4-3 sweep: the tree's
    simulator with ``method="exact-python"`` (its kernel source run by the interpreter),
    driven by the loop of the tree's ``sweep`` (state carried; ``discard`` periods, then
    ``kept`` periods with crossings, classified with ``n_max``), up then down.  Timed once.
    Returns the seconds (wall and CPU) and the labels.

Both the layout of commit 66a850a (``rattle_lab.sdf``, ``rattle_lab.analysis``,
``rattle_lab.thresholds``) and today's (``rattle_lab.model.sdf``, ``rattle_lab.model.analysis``,
``rattle_lab.detect.thresholds``) are understood; the older is tried first.
"""

from __future__ import annotations

import functools
import json
import math
import os
import sys
import time
from pathlib import Path
from typing import Any


def _check_tree() -> Path:
    import rattle_lab

    here = Path(rattle_lab.__file__).resolve().parent.parent
    wanted = [Path(p).resolve() for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    if here not in wanted:
        raise SystemExit(f"rattle_lab was imported from {here}, not from the baseline tree "
                         f"{os.environ.get('PYTHONPATH')!r}")
    return here


def _clear_caches(module: Any) -> None:
    """Clear the functools memo caches of ``module`` (e.g. the stable 1/1 orbit per level)."""
    for obj in vars(module).values():
        if isinstance(obj, functools._lru_cache_wrapper):
            obj.cache_clear()


def _ramp_fit(job: dict[str, Any]) -> dict[str, Any]:
    try:
        from rattle_lab.thresholds import Threshold  # layout of 66a850a
    except ImportError:
        from rattle_lab.detect.thresholds import Threshold  # type: ignore[no-redef]
    from rattle_lab.fit import RampSpec, fit_restitution_down, model_threshold
    from rattle_lab.fit import _ramp_model

    ths = [Threshold(**t) for t in job["thresholds"]]
    plate = job["plate"]
    zeta = float(job["zeta"])
    model_threshold(RampSpec.from_threshold(ths[0]), e=0.6, zeta=zeta, **plate)  # warm-up
    best = cpu = math.inf
    fit = None
    for _ in range(int(job["repeat"])):
        _clear_caches(_ramp_model)
        c0 = time.process_time()
        t0 = time.perf_counter()
        fit = fit_restitution_down(ths, zeta=zeta, e_bounds=tuple(job["e_bounds"]),
                                   e_step=float(job["e_step"]), **plate)
        best = min(best, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    assert fit is not None
    # a tree before one class per fit has the estimate in ``.e`` (a ParamEstimate, NaN where
    # not available, before the one Estimate type); today's fit is the estimate
    e = getattr(fit, "e", fit)
    return {"seconds": best, "cpu_seconds": cpu,
            "e": float("nan") if e.value is None else float(e.value),
            "stderr": float("nan") if e.stderr is None else float(e.stderr)}


def _sweep(job: dict[str, Any]) -> dict[str, Any]:
    try:  # layout of 66a850a
        from rattle_lab.analysis.sweep import classify_impacts
        from rattle_lab.sdf import SDFParams, SDFState, simulate

        def classify(p: Any, res: Any, t0: float, state: Any) -> str:
            return classify_impacts(res.impacts.t, res.impacts.v_in, t_start=t0,
                                    t_stop=state.t, omega=p.omega, n_max=n_max).label
    except ImportError:
        from rattle_lab.model.analysis._sweep import classify_settled
        from rattle_lab.model.sdf import SDFParams, SDFState, simulate  # type: ignore[no-redef]

        def classify(p: Any, res: Any, t0: float, state: Any) -> str:
            regime, _ = classify_settled(p, res.impacts.t, res.impacts.v_in, t_start=t0,
                                         end_state=state, n_max=n_max, settle_cycles=0)
            return regime.label

    base = SDFParams(**job["base"])
    values = [float(w) for w in job["values"]]
    discard, kept, n_max = int(job["discard"]), int(job["kept"]), int(job["n_max"])
    method = job["method"]
    # untimed warm-up of the compiled classifier (the simulator itself is not compiled)
    p0 = SDFParams(F=base.F, omega=values[0], zeta=base.zeta, e=base.e)
    r0 = simulate(p0, cycles=kept, crossings=True)
    classify(p0, r0, 0.0, r0.state)
    labels = []
    c_start = time.process_time()
    t_start = time.perf_counter()
    state = SDFState(**job["state"])
    for order in (values, values[::-1]):
        for w in order:
            p = SDFParams(F=base.F, omega=w, zeta=base.zeta, e=base.e)
            state = simulate(p, cycles=discard, state=state, method=method).state
            t0 = state.t
            res = simulate(p, cycles=kept, state=state, crossings=True, method=method)
            state = res.state
            labels.append(classify(p, res, t0, state))
    return {"seconds": time.perf_counter() - t_start, "cpu_seconds": time.process_time() - c_start,
            "labels": labels}


def main() -> int:
    job = json.loads(sys.stdin.read())
    tree = _check_tree()
    out = {"ramp_fit": _ramp_fit, "sweep": _sweep}[job["task"]](job)
    out["tree"] = str(tree)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
