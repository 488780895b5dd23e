"""Analysis of the nondimensional SDF impact oscillator: periodic orbits and bifurcation sets.

* :mod:`rattle_lab.model.analysis.orbits`: closed-form 1/n orbits (thesis 3.1-3.3),
  their existence and Floquet multipliers; m/n orbits by Newton shooting.
* :mod:`rattle_lab.model.analysis.bifsets`: regions of existence and stability of
  the 1/n orbits in the (omega, F) plane with their boundary curves (thesis
  3.3, Fig. 3-7, 3-9, 3-10).
* :mod:`rattle_lab.model.analysis.sweep`: slow parameter sweeps with the state
  carried over, regime classification (thesis 4.2-4.3, Fig. 4-3 to 4-5).
* :mod:`rattle_lab.model.analysis.lyapunov`: the largest Lyapunov exponent, exactly
  from the impact log (transition and saltation matrices).
* :mod:`rattle_lab.model.analysis.maps`: regime maps, basins of attraction and the
  disturbance study (thesis 4.3.3, Fig. 4-7), run serially or through Dask.
"""

from ._disturbance import DisturbanceMap, disturbance_map, disturbance_threshold
from ._sweep import (
    LYAPUNOV_MODES,
    SWEEP_PARAMS,
    Regime,
    Sweep,
    SweepPoint,
    classify_impacts,
    sweep,
    sweep_up_down,
    sweep_values,
    write_sweeps_csv,
)
from ._sweep_thresholds import SweepThresholds, sweep_thresholds
from .bifsets import BifurcationSets, BoundaryCurve, bifurcation_sets
from .lyapunov import LyapunovResult, lyapunov_exponent, lyapunov_from_result, tangent_log_growth
from .maps import AttractorMap, basin_map, regime_map
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
    "Regime",
    "SweepPoint",
    "Sweep",
    "LyapunovResult",
    "AttractorMap",
    "DisturbanceMap",
    "classify_impacts",
    "sweep_values",
    "sweep",
    "sweep_up_down",
    "write_sweeps_csv",
    "lyapunov_exponent",
    "lyapunov_from_result",
    "tangent_log_growth",
    "regime_map",
    "basin_map",
    "disturbance_threshold",
    "disturbance_map",
    "SweepThresholds",
    "sweep_thresholds",
    "SWEEP_PARAMS",
    "LYAPUNOV_MODES",
]
