"""Analysis of the nondimensional SDF impact oscillator: periodic orbits and bifurcation sets.

* :mod:`rattle_lab.analysis.orbits`: closed-form 1/n orbits (thesis 3.1-3.3),
  their existence and Floquet multipliers; m/n orbits by Newton shooting.
* :mod:`rattle_lab.analysis.bifsets`: regions of existence and stability of
  the 1/n orbits in the (omega, F) plane with their boundary curves (thesis
  3.3, Fig. 3-7, 3-9, 3-10).
"""

from .bifsets import BifurcationSets, BoundaryCurve, bifurcation_sets, plot_bifurcation_sets
from .orbits import (
    BranchEvent,
    OneOverNOrbit,
    PeriodicOrbit,
    branch_events,
    find_periodic_orbit,
    floquet_multipliers,
    grazing_forcing,
    impact_map,
    impact_quadratic,
    impact_velocities,
    one_over_n_orbits,
    orbit_clearance,
    orbit_forcing,
    periodic_orbit_from_impacts,
    saddle_node_forcing,
)

__all__ = [
    "OneOverNOrbit",
    "BranchEvent",
    "PeriodicOrbit",
    "BifurcationSets",
    "BoundaryCurve",
    "one_over_n_orbits",
    "impact_quadratic",
    "impact_velocities",
    "orbit_forcing",
    "floquet_multipliers",
    "orbit_clearance",
    "grazing_forcing",
    "saddle_node_forcing",
    "branch_events",
    "impact_map",
    "find_periodic_orbit",
    "periodic_orbit_from_impacts",
    "bifurcation_sets",
    "plot_bifurcation_sets",
]
