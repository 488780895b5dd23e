"""The report's computing half: gather a store, compute each page's content, render it.

:func:`gather` reads the store (:class:`ReportData`), :func:`build_report_content` calls
the functions that own each computation (:mod:`rattle_lab.fit`, :mod:`rattle_lab.detect`,
:mod:`rattle_lab.acoustics`, :mod:`rattle_lab.model`; the model pages' simulations run
here) and returns the frozen :class:`rattle_lab.report.ReportContent`, which
:mod:`rattle_lab.report` draws.
"""

from ._build import SECTIONS, build_pages, build_report_content, write_report
from ._content import Missing
from ._gather import ReportData, gather
from ._summary import shock_lines

__all__ = ["write_report", "build_report_content", "build_pages", "gather", "ReportData",
           "SECTIONS", "Missing", "shock_lines"]
