"""Regenerate the report's reference images (``tests/data/report_pages``), explicitly.

Run after an intended change to a report page, then look at the images and commit them::

    make reference-images        # or: .venv/bin/python tests/regen_reference_images.py

It builds the report exactly as the tests do (:mod:`report_fixture`: the default scene,
ingested and fitted with default settings) and writes each page's drawn structure
(:func:`report_images.structure_rasters`).  The tests only compare; none writes a reference.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from report_fixture import build_report, build_stores  # noqa: E402
from report_images import REF_DIR, save_references, structure_rasters  # noqa: E402

from rattle_lab.rig import write_synthetic  # noqa: E402


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        record = folder / "campaign.h5"
        write_synthetic("default", record, quiet=True)
        stores = build_stores(record, folder)
        result = build_report(stores["fitted"], folder / "report.pdf")
        paths = save_references(structure_rasters(result.path))
    print(f"{len(paths)} reference images written to {REF_DIR}; look at them before committing")
    return 0


if __name__ == "__main__":
    sys.exit(main())
