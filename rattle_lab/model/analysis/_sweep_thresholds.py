"""Impact onset and disappearance of a slow F sweep up and back down (the model's ramp)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams

from ._sweep import sweep_up_down


@dataclass(frozen=True)
class SweepThresholds:
    """Forcing amplitudes at which a slow F sweep starts and stops impacting.

    Attributes
    ----------
    onset_F : float
        Nondimensional ``F`` of the first impacts on the way up (NaN: none on the grid).
    disappearance_F : float
        ``F`` below which the impacts stop on the way back down (NaN: none on the grid).
    step_F : float
        The grid step: each threshold is the midpoint of the step below the first
        amplitude with impacts, so it is known to within ``+/- step_F / 2``.
    """

    onset_F: float
    disappearance_F: float
    step_F: float


def sweep_thresholds(omega: float, F_grid: npt.ArrayLike, *, zeta: float, e: float,
                     cycles: int = 60, discard: int = 40, n_max: int = 6) -> SweepThresholds:
    """Onset and disappearance of impacts in an F sweep up and back down at fixed ``omega``.

    The model's counterpart of a measured amplitude ramp: :func:`sweep_up_down` over
    ``F_grid`` (ascending, evenly spaced), ``cycles`` forcing periods per amplitude of
    which ``discard`` are transients, no Lyapunov exponents.  A threshold lies within
    one step below the lowest amplitude with impacts; it is reported as the middle of
    that step.

    Parameters
    ----------
    omega : float
        Nondimensional forcing frequency ``f / f_s`` (eq. 2.28).
    F_grid : array_like
        Nondimensional forcing amplitudes, ascending, at least one.
    zeta, e : float
        Damping ratio and coefficient of restitution.
    cycles, discard, n_max : int
        As for :func:`rattle_lab.model.analysis.sweep`.

    Returns
    -------
    SweepThresholds

    Raises
    ------
    ParameterError
        If ``F_grid`` is empty.
    """
    grid = np.asarray(F_grid, dtype=float)
    if grid.size == 0:
        raise ParameterError("`F_grid` must hold at least one amplitude")
    step = float(grid[1] - grid[0]) if grid.size > 1 else float(grid[0])
    s_up, s_dn = sweep_up_down("F", grid, base=SDFParams(F=grid[0], omega=omega, zeta=zeta, e=e),
                               cycles=cycles, discard=discard, n_max=n_max, lyapunov="none",
                               quiet=True)
    hit_up = [p.value for p in s_up.points if p.impact_velocities.size]
    hit_dn = [p.value for p in s_dn.points if p.impact_velocities.size]
    on_F = min(hit_up) - step / 2 if hit_up else np.nan
    off_F = min(hit_dn) - step / 2 if hit_dn else np.nan
    return SweepThresholds(float(on_F), float(off_F), step)
