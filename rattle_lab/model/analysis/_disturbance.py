"""The disturbance study (thesis 4.3.3, Fig. 4-6, 4-7).

The smallest kick that starts a sustained rattle, and its map over (F, omega).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab._version import __version__
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams, SDFState, particular_coeffs, simulate

from ._dask import check_execution, chunk_rows, run_chunks
from ._sweep import (
    _check_int,
)
from .maps import _axis

# ---------------------------------------------------------------------------
# Disturbance study
# ---------------------------------------------------------------------------

def _impact_free_start(p: SDFParams, kick: float) -> SDFState:
    """On the impact-free response at its upward x = 0 crossing, with ``kick`` added to v."""
    A_c, A_s = particular_coeffs(p.F, p.omega, p.zeta)
    amplitude = math.hypot(float(A_c), float(A_s))
    # x_p = R cos(theta - delta) is 0 and rising at theta = delta - pi/2, with v = omega R.
    theta0 = math.atan2(float(A_s), float(A_c)) - 0.5 * math.pi
    return SDFState(x=0.0, v=p.omega * amplitude + kick, theta=theta0)


def _sustained(p: SDFParams, kick: float, cycles: int, check_cycles: int) -> bool:
    res = simulate(p, cycles=cycles, state=_impact_free_start(p, kick))
    t_check = (cycles - check_cycles) * p.period
    if res.impacts.t.size and res.impacts.t[-1] >= t_check:
        return True
    return res.sticking.shape[0] > 0 and bool(res.sticking[-1, 1] >= t_check)


def _threshold(p: SDFParams, kick_max: float, kick_tol: float, n_scan: int, cycles: int,
               check_cycles: int) -> float:
    grazing = math.hypot((1.0 - p.omega) * (1.0 + p.omega), 2.0 * p.zeta * p.omega)
    if p.F >= grazing:
        return math.nan  # no impact-free response to disturb (eq. 3.4)
    lo, hi = 0.0, math.inf
    for j in range(1, n_scan + 1):
        kick = kick_max * j / n_scan
        if _sustained(p, kick, cycles, check_cycles):
            hi = kick
            break
        lo = kick
    if math.isinf(hi):
        return math.inf
    while hi - lo > kick_tol:
        mid = 0.5 * (lo + hi)
        if _sustained(p, mid, cycles, check_cycles):
            hi = mid
        else:
            lo = mid
    return hi


def _disturbance_rows(task: tuple[np.ndarray, tuple[float, float, int, int, int]]) -> np.ndarray:
    """Disturbance threshold of each row ``(F, omega, zeta, e)``."""
    rows, (kick_max, kick_tol, n_scan, cycles, check_cycles) = task
    out = np.empty(rows.shape[0])
    for k in range(rows.shape[0]):
        F, w, z, e = (float(q) for q in rows[k])
        out[k] = _threshold(SDFParams(F=F, omega=w, zeta=z, e=e), kick_max, kick_tol, n_scan,
                            cycles, check_cycles)
    return out


def _check_disturbance(kick_max: float, kick_tol: float, n_scan: object, cycles: object,
                       check_cycles: object) -> tuple[int, int, int]:
    if not (math.isfinite(kick_max) and kick_max > 0):
        raise ParameterError(f"`kick_max` must be finite and > 0, was {kick_max}")
    if not (math.isfinite(kick_tol) and 0 < kick_tol < kick_max):
        raise ParameterError(f"`kick_tol` must be in (0, kick_max), was {kick_tol}")
    n_scan_i = _check_int("n_scan", n_scan, 1)
    cycles_i = _check_int("cycles", cycles, 2)
    check_i = _check_int("check_cycles", check_cycles, 1)
    if check_i >= cycles_i:
        raise ParameterError(f"`check_cycles` must be < cycles = {cycles_i}, was {check_i}")
    return n_scan_i, cycles_i, check_i


def disturbance_threshold(params: SDFParams, *, kick_max: float = 2.0, kick_tol: float = 1e-3,
                          n_scan: int = 20, cycles: int = 200, check_cycles: int = 20) -> float:
    """Smallest velocity kick that turns the impact-free response into sustained impact.

    The mass starts on the impact-free (linear) response as it crosses
    ``x = 0`` upwards, with velocity ``omega R + kick`` (``R = F / sqrt(D)``,
    eq. 4.7), as in the thesis's Fig. 4-6.  Impact is *sustained* if at least
    one impact (or a stuck interval) occurs in the last ``check_cycles`` of
    ``cycles`` forcing periods.  On the impact-free attractor the kick's
    transient decays like ``exp(-zeta t)``: with the defaults (``zeta = 0.05``)
    it has shrunk by ``exp(-50)`` or more before the check starts, so no
    transient impact is counted; a trajectory that comes close to the
    unstable 1/1 orbit lingers there for a time that grows only like
    ``log(1 / distance)``, so the bracket ends are classified correctly to
    within ``kick_tol``.

    The kicks ``kick_max * j / n_scan`` (``j = 1, 2, ...``) are tried in turn;
    the first one that sustains impact is refined by bisection against the
    previous one to ``kick_tol``.  A window of sustained impact narrower than
    ``kick_max / n_scan`` below the first one found can be missed.

    Parameters
    ----------
    params : SDFParams
        Nondimensional parameters; ``F`` below the grazing forcing (eq. 3.4).
    kick_max : float
        Largest kick tried (nondimensional velocity), > 0.
    kick_tol : float
        Width of the final bracket, in ``(0, kick_max)``.
    n_scan : int
        Number of kicks of the coarse scan.
    cycles, check_cycles : int
        Run length after the kick and the final window checked for impacts.

    Returns
    -------
    float
        The threshold kick (upper end of the final bracket, so that kick
        sustains impact); NaN if ``F`` is at or above the grazing forcing (no
        impact-free response exists); ``inf`` if no kick up to ``kick_max`` does.

    Raises
    ------
    ParameterError
        On an invalid argument.

    Examples
    --------
    >>> from rattle_lab.model.sdf import SDFParams
    >>> kick = disturbance_threshold(SDFParams(F=0.2, omega=1.15, zeta=0.05, e=0.6))
    >>> bool(0.0 < kick < 2.0)
    True
    """
    if not isinstance(params, SDFParams):
        raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
    n_scan_i, cycles_i, check_i = _check_disturbance(kick_max, kick_tol, n_scan, cycles,
                                                     check_cycles)
    return _threshold(params, float(kick_max), float(kick_tol), n_scan_i, cycles_i, check_i)


@dataclass(frozen=True)
class DisturbanceMap:
    """Disturbance thresholds over an ``(F, omega)`` grid (thesis Fig. 4-7).

    Attributes
    ----------
    F, omega : ndarray
        Grid axes (nondimensional).
    zeta, e : float
        Damping ratio and restitution.
    threshold : ndarray, shape (F.size, omega.size)
        Smallest kick that sustains impact (:func:`disturbance_threshold`):
        NaN at or above grazing, ``inf`` if none up to ``kick_max``.
    hysteresis : ndarray of bool
        The hysteresis region: ``omega > 1`` and ``F_sn(omega) < F < F_g(omega)``
        (1/1 saddle-node, eq. 3.11, and grazing, eq. 3.4), where the
        impact-free response and the 1/1 orbit coexist.
    kick_max, kick_tol : float
    n_scan, cycles, check_cycles : int
        The search settings.
    provenance : dict
        What made it.
    """

    F: np.ndarray
    omega: np.ndarray
    zeta: float
    e: float
    threshold: np.ndarray
    hysteresis: np.ndarray
    kick_max: float
    kick_tol: float
    n_scan: int
    cycles: int
    check_cycles: int
    provenance: dict[str, object] = field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary; ``inf`` becomes the string ``"inf"``, NaN None."""
        def cell(v: float) -> float | str | None:
            if math.isnan(v):
                return None
            return "inf" if math.isinf(v) else float(v)

        return {"kind": "disturbance", "F": self.F.tolist(), "omega": self.omega.tolist(),
                "zeta": self.zeta, "e": self.e,
                "threshold": [[cell(v) for v in row] for row in self.threshold.tolist()],
                "hysteresis": self.hysteresis.tolist(), "kick_max": self.kick_max,
                "kick_tol": self.kick_tol, "n_scan": self.n_scan, "cycles": self.cycles,
                "check_cycles": self.check_cycles, "provenance": self.provenance}


def _hysteresis_region(F: np.ndarray, omega: np.ndarray, zeta: float, e: float) -> np.ndarray:
    from .orbits import saddle_node_forcing

    F_sn, v_sn = saddle_node_forcing(1, omega, zeta, e)
    F_g = np.hypot((1.0 - omega) * (1.0 + omega), 2.0 * zeta * omega)
    ok = (omega > 1.0) & (v_sn > 0.0)
    return ok[None, :] & (F[:, None] > F_sn[None, :]) & (F[:, None] < F_g[None, :])


def disturbance_map(F: ArrayLike, omega: ArrayLike, *, zeta: float = 0.05, e: float = 0.6,
                    kick_max: float = 2.0, kick_tol: float = 1e-3, n_scan: int = 20,
                    cycles: int = 200, check_cycles: int = 20, chunk_size: int = 16,
                    workers: int = 1, scheduler: str | None = None,
                    quiet: bool = True) -> DisturbanceMap:
    """Disturbance thresholds (:func:`disturbance_threshold`) over an ``(F, omega)`` grid.

    The level curves ``threshold = V`` are the thesis's demarcation curves
    (Fig. 4-7): above the curve of ``V`` (larger ``F``) a kick ``V`` sets the
    system into sustained impact.

    Parameters
    ----------
    F, omega : array_like
        Grid axes (nondimensional).
    zeta, e : float
        Damping ratio and restitution.
    kick_max, kick_tol, n_scan, cycles, check_cycles
        As for :func:`disturbance_threshold`.
    chunk_size, workers, scheduler, quiet
        As for :func:`regime_map`.

    Returns
    -------
    DisturbanceMap

    Raises
    ------
    ParameterError
        On an invalid argument.
    """
    Fa, wa = _axis("F", F), _axis("omega", omega)
    n_scan_i, cycles_i, check_i = _check_disturbance(kick_max, kick_tol, n_scan, cycles,
                                                     check_cycles)
    _check_int("chunk_size", chunk_size, 1)
    workers_i, sched = check_execution(workers, scheduler)
    SDFParams(F=float(Fa.min()), omega=float(wa.min()), zeta=zeta, e=e)
    SDFParams(F=float(Fa.max()), omega=float(wa.max()), zeta=zeta, e=e)
    FF, WW = np.meshgrid(Fa, wa, indexing="ij")
    rows = np.column_stack([FF.ravel(), WW.ravel(), np.full(FF.size, float(zeta)),
                            np.full(FF.size, float(e))])
    settings = (float(kick_max), float(kick_tol), n_scan_i, cycles_i, check_i)
    chunks = [(c, settings) for c in chunk_rows(rows, int(chunk_size))]
    parts = run_chunks(_disturbance_rows, chunks, workers=workers_i, scheduler=sched,
                       desc="disturbance map", quiet=quiet)
    threshold = np.concatenate(parts).reshape(FF.shape)
    provenance: dict[str, object] = {
        "package": "rattle_lab", "version": __version__,
        "function": "rattle_lab.model.analysis.disturbance_map",
        "arguments": {"n_F": int(Fa.size), "n_omega": int(wa.size), "zeta": float(zeta),
                      "e": float(e), "kick_max": float(kick_max), "kick_tol": float(kick_tol),
                      "n_scan": n_scan_i, "cycles": cycles_i, "check_cycles": check_i}}
    return DisturbanceMap(F=Fa, omega=wa, zeta=float(zeta), e=float(e), threshold=threshold,
                          hysteresis=_hysteresis_region(Fa, wa, float(zeta), float(e)),
                          kick_max=float(kick_max), kick_tol=float(kick_tol), n_scan=n_scan_i,
                          cycles=cycles_i, check_cycles=check_i, provenance=provenance)


__all__ = ["DisturbanceMap", "disturbance_threshold", "disturbance_map"]
