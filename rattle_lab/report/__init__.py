"""The PDF report of an ingest store (``rattle-lab report store.h5 -o report.pdf``).

Pages: a summary (fitted gap, zeta, f_s, e, SPL law with uncertainties;
data-quality flags; provenance; missing sections and why), the rig and
calibration table, the thresholds with the eq. (3.4) fit (thesis Fig. 6-2,
6-3), the impact-pattern map (Fig. 6-5), example waveforms (Fig. 6-4, 6-6),
the SPL law (Fig. 6-7) and model predictions at the fitted parameters.
"""

from ._build import SECTIONS, ReportResult, build_pages, write_report
from ._data import ReportData, gather

__all__ = ["write_report", "build_pages", "ReportResult", "ReportData", "gather", "SECTIONS"]
