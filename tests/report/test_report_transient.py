"""The report and the fit table of a transient record (issue 27 items 1-3), on the real
forced-shock record of ../shared/realdata with its shipped mapping.

A 5 Hz shaker sine with one commanded shock pulse (the pulse is the timing truth): the
drive channel that carries the pulse is the cause and comes first, its onset is the rise
through 0.1 % of its peak (it rests at exactly zero; the first sample above zero is a
denormal of its tail, sample 3416), the channels on the accelerometers' clock give their
delays in samples and the two clocks are named; the report says what it is and shows the
shocks, with a figure of the waveforms aligned on each onset.  Independent reference: the
pulse read from the file by the reader, its first sample above 0.1 % of its peak (6294)
and its peak (6600).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pypdf
import pytest
from conftest import REALDATA
from record_factory import run_command

from rattle_lab.records import read

ROOT = Path(__file__).resolve().parents[2]
MAPPING = ROOT / "data_schema" / "mappings" / "forced_shock_lvm.toml"
LVM = REALDATA / "forced_shock" / "vibration_0.2.lvm"  # conftest: the one real-data setting

pytestmark = pytest.mark.skipif(not LVM.is_file(),
                                reason=f"real records not available: {LVM} is absent")


@pytest.fixture(scope="module")
def shock_store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The record ingested (flags kept) and fitted; ``(store, fit table)``."""
    store = tmp_path_factory.mktemp("shock") / "store.h5"
    proc = run_command("ingest", str(LVM), "--mapping", "forced_shock_lvm", "-o", str(store),
                   "--allow-flagged", "--quiet")
    assert proc.returncode == 0, proc.stderr
    proc = run_command("fit", str(store), "--quiet")
    assert proc.returncode == 0, proc.stderr
    return store, proc.stdout


def _pulse() -> tuple[int, int]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cmd = read(LVM, mapping=MAPPING).runs[0].channel("shock_command").read()
    return int(np.flatnonzero(cmd > 1e-3 * cmd.max())[0]), int(np.argmax(cmd))


def test_the_fit_table_lists_the_drive_as_the_cause_and_names_the_clocks(shock_store) -> None:
    _, table = shock_store
    rows = [line.strip() for line in table.splitlines() if line.startswith("    ")]
    lo, hi = _pulse()
    assert rows[0].startswith("cause    shock_command (drive_signal, clock A): "
                              f"onset sample {lo} ")
    assert f"peak sample {hi} " in rows[0]
    base = next(r for r in rows if r.startswith("response base (base_acceleration, clock B)"))
    assert "samples after the cause's onset sample (clock B against A: no delay in seconds" \
        in base
    assert " ms after the cause" not in table  # no time difference across the two clocks
    assert rows[-1].startswith("clocks: A 1650.17 Hz (shock_command, sine_command); "
                               "B 1706.48 Hz (composite_command, base, board); their rates "
                               "differ by 3.4 %")


def test_the_report_of_a_transient_store_shows_the_shocks(shock_store,
                                                          tmp_path: Path) -> None:
    store, _ = shock_store
    out = tmp_path / "shock.pdf"
    proc = run_command("report", str(store), "-o", str(out))
    assert proc.returncode == 0, proc.stderr
    reader = pypdf.PdfReader(out)
    texts = [" ".join(p.extract_text().split()) for p in reader.pages]
    assert len(texts) == 3  # summary, rig, the shock of the one run
    assert texts[0].startswith("rattle_lab report: transient records (shocks)")
    assert "fitted gap" not in texts[0] and "not fitted" not in texts[0]
    lo, hi = _pulse()
    for text in (texts[0], texts[2]):  # the summary and the shock page list every channel
        assert f"cause shock_command (drive_signal, clock A): onset sample {lo}" in text
        for name in ("sine_command", "composite_command", "base", "board"):
            assert f"response {name} (" in text
    shock = texts[2]
    assert "Shock of transient run" in shock and " - shocks - " in shock
    assert "time from the channel's own onset (ms, on its own clock)" in shock
    # one axes per channel, each a drawn waveform (path operators in the content stream)
    content = reader.pages[2].get_contents().get_data()
    assert content.count(b" l\n") > 500
