"""Pipelines: declared stages run lazily, with results cached by content hash in the store.

A pipeline TOML (see ``pipelines/``) names the outputs wanted and the
parameters of each stage::

    [pipeline]
    name = "threshold_campaign"
    outputs = ["results"]        # any of: store, detections, thresholds, results, report
    [simulate]                   # seed = 7 (optional; for scene inputs)
    [ingest]                     # allow_flagged = false
    [detect]                     # ImpactParams fields, window_s, first_fraction, max_lag_s
    [fit]                        # participation, vary_participation, outlier_k, ...
    [report]                     # model = true

The ``[detect]`` and ``[fit]`` tables are those of ``rattle-lab fit --pipeline``
(validated by :func:`rattle_lab.fit.load_pipeline`), so one file serves both.

Stages and what they call (the same library functions as the CLI commands):

==========  ==========================================================  ==================
stage       calls                                                       depends on
==========  ==========================================================  ==================
simulate    :func:`rattle_lab.rig.write_synthetic`                      scene inputs only
ingest      :func:`rattle_lab.store.ingest`                             simulate
detect      :func:`rattle_lab.detect.analyse_run`, per run              ingest
thresholds  :func:`rattle_lab.detect.thresholds.tabulate_thresholds`    detect
fit         :func:`rattle_lab.fit.fit_runs` (as ``rattle-lab fit``),    thresholds, detect
            :func:`rattle_lab.store.write_results`
report      :func:`rattle_lab.workflow.write_report`                    fit, ingest
==========  ==========================================================  ==================

Each stage has a *key*: the SHA-256 of its parameters, the package version and
the keys of the stages it depends on (the simulate key hashes the scene file's
bytes; the ingest key the input files' SHA-256).  Keys are computed without
running anything.  A stage runs only if a requested output needs it and its
key differs from the one recorded in the store under ``/pipeline_cache`` (or
its output is gone); so a changed parameter reruns exactly the stages
downstream of it.  :attr:`PipelineRun.executed` lists the stages run.

A stage's output is also checked before it counts as up to date: the store's
records must be those of the inputs (``ingest``), ``/results`` must be the one
the fit stage wrote (``fit``; a later ``rattle-lab fit`` on the store replaces
it), the report must have the bytes it was written with.

Per-run detection is independent across runs: with ``scheduler`` (a
``dask.distributed`` address, or a ``Client``) it is mapped over the cluster;
results are identical to the serial run (the same function on the same data).
Each task checks that its worker runs the same rattle_lab code as this process
(:func:`code_fingerprint`); a worker with another installation, or with a
source tree edited since this process took its fingerprint (on first use), fails the stage with a
:class:`~rattle_lab.exceptions.ParameterError` instead of mixing results of
different code.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rattle_lab._atomic import atomic_path
from rattle_lab._resources import find_resource
from rattle_lab._version import __version__
from rattle_lab.exceptions import OutputError, ParameterError
from rattle_lab.store import (CACHE_GROUP, check_linked_inputs, has_path, output_digest,
                              read_cache_keys, read_cached, record_cache_keys, store_lock, write_cached)
from ._pipeline_spec import (DEPENDS, OUTPUTS, STAGES, Pipeline, Stage, load_pipeline_file,
                             parse_pipeline)

if TYPE_CHECKING:
    from rattle_lab.detect import DetectParams

#: Layout of the cached products (their classes' places and fields); a change re-runs the
#: stages whose products a store caches.  2: the classes moved with the data-flow layout and
#: RunResult gained chain_flags and shocks.  3: ImpactLog gained velocity_note.  4: ImpactLog
#: gained velocity_offset_m_s, ringing_share and ringing_ratio.  5: ImpactLog gained
#: ring_modes (and ringing_problem, never cached).  6: ImpactLog gained velocity_delay_* and
#: step_guard_s, velocity_delay_window_s, e_per_delay_s, e_window_change (issue 28).  7: and
#: e_measurand_diff (format 6 was briefly on main without it).  8: and velocity_delay_method
#: and velocity_delay_note.  9: ImpactParams (in ImpactLog.params) gained ring_fundamental.
#: 10: ImpactLog gained decoder, ImpactParams identify_decoder.  11: the same layout, other
#: results (the contact pulse's rule and the sound windows' guard; a cached detection of 10
#: would stand for what this code no longer gives).  12: the same layout, other results (the
#: flight model's ringing weighted by its own velocity changes to their fixed point).
CACHE_FORMAT = 12

#: Parameters of [fit] that the per-run analysis (detect stage) uses.
_DETECT_FIT_KEYS = ("n_confirm", "speed_of_sound_m_s")
#: Seconds to wait for a scheduler given by address.
CONNECT_TIMEOUT_S = 10


def _source_digest() -> str:
    # rattle_lab's version and the SHA-256 of its Python sources (relative path + bytes).
    root = Path(__file__).resolve().parents[1]   # the rattle_lab package
    h = hashlib.sha256(__version__.encode())
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes())
    return f"{__version__}+{h.hexdigest()[:16]}"


#: This process's :func:`code_fingerprint`, taken on first use (None until then).
_FINGERPRINT: str | None = None


def code_fingerprint() -> str:
    """Version and source digest of the rattle_lab code this process runs.

    ``"<version>+<16 hex digits>"``: the SHA-256 of every ``.py`` file of the
    package (relative path and bytes), taken on the first call (a pipeline run maps its
    tasks, a worker runs its first task; importing the module reads no file) and kept
    for the life of the process.  Two processes (this one and a Dask worker) with equal
    fingerprints run the same code.

    Returns
    -------
    str

    Examples
    --------
    >>> code_fingerprint().startswith(__version__ + "+")
    True
    """
    global _FINGERPRINT
    if _FINGERPRINT is None:
        _FINGERPRINT = _source_digest()
    return _FINGERPRINT


@dataclass
class PipelineRun:
    """What :func:`run_pipeline` did.

    Attributes
    ----------
    store : Path
    executed : list of str
        Stages run, in order (``simulate`` once per scene simulated).
    cached : list of str
        Stages needed but up to date (not rerun).
    outputs : dict of str to Path
        The requested outputs (the store, or the report PDF).
    keys : dict of str to str
        The content key of each needed stage.
    """

    store: Path
    executed: list[str] = field(default_factory=list)
    cached: list[str] = field(default_factory=list)
    outputs: dict[str, Path] = field(default_factory=dict)
    keys: dict[str, str] = field(default_factory=dict)


# --- content keys and the cache in the store -------------------------------------------------

def _digest(obj: Any) -> str:
    text = json.dumps(obj, sort_keys=True, default=str, allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _is_scene(item: str) -> bool:
    return item == "default" or Path(item).suffix.lower() == ".toml"


def _scene_bytes(item: str) -> bytes:
    if item == "default":
        item = str(find_resource("scenes", "default"))   # the embedded scene
    try:
        return Path(item).read_bytes()
    except OSError as exc:
        raise ParameterError(f"{item}: cannot read scene: {exc}") from exc


def read_detections(store: str | os.PathLike[str]) -> tuple[Any, ...]:
    """The per-run detection results the detect stage cached in ``store``.

    Returns
    -------
    tuple of RunResult

    Raises
    ------
    DataError
        If the store holds none.
    """
    return read_cached(store, "detect")


# --- stage functions --------------------------------------------------------------------------

def detect_run(store: str, input_key: str, run_id: str,
               detect: DetectParams | Mapping[str, Any], fit: Mapping[str, Any],
               code: str | None = None, reuse: Any = None) -> Any:
    """Detection results of one stored run (:func:`rattle_lab.detect.analyse_run`).

    A pure function of its arguments: what the serial loop and the Dask
    workers call.

    Parameters
    ----------
    store : str
        The ingest store.
    input_key, run_id : str
        The run.
    detect : DetectParams or mapping
        The ``[detect]`` parameters.
    fit : mapping
        The ``[fit]`` parameters.
    code : str, optional
        The caller's :func:`code_fingerprint`; if given, this process must run
        the same code.
    reuse : RunResult, optional
        The run's result from an earlier pass whose parameters differ in the velocity
        model's only (``analyse_run``'s ``reuse``).

    Returns
    -------
    RunResult

    Raises
    ------
    ParameterError
        If ``code`` differs from this process's fingerprint (a Dask worker with
        another rattle_lab).
    """
    from rattle_lab.detect import analyse_run
    from rattle_lab.store import open_stored_record

    _same_code(code)
    from threadpoolctl import threadpool_limits

    # one BLAS thread, as on a Dask worker (which runs with one): the flight model's
    # searches follow the last bits of their sums, and a result must not depend on where
    # it was computed
    with open_stored_record(store, input_key) as record, \
            threadpool_limits(limits=1, user_api="blas"):
        return analyse_run(input_key, record.run(run_id), detect=detect, fit=fit,
                           mic_distance_m=record.rig.mic_distance_m, reuse=reuse)


def redetect_run(store: str, input_key: str, run_id: str, reuse: Any,
                 detect: DetectParams | Mapping[str, Any], fit: Mapping[str, Any],
                 code: str | None = None) -> Any:
    """:func:`detect_run` with ``reuse`` given per run: the campaign's ringing passes."""
    return detect_run(store, input_key, run_id, detect, fit, code, reuse)


def _same_code(code: str | None) -> None:
    if code is not None and code != code_fingerprint():
        raise ParameterError(f"`scheduler`: a worker runs other rattle_lab code ({code_fingerprint()}) "
                             f"than the caller ({code}); install the same rattle_lab on the "
                             "workers (or restart them after editing the sources)")


def detect_task(store: str, input_key: str, run_id: str, index: int, reuse: Any,
                detect: DetectParams | Mapping[str, Any], fit: Mapping[str, Any],
                code: str | None = None) -> Any:
    """One task of the detect stage: a whole run (``index < 0``, :func:`detect_run`) or the
    impacts of segment ``index`` of a long run (:func:`rattle_lab.detect.segment_impacts`)."""
    if index < 0:
        return detect_run(store, input_key, run_id, detect, fit, code, reuse)
    from threadpoolctl import threadpool_limits

    from rattle_lab.detect import segment_impacts
    from rattle_lab.store import open_stored_record

    _same_code(code)
    with open_stored_record(store, input_key) as record, \
            threadpool_limits(limits=1, user_api="blas"):
        return segment_impacts(input_key, record.run(run_id), index, detect)


def sound_task(store: str, input_key: str, run_id: str, index: int, t_s: Any,
               detect: DetectParams | Mapping[str, Any], fit: Mapping[str, Any],
               code: str | None = None) -> Any:
    """The sound of segment ``index`` of a long run, given the run's impact times
    (:func:`rattle_lab.detect.segment_sound`): the detect stage's second round of tasks."""
    from threadpoolctl import threadpool_limits

    from rattle_lab.detect import segment_sound
    from rattle_lab.store import open_stored_record

    _same_code(code)
    with open_stored_record(store, input_key) as record, \
            threadpool_limits(limits=1, user_api="blas"):
        return segment_sound(input_key, record.run(run_id), index, t_s, detect, fit,
                             record.rig.mic_distance_m)


def _refused_at_once(address: str) -> None:
    """Raise ConnectionRefusedError when nothing listens at a ``tcp://`` address.

    A Dask client retries a refused connection until its timeout (10 s); a mistyped
    port on a reachable host is known at the first try.  Other errors (an unknown or
    unreachable host, a scheme other than tcp) are left to the client."""
    import socket
    from urllib.parse import urlsplit

    parts = urlsplit(address)
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        return
    if parts.scheme != "tcp" or not host or port is None:
        return
    try:
        socket.create_connection((host, port), timeout=CONNECT_TIMEOUT_S).close()
    except ConnectionRefusedError:
        raise ConnectionRefusedError(f"nothing listens at {host}:{port}: "
                                     "connection refused") from None
    except OSError:
        return


def _connect(scheduler: Any) -> tuple[Any, bool]:
    """A ``distributed.Client`` for ``scheduler`` and whether this call owns it."""
    from distributed import Client

    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ParameterError(f"`scheduler` must be an address like 'tcp://host:8786' or a "
                             f"distributed.Client, was {scheduler!r}")
    try:
        _refused_at_once(scheduler.strip())
        return Client(scheduler.strip(), timeout=CONNECT_TIMEOUT_S), True
    except (OSError, TimeoutError, ValueError) as exc:
        raise ParameterError(f"`scheduler` {scheduler!r}: cannot connect "
                             f"({' '.join(str(exc).split()) or type(exc).__name__})") from None


def _local_workers(scheduler: Any) -> int | None:
    """The worker count of ``scheduler = "local"`` or ``"local:N"`` (None for anything else).

    Raises
    ------
    ParameterError
        For ``"local:"`` followed by anything but a whole number >= 1.
    """
    if not isinstance(scheduler, str) or not scheduler.strip().startswith("local"):
        return None
    text = scheduler.strip()
    if text == "local":
        return max(1, os.cpu_count() or 1)
    count = text.removeprefix("local:")
    if text.startswith("local:") and count.isdigit() and int(count) >= 1:
        return int(count)
    raise ParameterError(f"`scheduler` {scheduler!r}: use 'local' (a worker per core), "
                         "'local:N' (N worker processes) or an address like 'tcp://host:8786'")


def detect_runs(store: str | os.PathLike[str], detect: DetectParams | Mapping[str, Any],
                fit: Mapping[str, Any], *, scheduler: Any = None, quiet: bool = True
                ) -> list[Any]:
    """Every stored run's detections; see :func:`_detect_runs`.

    ``scheduler = "local"`` or ``"local:N"`` starts a ``dask.distributed`` ``LocalCluster`` of
    one worker process per core (or ``N``), one thread each, on this machine for the call and
    closes it after: the cluster path without a cluster to set up."""
    workers = _local_workers(scheduler)
    if workers is None:
        return _detect_runs(store, detect, fit, scheduler=scheduler, quiet=quiet)
    import logging

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, processes=True, threads_per_worker=1,
                      dashboard_address=None, silence_logs=logging.CRITICAL) as cluster, \
            Client(cluster) as client:
        return _detect_runs(store, detect, fit, scheduler=client, quiet=quiet)


def _detect_runs(store: str | os.PathLike[str], detect: DetectParams | Mapping[str, Any],
                 fit: Mapping[str, Any], *, scheduler: Any = None, quiet: bool = True
                 ) -> list[Any]:
    """Every stored run's detections (:func:`detect_run`), serially or on a Dask cluster.

    Then the campaign's ringing search (:func:`rattle_lab.detect.campaign_ringing`), which
    detects runs again through the same serial or cluster path.

    The detect stage of a pipeline and of :func:`fit_store`.  The inputs the store links
    to are re-hashed first (they must be the bytes that were ingested).  The progress bar
    counts channel samples (rate in samples/s and the time left).

    Returns
    -------
    list of RunResult
        In the catalogue's order of runs.
    """
    from rattle_lab.store import read_catalogue

    catalogue = read_catalogue(store, level="runs")
    check_linked_inputs(store, dict.fromkeys(catalogue["input_key"]))
    jobs = [(str(store), str(k), str(r)) for k, r in zip(catalogue["input_key"],
                                                       catalogue["run_id"])]
    channels = read_catalogue(store, level="channels")
    samples: dict[tuple[str, str], int] = {}
    for k, r, n in zip(channels["input_key"], channels["run_id"], channels["n_samples"]):
        samples[(str(k), str(r))] = samples.get((str(k), str(r)), 0) + int(n)
    weights = [samples.get((k, r), 0) for _, k, r in jobs]
    from rattle_lab.detect import DetectParams, campaign_measurand, campaign_ringing

    params = DetectParams.from_mapping(detect)
    results = _map_runs(jobs, params, fit, scheduler=scheduler, quiet=quiet, desc="detect",
                        weights=weights)

    velocity_fields = ("velocity_model", "ring_modes", "ring_modes_runs", "ring_fundamental",
                       "measurand_if_undetermined")

    def redetect(indices: list[int], again: DetectParams, label: str) -> list[Any]:
        # the passes change the velocity model only: the impacts come out at the same times,
        # and their sound, levels, pattern and threshold are taken from the first pass
        # (analyse_run checks the times; other parameters changed: nothing is reused).  The
        # tasks get only what recognises a run's impacts (a cluster would ship the rest both
        # ways); the rest is put back here, from the first pass
        same = replace(again, **{k: getattr(params, k) for k in velocity_fields})
        if same != params:
            return _map_runs([jobs[i] for i in indices], again, fit, scheduler=scheduler,
                             quiet=quiet, desc=label, weights=[weights[i] for i in indices])
        out = _map_runs([jobs[i] for i in indices], again, fit, scheduler=scheduler,
                        quiet=quiet, desc=label, weights=[weights[i] for i in indices],
                        reuse=[_recognisable(results[i]) for i in indices])
        return [_restored(results[i], r) for i, r in zip(indices, out)]

    results = campaign_ringing(results, params, redetect)
    # then an undeclared vibrometer's measurand where some runs establish it and others
    # cannot, from the runs' last reading (where the plate rings, the flight model's
    # velocities and modes: the first pass's local fits read the ringing; on the independent
    # generator's seeds 15 and 36 of `chain_timing.py` only the last reading of the 99 Hz
    # dwell establishes panel_absolute)
    ring = next((r.impacts.params for r in results
                 if r.impacts is not None and r.impacts.ring_modes), None)
    last = params if ring is None else replace(
        params, ring_modes=[list(m) for m in ring.ring_modes],
        ring_modes_runs=ring.ring_modes_runs, ring_fundamental=list(ring.ring_fundamental))
    results, _ = campaign_measurand(results, last, redetect)
    return results


def _recognisable(first: Any) -> Any:
    """What a detection pass needs of a run's first result to recognise its impacts (their
    times, :func:`rattle_lab.detect.analyse_run`'s ``reuse``): without the sound, levels,
    acoustics and threshold, and the flight model's samples (``ringing_problem``)."""
    if first.impacts is None:
        return None
    return replace(first, peaks=None, acoustics=None, threshold=None,
                   impacts=replace(first.impacts, ringing_problem=None))


def _restored(first: Any, again: Any) -> Any:
    """``again`` with what follows from the impact times taken from ``first`` where the
    times are the same (where :func:`_recognisable` let the pass reuse them)."""
    import numpy as np

    if (again.status == "ok" and first.status == "ok" and again.impacts is not None
            and first.impacts is not None
            and np.array_equal(again.impacts.t_s, first.impacts.t_s)):
        return replace(first, impacts=again.impacts, chain_flags=again.chain_flags)
    return again


#: glibc's ``mallopt`` parameters (``<malloc.h>``) and the values :func:`_glibc_thresholds` sets.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_MMAP_THRESHOLD_BYTES = 32 * 2**20     # glibc's largest dynamic mmap threshold (64-bit)
_TRIM_THRESHOLD_BYTES = 64 * 2**20     # twice it, as glibc's dynamic rule sets
_MALLOC_SET = False


def _glibc_thresholds() -> None:
    """Give a Dask worker process glibc's own allocation behaviour for large arrays (once).

    A Dask nanny starts its workers with ``MALLOC_TRIM_THRESHOLD_=65536``.  Any explicit
    threshold turns off glibc's dynamic mmap threshold, so every array of 128 KiB or more is
    mapped from the kernel when allocated and unmapped when freed.  A run's detection
    allocates thousands of such temporaries, each paying its page faults again.  Measured on 29
    Nov 2026 (2-core machine, a 20 s run of 4 channels at 25.6 kHz): one whole-run detection
    task took 1.8-2.0 s under that variable against 0.9-1.2 s without it.  The cluster was then
    no faster than one process.  This sets the thresholds that glibc's dynamic rule reaches
    for such arrays: mmap above 32 MiB, trim above 64 MiB.  The task's results do not change.
    Only where the variable is set and the C library has ``mallopt`` (Linux).
    """
    global _MALLOC_SET
    if _MALLOC_SET:
        return
    _MALLOC_SET = True
    if "MALLOC_TRIM_THRESHOLD_" not in os.environ:
        return
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):   # not glibc (or no symbol table): leave it
        return
    mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD_BYTES)
    mallopt(_M_TRIM_THRESHOLD, _TRIM_THRESHOLD_BYTES)


def _task(func: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``func(*args, **kwargs)`` on a worker, after :func:`_glibc_thresholds`."""
    _glibc_thresholds()
    return func(*args, **kwargs)


def map_tasks(func: Callable[..., Any], tasks: Sequence[tuple[Any, ...]], *,
              scheduler: Any = None, quiet: bool = True, desc: str = "",
              weights: Sequence[int] | None = None, unit: str = "sample",
              **kwargs: Any) -> list[Any]:
    """``[func(*task, **kwargs) for task in tasks]``, serially or on a Dask cluster, in order.

    The cluster path of the pipeline: each task is submitted as one Dask task (``pure=False``:
    two equal tasks both run; a worker first gets glibc's own thresholds for large
    allocations back, :func:`_glibc_thresholds`); a task whose worker dies is run again by Dask on another
    worker (the scheduler's ``allowed-failures``), and its result is taken once, from the
    attempt that finished.  Tasks must open their own files (an h5py handle cannot be
    pickled) and the workers should be processes (libhdf5 runs one call at a time per
    process).

    Parameters
    ----------
    func : callable
        A module-level function (importable on the workers).
    tasks : sequence of tuple
        Positional arguments of each call.
    scheduler : str or distributed.Client, optional
        A ``dask.distributed`` scheduler address or client (default: serially here).
    quiet : bool
        No progress bar (one is drawn on a terminal otherwise).
    desc : str
        The progress bar's label.
    weights : sequence of int, optional
        Work per task (channel samples): the progress bar then shows samples/s and the
        time left; without it, tasks.
    unit : str
        The unit of ``weights``.
    **kwargs
        Keyword arguments of every call.

    Returns
    -------
    list
        The results, in the order of ``tasks``.

    Raises
    ------
    ParameterError
        If the scheduler cannot be reached (one line, the address named).

    Examples
    --------
    >>> map_tasks(divmod, [(7, 2), (9, 4)])
    [(3, 1), (2, 1)]
    """
    from rattle_lab._progress import progress_bar

    tasks = list(tasks)
    if weights is None:
        weights, unit = [1] * len(tasks), "task"
    weights = [int(w) for w in weights]
    results: list[Any] = [None] * len(tasks)
    with progress_bar(sum(weights), desc=desc, quiet=quiet, unit=unit,
                      unit_scale=unit != "task") as bar:
        if scheduler is None:
            for i, task in enumerate(tasks):
                results[i] = func(*task, **kwargs)
                bar.update(weights[i])
            return results
        from distributed import as_completed

        client, owned = _connect(scheduler)
        try:
            # each task is named after ``func`` (``detect_task-<uuid>``), as Dask would
            import uuid

            keys = [f"{getattr(func, '__name__', 'task')}-{uuid.uuid4().hex}" for _ in tasks]
            futures = client.map(_task, [func] * len(tasks), *zip(*tasks), key=keys,
                                 pure=False, **kwargs) if tasks else []
            position = {f.key: i for i, f in enumerate(futures)}
            for fut in as_completed(futures):
                i = position[fut.key]
                results[i] = fut.result()
                bar.update(weights[i])
            return results
        finally:
            if owned:
                client.close()


def _segment_counts(jobs: list[tuple[str, str, str]], detect: DetectParams) -> list[int]:
    """How many segments each run is analysed in (0: whole), from the records' metadata."""
    from rattle_lab.detect import run_segments
    from rattle_lab.store import open_stored_record

    counts: list[int] = []
    opened: dict[tuple[str, str], Any] = {}
    try:
        for store, key, run_id in jobs:
            if (store, key) not in opened:
                opened[(store, key)] = open_stored_record(store, key)
            spans = run_segments(key, opened[(store, key)].run(run_id), detect)
            counts.append(len(spans) if spans else 0)
    finally:
        for record in opened.values():
            record.close()
    return counts


def _map_runs(jobs: list[tuple[str, str, str]], detect: DetectParams,
              fit: Mapping[str, Any], *, scheduler: Any, quiet: bool, desc: str,
              weights: Sequence[int] | None = None, reuse: Sequence[Any] | None = None
              ) -> list[Any]:
    """Every job's :class:`~rattle_lab.detect.RunResult`, in order: serially or on a Dask
    cluster (with ``reuse``, one earlier result per job).

    A run analysed whole is one task (:func:`detect_task`).  A long run
    (:func:`rattle_lab.detect.run_segments`) is a task per segment for its impacts; its
    segments' impacts are merged here, then (unless ``reuse`` recognises them) a second
    round of tasks finds each segment's sound (:func:`sound_task`), and the run is
    assembled here: the same steps, and the same numbers, as
    :func:`rattle_lab.detect.analyse_run` takes in one process."""
    from rattle_lab.detect import assemble_segments, merge_segment_impacts, reused_result
    from rattle_lab.store import open_stored_record

    counts = _segment_counts(jobs, detect)
    w = list(weights) if weights is not None else [1] * len(jobs)
    tasks: list[tuple[Any, ...]] = []
    owner: list[tuple[int, int]] = []
    task_w: list[int] = []
    for i, (job, n) in enumerate(zip(jobs, counts, strict=True)):
        for j in (range(n) if n else (-1,)):
            tasks.append((*job, j, reuse[i] if reuse is not None and j < 0 else None))
            owner.append((i, j))
            task_w.append(max(1, w[i] // max(n, 1)))
    extra: dict[str, Any] = {"detect": detect, "fit": fit}
    if scheduler is not None:
        extra = {"detect": detect, "fit": dict(fit), "code": code_fingerprint()}
    out = map_tasks(detect_task, tasks, scheduler=scheduler, quiet=quiet, desc=desc,
                    weights=task_w if weights is not None else None, **extra)
    results: list[Any] = [None] * len(jobs)
    parts: dict[int, list[Any]] = {}
    for (i, j), res in zip(owner, out):
        if j < 0:
            results[i] = res
        else:
            parts.setdefault(i, []).append(res)
    merged: dict[int, tuple[Any, tuple[str, ...]]] = {}
    sound_jobs: list[tuple[Any, ...]] = []
    sound_owner: list[int] = []
    sound_w: list[int] = []
    for i, segs in parts.items():
        store, key, run_id = jobs[i]
        with open_stored_record(store, key) as record:
            run = record.run(run_id)
            log, flags = merge_segment_impacts(key, run, segs, detect)
            mic_n = sum(c.n_samples for c in run.channels if c.quantity == "sound_pressure")
            has_mic = mic_n > 0
        merged[i] = (log, flags)
        results[i] = reused_result(reuse[i] if reuse is not None else None, key, run_id, log,
                                   flags)
        if results[i] is None and has_mic:
            for j in range(len(segs)):
                sound_jobs.append((store, key, run_id, j, log.t_s))
                sound_owner.append(i)
                sound_w.append(max(1, mic_n // len(segs)))
    sounds: dict[int, list[Any]] = {}
    if sound_jobs:
        done = map_tasks(sound_task, sound_jobs, scheduler=scheduler, quiet=quiet,
                         desc=f"{desc}: sound", weights=sound_w, **extra)
        for i, res in zip(sound_owner, done):
            sounds.setdefault(i, []).append(res)
    for i, (log, flags) in merged.items():
        if results[i] is None:
            store, key, run_id = jobs[i]
            with open_stored_record(store, key) as record:
                results[i] = assemble_segments(key, record.run(run_id), log, flags,
                                               sounds.get(i), detect, fit,
                                               record.rig.mic_distance_m)
    return results


def _fit_and_write(store: Path, runs: Sequence[Any], curve: Any, pipeline: Pipeline) -> None:
    # The same fits as `rattle-lab fit` (rattle_lab.fit.fit_runs), on the cached detections.
    from rattle_lab.fit import fit_runs
    from rattle_lab.store import write_results

    write_results(store, fit_runs(store, list(runs), detect=pipeline.params["detect"],
                                  fit=pipeline.params["fit"], curve=curve,
                                  provenance={"via": "rattle_lab.workflow.pipeline",
                                              "pipeline": pipeline.name}))


def _file_hash(path: Path) -> str:
    from rattle_lab.store import file_hash

    return file_hash(path)


# --- the runner -------------------------------------------------------------------------------

def needed_stages(outputs: Sequence[str], *, scenes: bool) -> list[Stage]:
    """The stages the requested outputs need, in execution order.

    Examples
    --------
    >>> needed_stages(["thresholds"], scenes=False)
    ['ingest', 'detect', 'thresholds']
    >>> needed_stages(["store"], scenes=True)
    ['simulate', 'ingest']
    """
    need: set[Stage] = set()
    todo = [OUTPUTS[o] for o in outputs]
    while todo:
        stage = todo.pop()
        if stage in need or (stage == "simulate" and not scenes):
            continue
        need.add(stage)
        todo.extend(DEPENDS[stage])
    return [s for s in STAGES if s in need]


def run_pipeline(pipeline: Pipeline, inputs: Sequence[str | os.PathLike[str]], *,
                 store: str | os.PathLike[str] | None = None, out_dir: str | os.PathLike[str] = ".",
                 scheduler: Any = None, log: Callable[[str], None] | None = None,
                 quiet: bool = True, report: str | os.PathLike[str] | None = None
                 ) -> PipelineRun:
    """Run the stages ``pipeline`` needs for its outputs, skipping those up to date.

    Parameters
    ----------
    pipeline : Pipeline
        From :func:`load_pipeline_file`.
    inputs : sequence of path-like
        Record files (any format ``rattle-lab ingest`` reads), or scenes
        (``.toml`` files, or ``"default"``), which are simulated into
        ``out_dir/<stem>.h5`` first.
    store : path-like, optional
        The store (default ``out_dir/<pipeline.name>.h5``).
    out_dir : path-like
        Directory of simulated records and of the report ``<pipeline.name>.pdf``
        (created, with its parents, if missing).
    scheduler : str or distributed.Client, optional
        Run per-run detection on this Dask cluster (default: serially here).
    log : callable, optional
        Called with one line when a stage starts (``"<stage>: running"``), ends
        (``"<stage>: done"``) or is skipped (``"<stage>: up to date"``).
    quiet : bool
        No progress bars (they are drawn on a terminal only, in any case).
    report : path-like, optional
        The report PDF (default ``out_dir/<pipeline.name>.pdf``).

    Returns
    -------
    PipelineRun

    Raises
    ------
    ParameterError
        If there are no inputs, an input is missing, ``out_dir`` is a file, the
        scheduler cannot be reached or one of its workers runs other rattle_lab code.
    RattleLabError
        Whatever a stage raises (the store is left as the last completed stage wrote it).
    """
    say = log or (lambda line: None)
    items = [str(i) for i in inputs]
    # a scene shipped with rattle_lab may be named instead of given as a file
    items = [i if i == "default" or Path(i).exists() else str(find_resource("scenes", i) or i)
             for i in items]
    if not items:
        raise ParameterError("`inputs` must name at least one record file or scene")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ParameterError(f"`out_dir` {str(out)!r} is not a directory")
    for item in items:
        if item != "default" and not Path(item).is_file():
            raise ParameterError(f"input {item!r}: no such file")
    try:  # the output folder is made, as `--out build/` leads a user to expect
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"`out_dir` {str(out)!r}: cannot be created: "
                          f"{exc.strerror or exc}") from exc
    store_path = Path(store) if store is not None else out / f"{pipeline.name}.h5"
    scenes = [i for i in items if _is_scene(i)]
    p = pipeline.params
    version = __version__
    # content keys, computed without running anything
    keys: dict[str, str] = {}
    sim_keys = {}
    raw_for: dict[str, Path] = {}
    for item in scenes:
        stem = "default" if item == "default" else Path(item).stem
        raw_for[item] = out / f"{stem}.h5"
        sim_keys[item] = _digest({"stage": "simulate", "v": version, "params": p["simulate"],
                                  "scene": hashlib.sha256(_scene_bytes(item)).hexdigest()})
    ingest_inputs = [sim_keys[i] if i in sim_keys else _file_hash(Path(i)) for i in items]
    keys["ingest"] = _digest({"stage": "ingest", "v": version, "params": p["ingest"],
                              "inputs": sorted(ingest_inputs)})
    from rattle_lab.detect import DetectParams

    # (DetectParams.to_dict is the [detect] table as given: the keys of existing stores hold)
    detect_params = {**DetectParams.from_mapping(p["detect"]).to_dict(),
                     **{k: p["fit"][k] for k in _DETECT_FIT_KEYS}}
    keys["detect"] = _digest({"stage": "detect", "v": version, "cache": CACHE_FORMAT,
                              "params": detect_params,
                              "up": keys["ingest"]})
    keys["thresholds"] = _digest({"stage": "thresholds", "v": version, "up": keys["detect"]})
    keys["fit"] = _digest({"stage": "fit", "v": version, "params": p["fit"],
                           "up": [keys["thresholds"], keys["detect"]]})
    keys["report"] = _digest({"stage": "report", "v": version, "params": p["report"],
                              "up": [keys["fit"], keys["ingest"]]})
    run = PipelineRun(store_path)
    stages = needed_stages(pipeline.outputs, scenes=bool(scenes))
    cache = read_cache_keys(store_path)
    report_path = Path(report) if report is not None else out / f"{pipeline.name}.pdf"
    runs: list[Any] | None = None
    curve: Any = None

    def fresh(stage: str, key: str, output_ok: bool) -> bool:
        if cache.get(stage) == key and output_ok:
            run.cached.append(stage)
            say(f"{stage}: up to date")
            return True
        say(f"{stage}: running")
        return False

    def done(stage: str, key: str, extra: Mapping[str, str] | None = None) -> None:
        run.executed.append(stage)
        run.keys[stage] = key
        say(f"{stage}: done")
        entries = {stage: key, **(extra or {})}
        cache.update(entries)
        if store_path.is_file():
            record_cache_keys(store_path, entries)

    for stage in stages:
        if stage == "simulate":
            from rattle_lab.rig import write_synthetic

            for item in scenes:
                raw = raw_for[item]
                ck = f"simulate:{raw.name}"
                ok = raw.is_file() and cache.get(f"{ck}:hash") == _file_hash(raw)
                if fresh(ck, sim_keys[item], ok):
                    continue
                write_synthetic(item, raw, seed=p["simulate"]["seed"], quiet=quiet)
                run.executed.append("simulate")
                say(f"simulate: {item} -> {raw}")
                cache.update({ck: sim_keys[item], f"{ck}:hash": _file_hash(raw)})
            continue
        key = keys[stage]
        run.keys[stage] = key
        if stage == "ingest":
            if fresh("ingest", key, cache.get("ingest:records") == output_digest(store_path,
                                                                                 "ingest")):
                continue
            from rattle_lab.store import ingest

            files = [raw_for.get(i, Path(i)) for i in items]
            if "ingest" in cache and store_path.is_file():
                # A store this pipeline made, with other inputs (e.g. a scene simulated with a
                # new seed: same run ids, new data): rebuild it from the current inputs; its
                # /results and /pipeline_cache are stale anyway.  A store the pipeline did not
                # make (no cached ingest key) is only ever appended to.
                with store_lock(store_path), atomic_path(store_path) as tmp:
                    tmp.unlink()
                    ingest(files, tmp, allow_flagged=p["ingest"]["allow_flagged"], quiet=quiet)
                kept = {k: v for k, v in cache.items() if k.startswith("simulate:")}
                cache.clear()
                cache.update(kept)
            else:
                ingest(files, store_path, allow_flagged=p["ingest"]["allow_flagged"],
                       quiet=quiet)
            # the simulate keys are recorded now that the store exists
            done("ingest", key, {**{k: v for k, v in cache.items() if k.startswith("simulate:")},
                                 "ingest:records": output_digest(store_path, "ingest")})
        elif stage == "detect":
            if fresh("detect", key, has_path(store_path, f"{CACHE_GROUP}/detect")):
                continue
            runs = detect_runs(store_path, p["detect"], {**p["fit"]}, scheduler=scheduler,
                               quiet=quiet)
            write_cached(store_path, "detect", runs)
            done("detect", key)
        elif stage == "thresholds":
            if fresh("thresholds", key, has_path(store_path, f"{CACHE_GROUP}/thresholds")):
                continue
            from rattle_lab.detect.thresholds import tabulate_thresholds

            if runs is None:
                runs = list(read_detections(store_path))
            curve = tabulate_thresholds([r.threshold for r in runs if r.threshold is not None])
            write_cached(store_path, "thresholds", curve)
            done("thresholds", key)
        elif stage == "fit":
            if fresh("fit", key, bool(cache.get("fit:results"))
                     and cache.get("fit:results") == output_digest(store_path, "fit")):
                continue
            if runs is None:
                runs = list(read_detections(store_path))
            if curve is None:
                curve = read_cached(store_path, "thresholds")
            _fit_and_write(store_path, runs, curve, pipeline)
            done("fit", key, {"fit:results": output_digest(store_path, "fit")})
        elif stage == "report":
            ok = report_path.is_file() and cache.get("report:hash") == _file_hash(report_path)
            if fresh("report", key, ok):
                continue
            from rattle_lab.workflow._report import write_report

            write_report(store_path, report_path, model=p["report"]["model"], quiet=quiet)
            done("report", key, {"report:hash": _file_hash(report_path)})
    for name in pipeline.outputs:
        run.outputs[name] = report_path if name == "report" else store_path
    return run


__all__ = ["Pipeline", "PipelineRun", "STAGES", "DEPENDS", "OUTPUTS", "load_pipeline_file",
           "parse_pipeline", "run_pipeline", "needed_stages", "read_detections", "detect_run",
           "detect_runs", "map_tasks", "code_fingerprint", "detect_task", "sound_task"]
