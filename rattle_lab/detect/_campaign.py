"""The plate's ringing modes found across a campaign's runs and taken out of each.

Moved from :mod:`rattle_lab.workflow.pipeline` (issue 29: detection in one room).  The
search needs the runs detected again with other parameters; how they are detected (serially
or on a Dask cluster) is the caller's: :func:`campaign_ringing` is given a ``redetect``
function.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from ._flights import campaign_ringing_model
from ._params import DetectParams
from ._run import RunResult

#: ``redetect(indices, params, label)``: the results of the runs at ``indices`` detected
#: again with ``params`` (``label`` names the pass, for a progress bar), in that order.
Redetect = Callable[[list[int], DetectParams, str], Sequence[RunResult]]


def campaign_ringing(results: Sequence[RunResult], detect: DetectParams,
                     redetect: Redetect) -> list[RunResult]:
    """The plate's ringing modes, found across the campaign's runs and taken out of each.

    Where runs ring after their impacts (their first detection ran the flight model) and
    at least one of them measured no share of the velocity jumps (its own model found no
    modes: they ring on past the next impact, or one run does not determine them), every
    ringing run's flights are pooled to find the plate's ringing modes
    (:func:`~rattle_lab.detect.campaign_ringing_model`; the other shaker runs' flights join
    them, detected again with ``velocity_model = "flights"``: their own test for ringing
    sees the tails on both sides of an impact and can pass them by), and every shaker run
    with impacts is detected again with them (``ring_modes``: each impact's ringing carried
    on, ``v_in`` and ``v_out`` from the flight model; ``ring_fundamental``: the plate's
    fundamental found with them on all the runs together), which supersedes the runs'
    shares.
    (Before 29 Nov 2026 this was done only where no run measured a share; heavily damped
    modes that one run's model finds in one run and not in another were then corrected by
    that run's share alone.)  Where every ringing run measured a share, the shares stand.
    Both passes change the velocity model
    only: ``redetect`` may start each run from its first pass's
    :attr:`~rattle_lab.detect.ImpactLog.recognition`.  Otherwise, where no mode is found,
    or where the modes give no run any velocities, the results are returned as they are
    (the fit then flags the ratios).  The runs' parts of the search are dropped from the
    results either way.

    Parameters
    ----------
    results : sequence of RunResult
        Every run's first detection (:func:`analyse_run`), in the order ``redetect`` indexes.
    detect : DetectParams
        The parameters they were detected with.
    redetect : callable
        ``redetect(indices, params, label)``: the runs at ``indices`` detected again with
        ``params``, in that order.

    Returns
    -------
    list of RunResult
    """
    logs = [r.impacts for r in results]
    ringing = [log for log in logs if log is not None and log.ringing_problem is not None]
    problems = [p for p in (log.ringing_problem for log in ringing) if p is not None]
    # a run whose own flight model found no modes: one run does not resolve them there
    unresolved = any(not np.isfinite(log.ringing_share) for log in ringing)
    if unresolved and detect.velocity_model != "local" and not detect.ring_modes:
        redo = [i for i, r in enumerate(results) if r.status == "ok"
                and r.impacts is not None and r.impacts.n_impacts
                and np.isfinite(r.freq_hz) and r.protocol != "transient"
                and np.isfinite(r.impacts.v_in_m_s).any()]
        # the tails are in the residual before an impact as well as after it, so the test
        # for ringing can pass a run by: the other shaker runs' flights join the search
        others = [i for i in redo if results[i].impacts.ringing_problem is None]  # type: ignore[union-attr]
        more = redetect(others, dataclasses.replace(detect, velocity_model="flights"),
                        "detect (flights)")
        problems += [r.impacts.ringing_problem for r in more
                     if r.impacts is not None and r.impacts.ringing_problem is not None]
        from threadpoolctl import threadpool_limits

        # one BLAS thread, as the per-run detection's (a result must not depend on where
        # it was computed)
        with threadpool_limits(limits=1, user_api="blas"):
            found = campaign_ringing_model(problems)
        modes = found.modes
        if modes:
            again = redetect(redo, dataclasses.replace(
                detect, ring_modes=[list(m) for m in modes], ring_modes_runs=len(problems),
                ring_fundamental=list(found.fundamental or ())),
                "detect (ringing modes)")
            if any(np.isfinite(r.impacts.v_in_m_s).any() for r in again
                   if r.impacts is not None):
                results = list(results)
                for i, r in zip(redo, again):
                    results[i] = r
            # (else the modes gave no run velocities: the first pass stands, and the fit
            # flags its ratios as uncorrected)
    # (and what the passes started from: neither is a result)
    return [r if r.impacts is None or (r.impacts.ringing_problem is None
                                       and r.impacts.recognition is None)
            else dataclasses.replace(r, impacts=dataclasses.replace(
                r.impacts, ringing_problem=None, recognition=None))
            for r in results]




def campaign_measurand(results: Sequence[RunResult], detect: DetectParams, redetect: Redetect
                       ) -> tuple[list[RunResult], DetectParams]:
    """An undeclared vibrometer's measurand, where some runs establish it and others cannot.

    The measurand is the chain's, the same in every run.  A run whose impacts come at one
    phase of the base motion (a dwell in periodic motion) cannot tell relative from
    absolute (:func:`~rattle_lab.detect.infer_measurand`: ``measurand_undetermined``, the
    relative reading kept and e's interval widened), while a run whose impacts spread over
    the phases can.  Where runs of the campaign establish one measurand and none the other,
    the undetermined runs are detected again with it (``measurand_if_undetermined``), and
    the parameters returned carry it for the passes that follow.  (On the independent
    generator's absolute vibrometers, seeds 27 and 36 of ``benchmarks/chain_timing.py``:
    the 93 Hz dwell established ``panel_absolute``, the steady 99 Hz dwell could not, and e
    came out +14.5 and +19.9 % with the relative reading.)  Where the user gave
    ``measurand_if_undetermined``, or the runs disagree, nothing changes.

    Returns
    -------
    (list of RunResult, DetectParams)
    """
    from ._chain import (CAMPAIGN_MEASURAND_NOTE, FLAG_MEASURAND_INFERRED,
                         FLAG_MEASURAND_UNDETERMINED)

    results = list(results)
    if detect.measurand_if_undetermined:
        return results, detect
    found: set[str] = set()
    open_: list[int] = []
    for i, r in enumerate(results):
        for f in getattr(r, "chain_flags", ()) or ():
            if f.startswith(f"{FLAG_MEASURAND_INFERRED}: ") and CAMPAIGN_MEASURAND_NOTE not in f:
                found.add("panel_absolute" if f.startswith(
                    f"{FLAG_MEASURAND_INFERRED}: panel_absolute") else "panel_relative_to_striker")
            elif (f.startswith(f"{FLAG_MEASURAND_UNDETERMINED}: ")
                  and r.impacts is not None and r.impacts.e_measurand_diff != 0.0):
                open_.append(i)
    if len(found) != 1 or not open_:
        return results, detect
    again = dataclasses.replace(detect, measurand_if_undetermined=found.pop())
    for i, r in zip(open_, redetect(open_, again, "detect (measurand)")):
        results[i] = r
    return results, again


__all__ = ["campaign_measurand", "campaign_ringing"]
