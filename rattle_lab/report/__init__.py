"""The PDF report: draws a computed :class:`ReportContent`, page by page, into one PDF.

Pages: a summary (fitted gap, zeta, f_s, e, SPL law with uncertainties;
data-quality flags; provenance; missing sections and why), the rig and
calibration table, the thresholds with the eq. (3.4) fit (thesis Fig. 6-2,
6-3), the impact-pattern map (Fig. 6-5), example waveforms (Fig. 6-4, 6-6),
the SPL law (Fig. 6-7) and model predictions at the fitted parameters.

The report renders what it is given and computes nothing: :func:`render_pages` draws
the content's pages and :func:`write_pdf` writes them atomically.  The content, frozen
plain data (``_content_types``), is computed from a store by
:func:`rattle_lab.workflow.build_report_content`; ``rattle-lab report`` and
:func:`rattle_lab.workflow.write_report` do both.  The package imports only the drawing
libraries, :mod:`rattle_lab.plot`'s styles and its own types (a test pins that).
"""

from ._content_types import ReportContent
from ._render import PAGES, ReportResult, render_pages, write_pdf

__all__ = ["write_pdf", "render_pages", "ReportResult", "ReportContent", "PAGES"]
