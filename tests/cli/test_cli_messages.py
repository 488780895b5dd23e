"""What the user reads when something is wrong (issue 27 items 8-10), through the installed
``rattle-lab``: one line, one prefix, what is wrong and what to do, the names and paths it
knows; never a raw ``[Errno 2]``, never "refusing to overwrite" from a command that reads.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from record_factory import run_cli, write

from rattle_lab._resources import resource_names
from rattle_lab.store import ingest

PREFIX = "rattle-lab: error: "


def _one_error_line(proc) -> str:
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(PREFIX), lines[0]
    assert "Errno" not in lines[0] and "Traceback" not in proc.stderr
    return lines[0]


@pytest.mark.parametrize("args, kind, typo, closest", [
    (("simulate", "defualt", "-o", "{tmp}/x.h5"), "scenes", "defualt", "default"),
    (("run", "thresold_campaign", "default", "--out", "{tmp}"), "pipelines",
     "thresold_campaign", "threshold_campaign"),
    (("ingest", "{tmp}/rec.h5", "--mapping", "forced_shok_lvm", "-o", "{tmp}/s.h5"),
     "mappings", "forced_shok_lvm", "forced_shock_lvm"),
])
def test_a_mistyped_name_lists_the_shipped_ones_and_the_closest(args, kind, typo, closest,
                                                                tmp_path: Path) -> None:
    write(tmp_path)
    proc = run_cli(*(a.format(tmp=tmp_path) for a in args))
    line = _one_error_line(proc)
    assert f"no shipped {kind[:-1]} {typo!r}" in line and "cannot read" in line
    assert f"(closest: {closest!r})" in line
    for name in resource_names(kind):
        assert name in line
    assert not list(tmp_path.glob("s.h5")) and not (tmp_path / "x.h5").exists()


def test_the_fit_pipeline_option_lists_the_shipped_pipelines(tmp_path: Path) -> None:
    proc = run_cli("fit", str(tmp_path / "store.h5"), "--pipeline", "ful_campaign")
    line = _one_error_line(proc)
    assert "(closest: 'full_campaign')" in line


@pytest.mark.parametrize("command", ["fit", "verify", "report", "export"])
def test_a_damaged_store_is_named_and_nothing_refused(command: str, tmp_path: Path) -> None:
    store = tmp_path / "store.h5"
    store.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\x00" * 64)  # a truncated, damaged HDF5 file
    extra = {"report": ["-o", str(tmp_path / "r.pdf")], "export": ["-o", str(tmp_path / "x.uff")]}
    proc = run_cli(command, str(store), *extra.get(command, []))
    line = _one_error_line(proc)
    assert "refusing to overwrite" not in line  # these commands do not write a new store
    assert f"{store}: is not a rattle_lab ingest store" in line
    assert "damaged" in line and "rattle-lab ingest" in line


def test_ingest_still_refuses_to_overwrite_a_foreign_file(tmp_path: Path) -> None:
    src = write(tmp_path)
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes")
    line = _one_error_line(run_cli("ingest", str(src), "-o", str(notes)))
    assert "refusing to overwrite it" in line and "another output name" in line
    assert notes.read_text() == "my notes"


def test_a_record_given_to_fit_says_ingest_it_first(tmp_path: Path) -> None:
    record = write(tmp_path)
    line = _one_error_line(run_cli("fit", str(record)))
    assert "is a record, not an ingest store: ingest it first" in line
    assert f"`rattle-lab ingest {record} -o store.h5`" in line
    lvm = tmp_path / "run1.lvm"  # a foreign record: the command names the shipped mappings
    lvm.write_text("LabVIEW Measurement\t\n")
    line = _one_error_line(run_cli("fit", str(lvm)))
    assert "ingest it first" in line and "--mapping" in line
    assert "forced_shock_lvm" in line and "droptable_lvm" in line


def test_usage_errors_have_the_same_prefix() -> None:
    line = _one_error_line(run_cli("fit"))
    assert line.startswith(PREFIX + "fit: the following arguments are required: STORE")
    line = _one_error_line(run_cli("model", "map"))
    assert line.startswith(PREFIX + "model map: ")


def test_the_reingest_advice_names_the_paths(tmp_path: Path) -> None:
    src = write(tmp_path, "run2.h5")
    store = tmp_path / "store.h5"
    ingest([src], store)  # linked by default (the store `rattle-lab ingest` writes; a setup step)
    moved = tmp_path / "elsewhere.h5"
    shutil.move(src, moved)
    proc = run_cli("verify", str(store))
    assert proc.returncode == 2
    assert f"`rattle-lab ingest --replace {src} -o {store}`" in proc.stdout
    assert "FILE" not in proc.stdout and "STORE" not in proc.stdout
    line = _one_error_line(run_cli("report", str(store), "-o", str(tmp_path / "r.pdf")))
    assert f"`rattle-lab ingest --replace {src} -o {store}`" in line, line
