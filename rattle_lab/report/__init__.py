"""The PDF report of an ingest store (``rattle-lab report store.h5 -o report.pdf``).

Pages: a summary (fitted gap, zeta, f_s, e, SPL law with uncertainties;
data-quality flags; provenance; missing sections and why), the rig and
calibration table, the thresholds with the eq. (3.4) fit (thesis Fig. 6-2,
6-3), the impact-pattern map (Fig. 6-5), example waveforms (Fig. 6-4, 6-6),
the SPL law (Fig. 6-7) and model predictions at the fitted parameters.

Three steps: :func:`gather` reads the store, :func:`build_report_content` computes
what each page shows (calling :mod:`rattle_lab.fit`, :mod:`rattle_lab.model` and
:mod:`rattle_lab.detect`), :func:`render_pages` draws it; the page modules compute
nothing.
"""

from ._build import (SECTIONS, ReportResult, build_pages, build_report_content, render_pages,
                     write_report)
from ._content import ReportContent
from ._data import ReportData, gather

__all__ = ["write_report", "build_pages", "ReportResult", "ReportData", "gather", "SECTIONS",
           "ReportContent", "build_report_content", "render_pages"]
