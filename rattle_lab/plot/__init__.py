"""Plots (matplotlib, Agg, no pyplot state) with labelled axes and units, written atomically.

The plot layer draws what the model and the fit computed; it computes nothing itself.
"""

from ._bifsets import BIFURCATION_LINESTYLES, plot_bifurcation_sets, smooth_region
from ._guides import db_slope_guide, power_law_guide
from ._figures import FIGURE_SUFFIXES, check_figure_path, save_figure
from ._maps import plot_attractor_map, plot_disturbance_map
from ._sweeps import plot_sweeps
from ._time_history import plot_time_history

__all__ = ["FIGURE_SUFFIXES", "check_figure_path", "save_figure", "plot_time_history",
           "plot_sweeps", "plot_bifurcation_sets", "plot_attractor_map", "plot_disturbance_map",
           "smooth_region", "db_slope_guide", "power_law_guide", "BIFURCATION_LINESTYLES"]
