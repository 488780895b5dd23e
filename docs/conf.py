"""Sphinx configuration of the rattle_lab API reference (``make docs``)."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # document the checkout, installed or not

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
]
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_typehints_format = "short"
# the ``:members:`` of a package are the names its ``__all__`` lists
exclude_patterns = ["_build"]
nitpicky = False
html_theme = "alabaster"
html_static_path: list[str] = []
