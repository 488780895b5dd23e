"""Shared drawing helpers of the report pages: page sizes, number format, tables, text pages."""

from __future__ import annotations

import math
import textwrap
from typing import Any

from matplotlib.figure import Figure

PAGE_SIZE_IN = (8.27, 11.69)  # A4 portrait
LANDSCAPE_IN = (11.69, 8.27)

#: Characters per line of the monospaced text pages (7.5 pt DejaVu Sans Mono on A4 portrait).
TEXT_WIDTH = 112


def landscape_figure() -> Figure:
    """An A4 landscape figure, constrained layout, with the bottom 2.5 % kept for the footer."""
    fig = Figure(figsize=LANDSCAPE_IN, layout="constrained")
    fig.get_layout_engine().set(rect=(0.0, 0.025, 1.0, 0.975))  # type: ignore[union-attr, call-arg]
    return fig


def fmt(x: Any, digits: str = ".4g") -> str:
    """``x`` formatted with ``digits``; ``"-"`` for None or a non-finite number."""
    if x is None:
        return "-"
    try:
        xf = float(x)
    except (TypeError, ValueError):
        return str(x)
    return "-" if not math.isfinite(xf) else format(xf, digits)


def table(ax: Any, rows: list[list[str]], cols: list[str], fontsize: float, *,
          fill_width: bool = False, row_scale: float = 1.35) -> None:
    """A table with a bold, shaded header row, at the top left of ``ax``.

    ``fill_width``: the columns span the axes' width, each in proportion to its longest
    entry (else each is as wide as its text).
    """
    widths = None
    if fill_width:
        longest = [max(len(str(x)) for x in [c, *(r[k] for r in rows)]) + 2
                   for k, c in enumerate(cols)]
        widths = [n / sum(longest) for n in longest]
    tab = ax.table(cellText=rows, colLabels=cols, loc="upper left", cellLoc="left",
                   colLoc="left", colWidths=widths)
    tab.auto_set_font_size(False)
    tab.set_fontsize(fontsize)
    if widths is None:
        tab.auto_set_column_width(list(range(len(cols))))
    tab.scale(1.0, row_scale)
    for (r, _), cell in tab.get_celld().items():
        if r == 0:
            cell.set_text_props(weight="bold")
            cell.set_facecolor("0.92")


def wrapped(line: str) -> list[str]:
    """``line`` wrapped to :data:`TEXT_WIDTH` characters, continuation lines indented."""
    if len(line) <= TEXT_WIDTH:
        return [line]
    indent = " " * (len(line) - len(line.lstrip()) + 4)
    return textwrap.wrap(line, TEXT_WIDTH, subsequent_indent=indent, break_long_words=True)


def text_pages(title: str, lines: list[str]) -> list[Figure]:
    """Pages of monospaced text (continued on further pages when long)."""
    per_page = 56
    chunks = [lines[i:i + per_page] for i in range(0, max(len(lines), 1), per_page)] or [[]]
    figs = []
    for k, chunk in enumerate(chunks):
        fig = Figure(figsize=PAGE_SIZE_IN)
        fig.text(0.06, 0.96, title + (" (continued)" if k else ""), fontsize=14,
                 weight="bold", va="top")
        y = 0.925
        for line in chunk:
            fig.text(0.06, y, line, fontsize=7.5, family="monospace", va="top")
            y -= 0.0155
        figs.append(fig)
    return figs


def text_page(title: str, lines: list[str]) -> Figure:
    """A page of monospaced text (the first page of :func:`text_pages`)."""
    return text_pages(title, lines)[0]
