"""The explorer: the thesis's Java applet (Appendix A, section 4.1.3) rebuilt with matplotlib.

* :mod:`rattle_lab.explorer._histories`: pure data: time histories split into
  forced and transient parts, impacts, CSV/HDF5 output with units.
* :mod:`rattle_lab.explorer._window`: :class:`Explorer`, the window and its
  widgets; runs headless (Agg) for tests and scripts.

``rattle-lab explore`` opens it (:mod:`rattle_lab.cli._explore`).
"""

from ._histories import (
    DATA_SUFFIXES,
    HISTORY_COLUMNS,
    IMPACT_COLUMNS,
    Histories,
    compute_histories,
    impacts_path,
    save_histories,
)
from ._window import DEFAULT_SAVE_PATH, Explorer, display_available

__all__ = [
    "Explorer",
    "Histories",
    "compute_histories",
    "save_histories",
    "impacts_path",
    "display_available",
    "HISTORY_COLUMNS",
    "IMPACT_COLUMNS",
    "DATA_SUFFIXES",
    "DEFAULT_SAVE_PATH",
]
