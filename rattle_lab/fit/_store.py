"""The fit of a store's detections: thresholds, grazing, restitution, SPL laws.

The per-run analysis (:func:`~rattle_lab.detect.analyse_run`, re-exported here) lives in
:mod:`rattle_lab.detect` (issue 29).  Over the store: the threshold curve, the grazing fit
(>= 4 upward thresholds), ``e`` from velocity ratios and from the downward thresholds, and
the SPL laws.
"""

from __future__ import annotations

import dataclasses
import math
import os
import sys
from collections.abc import Mapping
from typing import Any

import numpy as np

from rattle_lab._version import __version__
from rattle_lab.acoustics import campaign_background  # [issue 26]
from rattle_lab.detect import DetectParams, analyse_run
from rattle_lab.exceptions import RattleLabError
from rattle_lab.records import Participation, resolve_participation
from rattle_lab.fit._results import RunResult, StoreFit
from rattle_lab.store import (input_hashes, open_stored_record, read_catalogue)
from rattle_lab.detect.thresholds import Threshold, tabulate_thresholds
from ._chain import (_crossing_curve, delay_systematic, measurand_systematic,  # noqa: F401
                     paired_plate_channels, relative_to_striker, run_chain_flags, runs_thresholds,
                     transient_shocks)
from ._grazing import fit_grazing
from ._plate_check import check_plate_model
from ._grazing_ramp import fit_grazing_ramp
from ._damping import fit_zeta_ramp
from ._restitution import (FLAG_RING_MODES_ONE_RUN, FLAG_RINGING_UNCORRECTED,
                           fit_restitution_down, ratios_of_runs)
from ._spl_law import fit_db_law, fit_linear_law
from ._estimates import (DownRestitution, Fits, GrazingSummary, RampDamping, RampGrazing,
                         SplLawSummary)
from ._summary import (FitSummary, ParticipationInfo, RunRow, SkippedRun, ThresholdTable,
                       TransientRun)
from ._params import FIT_KEYS, check_fit_params, load_pipeline


def _f(x: Any) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def json_ready(obj: Any) -> Any:
    """A copy of ``obj`` that :func:`json.dumps` writes as strict JSON.

    Dicts and lists/tuples are walked recursively (tuples become lists); NumPy
    scalars become Python ``int``, ``float`` or ``bool``; non-finite floats
    (NaN, +-Inf) become ``None``.  Everything else is returned unchanged.
    This is how :func:`fit_store` cleans the provenance it writes.  A
    :class:`~rattle_lab.fit.FitSummary` is returned unchanged: it holds JSON values
    by construction (its ``to_dict()`` is the JSON form).

    Parameters
    ----------
    obj : Any
        A nest of dicts, lists, tuples and scalars (e.g. from :func:`summarise_fits`).

    Returns
    -------
    Any
        The cleaned copy; ``obj`` is not modified.

    Examples
    --------
    >>> import numpy as np
    >>> json_ready({"a": (np.float64(1.5), float("nan")), "n": np.int64(3), "ok": np.bool_(True)})
    {'a': [1.5, None], 'n': 3, 'ok': True}
    """
    if isinstance(obj, dict):
        return {k: json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_ready(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return _f(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def store_participation(store: str | os.PathLike[str], given: float | None,
                        source: str = "pipeline") -> Participation:
    """The modal participation ``Q1/Q2`` for a fit of ``store``, and where it came from.

    ``given`` (a pipeline's or the command line's ``participation``) wins; else the
    records' rig metadata (``modal_participation``, or the plate geometry through the plate
    model); else 1.0, with the data-quality flag ``participation_assumed``.  See
    :func:`rattle_lab.records._chain.resolve_participation`.
    """
    return resolve_participation([] if given is not None else store_rigs(store), given, source)


def store_rigs(store: str | os.PathLike[str]) -> list[Any]:
    """The rig of every record in ``store`` (in catalogue order)."""
    rigs = []
    catalogue = read_catalogue(store, level="runs")
    for key in dict.fromkeys(catalogue["input_key"]):
        record = open_stored_record(store, key)
        try:
            rigs.append(record.rig)
        finally:
            record.close()
    return rigs


def fit_runs(store: str | os.PathLike[str], runs: list[RunResult], *,
             detect: DetectParams | Mapping[str, Any], fit: Mapping[str, Any], curve: Any = None,
             participation_source: str = "pipeline",
             provenance: Mapping[str, Any] | None = None) -> StoreFit:
    """The store-level fits of per-run detections: what ``fit`` and the pipeline both write.

    The one place that turns :func:`analyse_run`'s results into a :class:`StoreFit`:
    the threshold table (unless ``curve`` is given), the participation (from ``fit``
    or the store's rig metadata, see :func:`store_participation`), the summary of
    :func:`summarise_fits` and the provenance (function, parameters, versions and
    the inputs' content hashes).

    Parameters
    ----------
    store : path-like
        The ingest store the runs came from.
    runs : list of RunResult
        Every run's detections, skipped runs included.
    detect : DetectParams or mapping
        The detection parameters used (provenance: :meth:`DetectParams.to_dict`).
    fit : mapping
        The fit parameters used (complete: see ``FIT_KEYS``).
    curve : ThresholdCurve, optional
        The threshold table, when already tabulated (the pipeline caches it).
    participation_source : str
        Where ``fit["participation"]`` came from, when given.
    provenance : mapping, optional
        Further provenance entries (the pipeline adds its name).

    Returns
    -------
    StoreFit
    """
    if curve is None:
        curve = tabulate_thresholds([r.threshold for r in runs if r.threshold is not None])
    rigs = store_rigs(store)
    given = fit.get("participation")
    participation = resolve_participation([] if given is not None else rigs, given,
                                          participation_source)
    summary = summarise_fits(list(runs), curve, fit, participation=participation)
    # issue 28: the rig's plate model against the fitted f_s (flag plate_model_disagrees)
    summary = check_plate_model(summary, rigs, participation,
                                lambda p: summarise_fits(list(runs), curve, fit, participation=p))
    prov = {"function": "rattle_lab.workflow.fit_store", **dict(provenance or {}),
            "rattle_lab_version": __version__, "python": sys.version.split()[0],
            "parameters": {"detect": DetectParams.from_mapping(detect).to_dict(),
                           "fit": dict(fit)},
            "inputs": input_hashes(store, list(dict.fromkeys(r.input_key for r in runs)))}
    return StoreFit(tuple(runs), curve, summary, json_ready(prov))


def restitution_down_summary(thresholds: list[Threshold], grazing: GrazingSummary,
                             fit: Mapping[str, Any], *, e_guess: float = 0.6
                             ) -> tuple[DownRestitution | None, RampDamping | None, dict[str, str]]:
    """``e`` from the downward thresholds (and the ramp-model damping) for the summary.

    With ``fit["restitution_method"] == "ramp"`` (default), ``zeta`` is first refitted to
    the upward thresholds with the ramp model (:func:`~rattle_lab.fit.fit_zeta_ramp`,
    entry ``damping_ramp``; the grazing fit's ``zeta`` carries the ramp lag), then ``e``
    is fitted with it and its standard error propagated
    (:func:`~rattle_lab.fit.fit_restitution_down`).  With ``"quasi-static"``, ``e`` is
    fitted to the saddle-node with the grazing fit's ``zeta``.

    Parameters
    ----------
    thresholds : list of Threshold
        Every measured ramp threshold (up and down).
    grazing : GrazingSummary
        Supplies ``gap_m``, ``f_s_hz``, ``participation`` (and ``zeta`` as a start).
    fit : mapping
        Fit parameters (``FIT_KEYS``).
    e_guess : float
        ``e`` for the confirming impacts of the upward replays (the velocity-ratio mean).

    Returns
    -------
    restitution_down : DownRestitution or None
        ``e`` with its stderr, 2 sigma interval, method, runs, the ``zeta`` used and the
        part of the stderr propagated from it, residuals and notes.
    damping_ramp : RampDamping or None
        With the ramp method: ``zeta`` from the ramp replay.
    not_fitted : dict
        Entry name -> reason, for what could not be fitted.
    """
    method = fit.get("restitution_method", FIT_KEYS["restitution_method"])
    n_confirm = int(fit.get("n_confirm", FIT_KEYS["n_confirm"]))
    hold = int(fit.get("level_hold_periods", FIT_KEYS["level_hold_periods"]))
    p = grazing.params
    modal: dict[str, Any] = dict(gap_m=p["gap_m"].value, f_s_hz=p["f_s_hz"].value,
                                 participation=p["participation"].value)
    down, ramp = None, None
    missing: dict[str, str] = {}
    zeta, zeta_se, zeta_note = p["zeta"].float_value, p["zeta"].stderr, ""
    if method == "ramp":
        try:
            ramp = fit_zeta_ramp(thresholds, zeta0=zeta, e=e_guess, n_confirm=n_confirm,
                                 level_hold_periods=hold, **modal)
            zeta, zeta_se = ramp.float_value, ramp.stderr
        except RattleLabError as exc:
            missing["damping_ramp"] = str(exc)
            zeta_note = f"zeta from the grazing fit (ramp-model damping not fitted: {exc})"
    try:
        down = fit_restitution_down(thresholds, zeta=zeta, method=method, n_confirm=n_confirm,
                                    zeta_stderr=0.0 if zeta_se is None else zeta_se,
                                    level_hold_periods=hold, **modal)
        if zeta_note:
            down = dataclasses.replace(down, notes=down.notes + (zeta_note,))
    except RattleLabError as exc:
        missing["restitution_down"] = str(exc)
    return down, ramp, missing


def _with_biases(grazing: GrazingSummary, ramp: RampDamping | None,
                 rg: RampGrazing | None = None) -> GrazingSummary:
    """The grazing fit with the biases of its ``gap_m`` and ``zeta`` named against the
    ramp-corrected fits (their intervals leave the ramp lag out)."""
    params = grazing.params
    if rg is not None:
        for n in ("gap_m", "zeta"):
            ref, q = rg.params[n].value, params[n]
            if q.value is not None and ref:
                params[n] = dataclasses.replace(q, bias_rel=q.value / ref - 1.0)
        gap = params["gap_m"]
        if gap.bias_rel is not None:
            params["gap_m"] = dataclasses.replace(gap, bias_note=(
                f"the ramp lag bends eq. (3.4): gap is {100 * gap.bias_rel:+.2f} % against the "
                "ramp-corrected fit (grazing_ramp), which corrects it; this interval does not "
                "include the lag"))
    zeta = params["zeta"]
    if ramp is not None and ramp.value is not None and ramp.value > 0 \
            and zeta.value is not None:
        # issue 15: name the bias of eq. (3.4)'s zeta, whose interval leaves it out
        bias = zeta.value / ramp.value - 1.0
        params["zeta"] = dataclasses.replace(zeta, bias_rel=bias, bias_note=(
            f"eq. (3.4) reads the ramp lag as damping: zeta is {100 * bias:+.1f} % against "
            "the ramp replay (damping_ramp), which corrects it; this interval does not "
            "include the lag"))
    return dataclasses.replace(grazing, gap_m=params["gap_m"], zeta=params["zeta"])


def summarise_fits(runs: list[RunResult], curve: Any, fit: Mapping[str, Any], *,
                   participation: Participation | None = None,
                   flags: list[str] | None = None) -> FitSummary:
    """Fit the store-level models to per-run detections; the summary ``/results`` stores.

    From the per-run results of :func:`analyse_run` and the threshold table of
    :func:`rattle_lab.detect.thresholds.tabulate_thresholds`: the eq. (3.4) grazing fit
    (gap, f_s, zeta; needs >= 4 upward thresholds), the coefficient of restitution
    from velocity ratios and from the disappearance thresholds, and the SPL laws
    (first peak, maximum peak, RMS per impact) against impact velocity.  A fit that
    cannot be made is named in ``not_fitted`` with the reason; nothing raises for it.

    Parameters
    ----------
    runs : list of RunResult
        Per-run detection results (any order; skipped runs are counted and listed).
    curve : ThresholdCurve
        Onset/disappearance thresholds against frequency.
    fit : mapping
        Fit parameters: every key of ``FIT_KEYS`` (``participation``,
        ``vary_participation``, ``outlier_k``, ``conf_interval``, ...).
    participation : Participation, optional
        The participation and its source (:func:`store_participation`); without it,
        ``fit["participation"]``, or 1.0 flagged ``participation_assumed`` when that is None.
    flags : list of str, optional
        Further data-quality flags, after those of each run's measurement chain
        (``"input_key/run_id: flag"``, see :func:`run_chain_flags`).

    Returns
    -------
    FitSummary
        Run counts, skipped runs (with reasons), one row per analysed run (protocol,
        freq_hz, n_impacts, pattern, delays in s, SPL in dB, threshold in m/s^2,
        acoustics), the threshold table, the fits (``grazing``: gap_m, f_s_hz, zeta,
        participation with stderr, unit and 95 % ci, plus correlation; ``restitution_ratio``;
        ``restitution_down`` and ``damping_ramp``: see :func:`restitution_down_summary`;
        ``spl_law_first|max|rms``: linear and dB laws), ``not_fitted`` (fit name ->
        reason), the transient runs' shocks (each channel, cause first), the participation
        (value, source) and ``data_quality`` flags (e.g. ``participation_assumed``, and each
        run's measurement-chain flags).  :meth:`FitSummary.to_dict` is its JSON form.

    Raises
    ------
    KeyError
        If ``fit`` lacks a key of ``FIT_KEYS`` the fits need.
    """
    if participation is None:
        participation = resolve_participation([], fit.get("participation"), "pipeline")
    fit = {**fit, "participation": participation.value}
    ok = [r for r in runs if r.status == "ok"]
    chain = tuple(f"{r.input_key}/{r.run_id}: {f}" for r in runs for f in r.chain_flags)
    missing: dict[str, str] = {}
    grazing_fit, grazing = None, None
    n_up = int(np.isfinite(curve.up_ms2).sum())
    if n_up >= 4:
        try:
            # eq. (3.4) models the level where the response reaches the gap: the crossing,
            # half a forcing period before the first impact on average (issue 15)
            up_crossing = _crossing_curve(runs_thresholds(ok), curve.freq_hz)
            grazing_fit = fit_grazing(curve.freq_hz, up_crossing,
                                      participation=fit["participation"],
                                      vary_participation=fit["vary_participation"],
                                      outlier_k=fit["outlier_k"],
                                      conf_interval=fit["conf_interval"])
        except RattleLabError as exc:
            missing["grazing"] = str(exc)
    else:
        missing["grazing"] = f"needs >= 4 upward thresholds, had {n_up}"
    # issue 15: the higher modes' share of each velocity jump, pooled over the runs whose
    # flight model gave one, is taken off every run's ratios
    rs = ratios_of_runs([r.impacts for r in ok if r.impacts is not None])
    ratio, ringing_flags = None, list[str]()
    notes = list[str]()
    if rs.ringing_runs:
        notes.append(f"the plate's higher modes ring after each impact: "
                     f"{100 * (math.nan if rs.ringing_share is None else rs.ringing_share):.1f} % "
                     "of each measured velocity "
                     f"jump (median of {rs.ringing_runs} runs' flight models) is theirs and is "
                     "taken off the ratios"
                     + ("" if rs.ringing_share_stderr is not None else "; one run: its error "
                        "is not in the standard error"))
    carried = [r.impacts for r in ok if r.impacts is not None and r.impacts.ring_modes]
    if carried:
        modes = carried[0].ring_modes
        n_src = max(int(log.params.ring_modes_runs) for log in carried)
        where = (f"found across {n_src} runs" if n_src > 1 else "found in one run"
                 if n_src == 1 else "given")
        n_with = sum(1 for log in carried if np.isfinite(log.v_in_m_s).any())
        fund = carried[0].params.ring_fundamental
        notes.append("the plate's higher modes ring after each impact: modes "
                     + ", ".join(f"{f:.1f} Hz (decay {s:.1f} 1/s)" for f, s in modes)
                     + f" {where}"
                     + (f", with the fundamental: {fund[0]:.2f} Hz decaying at {fund[1]:.2f} "
                        "1/s, from all those runs together" if fund else "")
                     + f"; in {n_with} runs v_in and v_out are the flight model's "
                     "with each impact's ringing carried on over the later flights (impacts "
                     "it gives no velocities are left out)")
        if n_src == 1:
            notes.append("one run only: within a run the modes' tails and the "
                         "fundamental's free response can trade off (single ramps of "
                         "the independent generator gave e from -10 % to +10 %); the "
                         "runs of a campaign at other frequencies pin the modes down")
            ringing_flags.append(FLAG_RING_MODES_ONE_RUN)
    if rs.ringing_runs_unmeasured:
        notes.append(f"the plate's higher modes ring after the impacts in "
                     f"{rs.ringing_runs_unmeasured} runs, but no run's flight model "
                     "measured their share of the velocity jumps and no modes were found "
                     "across the runs: these ratios include them and are biased; e from the "
                     "downward thresholds does not depend on them")
        ringing_flags.append(FLAG_RINGING_UNCORRECTED)
    # issue 28: an error of a measured vibrometer delay moves every ratio of a run alike
    delay_se, delay_notes = delay_systematic([r.impacts for r in ok])
    notes.extend(delay_notes)
    # issue 28: an undeclared measurand the data could not establish: both readings inside
    measurand_se, measurand_note = measurand_systematic([r.impacts for r in ok])
    if measurand_note:
        notes.append(measurand_note)
    # the ramp replays need an e only for their confirming impacts (the onset hardly
    # depends on it): a ratio outside [0, 1] (local fits that read a ringing plate's tails,
    # e 1.08 on benchmarks/ringing_cost.py's campaign) must not cost the ramp-corrected fits
    e_guess = rs.value if (rs.n and rs.value is not None
                           and 0.0 <= rs.value <= 1.0) else 0.6
    if rs.n:
        se = math.nan if rs.stderr is None else rs.stderr
        ratio = dataclasses.replace(rs, stderr=float(np.hypot(np.hypot(se, delay_se),
                                                              measurand_se)),
                                    notes=tuple(notes))
    else:
        missing["restitution_ratio"] = " ".join(
            ["no impact with a velocity on both sides"] + [f"({n})" for n in notes])
    # issue 15: the ramp lag biases eq. (3.4)'s gap as well as its zeta; the ramp-corrected
    # fit removes each threshold's replayed lag and gives gap, f_s and zeta together
    rg: RampGrazing | None = None
    if (grazing_fit is not None and not fit["vary_participation"]
            and fit.get("restitution_method", FIT_KEYS["restitution_method"]) == "ramp"):
        try:
            rg = fit_grazing_ramp(runs_thresholds(ok), participation=fit["participation"],
                                  e=e_guess, n_confirm=int(fit.get("n_confirm", 3)),
                                  level_hold_periods=int(fit.get("level_hold_periods", 1)))
        except RattleLabError as exc:
            missing["grazing_ramp"] = str(exc)
    down, ramp = None, None
    if grazing_fit is not None and np.isfinite(curve.down_ms2).any():
        down, ramp, missing_down = restitution_down_summary(
            [r.threshold for r in ok if r.threshold is not None],
            rg.grazing if rg is not None and rg.grazing is not None else grazing_fit, fit,
            e_guess=e_guess)
        missing.update(missing_down)
    else:
        missing["restitution_down"] = "needs a grazing fit and downward thresholds"
    if grazing_fit is not None:
        grazing = _with_biases(grazing_fit, ramp, rg)
    v = np.concatenate([np.abs(r.impacts.v_in_m_s) for r in ok if r.peaks is not None
                        and r.impacts is not None] or [np.zeros(0)])
    laws: dict[str, SplLawSummary] = {}
    for name in ("first", "max", "rms"):
        attr = {"first": "p_first_pa", "max": "p_max_pa", "rms": "p_rms_pa"}[name]
        pr = np.concatenate([getattr(r.peaks, attr) for r in ok if r.peaks is not None
                             and r.impacts is not None] or [np.zeros(0)])
        try:
            laws[f"spl_law_{name}"] = SplLawSummary(fit_linear_law(v, pr), fit_db_law(v, pr))
        except RattleLabError as exc:
            missing[f"spl_law_{name}"] = str(exc)
    # [issue 26] each run's rattle loudness against the background stretches of all runs
    acoustic = campaign_background([r.acoustics.summary() if r.acoustics is not None else None
                                    for r in ok])
    rows = [RunRow(r.input_key, r.run_id, r.protocol, r.freq_hz,
                   r.impacts.n_impacts if r.impacts else 0, r.pattern, r.acoustic_delay_s,
                   r.expected_delay_s, r.spl_rms_db, r.spl_rms_a_db,
                   r.threshold.accel_ms2 if r.threshold else None,
                   **(a or {}))  # [issue 17]
            for r, a in zip(ok, acoustic)]
    return FitSummary(
        n_runs=len(runs), n_ok=len(ok), runs=tuple(rows),
        skipped=tuple(SkippedRun(r.input_key, r.run_id, r.reason)
                      for r in runs if r.status == "skipped"),
        thresholds=ThresholdTable(curve.freq_hz, curve.up_ms2, curve.down_ms2,
                                  curve.hysteresis_ms2, curve.up_se_ms2, curve.down_se_ms2),
        fits=Fits(grazing=grazing, grazing_ramp=rg, restitution_ratio=ratio,
                  damping_ramp=ramp,
                  restitution_down=down, **laws),
        not_fitted=missing,
        participation=ParticipationInfo(participation.value, participation.source),
        # (a store of single shocks fits no modal law: the participation does not enter)
        data_quality=(tuple(participation.flags) if any(r.protocol != "transient" for r in ok)
                      else ()) + chain + tuple(ringing_flags)
        + tuple(flags or ()),
        transients=tuple(TransientRun(r.input_key, r.run_id, tuple(dict(c) for c in r.shocks))
                         for r in ok if r.protocol == "transient"))


__all__ = ["analyse_run", "check_fit_params", "fit_runs", "json_ready", "load_pipeline", "paired_plate_channels",
           "relative_to_striker", "restitution_down_summary", "run_chain_flags",
           "store_participation", "store_rigs", "summarise_fits", "transient_shocks"]
