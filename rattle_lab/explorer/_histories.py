"""What the explorer shows, as pure data: time histories split into parts, and impacts.

:func:`compute_histories` runs the exact simulator (:func:`rattle_lab.model.sdf.simulate`)
and splits each of displacement, velocity and acceleration into its forced
(particular, steady-state linear) and transient (homogeneous) parts, as the
thesis's applet does (Appendix A.3, ``Screen.java``: ``X_FORCED``,
``X_TRANSIENT``, ...).  :func:`save_histories` writes them, with the impacts,
to CSV or HDF5 with units, atomically.

All model quantities are nondimensional (thesis eq. 2.28-2.32); the physical
columns use the scales of one mode with natural frequency ``f_s_hz`` and one
gap ``gap_m``:

* time ``t_s = t / omega_s`` with ``omega_s = 2 pi f_s`` (eq. 2.29);
* displacement ``x_m = x h`` (eq. 2.30);
* velocity ``v_ms = v omega_s h`` (eq. 4.4);
* acceleration ``a_ms2 = a omega_s^2 h`` (eq. 2.30 differentiated twice).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from rattle_lab._atomic import atomic_path
from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.scaling import accel_ms2_from_F
from rattle_lab.model.sdf import SimImpacts, SDFParams, SDFState, SimResult, particular_state, simulate

TWO_PI = 2.0 * math.pi

#: File suffixes :func:`save_histories` writes, and the format of each.
DATA_SUFFIXES: dict[str, Literal["csv", "hdf5"]] = {".csv": "csv", ".h5": "hdf5", ".hdf5": "hdf5"}

#: Columns of the time-history table: name, unit, description.
HISTORY_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("t", "1", "time omega_s t_s (nondimensional)"),
    ("time_s", "s", "physical time t_s"),
    ("x", "1", "displacement x = x_s / h (nondimensional)"),
    ("x_m", "m", "modal displacement x_s"),
    ("x_forced", "1", "forced (particular) part of x (nondimensional)"),
    ("x_transient", "1", "transient (homogeneous) part x - x_forced (nondimensional)"),
    ("v", "1", "velocity dx/dt (nondimensional)"),
    ("v_ms", "m/s", "modal velocity"),
    ("v_forced", "1", "forced part of v (nondimensional)"),
    ("v_transient", "1", "transient part v - v_forced (nondimensional)"),
    ("a", "1", "acceleration d2x/dt2 (nondimensional)"),
    ("a_ms2", "m/s^2", "modal acceleration"),
    ("a_forced", "1", "forced part of a (nondimensional)"),
    ("a_transient", "1", "transient part a - a_forced (nondimensional)"),
    ("excitation", "1", "excitation F cos(omega t + phi) (nondimensional)"),
)

#: Columns of the impact table: name, unit, description.
IMPACT_COLUMNS: tuple[tuple[str, str, str], ...] = (
    ("t", "1", "impact time (nondimensional)"),
    ("time_s", "s", "physical impact time"),
    ("phase_rad", "rad", "forcing phase omega t + phi at impact, in [0, 2 pi)"),
    ("v_in", "1", "incoming impact velocity (nondimensional)"),
    ("v_in_ms", "m/s", "incoming impact velocity"),
    ("v_out", "1", "outgoing velocity magnitude e v_in (nondimensional)"),
    ("v_out_ms", "m/s", "outgoing velocity magnitude"),
)


@dataclass(frozen=True)
class Histories:
    """Time histories of one explorer run and its impacts.

    Attributes
    ----------
    params : SDFParams
        The nondimensional parameters simulated.
    gap_m : float
        Gap ``h`` [m] used for the physical columns.
    f_s_hz : float
        Modal frequency ``f_s`` [Hz] used for the physical columns.
    participation : float
        ``Q1 / Q2`` of the mode: base acceleration ``A_e`` gives
        ``F = participation A_e / (omega_s^2 h)`` (eq. 2.27, 2.31); 1 for a
        single-degree-of-freedom oscillator on a shaken base.
    start_state : SDFState
        The state the run started from.
    result : SimResult
        What :func:`rattle_lab.model.sdf.simulate` returned (``result.dense`` holds
        ``x``, ``v``, ``a``, ``forced``, ``transient`` and ``excitation``).
    t, x, v, a : ndarray
        Sample times and the total displacement, velocity, acceleration
        (nondimensional; ``a = 0`` while stuck on the stop).
    x_forced, v_forced, a_forced : ndarray
        Forced parts: the particular solution ``x_p`` of
        ``x'' + 2 zeta x' + x = F cos(theta)``, ``v_p = x_p'`` and
        ``a_p = F cos(theta) - 2 zeta v_p - x_p``.  At the undamped resonance
        (``zeta = 0``, ``omega = 1``) the particular solution is secular and
        restarts at every impact; ``v_forced`` and ``a_forced`` are NaN there.
    x_transient, v_transient, a_transient : ndarray
        ``x - x_forced`` etc.: the homogeneous part carried since the last impact.
    excitation : ndarray
        ``F cos(omega t + phi)`` (nondimensional, the right-hand side of eq. 2.33).
    """

    params: SDFParams
    gap_m: float
    f_s_hz: float
    participation: float
    start_state: SDFState
    result: SimResult
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    x_forced: np.ndarray
    v_forced: np.ndarray
    a_forced: np.ndarray
    x_transient: np.ndarray
    v_transient: np.ndarray
    a_transient: np.ndarray
    excitation: np.ndarray

    @property
    def impacts(self) -> SimImpacts:
        """Every impact of the run (nondimensional)."""
        return self.result.impacts

    @property
    def omega_s_rad_s(self) -> float:
        """Modal angular frequency ``2 pi f_s`` [rad/s]."""
        return TWO_PI * self.f_s_hz

    @property
    def accel_ms2(self) -> float:
        """Base-acceleration amplitude ``A_e = F omega_s^2 h / participation`` [m/s^2]."""
        return float(accel_ms2_from_F(self.params.F, self.participation, self.omega_s_rad_s,
                                      self.gap_m))

    @property
    def freq_hz(self) -> float:
        """Excitation frequency ``omega f_s`` [Hz]."""
        return self.params.omega * self.f_s_hz

    def history_table(self) -> dict[str, np.ndarray]:
        """The columns of :data:`HISTORY_COLUMNS`, in that order."""
        w, h = self.omega_s_rad_s, self.gap_m
        return {
            "t": self.t, "time_s": self.t / w,
            "x": self.x, "x_m": self.x * h,
            "x_forced": self.x_forced, "x_transient": self.x_transient,
            "v": self.v, "v_ms": self.v * w * h,
            "v_forced": self.v_forced, "v_transient": self.v_transient,
            "a": self.a, "a_ms2": self.a * w * w * h,
            "a_forced": self.a_forced, "a_transient": self.a_transient,
            "excitation": self.excitation,
        }

    def impact_table(self) -> dict[str, np.ndarray]:
        """The columns of :data:`IMPACT_COLUMNS`, in that order."""
        w, h = self.omega_s_rad_s, self.gap_m
        imp = self.impacts
        return {
            "t": np.asarray(imp.t), "time_s": imp.t / w, "phase_rad": np.asarray(imp.phase),
            "v_in": np.asarray(imp.v_in), "v_in_ms": imp.v_in * w * h,
            "v_out": np.asarray(imp.v_out), "v_out_ms": imp.v_out * w * h,
        }

    def attributes(self) -> dict[str, float | str]:
        """Parameters and provenance, as file attributes."""
        p, s = self.params, self.start_state
        return {
            "F": p.F, "omega": p.omega, "zeta": p.zeta, "e": p.e,
            "gap_m": self.gap_m, "f_s_hz": self.f_s_hz, "participation": self.participation,
            "accel_ms2": self.accel_ms2, "freq_hz": self.freq_hz,
            "start_t": s.t, "start_x": s.x, "start_v": s.v, "start_theta": s.theta,
            "start_stuck": str(bool(s.stuck)),
            "provenance": json.dumps({
                "package": "rattle_lab", "version": __version__,
                "function": "rattle_lab.explorer.compute_histories",
                "simulator": f"rattle_lab.model.sdf.simulate(method={self.result.method!r})",
            }),
        }


def _check_positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"`{name}` must be finite and > 0, was {value}")
    return value


def compute_histories(params: SDFParams, *, cycles: float = 20.0, n_per_cycle: int = 100,
                      state: SDFState | None = None, gap_m: float = 1e-3, f_s_hz: float = 100.0,
                      participation: float = 1.0) -> Histories:
    """Simulate ``cycles`` forcing periods from ``state`` and split the motion into parts.

    Parameters
    ----------
    params : SDFParams
        Nondimensional parameters.
    cycles : float
        Forcing periods to simulate (> 0).
    n_per_cycle : int
        Samples per forcing period (>= 4); ``round(cycles * n_per_cycle) + 1``
        samples in all, the first at ``state.t`` and the last at the end.
    state : SDFState, optional
        Start (default: at rest at x = 0, phase 0).
    gap_m, f_s_hz, participation : float
        Physical scales (see :class:`Histories`); > 0, > 0 and != 0.

    Returns
    -------
    Histories

    Raises
    ------
    ParameterError
        On an invalid argument.

    Examples
    --------
    >>> import numpy as np
    >>> from rattle_lab.model.sdf import SDFParams
    >>> h = compute_histories(SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6), cycles=5)
    >>> bool(np.allclose(h.x, h.x_forced + h.x_transient))
    True
    """
    cycles = _check_positive("cycles", cycles)
    if isinstance(n_per_cycle, bool) or not isinstance(n_per_cycle, (int, np.integer)) \
            or n_per_cycle < 4:
        raise ParameterError(f"`n_per_cycle` must be an integer >= 4, was {n_per_cycle!r}")
    gap_m = _check_positive("gap_m", gap_m)
    f_s_hz = _check_positive("f_s_hz", f_s_hz)
    participation = float(participation)
    if not math.isfinite(participation) or participation == 0.0:
        raise ParameterError(f"`participation` must be finite and != 0, was {participation}")
    start = SDFState() if state is None else state
    duration = cycles * params.period
    n_samples = round(cycles * int(n_per_cycle)) + 1
    t = start.t + np.linspace(0.0, duration, n_samples)
    res = simulate(params, duration=duration, state=start, dense_t=t,
                   dense_fields=("x", "v", "a", "forced", "transient", "excitation"))
    d = res.dense
    assert d is not None and d.x is not None and d.v is not None and d.a is not None
    assert d.forced is not None and d.transient is not None and d.excitation is not None
    F, w, z = params.F, params.omega, params.zeta
    theta = start.theta + w * (t - start.t)
    if z == 0.0 and w == 1.0:
        # the secular particular solution restarts at every impact: no single forced part
        v_forced = np.full_like(t, np.nan)
    else:
        v_forced = np.asarray(particular_state(F, w, z, theta)[1], dtype=float)
    # the particular solution solves the linear equation: a_p = F cos(theta) - 2 zeta v_p - x_p
    a_forced = d.excitation - 2.0 * z * v_forced - d.forced
    return Histories(
        params=params, gap_m=gap_m, f_s_hz=f_s_hz, participation=participation,
        start_state=start, result=res, t=t, x=d.x, v=d.v, a=d.a,
        x_forced=d.forced, v_forced=v_forced, a_forced=a_forced,
        x_transient=d.transient, v_transient=d.v - v_forced, a_transient=d.a - a_forced,
        excitation=d.excitation)


def impacts_path(path: str | Path) -> Path:
    """Where :func:`save_histories` writes the impacts of a CSV ``path``: ``<stem>_impacts.csv``."""
    p = Path(path)
    return p.with_name(f"{p.stem}_impacts{p.suffix}")


def _write_csv(target: Path, columns: tuple[tuple[str, str, str], ...],
               table: dict[str, np.ndarray], header: list[str]) -> None:
    with atomic_path(target) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            for line in header:
                fh.write(f"# {line}\n")
            fh.write("# units: " + ", ".join(f"{n} [{u}]" for n, u, _ in columns) + "\n")
            writer = csv.writer(fh)
            writer.writerow([n for n, _, _ in columns])
            rows = np.column_stack([table[n] for n, _, _ in columns]) if table["t"].size \
                else np.empty((0, len(columns)))
            for row in rows:
                writer.writerow([repr(float(v)) for v in row])


def save_histories(hist: Histories, path: str | Path) -> tuple[Path, ...]:
    """Write the time histories and impacts of ``hist``, atomically, with units.

    ``.csv``: two files, ``path`` (time histories, :data:`HISTORY_COLUMNS`)
    and ``<stem>_impacts.csv`` (:data:`IMPACT_COLUMNS`), each with ``#``
    comment lines giving the parameters and the unit of every column
    (``pandas.read_csv(path, comment="#")`` reads them).

    ``.h5`` / ``.hdf5``: one file with groups ``/time_history`` and
    ``/impacts``, one dataset per column with attributes ``units`` and
    ``description``; the root carries the parameters and the provenance.

    Parameters
    ----------
    hist : Histories
        What to write.
    path : str or Path
        Target; its suffix picks the format.

    Returns
    -------
    tuple of Path
        The files written.

    Raises
    ------
    ParameterError
        If the suffix is not one of :data:`DATA_SUFFIXES`.
    OutputError
        If the directory does not exist (nothing is written then).
    """
    p = Path(path)
    fmt = DATA_SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        raise ParameterError(
            f"data file {str(p)!r} must end in one of {', '.join(DATA_SUFFIXES)}")
    attrs = hist.attributes()
    if fmt == "csv":
        header = ["rattle_lab explorer: SDF impact oscillator, thesis eq. 2.33",
                  "parameters: " + json.dumps({k: v for k, v in attrs.items()
                                               if k != "provenance"}),
                  "provenance: " + str(attrs["provenance"])]
        second = impacts_path(p)
        _write_csv(p, HISTORY_COLUMNS, hist.history_table(), header + ["time histories"])
        _write_csv(second, IMPACT_COLUMNS, hist.impact_table(), header + ["impacts"])
        return (p, second)
    import h5py

    with atomic_path(p) as tmp:
        with h5py.File(tmp, "w") as f:
            for key, value in attrs.items():
                f.attrs[key] = value
            for group_name, columns, table in (
                    ("time_history", HISTORY_COLUMNS, hist.history_table()),
                    ("impacts", IMPACT_COLUMNS, hist.impact_table())):
                g = f.create_group(group_name)
                for name, unit, description in columns:
                    ds = g.create_dataset(name, data=np.asarray(table[name], dtype=float))
                    ds.attrs["units"] = unit
                    ds.attrs["description"] = description
    return (p,)


__all__ = ["Histories", "compute_histories", "save_histories", "impacts_path",
           "HISTORY_COLUMNS", "IMPACT_COLUMNS", "DATA_SUFFIXES"]
