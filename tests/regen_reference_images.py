"""Regenerate the report's reference images (``tests/data/report_pages``), explicitly.

Run after an intended change to a report page, then look at the images and commit them::

    make reference-images        # or: .venv/bin/python tests/regen_reference_images.py

It builds the report exactly as the tests do (:mod:`report_fixture`: the default scene,
ingested and fitted with default settings), writes its content as the snapshot the image
tests draw (:data:`report_images.CONTENT_SNAPSHOT`) and each page's drawn structure
(:func:`report_images.structure_rasters`).  The tests only compare; none writes a reference.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from report_fixture import build_stores  # noqa: E402
from report_images import (  # noqa: E402
    REF_DIR,
    save_content_snapshot,
    save_references,
    structure_rasters,
)

from rattle_lab.report import write_pdf  # noqa: E402
from rattle_lab.rig import write_synthetic  # noqa: E402
from rattle_lab.workflow import build_report_content, gather  # noqa: E402


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        record = folder / "campaign.h5"
        write_synthetic("default", record, quiet=True)
        stores = build_stores(record, folder)
        content = build_report_content(gather(stores["fitted"]), model=True)
        save_content_snapshot(content)
        result = write_pdf(content, folder / "report.pdf")
        paths = save_references(structure_rasters(result.path))
    print(f"{len(paths)} reference images and the content snapshot written to {REF_DIR}; "
          "look at them before committing")
    return 0


if __name__ == "__main__":
    sys.exit(main())
