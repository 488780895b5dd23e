"""Issue 29: throughput of ``rattle-lab fit`` and its parts, against what a user would use instead.

One run, one machine, one table (machine, date and load average printed with it):

* **end to end**: the installed ``rattle-lab fit STORE --json --quiet`` (default settings,
  every stage) on a long campaign written by the independent generator
  ``tests/independent_campaign.py`` (two files, 4 channels), in channel samples per second
  of wall time, and its peak RSS (``wait4``);
* **a plain h5py read** of the same samples (every channel of every run, read whole);
* **ObsPy's** ``classic_sta_lta`` and ``recursive_sta_lta`` (C) on one channel of the
  campaign (if ObsPy, the ``bench`` extra, is installed);
* **loudness**: ``rattle_lab.acoustics.loudness`` (ISO 532-1, compiled) on a 51.2 kHz
  microphone signal, as a multiple of real time per CPU second, beside MoSQITo's
  ``loudness_zwtv`` on one second;
* **psychoacoustics** (issue 26): each metric of ``benchmarks/psychoacoustics.py`` per CPU
  second on a 51.2 kHz channel, and the floor of any ECMA-418-2 implementation
  (``benchmarks/ecma418_floor.py``);
* **imports**: what ``rattle-lab fit`` pays for imports (``PYTHONPROFILEIMPORTTIME``: the sum
  of the top-level imports' cumulative times, a run on a small store);
* **scale-out**: the same fit (detect stage on the cluster) serial and on a ``LocalCluster``
  of 2 worker processes; the speed-up; a projection for a week of 4-channel 51.2 kHz data
  (1.2e11 samples) from the measured per-worker rate and scaling, and the cluster size for
  10 minutes;
* **streaming**: an hour (by default) of synthetic 4-channel 51.2 kHz data generated chunk by
  chunk on the workers (no file) through the pipeline's cluster path
  (:func:`rattle_lab.workflow.pipeline.map_tasks`): levels of every channel, ISO 532-1
  loudness of the microphone.

Run: ``.venv/bin/python benchmarks/throughput.py`` (``--seconds`` sets the campaign's length
per run; ``--stream-hours`` the synthetic stream).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from independent_campaign import Chain, Plant, write_campaign  # noqa: E402
from psychoacoustics import measure as psycho_measure  # noqa: E402

WEEK_SAMPLES = 1.2e11      # 4 channels x 51.2 kHz x 7 days (1.24e11), as the issue rounds it
TEN_MINUTES_S = 600.0


def entry_point() -> str:
    exe = Path(sys.executable).with_name("rattle-lab")
    return str(exe) if exe.exists() else "rattle-lab"


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg()
    return (f"{cpu}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}; "
            f"{datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC; load average "
            f"{load[0]:.1f} at the start")


def grazing_ms2(plant: Plant, f_hz: float) -> float:
    w, r = 2 * math.pi * plant.f_s_hz, f_hz / plant.f_s_hz
    return plant.gap_m * w * w * math.sqrt((1 - r * r) ** 2 + (2 * plant.zeta * r) ** 2) / plant.q


def write_long_campaign(folder: Path, seconds: float, fs_hz: float) -> list[Path]:
    """Two files of three dwell runs each, ``seconds`` long per run, above grazing."""
    plant = Plant()
    files = []
    for k, freqs in enumerate(((93.0, 95.0, 97.0), (94.0, 96.0, 99.0))):
        runs = [{"run_id": f"dwell_{f:g}", "protocol": "sine_dwell", "freq_hz": f,
                 "levels": np.full(int(seconds * f), 1.5 * grazing_ms2(plant, f))}
                for f in freqs]
        path = folder / f"campaign_{k}.h5"
        write_campaign(path, plant, Chain(fs_hz=fs_hz), runs, seed=11 + k)
        files.append(path)
    return files


def write_long_run(folder: Path, seconds: float, fs_hz: float) -> Path:
    """One file of one dwell run ``seconds`` long (the independent generator), ingested."""
    plant = Plant()
    path = folder / f"long_{seconds:g}.h5"
    write_campaign(path, plant, Chain(fs_hz=fs_hz), [
        {"run_id": "dwell_95", "protocol": "sine_dwell", "freq_hz": 95.0,
         "levels": np.full(int(seconds * 95.0), 1.5 * grazing_ms2(plant, 95.0))}], seed=17)
    from rattle_lab.store import ingest

    store = folder / f"long_{seconds:g}_store.h5"
    ingest([path], store, quiet=True)
    return store


def channel_samples(files: list[Path]) -> int:
    import h5py

    n = 0
    for path in files:
        with h5py.File(path, "r") as fh:
            for run in fh["runs"].values():
                n += sum(d.size for d in run["channels"].values())
    return n


def h5py_read(files: list[Path]) -> tuple[float, int]:
    import h5py

    t0 = time.perf_counter()
    n = 0
    for path in files:
        with h5py.File(path, "r") as fh:
            for run in fh["runs"].values():
                for d in run["channels"].values():
                    n += d[...].size
    return time.perf_counter() - t0, n


def _peak_rss_watch(pid: int, out: list[int], done: Any) -> None:
    """Poll ``/proc/PID/status`` for VmHWM (the peak RSS of the program the child runs, since
    its exec) until ``done`` is set."""
    path = f"/proc/{pid}/status"
    while not done.is_set():
        try:
            with open(path) as fh:
                for line in fh:
                    if line.startswith("VmHWM:"):
                        out[0] = max(out[0], int(line.split()[1]) * 1024)
        except (OSError, ValueError):
            pass
        done.wait(0.02)


def run_timed(cmd: list[str], env: dict[str, str] | None = None) -> tuple[float, int, str, str]:
    """Wall time, peak RSS (bytes), stdout, stderr of a command.

    The peak RSS is the child program's own: its ``VmHWM`` polled every 20 ms.  (The
    ``ru_maxrss`` of ``wait4`` or ``RUSAGE_CHILDREN`` also counts the moment between fork
    and exec, when the child is a copy of this process, hundreds of MiB.)  Where ``/proc``
    is absent, ``wait4``'s figure."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)
    peak, done = [0], threading.Event()
    watch = threading.Thread(target=_peak_rss_watch, args=(proc.pid, peak, done), daemon=True)
    watch.start()
    with ThreadPoolExecutor(2) as pool:   # drain both pipes while waiting for the child
        f_out = pool.submit(proc.stdout.read)  # type: ignore[union-attr]
        f_err = pool.submit(proc.stderr.read)  # type: ignore[union-attr]
        out, err = f_out.result(), f_err.result()   # EOF: the child is exiting
        done.set()
        watch.join()
        _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    rss = peak[0] or usage.ru_maxrss * 1024
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}): {err[-2000:]}")
    return wall, rss, out, err


def import_seconds(store: Path) -> float:
    env = dict(os.environ, PYTHONPROFILEIMPORTTIME="1")
    _, _, _, err = run_timed([entry_point(), "fit", str(store), "--json", "--quiet"], env=env)
    total = 0
    for line in err.splitlines():
        if line.startswith("import time:") and line.count("|") == 2:
            self_us, cum_us, name = line[len("import time:"):].split("|")
            if name.strip() != "imported package" and name == " " + name.strip():
                total += int(cum_us)  # a top-level import (no indentation)
    return total / 1e6


def obspy_rates(files: list[Path]) -> dict[str, float] | str:
    try:
        from obspy.signal.trigger import classic_sta_lta, recursive_sta_lta
    except ImportError as exc:
        return f"not installed ({exc.name}); pip install -e '.[bench]'"
    import h5py

    with h5py.File(files[0], "r") as fh:
        d = fh["runs"]["dwell_93"]["channels"]["velocity"]
        fs = float(d.attrs["sample_rate_hz"])
        x = np.asarray(d[...], dtype=np.float64)
    nsta, nlta = int(0.002 * fs), int(0.05 * fs)
    out = {}
    for name, fn in (("classic_sta_lta", classic_sta_lta), ("recursive_sta_lta",
                                                           recursive_sta_lta)):
        fn(x[:10000], nsta, nlta)
        t0 = time.process_time()
        fn(x, nsta, nlta)
        out[name] = x.size / (time.process_time() - t0)
    return out


def detection_rate(store: Path) -> tuple[float, int, int]:
    """The detection stage alone, as ``analyse_run`` calls it (no flight model, no ringing
    search, no acoustics): ``detect_impacts`` on the plate channels (trigger, impact times,
    local-fit v_in/v_out) and ``sound_peaks`` on the microphone, every run of the store, one
    BLAS thread.  Returns (channel samples per CPU second, channel samples, impacts)."""
    from threadpoolctl import threadpool_limits

    from rattle_lab.detect import detect_impacts, sound_peaks
    from rattle_lab.detect._chain import _fs_of, _t0_of, paired_plate_channels
    from rattle_lab.store import open_stored_record, read_catalogue

    cat = read_catalogue(store, level="runs")
    cpu, n, n_imp = 0.0, 0, 0
    for key, run_id in zip(cat["input_key"], cat["run_id"]):
        with open_stored_record(store, key) as record:
            run = record.run(run_id)
            by_q = {c.quantity: c for c in run.channels}
            fs, t0, v, a = paired_plate_channels(run, by_q.get("plate_velocity"),
                                                 by_q.get("plate_acceleration"))
            mic = by_q["sound_pressure"]
            p, fs_mic, t0_mic = mic.read(), _fs_of(run, mic), _t0_of(run, mic)
        freq = float(run.excitation_freq_hz)
        with threadpool_limits(1):
            c0 = time.process_time()
            log = detect_impacts(fs, velocity_m_s=v, accel_ms2=a, start_time_s=t0,
                                 excitation_freq_hz=freq)
            sound_peaks(p, fs_mic, log.t_s, start_time_s=t0_mic, excitation_freq_hz=freq)
            cpu += time.process_time() - c0
        n += sum(x.size for x in (v, a, p) if x is not None)
        n_imp += log.t_s.size
    return n / cpu, n, n_imp


def loudness_rates(seconds: float = 30.0) -> tuple[float, float, float]:
    """Compiled loudness at 51.2 kHz: x real time per CPU second and per wall second;
    MoSQITo's x real time (one second of sound at 48 kHz)."""
    from rattle_lab.acoustics import loudness

    fs = 51200.0
    rng = np.random.default_rng(1)
    t = np.arange(int(seconds * fs)) / fs
    p = 0.05 * rng.standard_normal(t.size) + 0.2 * np.sin(2 * np.pi * 1000 * t) \
        * (np.sin(2 * np.pi * 3 * t) > 0.6)
    loudness(p[:int(fs)], fs)  # load the compiled code
    best_cpu, best_wall = math.inf, math.inf
    for _ in range(3):
        c0, w0 = time.process_time(), time.perf_counter()
        loudness(p, fs)
        best_cpu = min(best_cpu, time.process_time() - c0)
        best_wall = min(best_wall, time.perf_counter() - w0)
    from mosqito.sq_metrics import loudness_zwtv

    c0 = time.process_time()
    loudness_zwtv(p[:48000], 48000)
    mosqito = 1.0 / (time.process_time() - c0)
    return seconds / best_cpu, seconds / best_wall, mosqito


def synthetic_chunk(seed: int, index: int, n: int, fs_hz: float) -> dict[str, float]:
    """Chunk ``index`` of a synthetic 4-channel record, generated here (on the worker):
    noise with decaying impacts every ~10 ms; its levels (sum of squares, peak) per channel
    and the ISO 532-1 loudness of the microphone (N5, Nmax)."""
    from rattle_lab.acoustics import loudness

    rng = np.random.default_rng([seed, index])
    x = 0.01 * rng.standard_normal((4, n)).astype(np.float32)
    hits = np.flatnonzero(rng.random(n) < 100.0 / fs_hz)
    ring = np.exp(-np.arange(256) / 40.0).astype(np.float32)
    for i in hits[hits < n - ring.size]:
        x[:, i:i + ring.size] += rng.standard_normal((4, 1)).astype(np.float32) * ring
    ld = loudness(x[3].astype(np.float64), fs_hz)
    return {"samples": float(x.size), "sumsq": float(np.sum(x.astype(np.float64) ** 2)),
            "peak": float(np.max(np.abs(x))), "n5": ld.n5_sone, "nmax": ld.nmax_sone}


#: The detection stream's record: the independent generator's plant and chain at 25.6 kHz,
#: a 95 Hz dwell at 1.5 times grazing, made in blocks of 10 s (950 forcing periods, so the
#: forcing's phase runs on from block to block), each from rest 2 s (190 periods) earlier.
STREAM_FS_HZ, STREAM_F_HZ, STREAM_BLOCK_S, STREAM_WARM_PERIODS = 25600.0, 95.0, 10.0, 190


def synthetic_run(tests_dir: str, seed: int, seconds: float) -> Any:
    """A ``seconds``-long 4-channel run whose samples are made on demand, block by block, by
    the independent generator (``tests/independent_campaign.py``): a lazy
    :class:`~rattle_lab.records.Run` (``GeneratedData`` channels), nothing on disk.  Each
    block is a pure function of ``(seed, block)``; a process keeps its last 8 blocks."""
    import functools

    if tests_dir not in sys.path:
        sys.path.insert(0, tests_dir)
    from independent_campaign import Chain, Plant, measure

    from rattle_lab.records import Channel, GeneratedData, Run

    plant, chain = Plant(), Chain(fs_hz=STREAM_FS_HZ)
    fs, f = STREAM_FS_HZ, STREAM_F_HZ
    block = int(round(STREAM_BLOCK_S * fs))
    warm = int(round(STREAM_WARM_PERIODS * fs / f))
    n = int(round(seconds / STREAM_BLOCK_S)) * block
    level = 1.5 * grazing_ms2(plant, f)

    @functools.lru_cache(maxsize=8)   # a segment and its margins: up to 6 blocks
    def made(j: int) -> dict[str, np.ndarray]:
        levels = np.full(STREAM_WARM_PERIODS + int(round(STREAM_BLOCK_S * f)), level)
        chans, _ = measure(plant, chain, 2 * math.pi * f, levels, np.random.default_rng((seed, j)))
        return {k: v[warm:warm + block] for k, v in chans.items()}

    def reader(name: str) -> Any:
        def read(start: int, stop: int) -> np.ndarray:
            if stop <= start:
                return np.zeros(0)
            parts = [made(j)[name] for j in range(start // block, (stop - 1) // block + 1)]
            lo = start - (start // block) * block
            return np.concatenate(parts)[lo:lo + stop - start]
        return read

    common = {"sample_rate_hz": fs, "start_time_s": 0.0}
    channels = [Channel("velocity", "plate_velocity", "m/s", GeneratedData(n, float, reader("velocity")),
                        measurand=chain.measurand, group_delay_s=chain.velocity_delay_s,
                        **common)]  # type: ignore[arg-type]
    for name, qty, units in (("plate", "plate_acceleration", "m/s^2"),
                             ("base", "base_acceleration", "m/s^2"), ("mic", "sound_pressure", "Pa")):
        channels.append(Channel(name, qty, units, GeneratedData(n, float, reader(name)),
                                **common))  # type: ignore[arg-type]
    return Run("stream", "sine_dwell", tuple(channels), excitation_freq_hz=f)


def stream_impacts(tests_dir: str, seed: int, seconds: float, index: int) -> Any:
    """Segment ``index`` of :func:`synthetic_run`'s record, made and detected on the worker."""
    from rattle_lab.detect import segment_impacts

    return segment_impacts("stream", synthetic_run(tests_dir, seed, seconds), index, {})


def stream_sound(tests_dir: str, seed: int, seconds: float, index: int, t_s: Any) -> Any:
    """The sound of segment ``index`` (sound peaks, levels, loudness), made on the worker."""
    from rattle_lab.detect import segment_sound

    from independent_campaign import Chain

    return segment_sound("stream", synthetic_run(tests_dir, seed, seconds), index, t_s, {}, {},
                         Chain().mic_m)


def stream_detection(client: Any, minutes: float, workers: int) -> tuple[str, str, str]:
    """``minutes`` of :func:`synthetic_run` through the cluster path of a long run: a task
    per segment for the impacts, merged here, a task per segment for the sound, assembled
    here (what ``fit`` does with a long stored run)."""
    from rattle_lab.detect import assemble_segments, merge_segment_impacts, run_segments
    from rattle_lab.workflow.pipeline import map_tasks

    tests_dir = str(Path(__file__).resolve().parents[1] / "tests")
    seconds = minutes * 60.0
    run = synthetic_run(tests_dir, 31, seconds)
    spans = run_segments("stream", run, {}) or []
    n = sum(c.n_samples for c in run.channels)
    t0 = time.perf_counter()
    run.channel("velocity").read(0, 1)   # one block of every channel, made here
    t_block = time.perf_counter() - t0
    t0 = time.perf_counter()
    parts = map_tasks(stream_impacts, [(tests_dir, 31, seconds, j) for j in range(len(spans))],
                      scheduler=client, quiet=True)
    log, flags = merge_segment_impacts("stream", run, parts, {})
    sounds = map_tasks(stream_sound, [(tests_dir, 31, seconds, j, log.t_s)
                                      for j in range(len(spans))], scheduler=client, quiet=True)
    from independent_campaign import Chain

    res = assemble_segments("stream", run, log, flags, sounds, {}, {}, Chain().mic_m)
    wall = time.perf_counter() - t0
    lv = res.acoustics.levels
    return (f"stream with detection: {minutes:g} min of 4-ch 25.6 kHz made on {workers} "
            "workers", f"{n / wall / 1e6:.2f} M samples/s",
            f"{n / 1e6:.0f} M samples in {wall:.0f} s, {len(spans)} segments made by the "
            f"independent generator on the workers (one {STREAM_BLOCK_S:g} s block of 4 "
            f"channels takes {t_block:.1f} s to make here, in both rounds); {log.n_impacts} "
            f"impacts ({log.n_impacts / seconds:.1f}/s), pattern {res.pattern!r}, LAeq "
            f"{lv.laeq_db:.1f} dB, N5 {res.acoustics.loudness.n5_sone:.1f} sone")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=50.0,
                    help="record length of each of the campaign's 6 runs, s (default 50: "
                         "6 x 50 s x 4 channels x 25.6 kHz = 30.7 M channel samples)")
    ap.add_argument("--fs", type=float, default=25600.0, help="the campaign's rate, Hz")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--stream-hours", type=float, default=1.0,
                    help="hours of synthetic 4-channel 51.2 kHz data through the cluster path")
    ap.add_argument("--chunk-s", type=float, default=10.0, help="streaming chunk, s")
    ap.add_argument("--stream-detect-minutes", type=float, default=5.0,
                    help="minutes of the independent generator's record made on the workers "
                         "and detected there, segment by segment (default 5; 0: none)")
    ap.add_argument("--long-seconds", type=float, nargs=2, default=(100.0, 400.0),
                    help="lengths of the two single-run records whose peak RSS of `fit` is "
                         "compared, s (default 100 400)")
    args = ap.parse_args()

    import logging

    from dask.distributed import Client, LocalCluster

    from rattle_lab.store import ingest
    from rattle_lab.workflow import fit_store
    from rattle_lab.workflow.pipeline import map_tasks

    print(f"# {machine()}", flush=True)
    rows: list[tuple[str, str, str]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        t0 = time.perf_counter()
        files = write_long_campaign(folder, args.seconds, args.fs)
        n_samples = channel_samples(files)
        store = folder / "store.h5"
        ingest(files, store, quiet=True)
        print(f"# campaign: {len(files)} files from tests/independent_campaign.py, "
              f"{n_samples / 1e6:.1f} M channel samples at {args.fs / 1e3:g} kHz "
              f"(written and ingested in {time.perf_counter() - t0:.0f} s)", flush=True)

        small = folder / "small"
        small.mkdir()
        write_campaign(small / "c.h5", Plant(), Chain(fs_hz=args.fs), [
            {"run_id": "dwell_95", "protocol": "sine_dwell", "freq_hz": 95.0,
             "levels": np.full(200, 1.5 * grazing_ms2(Plant(), 95.0))}], seed=3)
        ingest([small / "c.h5"], small / "s.h5", quiet=True)
        # compiled code into numba's cache first (a user's second run), then the imports
        run_timed([entry_point(), "fit", str(small / "s.h5"), "--json", "--quiet"])
        imp = import_seconds(small / "s.h5")
        rows.append(("imports of `rattle-lab fit` (PYTHONPROFILEIMPORTTIME)", f"{imp:.2f} s",
                     "goal <= 1 s"))
        print(rows[-1], flush=True)

        wall, rss, out, _ = run_timed([entry_point(), "fit", str(store), "--json", "--quiet"])
        n_ok = json.loads(out).get("n_ok")
        rows.append(("rattle-lab fit, end to end (default settings)",
                     f"{n_samples / wall / 1e6:.2f} M samples/s",
                     f"{wall:.1f} s wall, {n_ok} runs fitted; peak RSS {rss / 2**20:.0f} MiB"))
        print(rows[-1], flush=True)
        # memory against a run's length: one run, then one four times longer
        long_rows = []
        for seconds in args.long_seconds:
            long_store = write_long_run(folder, seconds, args.fs)
            n_long = sum(channel_samples([p]) for p in folder.glob(f"long_{seconds:g}.h5"))
            w_long, rss_long, out_long, _ = run_timed([entry_point(), "fit", str(long_store),
                                                       "--json", "--quiet"])
            e_long = (json.loads(out_long).get("fits", {}).get("restitution_ratio") or {}
                      ).get("value")
            long_rows.append(f"{seconds:g} s run ({n_long / 1e6:.0f} M samples): "
                             f"{rss_long / 2**20:.0f} MiB, {w_long:.0f} s, e {e_long:.4f}")
            long_store.unlink()
        rows.append(("peak RSS of rattle-lab fit against the run's length",
                     " / ".join(r.split(":")[1].split(",")[0].strip() for r in long_rows),
                     "; ".join(long_rows) + " (truth e 0.55); goal <= 1 GiB whatever the length"))
        print(rows[-1], flush=True)
        t_read, n_read = h5py_read(files)
        rows.append(("plain h5py read of the same samples", f"{n_read / t_read / 1e6:.0f} M "
                     "samples/s", f"{t_read:.2f} s; fit is {wall / t_read:.0f}x slower"))
        det_rate, det_n, det_imp = detection_rate(store)
        rows.append(("detection stage alone (detect_impacts + sound_peaks)",
                     f"{det_rate / 1e6:.2f} M samples/s per CPU s",
                     f"{det_n / 1e6:.1f} M samples of velocity, plate and mic, {det_imp} impacts, "
                     "one BLAS thread; goal >= 100 M"))
        print(rows[-1], flush=True)
        sta = obspy_rates(files)
        if isinstance(sta, str):
            rows.append(("ObsPy STA/LTA", "-", sta))
        else:
            for name, rate in sta.items():
                rows.append((f"ObsPy {name} (one channel, CPU time)",
                             f"{rate / 1e6:.0f} M samples/s", "per core"))
        print(rows[-1], flush=True)

        cpu_x, wall_x, mosq_x = loudness_rates()
        rows.append(("ISO 532-1 loudness, 51.2 kHz mic (compiled)",
                     f"{cpu_x:.0f}x real time per CPU s",
                     f"{wall_x:.0f}x per wall s; MoSQITo {mosq_x:.2f}x; goal >= 200x"))
        print(rows[-1], flush=True)
        # issue 26: every psychoacoustic metric, per core (benchmarks/psychoacoustics.py)
        for name, sound, t in psycho_measure(10.0):
            rate = sound / t if t > 0 else float("nan")
            rows.append((f"{name}, 51.2 kHz" if "floor" not in name else name,
                         f"{rate:.1f}x real time per CPU s",
                         f"{t:.3f} CPU s for {sound:g} s of sound; goal >= 50x"))
        print(rows[-1], flush=True)

        # scale-out: the same fit, detect stage serial and on the cluster
        t0 = time.perf_counter()
        serial = fit_store(store, write=False)
        t_serial = time.perf_counter() - t0
        with LocalCluster(n_workers=args.workers, processes=True, threads_per_worker=1,
                          dashboard_address=":0", silence_logs=logging.ERROR) as lc, \
                Client(lc) as client:
            client.run(lambda: __import__("rattle_lab.workflow.pipeline"))  # warm the workers
            t0 = time.perf_counter()
            remote = fit_store(store, write=False, scheduler=client)
            t_cluster = time.perf_counter() - t0
            same = (json.dumps(serial.summary.to_dict(), sort_keys=True, default=str)
                    == json.dumps(remote.summary.to_dict(), sort_keys=True, default=str))
            speedup = t_serial / t_cluster
            per_worker = n_samples / t_cluster / args.workers
            rows.append((f"fit_store serial / on a LocalCluster of {args.workers} workers",
                         f"{speedup:.2f}x speed-up",
                         f"{t_serial:.1f} s / {t_cluster:.1f} s; results identical: {same}; "
                         "goal >= 1.8x"))
            print(rows[-1], flush=True)
            efficiency = speedup / args.workers
            # the per-worker rate measured on the cluster (its scaling losses included)
            need = math.ceil(WEEK_SAMPLES / TEN_MINUTES_S / per_worker)
            rows.append(("projection: a week of 4-ch 51.2 kHz (1.2e11 samples), fit path",
                         f"{WEEK_SAMPLES / per_worker / 3600:.1f} worker-hours",
                         f"{per_worker / 1e6:.2f} M samples/s per worker at {efficiency:.0%} "
                         f"scaling: {need} workers for 10 minutes"))
            print(rows[-1], flush=True)

            # streaming: synthetic data generated chunk by chunk on the workers
            fs = 51200.0
            n_chunk = int(args.chunk_s * fs)
            n_chunks = math.ceil(args.stream_hours * 3600.0 / args.chunk_s)
            tasks = [(29, k, n_chunk, fs) for k in range(n_chunks)]
            t0 = time.perf_counter()
            parts = map_tasks(synthetic_chunk, tasks, scheduler=client, quiet=True,
                              weights=[4 * n_chunk] * n_chunks)
            t_stream = time.perf_counter() - t0
            total = sum(p["samples"] for p in parts)
            leq = 10 * math.log10(sum(p["sumsq"] for p in parts) / total / 4e-10)
            stream_rate = total / t_stream
            need_s = math.ceil(WEEK_SAMPLES / TEN_MINUTES_S / (stream_rate / args.workers))
            rows.append((f"stream: {args.stream_hours:g} h of synthetic 4-ch 51.2 kHz on "
                         f"{args.workers} workers", f"{stream_rate / 1e6:.2f} M samples/s",
                         f"{total / 1e9:.2f} G samples in {t_stream:.0f} s ({n_chunks} chunks "
                         f"made on the workers, no file); levels + loudness: week in 10 min "
                         f"needs {need_s} workers; max N {max(p['nmax'] for p in parts):.1f} "
                         f"sone, Leq {leq:.1f} dB"))
            print(rows[-1], flush=True)

            if args.stream_detect_minutes > 0:
                rows.append(stream_detection(client, args.stream_detect_minutes, args.workers))
                print(rows[-1], flush=True)

    width = max(len(r[0]) for r in rows)
    print()
    print(f"{'measure':<{width}}  {'rate':<32}  notes")
    print(f"{'-' * width}  {'-' * 32}  -----")
    for name, rate, note in rows:
        print(f"{name:<{width}}  {rate:<32}  {note}")


if __name__ == "__main__":
    main()
