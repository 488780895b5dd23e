"""``rattle-lab report`` and ``rattle-lab run`` through the installed entry point."""

from __future__ import annotations

from pathlib import Path

import pypdf
import pytest

from rattle_lab.store import ingest
from record_factory import run_cli

PIPELINES = Path(__file__).resolve().parents[2] / "pipelines"


@pytest.fixture(scope="module")
def bare_store(small_campaign_record: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The shortened default scene, ingested and not fitted (what these tests check does not
    depend on the record's length)."""
    store = tmp_path_factory.mktemp("clireport") / "store.h5"
    ingest([small_campaign_record], store)
    return store


def test_report_prints_path_and_notes_missing_sections(bare_store: Path, tmp_path: Path) -> None:
    out = tmp_path / "r.pdf"
    proc = run_cli("report", str(bare_store), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip().splitlines()[-1] == str(out)
    assert "section 'thresholds' left out" in proc.stderr and "rattle-lab fit" in proc.stderr
    assert len(pypdf.PdfReader(out).pages) == 2


@pytest.mark.parametrize("case", ["absent", "not_a_store", "bad_suffix"])
def test_report_errors_are_one_line_exit_2(case: str, bare_store: Path, tmp_path: Path) -> None:
    out = tmp_path / ("r.png" if case == "bad_suffix" else "r.pdf")
    store = {"absent": tmp_path / "absent.h5", "bad_suffix": bare_store,
             "not_a_store": tmp_path / "text.h5"}[case]
    if case == "not_a_store":
        store.write_text("not hdf5")
    proc = run_cli("report", str(store), "-o", str(out))
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert len(proc.stderr.strip().splitlines()) == 1
    assert proc.stderr.startswith("rattle-lab: error: ")
    assert not out.exists()


def test_run_pipeline_cli(small_campaign_record: Path, tmp_path: Path) -> None:
    pipe = tmp_path / "store_only.toml"
    pipe.write_text('[pipeline]\nname = "only"\noutputs = ["store"]\n')
    proc = run_cli("run", str(pipe), str(small_campaign_record), "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == f"store\t{tmp_path / 'only.h5'}\n"
    assert "ingest: done" in proc.stderr
    proc = run_cli("run", str(pipe), str(small_campaign_record), "--out", str(tmp_path),
                   "--quiet")
    assert proc.returncode == 0 and proc.stderr == ""


def test_run_pipeline_cli_errors(tmp_path: Path) -> None:
    proc = run_cli("run", str(PIPELINES / "threshold_campaign.toml"), str(tmp_path / "x.h5"))
    assert proc.returncode == 2 and "no such file" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    bad = tmp_path / "bad.toml"
    bad.write_text("[pipeline]\noutputs = ['pdf']\n")
    proc = run_cli("run", str(bad), "default")
    assert proc.returncode == 2 and "unknown output 'pdf'" in proc.stderr
