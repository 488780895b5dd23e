"""Benchmark of the store's safety nets: time to refuse hostile inputs, concurrent writers,
and the cost of content verification.

Usage::

    python benchmarks/store_reliability.py            # 400 MB record for the verify timing
    python benchmarks/store_reliability.py --quick    # 40 MB, under a minute in all

Three tables:

1. Hostile inputs through :func:`rattle_lab.cli.main` (in-process): seconds until exit 2,
   for inputs that declare 1e12 samples (HDF5 chunked dataset, LVM header, NPY header)
   and references out of the input.  The alternative a user would otherwise get is reading
   the declared samples (1e12 float32 = 4 TB), shown as the time a plain read of 4 TB
   would take at the measured read speed of this machine.
2. Concurrent writers: ``W`` processes ingesting ``N`` one-run records, one store write per
   record, into one store, against one process ingesting the same records; runs found.
3. ``verify_store`` (full re-hash of the linked input) against a plain read of the same
   file and SHA-256 of it.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from record_factory import make_record, write_record  # noqa: E402

from rattle_lab.cli import main  # noqa: E402
from rattle_lab.store import ingest, read_catalogue, verify_store  # noqa: E402

MIC = "runs/dwell_094/channels/mic"
LVM_MAPPING = ('[mapping]\nversion = 1\n[campaign]\ncampaign_id = "b"\n[rig]\napparatus = "other"\n'
               '[[runs]]\nrun_id = "r"\nprotocol = "transient"\n[[runs.channels]]\nname = "acc"\n'
               'source = "{source}"\nquantity = "base_acceleration"\n')
LVM_HEAD = ("LabVIEW Measurement\t\nSeparator\tTab\nDecimal_Separator\t.\nX_Columns\tOne\n"
            "***End_of_Header***\t\n\nChannels\t1\t\nSamples\t1000000000000\t\n"
            "Y_Unit_Label\tm/s^2\t\nX0\t0\t\nDelta_X\t0.0005\t\n***End_of_Header***\t\t\n"
            "X_Value\tacc\tComment\n0\t1.0\n")


def _timed_main(args: list[str]) -> tuple[float, int, str]:
    err = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        rc = main(args)
    return time.perf_counter() - t0, rc, err.getvalue().strip()


def hostile(work: Path, read_gb_s: float) -> None:
    cases = {}
    src = write_record(work / "huge.h5", make_record(n=1024))
    with h5py.File(src, "a") as fh:
        attrs = dict(fh[MIC].attrs)
        del fh[MIC]
        fh.create_dataset(MIC, shape=(10**12,), dtype="f4", chunks=(1 << 16,)).attrs.update(attrs)
    cases["HDF5 chunked, 1e12 samples declared"] = ["ingest", str(src)]
    (work / "huge.lvm").write_text(LVM_HEAD)
    (work / "lvm.toml").write_text(LVM_MAPPING.format(source="acc"))
    cases["LVM header, 1e12 samples declared"] = ["ingest", str(work / "huge.lvm"), "--mapping",
                                                  str(work / "lvm.toml")]
    header = b"{'descr': '<f4', 'fortran_order': False, 'shape': (1000000000000,), }"
    header = header.ljust(117) + b"\n"
    (work / "huge.npy").write_bytes(b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header)
    (work / "npy.toml").write_text(LVM_MAPPING.format(source="0"))
    cases["NPY header, 1e12 samples declared"] = ["ingest", str(work / "huge.npy"), "--mapping",
                                                  str(work / "npy.toml")]
    link = write_record(work / "link.h5", make_record(n=1024))
    with h5py.File(link, "a") as fh:
        del fh[MIC]
        fh[MIC] = h5py.ExternalLink("/etc/hostname", "/x")
    cases["HDF5 external link to /etc/hostname"] = ["ingest", str(link)]
    print("\nHostile inputs (in-process rattle_lab.cli.main; exit status 2 expected)")
    print(f"{'input':40s} {'time to exit [s]':>17s} {'exit':>5s}  {'reading it instead':>20s}")
    for name, args in cases.items():
        dt, rc, err = _timed_main([*args, "-o", str(work / "s.h5"), "--quiet"])
        alt = "n/a" if "link" in name else f"{4e12 / (read_gb_s * 1e9) / 3600:.1f} h (4 TB)"
        print(f"{name:40s} {dt:17.3f} {rc:5d}  {alt:>20s}")
        assert rc == 2, err


WORKER = ("import sys\nfrom rattle_lab.store import ingest\n"
          "for f in sys.argv[2:]:\n    ingest([f], sys.argv[1])\n")


def concurrent(work: Path, n: int, writers: int) -> None:
    files = [write_record(work / f"c{i:03d}.h5", make_record(f"camp{i:03d}", n=512, seed=i))
             for i in range(n)]
    rows = []
    for label, k in ((f"{writers} processes at once", writers), ("1 process", 1)):
        store = work / f"store_{k}.h5"
        t0 = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-c", WORKER, str(store),
                                   *map(str, files[j::k])]) for j in range(k)]
        codes = [p.wait() for p in procs]
        dt = time.perf_counter() - t0
        found = len(read_catalogue(store, level="runs"))
        rows.append((label, dt, found, n - found, codes))
    print(f"\nConcurrent writers: {n} one-run records, one store write per record")
    print(f"{'writers':24s} {'wall [s]':>9s} {'runs found':>11s} {'runs lost':>10s}  exit codes")
    for label, dt, found, lost, codes in rows:
        print(f"{label:24s} {dt:9.2f} {found:11d} {lost:10d}  {codes}")


def verify_cost(work: Path, mb: int) -> float:
    n = mb * (1 << 20) // (5 * 4)
    rec = write_record(work / "long.h5", make_record("long", n=n))
    store = work / "v.h5"
    ingest([rec], store)
    t0 = time.perf_counter()
    with open(rec, "rb") as fh:
        while fh.read(32 << 20):
            pass
    t_read = time.perf_counter() - t0
    t0 = time.perf_counter()
    h = hashlib.sha256()
    with open(rec, "rb") as fh:
        while block := fh.read(32 << 20):
            h.update(block)
    t_sha = time.perf_counter() - t0
    t0 = time.perf_counter()
    assert verify_store(store) == []
    t_verify = time.perf_counter() - t0
    size_mb = rec.stat().st_size / 1e6
    print(f"\nContent verification of a linked {size_mb:.0f} MB input (file in the page cache)")
    print(f"{'method':34s} {'time [s]':>9s} {'MB/s':>8s} {'vs read':>8s}")
    for name, dt in (("plain read (32 MB blocks)", t_read), ("SHA-256", t_sha),
                     ("verify_store (XXH3-128, default)", t_verify)):
        print(f"{name:34s} {dt:9.3f} {size_mb / dt:8.0f} {dt / t_read:7.2f}x")
    return size_mb / 1e3 / t_read


def main_() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as name:
        work = Path(name)
        read_gb_s = verify_cost(work, 40 if args.quick else 400)
        hostile(work, read_gb_s)
        concurrent(work, 20 if args.quick else 50, 4)
    print("\n(timings on a shared 2-core machine under load from other jobs)")


if __name__ == "__main__":
    main_()
