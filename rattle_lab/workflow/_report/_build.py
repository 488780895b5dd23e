"""The report of a store: gather, compute each page's content, and hand it to the renderer."""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from matplotlib.figure import Figure

from rattle_lab._version import __version__
from rattle_lab.report import (PAGES, ReportContent, ReportResult, pdf_output, render_pages,
                               write_pdf)
from . import _content, _content_model, _content_runs, _shocks
from ._content import build_content
from ._gather import ReportData, gather

_BUILDERS: dict[str, Callable[..., Any]] = {
    "rig and calibration": _content.rig_content,
    "shocks": _shocks.shock_content,
    "thresholds": _content.threshold_content,
    "impact patterns": _content.pattern_content,
    "waveforms": _content_runs.waveform_content,
    "SPL law": _content.spl_content,
    "acoustics": _content_runs.acoustics_content,
    "model predictions": _content_model.model_content,
}

#: Sections in page order: (name, content builder, page renderer), the report's
#: :data:`rattle_lab.report.PAGES` with the builder of each.  The summary page comes first.
#: The builder computes the page's content from the gathered data (or raises ``Missing``);
#: the renderer only draws it.
SECTIONS: tuple[tuple[str, Callable[..., Any], Callable[[Any], list[Figure]]], ...] = tuple(
    (name, _BUILDERS[name], render) for name, render in PAGES)


def write_report(store: str | os.PathLike[str], output: str | os.PathLike[str], *,
                 model: bool = True, quiet: bool = True) -> ReportResult:
    """Write the multi-page PDF report of an ingest store (after ``rattle-lab fit``).

    :func:`gather`, :func:`build_report_content`, then
    :func:`rattle_lab.report.write_pdf`.  Each section is drawn only if its data
    exist; otherwise the summary page says which section is missing and why.  The
    same store gives the same bytes (fixed PDF dates, no wall-clock time in the
    content).

    Parameters
    ----------
    store : path-like
        An ingest store, with or without ``/results``.
    output : path-like
        The PDF to write (``.pdf``); written atomically.
    model : bool
        Include the model predictions (bifurcation sets and sweeps at the fitted
        parameters; a few seconds).
    quiet : bool
        No progress bar (one is drawn on a terminal for the model sweeps otherwise).

    Returns
    -------
    rattle_lab.report.ReportResult

    Raises
    ------
    StoreError
        If ``store`` does not exist or is not an ingest store.
    ParameterError
        If ``output`` does not end in ``.pdf`` (checked before the store is read).
    OutputError
        If the output directory does not exist or the file cannot be written.
    """
    output = pdf_output(output)
    content = build_report_content(gather(store), model=model, quiet=quiet)
    return write_pdf(content, output)


def build_report_content(data: ReportData, *, model: bool = True, quiet: bool = True
                         ) -> ReportContent:
    """Compute what every page shows, section by section of :data:`SECTIONS`.

    Parameters
    ----------
    data : ReportData
        From :func:`gather` (not modified).
    model : bool
        Include the model predictions (the bifurcation sets and sweeps are computed here).
    quiet : bool
        No progress bar.

    Returns
    -------
    rattle_lab.report.ReportContent
        Frozen; :func:`rattle_lab.report.render_pages` draws it.
    """
    builders = tuple((name, build) for name, build, _ in SECTIONS)
    return build_content(data, builders, model=model, quiet=quiet, version=__version__)


def build_pages(data: ReportData, *, model: bool = True, quiet: bool = True
                ) -> tuple[list[tuple[str, Figure]], tuple[str, ...]]:
    """Every page of the report, in order and numbered, and the sections present.

    :func:`build_report_content` then :func:`rattle_lab.report.render_pages`; sections
    whose data are missing are left out and listed, with the reason, on the summary page.

    Parameters
    ----------
    data : ReportData
        From :func:`gather` (not modified).
    model : bool
        Include the model predictions.
    quiet : bool
        No progress bar.

    Returns
    -------
    pages : list of (str, Figure)
        Section name and figure of each page.
    sections : tuple of str
        The sections present, ``"summary"`` first.
    """
    return render_pages(build_report_content(data, model=model, quiet=quiet))
