"""Assemble the report pages into one PDF, atomically and reproducibly."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from rattle_lab._atomic import atomic_path
from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError
from . import _content, _content_model, _content_runs, _pages, _pages_acoustics, _pages_model
from ._common import text_pages, wrapped
from ._content import ReportContent, build_content
from ._data import ReportData, gather

#: Sections in page order: (name, content builder, page renderer).  The summary page comes
#: first.  The builder computes the page's content from the gathered data (or raises
#: ``Missing``); the renderer only draws it.
SECTIONS: tuple[tuple[str, Callable[..., Any], Callable[[Any], list[Figure]]], ...] = (
    ("rig and calibration", _content.rig_content, _pages.rig_page),
    ("thresholds", _content.threshold_content, _pages.threshold_page),
    ("impact patterns", _content.pattern_content, _pages.pattern_page),
    ("waveforms", _content_runs.waveform_content, _pages.waveform_page),
    ("SPL law", _content.spl_content, _pages.spl_page),
    ("acoustics", _content_runs.acoustics_content, _pages_acoustics.acoustics_page),
    ("model predictions", _content_model.model_content, _pages_model.model_pages),
)


@dataclass(frozen=True)
class ReportResult:
    """What :func:`write_report` wrote.

    Attributes
    ----------
    path : Path
        The PDF.
    n_pages : int
        Pages in it (summary included).
    sections : tuple of str
        Sections present, in page order.
    missing : dict of str to str
        Sections (or parts) left out, with the reason (also on the summary page).
    """

    path: Path
    n_pages: int
    sections: tuple[str, ...]
    missing: dict[str, str]


def write_report(store: str | os.PathLike[str], output: str | os.PathLike[str], *,
                 model: bool = True, quiet: bool = True) -> ReportResult:
    """Write the multi-page PDF report of an ingest store (after ``rattle-lab fit``).

    Each section is drawn only if its data exist; otherwise the summary page
    says which section is missing and why.  The same store gives the same
    bytes (fixed PDF dates, no wall-clock time in the content).

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
    ReportResult

    Raises
    ------
    StoreError
        If ``store`` does not exist or is not an ingest store.
    ParameterError
        If ``output`` does not end in ``.pdf``.
    OutputError
        If the output directory does not exist or the file cannot be written.
    """
    import matplotlib
    from matplotlib.backends.backend_pdf import PdfPages

    output = Path(output)
    if output.suffix.lower() != ".pdf":
        raise ParameterError(f"`output` must end in .pdf, was {str(output)!r}")
    data = gather(store)
    content = build_report_content(data, model=model, quiet=quiet)
    all_pages, sections = render_pages(content)
    n = len(all_pages)
    # Fixed metadata (no dates) and fixed hash salt: identical bytes for the same store.
    metadata = {"Title": f"rattle_lab report: {data.store.name}", "Creator": "rattle_lab",
                "Subject": "sections: " + ", ".join(sections),
                "CreationDate": None, "ModDate": None}
    with matplotlib.rc_context({"pdf.fonttype": 42, "svg.hashsalt": "rattle_lab"}):
        with atomic_path(output) as tmp:
            with PdfPages(tmp, metadata=metadata) as pdf:  # type: ignore[arg-type]
                for _, fig in all_pages:
                    pdf.savefig(fig)
    return ReportResult(output, n, sections, dict(content.missing))


def build_report_content(data: ReportData, *, model: bool = True, quiet: bool = True
                         ) -> ReportContent:
    """Compute what every page shows (:func:`._content.build_content` over :data:`SECTIONS`).

    Parameters
    ----------
    data : ReportData
        From :func:`gather` (not modified).
    model : bool
        Include the model predictions.
    quiet : bool
        No progress bar.
    """
    builders = tuple((name, build) for name, build, _ in SECTIONS)
    return build_content(data, builders, model=model, quiet=quiet, version=__version__)


def render_pages(content: ReportContent) -> tuple[list[tuple[str, Figure]], tuple[str, ...]]:
    """Draw every page of ``content``, in order and numbered; nothing is computed here.

    Returns
    -------
    pages : list of (str, Figure)
        Section name and figure of each page; each page carries its footer
        ("Page i of n - section - store").
    sections : tuple of str
        The sections present, ``"summary"`` first.
    """
    renderers = {name: render for name, _, render in SECTIONS}
    pages: list[tuple[str, Figure]] = []
    for name, page_content in content.sections:
        pages.extend((name, fig) for fig in renderers[name](page_content))
    sections = [name for name, _ in content.sections]
    lines = list(content.summary_lines)
    lines += ["", "Sections"]
    lines += wrapped("  included: summary, " + ", ".join(sections))
    for name, why in content.missing.items():
        lines += wrapped(f"  missing: {name}: {why}")
    summary = text_pages("rattle_lab report: fitted gap, zeta, f_s, e and SPL law", lines)
    all_pages = [*(("summary", fig) for fig in summary), *pages]
    n = len(all_pages)
    store_name = content.data.store.name
    for i, (name, fig) in enumerate(all_pages, start=1):
        fig.text(0.5, 0.008, f"Page {i} of {n}  -  {name}  -  {store_name}", ha="center",
                 va="bottom", fontsize=7, color="0.3")
    return all_pages, ("summary", *sections)


def build_pages(data: ReportData, *, model: bool = True, quiet: bool = True
                ) -> tuple[list[tuple[str, Figure]], tuple[str, ...]]:
    """Every page of the report, in order and numbered, and the sections present.

    :func:`build_report_content` then :func:`render_pages`; sections whose data are
    missing are left out and listed, with the reason, on the summary page.

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
