"""Coefficient of restitution: from per-impact velocity ratios, and from downward thresholds.

Above resonance the stable 1/1 orbit is lost at its saddle-node (eq. 3.11), so
the disappearance threshold on a downward ramp is, dimensionally::

    A_down(f) = h omega_s^2 F_sn(f / f_s, zeta, e) / q

with ``F_sn`` from :func:`rattle_lab.analysis.saddle_node_forcing`; ``e`` is
fitted with ``h, f_s, zeta, q`` held at the grazing-fit values.
"""

from __future__ import annotations

from dataclasses import dataclass

import lmfit
import numpy as np

from ..analysis import saddle_node_forcing
from ..exceptions import ConvergenceError, ParameterError
from ._common import ParamEstimate


@dataclass(frozen=True)
class RestitutionStats:
    """``e`` from per-impact ratios ``-v_out/v_in``.

    Attributes
    ----------
    mean, std, median : float
        Of the finite ratios in (0, 1.5); nondimensional.
    n : int
        Number of ratios used.
    stderr : float
        ``std / sqrt(n)``.
    """

    mean: float
    std: float
    median: float
    n: int
    stderr: float


def restitution_from_ratios(e_values: object) -> RestitutionStats:
    """Statistics of per-impact restitution ratios (non-finite or implausible ones dropped).

    Examples
    --------
    >>> s = restitution_from_ratios([0.7, 0.8, 0.9, float("nan")])
    >>> round(s.mean, 12), s.n
    (0.8, 3)
    """
    e = np.asarray(e_values, dtype=float).ravel()
    e = e[np.isfinite(e) & (e > 0) & (e < 1.5)]
    if e.size == 0:
        return RestitutionStats(np.nan, np.nan, np.nan, 0, np.nan)
    std = float(np.std(e, ddof=1)) if e.size > 1 else np.nan
    return RestitutionStats(float(np.mean(e)), std, float(np.median(e)), int(e.size),
                            std / np.sqrt(e.size) if e.size > 1 else np.nan)


def saddle_node_threshold_ms2(freq_hz: np.ndarray, e: float, gap_m: float, f_s_hz: float,
                              zeta: float, participation: float) -> np.ndarray:
    """Disappearance threshold at the 1/1 saddle-node (eq. 3.11), dimensional, m/s^2."""
    with np.errstate(invalid="ignore"):
        F_sn, _ = saddle_node_forcing(1, np.asarray(freq_hz, dtype=float) / f_s_hz, zeta, e)
    return gap_m * (2 * np.pi * f_s_hz) ** 2 * F_sn / participation


@dataclass(frozen=True)
class RestitutionFit:
    """``e`` fitted to downward thresholds above resonance.

    Attributes
    ----------
    e : ParamEstimate
        Fitted coefficient of restitution.
    freq_hz, accel_ms2, residuals_ms2 : ndarray
        Points used (above ``f_s``, on a physical fold) and model minus data, m/s^2.
    """

    e: ParamEstimate
    freq_hz: np.ndarray
    accel_ms2: np.ndarray
    residuals_ms2: np.ndarray

    @property
    def params(self) -> dict[str, ParamEstimate]:
        """``{"e": ...}`` (same shape as the other fits)."""
        return {"e": self.e}


def fit_restitution_down(freq_hz: object, down_ms2: object, *, gap_m: float, f_s_hz: float,
                         zeta: float, participation: float = 1.0, e0: float = 0.7) -> RestitutionFit:
    """Fit ``e`` to disappearance thresholds above resonance (``freq_hz > f_s_hz``).

    Raises
    ------
    ParameterError
        With no usable point above resonance.
    ConvergenceError
        If the fit fails.
    """
    f = np.asarray(freq_hz, dtype=float)
    a = np.asarray(down_ms2, dtype=float)
    use = np.isfinite(f) & np.isfinite(a) & (f > f_s_hz) & (a > 0)
    if use.sum() < 1:
        raise ParameterError(f"no finite downward threshold above f_s = {f_s_hz:.6g} Hz to fit e to")
    fu, au = f[use], a[use]
    model = lmfit.Model(saddle_node_threshold_ms2, independent_vars=["freq_hz"])
    pars = model.make_params(e=dict(value=e0, min=1e-3, max=0.999),
                             gap_m=dict(value=gap_m, vary=False), f_s_hz=dict(value=f_s_hz, vary=False),
                             zeta=dict(value=zeta, vary=False),
                             participation=dict(value=participation, vary=False))
    res = model.fit(au, pars, freq_hz=fu, weights=1.0 / au, nan_policy="omit")
    if not res.success or not np.isfinite(res.params["e"].value):
        raise ConvergenceError(f"the restitution fit did not converge: {res.message}")
    p = res.params["e"]
    std = float(p.stderr) if p.stderr is not None else np.nan
    est = ParamEstimate("e", float(p.value), std, float(p.value) - 2 * std, float(p.value) + 2 * std,
                        True)
    return RestitutionFit(est, fu, au, res.eval(freq_hz=fu) - au)
