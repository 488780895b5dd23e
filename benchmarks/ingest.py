"""Benchmark of ``rattle_lab.store``: throughput against plain h5py reads, and peak memory.

Usage::

    python benchmarks/ingest.py            # a 60-minute, 4-channel, 51.2 kHz record (2.9 GB)
    python benchmarks/ingest.py --quick    # a 5-minute record, under a minute in all
    python benchmarks/ingest.py --minutes 10 --repeat 3 --dir /tmp

It writes a long synthetic record (float32 volts and m/s^2, sine plus noise), then times

* a plain h5py read of the same channels, chunk by chunk (the reference);
* a plain h5py copy into a new file (read + write, no checks: the floor of any copying ingest);
* SHA-256 of the input file (what a cryptographic content hash costs) and XXH3-128
  (``rattle_lab.store.file_hash``, the content hash used for idempotence);
* ``ingest()`` with the default ``storage="link"``: hashing, schema validation, quality checks,
  the SI conversion factors, virtual datasets onto the input, the catalogue, atomically;
* ``ingest(storage="copy")``: the same, copying every sample into the store;

and runs one more ingest in a fresh process to read its peak resident memory
(its ``VmHWM``; ``ru_maxrss`` where /proc is absent).  Times are the best of ``--repeat``
runs with the file in the page cache.
Target: ingest within 3x the plain read time (PASS/FAIL is printed).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import h5py
import numpy as np

import hashlib

from rattle_lab.store import file_hash, ingest
from rattle_lab.store._ingest_types import HASH_BLOCK_BYTES
from rattle_lab.records import Channel, GeneratedData, Record, Rig, Run, write_record

FS_HZ = 51200.0
CHUNK = 1 << 20
TARGET_RATIO = 3.0


def make_record(n_samples: int) -> Record:
    """Four float32 channels: two in raw volts with sensitivities, two in SI units."""

    def signal(seed: int, amplitude: float) -> GeneratedData:
        def make(start: int, stop: int) -> np.ndarray:
            t = np.arange(start, stop) / FS_HZ
            noise = np.random.default_rng((seed, start)).standard_normal(stop - start)
            return (amplitude * (np.sin(2 * np.pi * 94.0 * t) + 0.01 * noise)).astype(np.float32)
        return GeneratedData(n_samples, np.float32, make)

    common = {"sample_rate_hz": FS_HZ, "start_time_s": 0.0}
    channels = [
        Channel("base", "base_acceleration", "V", signal(1, 0.5), sensitivity=100.0,
                sensitivity_units="mV/g", **common),
        Channel("plate", "plate_acceleration", "m/s^2", signal(2, 20.0), **common),
        Channel("velocity", "plate_velocity", "V", signal(3, 2.0), sensitivity=25.0,
                sensitivity_units="(mm/s)/V", **common),
        Channel("mic", "sound_pressure", "Pa", signal(4, 0.2), **common),
    ]
    return Record("bench", "measured", Rig("other", description="benchmark record"),
                  [Run("long", "transient", channels)])


def best_of(repeat: int, func) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        func()
        times.append(time.perf_counter() - t0)
    return min(times)


def plain_read(path: Path) -> None:
    with h5py.File(path, "r") as fh:
        for ds in fh["runs/long/channels"].values():
            for start in range(0, ds.shape[0], CHUNK):
                ds[start:start + CHUNK]


def plain_copy(path: Path, out: Path) -> None:
    with h5py.File(path, "r") as fh, h5py.File(out, "w") as dst:
        for name, ds in fh["runs/long/channels"].items():
            target = dst.create_dataset(name, shape=ds.shape, dtype=ds.dtype)
            for start in range(0, ds.shape[0], CHUNK):
                target[start:start + CHUNK] = ds[start:start + CHUNK]


def sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(HASH_BLOCK_BYTES):
            h.update(block)
    return h.hexdigest()


def fresh_ingest(path: Path, store: Path, storage: str = "link") -> None:
    if store.exists():
        store.unlink()
    ingest([path], store, storage=storage)  # type: ignore[arg-type]


# The peak RSS is this process's VmHWM (its own memory since exec): ru_maxrss also counts the
# moment between fork and exec, when the child is a copy of the benchmark's process
MEASURE = textwrap.dedent("""
    import json, resource, sys, time
    t0 = time.perf_counter()
    from rattle_lab.store import ingest
    ingest([sys.argv[1]], sys.argv[2], storage=sys.argv[3])
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    try:
        with open("/proc/self/status") as fh:
            peak = next(int(x.split()[1]) / 1024 for x in fh if x.startswith("VmHWM:"))
    except (OSError, StopIteration):
        pass
    print(json.dumps({"seconds": time.perf_counter() - t0, "maxrss_mib": peak}))
""")


def rig_synthesis_rows(repeat: int) -> list[tuple[str, float, float, str]]:
    """Rig synthesis of the default scene (rig developer's rows): the full scene (five
    channels at 20 kHz), without the microphone, and threshold-only (base accelerometer
    only: no dense motion, no acoustic model).  Records stay in memory (no file written).
    MB/s is float32 sample output; the note gives seconds per simulated second."""
    import copy
    import tomllib
    from importlib import resources

    from rattle_lab.rig import parse_scene, synthesize

    base = tomllib.loads(resources.files("rattle_lab").joinpath("data/scenes/default.toml")
                         .read_text("utf-8"))
    variants = [("full scene (5 channels)", None),
                ("no microphone (4 channels)", ("base", "plate", "velocity", "drive")),
                ("threshold-only (base only)", ("base",))]
    rows = []
    for label, keep in variants:
        data = copy.deepcopy(base)
        if keep is not None:
            data["sensors"] = {k: v for k, v in data["sensors"].items() if k in keep}
            if "mic" not in keep:
                data.pop("acoustic")
        scene = parse_scene(data, "default")
        sim_s = sum(r.duration_s for r in scene.runs)
        n_values = sum(round(r.duration_s * scene.sample_rate_hz) for r in scene.runs) * len(scene.sensors)
        seconds = best_of(repeat, lambda: synthesize(scene))  # noqa: B023 (called at once)
        rows.append((f"rig synth, default: {label}", seconds, 4 * n_values / 1e6 / seconds,
                     f"{seconds / sim_s * 1e3:.1f} ms per simulated s ({sim_s:g} s)"))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a 5-minute record (under a minute)")
    parser.add_argument("--minutes", type=float, help="record length in minutes (default 60, quick 5)")
    parser.add_argument("--repeat", type=int, help="timed repetitions (default 3, full run 2)")
    parser.add_argument("--dir", help="folder for the temporary files (default: system temp)")
    args = parser.parse_args(argv)
    minutes = args.minutes or (5.0 if args.quick else 60.0)
    repeat = args.repeat or (3 if args.quick or minutes <= 10 else 2)
    n_samples = round(minutes * 60 * FS_HZ)
    work = Path(tempfile.mkdtemp(prefix="rattle_ingest_bench_", dir=args.dir))
    try:
        record_path = work / "long.h5"
        t0 = time.perf_counter()
        write_record(record_path, make_record(n_samples))
        t_write = time.perf_counter() - t0
        mb = 4 * n_samples * 4 / 1e6

        t_read = best_of(repeat, lambda: plain_read(record_path))
        t_copy = best_of(repeat, lambda: plain_copy(record_path, work / "copy.h5"))
        (work / "copy.h5").unlink()
        t_sha = best_of(repeat, lambda: sha256_file(record_path))
        t_hash = best_of(repeat, lambda: file_hash(record_path))
        t_ingest = best_of(repeat, lambda: fresh_ingest(record_path, work / "store.h5"))
        t_copy_ingest = best_of(repeat, lambda: fresh_ingest(record_path, work / "store.h5", "copy"))
        (work / "store.h5").unlink()
        mem = {}
        for storage in ("link", "copy"):
            proc = subprocess.run([sys.executable, "-c", MEASURE, str(record_path),
                                   str(work / f"m_{storage}.h5"), storage],
                                  check=True, capture_output=True, text=True)
            mem[storage] = json.loads(proc.stdout)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    ratio = t_ingest / t_read
    rows = [
        ("record written (write_record, generated data)", t_write, mb / t_write, ""),
        ("plain h5py read, 1 Mi-sample chunks", t_read, mb / t_read, "reference"),
        ("plain h5py copy (read + write, no checks)", t_copy, mb / t_copy, f"{t_copy / t_read:.2f}x read"),
        ("sha256 of the input file (for comparison)", t_sha, mb / t_sha, f"{t_sha / t_read:.2f}x read"),
        ("xxh3_128 of the input file (file_hash)", t_hash, mb / t_hash, f"{t_hash / t_read:.2f}x read"),
        ("ingest, storage=link (default)", t_ingest, mb / t_ingest, f"{ratio:.2f}x read"),
        ("ingest, storage=copy", t_copy_ingest, mb / t_copy_ingest,
         f"{t_copy_ingest / t_read:.2f}x read, {t_copy_ingest / t_copy:.2f}x plain copy"),
        *((f"ingest, storage={k}, fresh process (imports)", m["seconds"], mb / m["seconds"],
           f"peak RSS {m['maxrss_mib']:.0f} MiB") for k, m in mem.items()),
        # --- rig synthesis (rig developer) ------------------------------------------------
        *rig_synthesis_rows(repeat),
    ]
    print(f"rattle_lab ingest benchmark: {minutes:g} min x 4 channels x {FS_HZ:g} Hz float32 = "
          f"{mb:.0f} MB of samples; best of {repeat}; page cache warm")
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, h5py {h5py.__version__}, numpy {np.__version__}")
    print()
    print(f"{'step':<48} {'time s':>8} {'MB/s':>8}  note")
    print(f"{'-' * 48} {'-' * 8} {'-' * 8}  {'-' * 24}")
    for name, seconds, rate, note in rows:
        print(f"{name:<48} {seconds:8.3f} {rate:8.0f}  {note}")
    print()
    verdict = "PASS" if ratio <= TARGET_RATIO else "FAIL"
    print(f"{verdict}: ingest (default storage=link) takes {ratio:.2f}x the plain h5py read time "
          f"(target <= {TARGET_RATIO:g}x)")
    peak = max(m["maxrss_mib"] for m in mem.values())
    print(f"peak memory of the ingest processes: {peak:.0f} MiB "
          f"(record {mb:.0f} MB; target well under 1024 MiB): {'PASS' if peak < 1024 else 'FAIL'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
