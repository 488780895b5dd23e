"""The measurement chain in the fit: the runs' delays and measurands, the crossing levels.

Split from :mod:`rattle_lab.fit._store` (issue 15); the per-run part (channels on one time
base, measurands, transient shocks) moved to :mod:`rattle_lab.detect._chain` (issue 29).
Over the runs of a store: the error of e from the vibrometer's delays and from measurands
the data could not establish, and the crossing levels of the ramp thresholds that the
eq. (3.4) fit takes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rattle_lab.detect import (CAUSE_QUANTITIES, FLAG_DELAY_CONTRADICTED,  # noqa: F401
                               FLAG_DELAY_ESTIMATED, FLAG_MEASURAND_INFERRED,
                               FLAG_MEASURAND_UNDETERMINED, SHOCK_QUANTITIES, infer_measurand,
                               median_and_error, paired_plate_channels, relative_to_striker,
                               run_chain_flags, transient_shocks, velocity_delay_flags)
from rattle_lab.fit._results import RunResult
from rattle_lab.detect.thresholds import Threshold, crossing_level_ms2


#: Least standard error, samples, a run's delay is weighted with when the runs' delays that
#: were not applied are pooled (a MAD of exactly 0 must not give a run infinite weight).
_POOL_FLOOR_SAMPLES = 1e-3


def _pooled_rms(d: list[float], s: list[float], slope: list[float]
                ) -> tuple[float, float, float]:
    """One chain's delay pooled over runs: the inverse-variance mean ``d_bar`` of ``d``
    (errors ``s``), its standard error ``s_bar``, and what reading at zero errs in e, the
    runs' median ``|d e / d delay|`` times ``hypot(d_bar, s_bar)``."""
    w = 1.0 / np.asarray(s) ** 2
    d_bar = float(np.sum(w * np.asarray(d)) / np.sum(w))
    s_bar = float(1.0 / np.sqrt(np.sum(w)))
    return d_bar, s_bar, float(np.median(slope)) * float(np.hypot(d_bar, s_bar))


def delay_systematic(logs: list[Any]) -> tuple[float, list[str]]:
    """The error of e from the runs' vibrometer delays, and notes (0 and none if none).

    In quadrature:

    * runs whose undeclared delay was measured and applied: ``|d e / d delay|`` times the
      delay's uncertainty, its standard error and the change of the estimate when the fits
      moved out of the step's unsettled part
      (:attr:`~rattle_lab.detect.ImpactLog.velocity_delay_window_s`) in quadrature, and in
      quadrature with that the change of e itself when they moved
      (:attr:`~rattle_lab.detect.ImpactLog.e_window_change`); the same chain times every
      run alike, so this is not averaged down over runs: the median over the runs;
    * runs whose undeclared delay was measured and left at zero (indistinguishable from it):
      the one chain's delay pooled over those runs (inverse-variance mean ``d`` with
      standard error ``s``); reading at zero errs by the true delay, whose root mean square
      is ``hypot(d, s)``, times the runs' median ``|d e / d delay|``.

    * runs whose declared delay was checked against the flights' own impact instants
      (``velocity_delay_method = "flights"``, nothing applied): the declaration stands,
      and what the instants measure after it (pooled as above) is how far reading at it
      may err, times the runs' median ``|d e / d delay|``.

    * runs whose decoder was identified and equalised (:attr:`~rattle_lab.detect.ImpactLog.decoder`):
      its delay stands, and what the impacts measure after it (the steps' centroids, or the
      flights' instants), in quadrature with its standard error, is how far it may be off,
      times ``|d e / d delay|`` (the median over the runs, with the first part).

    Declared delays otherwise add nothing here (a contradiction is flagged instead).
    """
    vals, deltas = [], []
    d_u, s_u, slope_u, fs_u = [], [], [], []
    d_c, s_c, slope_c, fs_c = [], [], [], []
    for log in logs:
        if log is None or not np.isfinite(log.e_per_delay_s):
            continue
        checked = (getattr(log, "velocity_delay_method", "steps") == "flights"
                   and not log.velocity_delay_applied_s)
        if getattr(log, "decoder", ""):
            # an identified and equalised decoder: its delay stands, and what the steps
            # measure after it (with its standard error) is how far it may be off
            rest = log.velocity_delay_s - log.velocity_delay_applied_s
            sd = float(np.hypot(np.nan_to_num(rest), np.nan_to_num(log.velocity_delay_stderr_s)))
            vals.append(abs(log.e_per_delay_s) * sd)
            deltas.append(sd * log.fs_hz)
        elif checked:
            if np.isfinite(log.velocity_delay_s) and np.isfinite(log.velocity_delay_stderr_s):
                d_c.append(log.velocity_delay_s)
                s_c.append(max(log.velocity_delay_stderr_s, _POOL_FLOOR_SAMPLES / log.fs_hz))
                slope_c.append(abs(log.e_per_delay_s))
                fs_c.append(log.fs_hz)
        elif log.velocity_delay_applied_s:
            sd = float(np.hypot(np.nan_to_num(log.velocity_delay_stderr_s),
                                np.nan_to_num(log.velocity_delay_window_s)))
            vals.append(float(np.hypot(abs(log.e_per_delay_s) * sd,
                                       np.nan_to_num(log.e_window_change))))
            deltas.append(sd * log.fs_hz)
        elif np.isfinite(log.velocity_delay_s) and np.isfinite(log.velocity_delay_stderr_s):
            d_u.append(log.velocity_delay_s)
            s_u.append(max(log.velocity_delay_stderr_s, _POOL_FLOOR_SAMPLES / log.fs_hz))
            slope_u.append(abs(log.e_per_delay_s))
            fs_u.append(log.fs_hz)
    notes = []
    se_a = se_u = 0.0
    if vals:
        se_a = float(np.median(vals))
        notes.append(f"the vibrometer's delay was measured from the impacts and applied in "
                     f"{len(vals)} runs; its uncertainty (median {np.median(deltas):.3f} samples: "
                     "standard error and the estimate's dependence on the fit windows) and the "
                     f"decoder's step response read by the velocity fits move e by {se_a:.4f} "
                     "(median of the runs), added to the standard error")
    if d_u:
        d_bar, s_bar, se_u = _pooled_rms(d_u, s_u, slope_u)
        fs = float(np.median(fs_u))
        notes.append(f"the vibrometer's delay is not declared; measured from the impacts in "
                     f"{len(d_u)} runs it is {1e6 * d_bar:.2f} +- {1e6 * s_bar:.2f} us "
                     f"({d_bar * fs:.3f} samples) and was left at zero (not distinguishable from "
                     "zero, or its per-impact values scatter by a sample or more: steps the "
                     "sampling does not resolve, or the plate's higher modes ringing in the "
                     f"vibrometer); reading at zero moves e by up to {se_u:.4f} (root mean "
                     "square), added to the standard error")
    se_c = 0.0
    if d_c:
        d_bar, s_bar, se_c = _pooled_rms(d_c, s_c, slope_c)
        fs = float(np.median(fs_c))
        notes.append(f"the declared delay is used; the impacts' own instants in the velocity "
                     f"(where the flight model's displacements either side meet, {len(d_c)} "
                     f"runs) lie {1e6 * d_bar:.2f} +- {1e6 * s_bar:.2f} us ({d_bar * fs:.3f} "
                     f"samples) after it; reading at the declared delay may err by that: e "
                     f"moves by up to {se_c:.4f} (root mean square), added to the standard "
                     "error")
    return float(np.sqrt(se_a**2 + se_u**2 + se_c**2)), notes


#: The runs' readings of e disagree where their chi-square about the weighted mean has a
#: probability below this (e is one property of the contact, read by one vibrometer).
_CONSISTENCY_P = 1e-3


def _chi2_p(m: np.ndarray, s: np.ndarray) -> float:
    """Probability of the runs' medians ``m`` (errors ``s``) scattering as much about their
    inverse-variance mean, were they one value."""
    from scipy.stats import chi2

    w = 1.0 / np.maximum(s, 1e-12) ** 2
    mean = float(np.sum(w * m) / np.sum(w))
    return float(chi2.sf(float(np.sum(w * (m - mean) ** 2)), m.size - 1))


def measurand_systematic(logs: list[Any]) -> tuple[float, str]:
    """The error of e from runs whose vibrometer measurand could not be established.

    Such runs keep the relative reading and record how far the absolute reading's e lies
    from it (:attr:`~rattle_lab.detect.ImpactLog.e_measurand_diff`).  Across two or more
    such runs, e (one property of the contact, read by one vibrometer) must come out the
    same in every run for the right reading: where the relative readings agree (chi-square
    probability above :data:`_CONSISTENCY_P`) and the absolute ones do not, the relative
    reading is established across the runs and nothing is added.  Otherwise, were the
    vibrometer absolute, e would move by the ratio-weighted mean of the differences over all
    runs with ratios (0 for the runs whose measurand is known): that mean's magnitude is
    returned, to be added to e's standard error in quadrature, so that the 95 % interval
    spans both readings.
    """
    n_tot, shift = 0, 0.0
    m0s, s0s, m1s, s1s = [], [], [], []
    for log in logs:
        if log is None:
            continue
        e = np.asarray(log.e, dtype=float)
        n = int(np.sum(np.isfinite(e)))
        n_tot += n
        diff = float(getattr(log, "e_measurand_diff", 0.0) or 0.0)
        if diff and n >= 5:
            shift += n * diff
            m0, s0 = median_and_error(e)
            m0s.append(m0)
            s0s.append(s0)
            m1s.append(m0 + diff)
            s1s.append(float(getattr(log, "e_measurand_alt_se", s0)))
    if not m0s or not n_tot:
        return 0.0, ""
    if len(m0s) >= 2:
        p0 = _chi2_p(np.asarray(m0s), np.asarray(s0s))
        p1 = _chi2_p(np.asarray(m1s), np.asarray(s1s))
        if p0 >= _CONSISTENCY_P > p1:
            return 0.0, (f"the vibrometer's measurand is not declared and no single run "
                         f"establishes it; across the {len(m0s)} runs the relative readings "
                         f"of e agree (chi-square probability {p0:.2g}) and the absolute ones "
                         f"do not ({p1:.2g}): read as relative to the striker")
    se = abs(shift / n_tot)
    return se, (f"the vibrometer's measurand is neither declared nor established from the data "
                f"in {len(m0s)} runs: they are read as relative to the striker; were it "
                f"absolute, e would move by {shift / n_tot:+.4f}, added to the standard error")



def runs_thresholds(runs: list[RunResult]) -> list[Threshold]:
    """The measured ramp thresholds of ``runs``."""
    return [r.threshold for r in runs if r.threshold is not None]


def _crossing_curve(thresholds: list[Threshold], freq_hz: np.ndarray) -> np.ndarray:
    """Upward crossing levels (:func:`~rattle_lab.detect.thresholds.crossing_level_ms2`) per frequency.

    Mean over the runs at each frequency, as :func:`~rattle_lab.detect.thresholds.tabulate_thresholds`;
    a threshold without a measured ramp keeps its impact level.
    """
    out = np.full(freq_hz.size, np.nan)
    for i, f in enumerate(freq_hz):
        vals = []
        for t in thresholds:
            if t.freq_hz == f and t.direction == "up" and np.isfinite(t.accel_ms2):
                c = crossing_level_ms2(t)
                vals.append(c if np.isfinite(c) else t.accel_ms2)
        if vals:
            out[i] = float(np.mean(vals))
    return out


__all__ = ["CAUSE_QUANTITIES", "FLAG_DELAY_CONTRADICTED", "FLAG_DELAY_ESTIMATED", "delay_systematic",
           "FLAG_MEASURAND_INFERRED", "FLAG_MEASURAND_UNDETERMINED", "SHOCK_QUANTITIES",
           "infer_measurand", "measurand_systematic", "paired_plate_channels", "relative_to_striker", "run_chain_flags",
           "runs_thresholds", "transient_shocks", "velocity_delay_flags"]
