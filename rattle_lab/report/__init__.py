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

from ._common import TEXT_WIDTH, fmt, wrapped
from ._content_types import (WAVEFORM_QUANTITIES, AcousticsContent, ChannelInfo, Field, GrazingCurve,
                             ListenerMetrics, ModelContent, PatternContent, RecordInfo, ReportContent, RigContent,
                             ShockContent, ShockRun, ShockTrace, SplContent, SplCurve,
                             SweepComparison, ThresholdContent, Trace, WaveformColumn,
                             WaveformContent)
from ._render import PAGES, ReportResult, pdf_output, render_pages, write_pdf

__all__ = ["write_pdf", "render_pages", "ReportResult", "ReportContent", "PAGES",
           # the content's parts, filled by rattle_lab.workflow
           "RigContent", "RecordInfo", "ChannelInfo", "ThresholdContent", "GrazingCurve",
           "PatternContent", "SplContent", "SplCurve", "WaveformContent", "WaveformColumn",
           "Trace", "WAVEFORM_QUANTITIES", "AcousticsContent", "ListenerMetrics", "ModelContent", "SweepComparison",
           "Field", "ShockContent", "ShockRun", "ShockTrace",
           # text layout of the report's pages, and the checked output path
           "TEXT_WIDTH", "fmt", "wrapped", "pdf_output"]
