"""Figure paths and atomic writing, shared by every plot."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rattle_lab._atomic import atomic_path
from rattle_lab.exceptions import OutputError, ParameterError

if TYPE_CHECKING:
    from matplotlib.figure import Figure


FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def check_figure_path(path: str | os.PathLike[str]) -> Path:
    """Check a figure's output path before any work is done; the format follows the suffix.

    Raises
    ------
    ParameterError
        If the suffix is not ``.png``, ``.pdf`` or ``.svg``.
    OutputError
        If the output directory does not exist.
    """
    p = Path(path)
    if p.suffix.lower() not in FIGURE_SUFFIXES:
        raise ParameterError(f"plot file {str(p)!r} must end in .png, .pdf or .svg")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"plot file {str(p)!r}: output directory {parent} does not exist")
    return p


def save_figure(fig: Figure, path: str | os.PathLike[str], *, dpi: float | None = None) -> Path:
    """Write ``fig`` atomically to ``path`` (format from the suffix; ``dpi`` for raster output)."""
    p = check_figure_path(path)
    fmt = p.suffix.lower().lstrip(".")
    kwargs: dict[str, Any] = {} if dpi is None else {"dpi": dpi}
    with atomic_path(p) as tmp:
        fig.savefig(tmp, format=fmt, metadata={"CreationDate": None} if fmt == "pdf" else None,
                    **kwargs)
    return p
