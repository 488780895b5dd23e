"""``rattle-lab fit``: the preset pipeline that ends at the results of an ingested store."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from rattle_lab.workflow.pipeline import detect_runs

if TYPE_CHECKING:
    from rattle_lab.detect import DetectParams


def fit_store(store: str | os.PathLike[str], *,
              detect: DetectParams | Mapping[str, Any] | None = None,
              fit: Mapping[str, Any] | None = None, write: bool = True, quiet: bool = True,
              participation_source: str = "pipeline", scheduler: Any = None) -> Any:
    """Detect and fit everything in an ingest store; write ``/results``: ``rattle-lab fit``.

    The preset pipeline that ends at the results, on a store that is already ingested and
    without the pipeline's cache: the detect stage (:func:`detect_runs`, serially or on
    ``scheduler``) and the fit stage (:func:`rattle_lab.fit.fit_runs`) of
    :func:`run_pipeline`, the same functions in the same order.

    Parameters
    ----------
    store : path-like
        An ingest store.
    detect : DetectParams or mapping, optional
        The detection parameters (a ``[detect]`` table: see
        :meth:`rattle_lab.detect.DetectParams.from_mapping`).
    fit : mapping, optional
        Keyword parameters of the fits (see :func:`rattle_lab.fit.load_pipeline`).
    write : bool
        Write ``/results`` into the store (atomically).
    quiet : bool
        No progress bar over the runs (one is drawn on a terminal otherwise).
    participation_source : str
        Where ``fit["participation"]`` came from, when given (``"pipeline"``,
        ``"command line"``); named in the summary's ``participation`` entry.
    scheduler : str or distributed.Client, optional
        Detect on this Dask cluster (default: serially here).

    Returns
    -------
    StoreFit

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store.
    ParameterError
        For an unknown parameter.
    """
    from rattle_lab.fit import check_fit_params

    detect = detect if detect is not None else {}
    fit_params = check_fit_params(fit)
    # the store is read (and a missing or foreign one refused) before the fits and the
    # acoustics are imported, so that a mistyped path costs a user no more than the store's
    # own imports
    runs = detect_runs(store, detect, fit_params, scheduler=scheduler, quiet=quiet)
    from rattle_lab.fit import fit_runs
    from rattle_lab.store import write_results

    result = fit_runs(store, runs, detect=detect, fit=fit_params,
                      participation_source=participation_source)
    if write:
        write_results(store, result)
    return result


__all__ = ["fit_store"]
