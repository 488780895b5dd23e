"""The store package (issue 16): layout version and migration, writers' lock, references out of
an input, declared extents, content verification and ``--replace``, temporary files."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
from record_factory import RATTLE_LAB, make_record, run_cli, run_command, write

from rattle_lab._atomic import TMP_MARKER, atomic_write_text, remove_stale_temporaries
from rattle_lab.cli import main
from rattle_lab.exceptions import DataError, FileFormatError, RattleLabError
from rattle_lab.store import StoreError
from rattle_lab.records._h5 import LinkError
from rattle_lab.store import (STORE_VERSION, check_linked_inputs, ingest, open_stored_record,
                              read_catalogue, verify_store)

FIXTURE_V2 = Path(__file__).resolve().parents[1] / "data" / "store_v2.h5"
MIC = "runs/dwell_094/channels/mic"


def _runs(store: Path) -> set[tuple[str, str]]:
    cat = read_catalogue(store, level="runs")
    return set(zip(cat["campaign_id"], cat["run_id"]))


# --- layout version and migration -----------------------------------------------------------

def test_a_store_of_the_previous_release_reads_and_is_migrated_by_the_next_writer(tmp_path):
    # tests/data/store_v2.h5 was written by the release before this change (layout version 2,
    # storage="copy", three runs of record_factory records of 256 samples).
    store = tmp_path / "old.h5"
    shutil.copyfile(FIXTURE_V2, store)
    with h5py.File(store, "r") as fh:
        assert fh.attrs["store_version"] == 2
    assert _runs(store) == {("plate96", "dwell_094"), ("plate96", "dwell_096"),
                            ("plate96", "ramp_01")}
    key = read_catalogue(store)["input_key"][0]
    with open_stored_record(store, key) as record:
        base = record.run("dwell_094").channel("base").read()
    # base: 0.5 V sine at 100 mV/g -> 5 g amplitude, in m/s^2 (record_factory.noisy_sine)
    assert base.shape == (256,) and np.all(np.isfinite(base)) and 40 < np.abs(base).max() < 60
    assert verify_store(store, linked_only=True) == []  # copied: nothing outside is read
    ingest([write(tmp_path, "new.h5", make_record("newcamp"))], store)
    with h5py.File(store, "r") as fh:
        assert fh.attrs["store_version"] == STORE_VERSION == 3
        assert all(g.attrs["ingest_link_targets"] == "{}" for g in fh["records"].values())
    assert _runs(store) == {("plate96", "dwell_094"), ("plate96", "dwell_096"),
                            ("plate96", "ramp_01"), ("newcamp", "dwell_094")}


def test_a_directory_as_the_store_is_one_line_exit_2(tmp_path, capsys):
    src = write(tmp_path)
    assert main(["ingest", str(src), "-o", str(tmp_path), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a directory" in err


# --- concurrent writers ---------------------------------------------------------------------

_WORKER = """
import sys
from rattle_lab.cli import main
store, files = sys.argv[1], sys.argv[2:]
for f in files:  # one store write per file: the most read-modify-write cycles
    rc = main(["ingest", f, "-o", store, "--quiet"])
    if rc:
        sys.exit(rc)
"""


@pytest.mark.slow
def test_four_concurrent_writers_lose_no_run(tmp_path):
    files = [write(tmp_path, f"r{i:02d}.h5", make_record(f"camp{i:02d}", n=512, seed=i))
             for i in range(50)]
    store = tmp_path / "store.h5"
    procs = [subprocess.Popen([sys.executable, "-c", _WORKER, str(store),
                               *map(str, files[k::4])], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for k in range(4)]
    errs = [p.communicate(timeout=600)[1] for p in procs]
    assert [p.returncode for p in procs] == [0, 0, 0, 0], errs
    assert _runs(store) == {(f"camp{i:02d}", "dwell_094") for i in range(50)}
    assert not [p for p in tmp_path.iterdir() if TMP_MARKER in p.name]


@pytest.mark.slow
def test_four_installed_entry_points_at_once_keep_all_their_runs(tmp_path):
    # The reproduction: four `rattle-lab ingest` processes, two files each.
    files = [write(tmp_path, f"r{i}.h5", make_record(f"c{i}", n=512, seed=i)) for i in range(8)]
    store = tmp_path / "store.h5"
    procs = [subprocess.Popen([str(RATTLE_LAB), "ingest", str(files[2 * k]), str(files[2 * k + 1]),
                               "-o", str(store), "--quiet"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for k in range(4)]
    for p in procs:
        assert p.wait(timeout=600) == 0, p.stderr.read() if p.stderr else ""
    assert _runs(store) == {(f"c{i}", "dwell_094") for i in range(8)}


# --- references out of an input ---------------------------------------------------------------

def _linked_channel(tmp_path: Path, kind: str, target_dir: Path) -> Path:
    """A record whose mic channel lives in ``target_dir/ext.h5`` (external link or VDS)."""
    tmp_path.mkdir(parents=True, exist_ok=True)
    src = write(tmp_path, "rec.h5")
    target_dir.mkdir(parents=True, exist_ok=True)
    ext = target_dir / "ext.h5"
    with h5py.File(src, "a") as fh:
        data, attrs = fh[MIC][()], dict(fh[MIC].attrs)
        del fh[MIC]
        with h5py.File(ext, "w") as out:
            out.create_dataset("d", data=data).attrs.update(attrs)
        rel = os.path.relpath(ext, src.parent)
        if kind == "external_link":
            fh[MIC] = h5py.ExternalLink(rel, "/d")
        else:
            layout = h5py.VirtualLayout(shape=data.shape, dtype=data.dtype)
            layout[:] = h5py.VirtualSource(rel, "d", shape=data.shape)
            fh.create_virtual_dataset(MIC, layout).attrs.update(attrs)
    return src


@pytest.mark.parametrize("kind", ["external_link", "virtual_dataset"])
def test_references_out_of_the_input_are_refused_by_default(tmp_path, kind, capsys):
    src = _linked_channel(tmp_path / "in", kind, tmp_path / "elsewhere")
    store = tmp_path / "store.h5"
    with pytest.raises(LinkError, match=r"rec\.h5: /runs/dwell_094/channels/mic: .*refers to "
                                         r"another file .*ext\.h5.*--allow-links"):
        ingest([src], store)
    assert main(["ingest", str(src), "-o", str(store), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "refers to another file" in err
    assert not store.exists()
    # --allow-links resolves only inside the input's folder: ext.h5 is outside
    with pytest.raises(LinkError, match=r"outside the input's folder"):
        ingest([src], store, allow_links=True)


@pytest.mark.parametrize("kind", ["external_link", "virtual_dataset"])
def test_allowed_references_inside_the_folder_are_hashed_and_verified(tmp_path, kind):
    src = _linked_channel(tmp_path / "in", kind, tmp_path / "in" / "parts")
    ext = tmp_path / "in" / "parts" / "ext.h5"
    store = tmp_path / "store.h5"
    key = ingest([src], store, allow_links=True).inputs[0].input_key
    with h5py.File(store, "r") as fh:
        targets = json.loads(fh[f"records/{key}"].attrs["ingest_link_targets"])
        # the samples reached through the reference are copied, not linked twice
        assert not fh[f"records/{key}/{MIC}"].is_virtual
    assert list(targets) == [str(ext.resolve())]
    assert verify_store(store) == []
    with open_stored_record(store, key) as record:
        original = record.run("dwell_094").channel("mic").read()
    st = ext.stat()
    with h5py.File(ext, "a") as fh:  # same size, same modification time, other samples
        fh["d"][:10] = fh["d"][:10] + 1.0
    os.utime(ext, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert ext.stat().st_size == st.st_size
    [bad] = verify_store(store)
    assert bad.path == str(ext.resolve()) and bad.problem == "changed" and bad.linked
    with pytest.raises(StoreError, match=r"ext\.h5 has changed since it was ingested"):
        check_linked_inputs(store)
    assert original.shape == (4096,)


# --- declared extents --------------------------------------------------------------------------

def _huge_chunked(tmp_path: Path) -> Path:
    src = write(tmp_path, "rec.h5")
    with h5py.File(src, "a") as fh:
        attrs = dict(fh[MIC].attrs)
        del fh[MIC]
        ds = fh.create_dataset(MIC, shape=(10**12,), dtype="f4", chunks=(1 << 16,))
        ds[: 1 << 16] = np.sin(np.arange(1 << 16, dtype=np.float32))
        ds.attrs.update(attrs)
    return src


def test_a_dataset_declaring_1e12_samples_is_refused_before_reading(tmp_path, capsys):
    src = _huge_chunked(tmp_path)
    assert src.stat().st_size < 2_000_000
    with pytest.raises(DataError, match=r"rec\.h5: /runs/dwell_094/channels/mic: dataset 'shape': "
                                        r"declares \(1000000000000,\) in 15258790 chunks but the "
                                        r"file stores 1"):
        ingest([src], tmp_path / "store.h5")
    assert main(["ingest", str(src), "-o", str(tmp_path / "store.h5"), "--quiet"]) == 2
    assert capsys.readouterr().err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.h5"]


def test_a_file_cut_inside_its_last_dataset_is_refused(tmp_path):
    src = write(tmp_path, "rec.h5")
    with h5py.File(src, "r") as fh:
        last = max((fh[f"runs/dwell_094/channels/{n}"].id.get_offset(), n)
                   for n in fh["runs/dwell_094/channels"])[1]
        ds = fh[f"runs/dwell_094/channels/{last}"]
        cut = ds.id.get_offset() + ds.id.get_storage_size() // 2
    with open(src, "r+b") as fh:
        fh.truncate(cut)
    with pytest.raises((FileFormatError, DataError), match=r"rec\.h5: "):
        ingest([src], tmp_path / "store.h5")
    assert not (tmp_path / "store.h5").exists()


# --- content verification and --replace ------------------------------------------------------

def _same_size_same_mtime_edit(path: Path) -> None:
    st = path.stat()
    with h5py.File(path, "a") as fh:
        fh[MIC][100:110] = fh[MIC][100:110] * 1.5
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert path.stat().st_size == st.st_size and path.stat().st_mtime_ns == st.st_mtime_ns


def test_a_changed_input_is_caught_by_verify_and_replace_recovers(tmp_path):
    src = write(tmp_path, "rec.h5")
    store = tmp_path / "store.h5"
    ingest([src], store)
    assert run_command("verify", str(store)).returncode == 0
    _same_size_same_mtime_edit(src)
    proc = run_command("verify", str(store))
    assert proc.returncode == 2, proc.stderr
    assert "MISMATCH" in proc.stdout and "rec.h5 has changed since it was ingested" in proc.stdout
    assert "1 mismatches" in proc.stdout
    # fit and report check before reading: exit 2, one line naming the file and the way out
    for command in (["fit", str(store), "--quiet"],
                    ["report", str(store), "-o", str(tmp_path / "r.pdf"), "--quiet"]):
        proc = run_command(*command)
        assert proc.returncode == 2, proc.stderr
        assert proc.stderr.count("\n") == 1 and "rec.h5 has changed" in proc.stderr
        assert "--replace" in proc.stderr
    assert not (tmp_path / "r.pdf").exists()
    # without --replace, the new content's run collides with the stored one ...
    proc = run_command("ingest", str(src), "-o", str(store), "--quiet")
    assert proc.returncode == 2 and "--replace" in proc.stderr
    # ... and the advised --replace works
    proc = run_command("ingest", str(src), "-o", str(store), "--replace", "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert run_command("verify", str(store)).returncode == 0
    assert _runs(store) == {("plate96", "dwell_094")}
    assert len(read_catalogue(store)) == 5  # one record's channels, the old one gone


def test_verify_notes_a_changed_copied_input_without_failing(tmp_path):
    src = write(tmp_path, "rec.h5")
    store = tmp_path / "store.h5"
    ingest([src], store, storage="copy")
    _same_size_same_mtime_edit(src)
    proc = run_command("verify", str(store))
    assert proc.returncode == 0 and "note:" in proc.stdout and "0 mismatches" in proc.stdout


def test_a_mapping_with_a_native_record_warns(tmp_path):
    src = write(tmp_path, "rec.h5")
    mapping = tmp_path / "map.toml"
    mapping.write_text('[mapping]\nversion = 1\n[campaign]\ncampaign_id = "x"\n[rig]\n'
                       'apparatus = "other"\n[[runs]]\nrun_id = "r"\nprotocol = "transient"\n'
                       '[[runs.channels]]\nname = "a"\nsource = "a"\n'
                       'quantity = "base_acceleration"\n')
    proc = run_command("ingest", str(src), "-o", str(tmp_path / "s.h5"), "--mapping", str(mapping),
                       "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert "MappingIgnoredWarning" in proc.stderr and "native rattle record" in proc.stderr


# --- temporary files, signals, output errors ----------------------------------------------------

def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_stale_temporaries_of_dead_writers_are_removed(tmp_path):
    dead = tmp_path / f".store.h5{TMP_MARKER}{_dead_pid()}-abc.h5"
    live = tmp_path / f".store.h5{TMP_MARKER}{os.getpid()}-def.h5"
    other = tmp_path / ".hidden.h5"
    for p in (dead, live, other):
        p.write_bytes(b"x" * 100)
    ingest([write(tmp_path, "rec.h5")], tmp_path / "store.h5")
    assert not dead.exists() and live.exists() and other.exists()
    assert remove_stale_temporaries(tmp_path) == []


def test_temporary_names_carry_the_pid(tmp_path, monkeypatch):
    seen = []
    real = os.replace

    def spy(src, dst):
        seen.append(Path(src).name)
        return real(src, dst)

    monkeypatch.setattr(os, "replace", spy)
    atomic_write_text(tmp_path / "x.txt", "hi")
    assert seen and seen[0].startswith(f".x.txt{TMP_MARKER}{os.getpid()}-")


def test_a_full_disk_is_one_line_exit_2_and_the_store_intact(tmp_path, monkeypatch, capsys):
    import errno

    import rattle_lab.store._layout as layout

    src = write(tmp_path, "rec.h5")
    store = tmp_path / "store.h5"
    ingest([src], store)
    before = store.read_bytes()

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(layout.shutil, "copyfile", full)
    other = write(tmp_path, "other.h5", make_record("c2"))
    assert main(["ingest", str(other), "-o", str(store), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no space left" in err.lower()
    assert store.read_bytes() == before
    assert not [p for p in tmp_path.iterdir() if TMP_MARKER in p.name]


def test_ctrl_c_inside_compiled_code_is_interrupted_130(monkeypatch, capsys):
    import argparse

    import rattle_lab.cli as cli

    def numba_like(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:  # what numba reports after a signal in nopython code
            raise SystemError("<built-in function x> returned a result with an exception set") \
                from exc

    parser = argparse.ArgumentParser()
    parser.set_defaults(func=numba_like)
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    assert cli.main([]) == 130
    assert capsys.readouterr().err == "rattle-lab: interrupted\n"


@pytest.mark.parametrize("args", [["model", "run", "--F", "1", "--omega", "1", "--zeta", "0.05",
                                   "--e", "0.6", "--cycles", "0"],
                                  ["model", "run", "--F", "1", "--omega", "-1", "--zeta", "0.05",
                                   "--e", "0.6"],
                                  ["model", "run", "--F", "1", "--omega", "1", "--zeta", "0.05",
                                   "--e", "1.5"]])
def test_argument_types_refuse_bad_values(args):
    proc = run_cli(*args)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    [line] = proc.stderr.splitlines()
    assert line.startswith("rattle-lab: error: model run: argument --")


def test_simulate_to_a_directory_is_one_line_exit_2(tmp_path):
    proc = run_cli("simulate", "default", "-o", str(tmp_path))
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr


def test_run_pipeline_creates_its_output_folder(tmp_path):
    # `rattle-lab run pipelines/full_campaign.toml default --out build/` in a fresh clone
    from rattle_lab.workflow.pipeline import parse_pipeline, run_pipeline

    src = write(tmp_path, "rec.h5")
    out = tmp_path / "build" / "nested"
    result = run_pipeline(parse_pipeline({"pipeline": {"name": "p", "outputs": ["store"]}}),
                          [src], out_dir=out)
    assert out.is_dir() and result.outputs["store"] == out / "p.h5"
    assert _runs(out / "p.h5") == {("plate96", "dwell_094")}


def test_writer_threads_of_one_process_serialize_too(tmp_path):
    import threading

    files = [write(tmp_path, f"t{i}.h5", make_record(f"t{i}", n=512, seed=i)) for i in range(8)]
    errors: list[BaseException] = []

    def one(f: Path) -> None:
        try:
            ingest([f], tmp_path / "s.h5")
        except BaseException as exc:  # noqa: BLE001 - collected and asserted below
            errors.append(exc)

    threads = [threading.Thread(target=one, args=(f,)) for f in files]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert errors == []
    assert _runs(tmp_path / "s.h5") == {(f"t{i}", "dwell_094") for i in range(8)}


@pytest.mark.parametrize("command", ["ingest", "model_run_plot"])
def test_a_read_only_folder_is_one_line_exit_2(tmp_path, monkeypatch, capsys, command):
    # chmod cannot make a folder read-only for root (the tests may run as root): the refusal
    # is injected where every atomic writer creates its temporary file.
    import errno

    import rattle_lab._atomic as atomic

    def refuse(*args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied")

    src = write(tmp_path, "rec.h5")
    monkeypatch.setattr(atomic.tempfile, "mkstemp", refuse)
    args = {"ingest": ["ingest", str(src), "-o", str(tmp_path / "s.h5"), "--quiet"],
            "model_run_plot": ["model", "run", "--F", "1", "--omega", "1", "--zeta", "0.1",
                               "--e", "0.5", "--cycles", "2", "--plot", str(tmp_path / "p.png")]}
    assert main(args[command]) == 2
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1 and "Permission denied" in captured.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rec.h5"]


def test_a_store_record_changed_after_it_was_read_is_read_and_validated_again(tmp_path):
    # open_stored_record reads and validates a record's attributes once per process and file
    # state (a fit opens every run of a file); a store changed in between must not be served
    # from that memory: here a channel's sample rate made invalid after the first read
    src = write(tmp_path, record=make_record(run_ids=("dwell_094", "dwell_095")))
    store = tmp_path / "s.h5"
    key = ingest([src], store).inputs[0].input_key
    with open_stored_record(store, key) as rec:
        first = rec.run("dwell_095").channel("mic").read()
    with open_stored_record(store, key) as rec:  # the remembered tree, the datasets read again
        np.testing.assert_array_equal(rec.run("dwell_095").channel("mic").read(), first)
    with h5py.File(store, "r+") as fh:
        runs = fh[f"records/{key}/runs/dwell_095/channels"]
        runs["mic"].attrs["sample_rate_hz"] = -1.0
    with pytest.raises(RattleLabError, match="sample_rate_hz"):
        open_stored_record(store, key)
