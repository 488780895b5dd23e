"""Sphinx configuration of the rattle_lab guide and API reference (``make docs``)."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # document the checkout, installed or not
sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))  # the rattle-lab-help directive

from rattle_lab import __version__  # noqa: E402

project = "rattle_lab"
author = "rattle_lab developers"
copyright = "rattle_lab developers, MIT licence"  # noqa: A001
version = release = __version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "myst_parser",  # the guide's pages are Markdown
    "clihelp",  # ``rattle-lab-help``: a command's --help, from the parser itself
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
# headings get anchors (``page.md#a-heading``) down to level 3
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
# the ``:members:`` of a package are the names its ``__all__`` lists
exclude_patterns = ["_build", "_ext"]
nitpicky = False
html_theme = "alabaster"
html_static_path: list[str] = []


def _schema_links_as_text(app: object, relative_path: object, parent_docname: str,
                          content: list[str]) -> None:
    """In the included ``data_schema/README.md``, links to its neighbouring files become text.

    They point at files beside it in the source tree (the JSON Schema, ``mappings/``), which
    are not pages of this guide; the text keeps their names.
    """
    import re

    if str(relative_path).replace("\\", "/").endswith("data_schema/README.md"):
        content[0] = re.sub(r"\[([^\]]+)\]\((?!https?:)[^)#]+\)", r"\1", content[0])


def setup(app) -> None:  # type: ignore[no-untyped-def]
    app.connect("include-read", _schema_links_as_text)
