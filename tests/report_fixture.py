"""The report the report tests look at, built the same way by the tests and by the
regeneration of the reference images (``tests/regen_reference_images.py``).

The default scene's record is ingested into a bare store, a copy is fitted
(:func:`rattle_lab.workflow.fit_store`, default settings) and the fitted store's full report
(model pages included) is written.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from rattle_lab.report import ReportResult
from rattle_lab.store import ingest
from rattle_lab.workflow import fit_store, write_report


def build_stores(record: Path, folder: Path) -> dict[str, Path]:
    """``{"bare": ingest-only store, "fitted": the same store fitted}`` in ``folder``."""
    bare = folder / "bare.h5"
    ingest([record], bare)
    fitted = folder / "fitted.h5"
    shutil.copyfile(bare, fitted)
    fit_store(fitted, quiet=True)
    return {"bare": bare, "fitted": fitted}


def build_report(fitted: Path, out: Path) -> ReportResult:
    """The full report of the fitted store (model pages included)."""
    return write_report(fitted, out)
