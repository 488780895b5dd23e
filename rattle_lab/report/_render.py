"""Draw a :class:`ReportContent` page by page and write it as one PDF, atomically, reproducibly."""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from rattle_lab._atomic import atomic_path
from rattle_lab.exceptions import ParameterError
from . import _pages, _pages_acoustics, _pages_model, _pages_shocks
from ._common import text_pages, wrapped
from ._content_types import ReportContent

#: Sections in page order after the summary: (name, page renderer).  The renderer takes the
#: section's content (:mod:`._content_types`) and returns its figures; it only draws.
PAGES: tuple[tuple[str, Callable[[Any], list[Figure]]], ...] = (
    ("rig and calibration", _pages.rig_page),
    ("shocks", _pages_shocks.shock_pages),
    ("thresholds", _pages.threshold_page),
    ("impact patterns", _pages.pattern_page),
    ("waveforms", _pages.waveform_page),
    ("SPL law", _pages.spl_page),
    ("acoustics", _pages_acoustics.acoustics_page),
    ("model predictions", _pages_model.model_pages),
)


@dataclass(frozen=True)
class ReportResult:
    """What :func:`write_pdf` (and :func:`rattle_lab.workflow.write_report`) wrote.

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


def pdf_output(output: str | os.PathLike[str]) -> Path:
    """``output`` as a path, checked to end in ``.pdf``.

    Raises
    ------
    ParameterError
        If it does not.
    """
    output = Path(output)
    if output.suffix.lower() != ".pdf":
        raise ParameterError(f"`output` must end in .pdf, was {str(output)!r}")
    return output


def render_pages(content: ReportContent) -> tuple[list[tuple[str, Figure]], tuple[str, ...]]:
    """Draw every page of ``content``, in order and numbered; nothing is computed here.

    The pages are laid out for Matplotlib's default style, so they are drawn in it, whatever
    the session's ``rcParams`` say (a user's ``matplotlibrc``, or a package that changes the
    font sizes when imported).

    Returns
    -------
    pages : list of (str, Figure)
        Section name and figure of each page; each page carries its footer
        ("Page i of n - section - store").
    sections : tuple of str
        The sections present, ``"summary"`` first.
    """
    import matplotlib.style

    with matplotlib.style.context("default"):
        return _render_pages(content)


def _render_pages(content: ReportContent) -> tuple[list[tuple[str, Figure]], tuple[str, ...]]:
    renderers = dict(PAGES)
    pages: list[tuple[str, Figure]] = []
    for name, page_content in content.sections:
        pages.extend((name, fig) for fig in renderers[name](page_content))
    sections = [name for name, _ in content.sections]
    lines = list(content.summary_lines)
    lines += ["", "Sections"]
    lines += wrapped("  included: summary, " + ", ".join(sections))
    for name, why in content.missing.items():
        lines += wrapped(f"  missing: {name}: {why}")
    summary = text_pages(content.title, lines)
    all_pages = [*(("summary", fig) for fig in summary), *pages]
    n = len(all_pages)
    for i, (name, fig) in enumerate(all_pages, start=1):
        fig.text(0.5, 0.008, f"Page {i} of {n}  -  {name}  -  {content.store_name}",
                 ha="center", va="bottom", fontsize=7, color="0.3")
    return all_pages, ("summary", *sections)


def write_pdf(content: ReportContent, output: str | os.PathLike[str]) -> ReportResult:
    """Draw ``content`` (:func:`render_pages`) into one PDF, written atomically.

    The same content gives the same bytes: the PDF has no dates and a fixed hash
    salt.

    Parameters
    ----------
    content : ReportContent
        What to draw (:func:`rattle_lab.workflow.build_report_content` computes it from a
        store).
    output : path-like
        The PDF to write (``.pdf``).

    Returns
    -------
    ReportResult

    Raises
    ------
    ParameterError
        If ``output`` does not end in ``.pdf``.
    OutputError
        If the output directory does not exist or the file cannot be written.
    """
    import matplotlib
    import matplotlib.style
    from matplotlib.backends.backend_pdf import PdfPages

    output = pdf_output(output)
    all_pages, sections = render_pages(content)
    n = len(all_pages)
    # Fixed metadata (no dates) and fixed hash salt: identical bytes for the same content.
    metadata = {"Title": f"rattle_lab report: {content.store_name}", "Creator": "rattle_lab",
                "Subject": "sections: " + ", ".join(sections),
                "CreationDate": None, "ModDate": None}
    with matplotlib.style.context("default"), \
            matplotlib.rc_context({"pdf.fonttype": 42, "svg.hashsalt": "rattle_lab"}):
        with atomic_path(output) as tmp:
            with PdfPages(tmp, metadata=metadata) as pdf:  # type: ignore[arg-type]
                for _, fig in all_pages:
                    pdf.savefig(fig)
    return ReportResult(output, n, sections, dict(content.missing))
