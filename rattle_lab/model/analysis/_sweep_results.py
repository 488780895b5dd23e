"""What a slow sweep records (:class:`SweepPoint`, :class:`Sweep`) and its CSV form.

The sweep itself is :func:`rattle_lab.model.analysis.sweep`; these are its frozen
results (all nondimensional) with their JSON-ready ``to_dict`` and
:func:`write_sweeps_csv`.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from rattle_lab.model.sdf import SDFParams, SDFState

from ._periods import Regime
from .lyapunov import LyapunovResult

SweepParam = Literal["omega", "F", "e", "gap"]
Direction = Literal["up", "down"]

__all__ = ["SweepParam", "Direction", "SweepPoint", "Sweep", "CSV_COLUMNS", "write_sweeps_csv"]


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------

def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


@dataclass(frozen=True)
class SweepPoint:
    """What a sweep records at one parameter value (all nondimensional).

    Attributes
    ----------
    value : float
        The swept parameter's value (for ``"gap"``: ``1/F``).
    params : SDFParams
        The full parameter set simulated.
    impact_velocities : ndarray
        Incoming velocity ``v_im`` of every impact in the kept periods.
    impact_phases : ndarray
        Forcing phase at those impacts, in ``[0, 2 pi)``.
    crossing_velocities : ndarray
        Velocity ``v_{x=0}^+`` of every upward crossing of ``x = 0`` in the kept periods.
    mean_impact_velocity : float
        ``sum(v_im) / n_kept``: average impact velocity per forcing cycle
        (thesis Appendix A.1); 0 without impacts.
    regime : Regime
        No impact, ``m/n`` periodic or aperiodic (:func:`classify_impacts`).
    sticking : bool
        The mass stuck to the stop (after complete chatter) in the kept periods.
    lyapunov : LyapunovResult or None
        Largest Lyapunov exponent, where computed (see ``sweep(lyapunov=...)``).
    linear_impact_velocity : float
        Linear estimate of the impact velocity, eq. (4.7)-(4.11)
        (``omega sqrt(x_max^2 - 1)``); NaN where linear theory predicts no impact.
    settle_cycles : float
        Extra forcing periods run (on a side run from the value's end state) to
        settle a periodic match that was still converging in the kept window
        (:func:`classify_settled`); 0 when it was settled at once.  The
        recorded impacts are those of the kept window either way.
    """

    value: float
    params: SDFParams
    impact_velocities: np.ndarray
    impact_phases: np.ndarray
    crossing_velocities: np.ndarray
    mean_impact_velocity: float
    regime: Regime
    sticking: bool
    lyapunov: LyapunovResult | None
    linear_impact_velocity: float
    settle_cycles: float = 0.0

    @property
    def chaotic(self) -> bool:
        """Aperiodic with a measured positive largest Lyapunov exponent."""
        return (self.regime.kind == "aperiodic" and self.lyapunov is not None
                and self.lyapunov.exponent > 0.0)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary (non-finite numbers become None)."""
        return {
            "value": self.value,
            "params": {"F": self.params.F, "omega": self.params.omega,
                       "zeta": self.params.zeta, "e": self.params.e},
            "impact_velocities": [float(x) for x in self.impact_velocities],
            "impact_phases": [float(x) for x in self.impact_phases],
            "crossing_velocities": [float(x) for x in self.crossing_velocities],
            "mean_impact_velocity": self.mean_impact_velocity,
            "classification": self.regime.label,
            "regime": self.regime.to_dict(),
            "sticking": self.sticking,
            "lyapunov": None if self.lyapunov is None else self.lyapunov.to_dict(),
            "chaotic": self.chaotic,
            "linear_impact_velocity": _num(self.linear_impact_velocity),
            "settle_cycles": self.settle_cycles,
        }


@dataclass(frozen=True)
class Sweep:
    """A slow sweep in one direction.

    Attributes
    ----------
    param : {"omega", "F", "e", "gap"}
        The swept parameter.
    direction : {"up", "down"}
        Increasing or decreasing values.
    points : tuple of SweepPoint
        One per value, in sweep order.
    base : SDFParams
        The fixed parameters (the swept one, and ``F`` for ``"gap"``, are
        replaced at each value).
    cycles, discard : int
        Forcing periods simulated and discarded at each value.
    initial_state, final_state : SDFState
        The state the sweep started from and ended in (continue from it).
    provenance : dict
        Package, version, function and arguments that made it.
    """

    param: SweepParam
    direction: Direction
    points: tuple[SweepPoint, ...]
    base: SDFParams
    cycles: int
    discard: int
    initial_state: SDFState
    final_state: SDFState
    provenance: dict[str, object] = field(default_factory=dict)

    @property
    def values(self) -> np.ndarray:
        """The swept values, in sweep order."""
        return np.array([p.value for p in self.points])

    @property
    def labels(self) -> list[str]:
        """Regime label at each value."""
        return [p.regime.label for p in self.points]

    @property
    def mean_impact_velocity(self) -> np.ndarray:
        """Average impact velocity per forcing cycle at each value."""
        return np.array([p.mean_impact_velocity for p in self.points])

    def transitions(self) -> list[dict[str, object]]:
        """Where the regime label changes: ``{"from", "to", "before", "after"}`` (values)."""
        out: list[dict[str, object]] = []
        for a, b in zip(self.points[:-1], self.points[1:]):
            if a.regime.label != b.regime.label:
                out.append({"from": a.regime.label, "to": b.regime.label,
                            "before": a.value, "after": b.value})
        return out

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary: settings and one entry per value.

        For a ``"gap"`` sweep each entry also carries the velocities divided by
        ``F`` (``*_over_F``), the quantities of thesis Fig. 4-4 (eq. 4.5), and
        ``inv_F`` (= ``value``).
        """
        points = []
        for p in self.points:
            d = p.to_dict()
            if self.param == "gap":
                F = p.params.F
                d["inv_F"] = p.value
                d["impact_velocities_over_F"] = [float(v) / F for v in p.impact_velocities]
                d["crossing_velocities_over_F"] = [float(v) / F for v in p.crossing_velocities]
                d["mean_impact_velocity_over_F"] = p.mean_impact_velocity / F
                d["linear_impact_velocity_over_F"] = _num(p.linear_impact_velocity / F)
            points.append(d)
        return {"param": self.param, "direction": self.direction,
                "base": {"F": self.base.F, "omega": self.base.omega, "zeta": self.base.zeta,
                         "e": self.base.e},
                "cycles": self.cycles, "discard": self.discard, "points": points,
                "provenance": self.provenance}


# ---------------------------------------------------------------------------
# Output: CSV (the plot is rattle_lab.plot.plot_sweeps)
# ---------------------------------------------------------------------------

CSV_COLUMNS = ("direction", "param", "value", "F", "omega", "zeta", "e", "classification",
               "m", "n", "n_impacts", "mean_impact_velocity", "max_impact_velocity",
               "linear_impact_velocity", "lyapunov", "sticking", "impact_velocities",
               "crossing_velocities")


def write_sweeps_csv(sweeps: Sequence[Sweep], path: str | os.PathLike[str]) -> Path:
    """Write sweeps as CSV (atomically): one row per direction and value.

    Columns are :data:`CSV_COLUMNS`; the velocity lists are ``;``-separated
    in ``repr`` precision, empty numbers are blank.

    Raises
    ------
    OutputError
        If the directory does not exist.
    """
    from rattle_lab._atomic import atomic_path

    def num(x: float | None) -> str:
        return "" if x is None or not math.isfinite(x) else repr(float(x))

    with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(CSV_COLUMNS)
        for sw in sweeps:
            for p in sw.points:
                lyap = p.lyapunov.exponent if p.lyapunov is not None else None
                writer.writerow([
                    sw.direction, sw.param, repr(p.value), repr(p.params.F),
                    repr(p.params.omega), repr(p.params.zeta), repr(p.params.e),
                    p.regime.label, p.regime.m, p.regime.n, p.impact_velocities.size,
                    repr(p.mean_impact_velocity),
                    num(float(p.impact_velocities.max()) if p.impact_velocities.size else None),
                    num(p.linear_impact_velocity),
                    "-inf" if lyap == -math.inf else num(lyap), int(p.sticking),
                    ";".join(repr(float(v)) for v in p.impact_velocities),
                    ";".join(repr(float(v)) for v in p.crossing_velocities)])
    return Path(path)
