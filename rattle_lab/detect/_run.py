"""The analysis of one run: its impacts, sound, pattern and ramp threshold.

Moved from :mod:`rattle_lab.fit._store` (issue 29: detection in one room).
:func:`analyse_run` turns one :class:`~rattle_lab.records.Run` into a :class:`RunResult`:
impacts from the plate velocity and/or plate acceleration (:func:`detect_impacts`) with
the vibrometer's delay and measurand checked against them; sound peaks, acoustic delay,
SPL and the acoustics with a microphone; the impact pattern with an excitation frequency;
the ramp threshold on ``amplitude_ramp_up/down`` runs with a base accelerometer; the shock
on every channel of a transient run.  A run without the channels it needs is *skipped*
with its reason; a run without impacts is a valid result.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from rattle_lab.acoustics import joined_acoustics, run_acoustics  # [issue 17, 26, 29]
from rattle_lab.exceptions import ParameterError
from rattle_lab.records import FLAG_MEASURAND_UNDECLARED, declared_delay_s
from ._chain import (SHOCK_QUANTITIES, _fs_of, _t0_of, infer_measurand, paired_plate_channels,
                     relative_to_striker, run_chain_flags, transient_shocks,
                     velocity_delay_flags)
from ._impacts import ImpactLog, Recognition, detect_impacts
from ._params import DetectParams
from ._patterns import impact_pattern
from ._segments import Span, core_mask, merge_arrays, merge_logs, segment_spans, segment_view
from ._sound import SoundPeaks, cross_correlation_delay, impulse_train, sound_peaks
from ._spl import a_weight, rms_spl_db, spl_db
from .thresholds import Threshold, ramp_threshold


@dataclass(frozen=True)
class RunResult:
    """Detection results of one run.

    Attributes
    ----------
    input_key, run_id, protocol : str
        Where the run is in the store and how it was excited.
    status : {"ok", "skipped"}
        ``"skipped"`` when the run lacks the channels needed (``reason`` says which).
    reason : str
        Why a run was skipped ("" otherwise).
    freq_hz : float
        Excitation frequency, Hz (NaN if not stated).
    channels_used : tuple of str
        Channel names used for detection.
    impacts : rattle_lab.detect.ImpactLog or None
        Detected impacts (possibly empty: a valid result).
    peaks : SoundPeaks or None
        Sound peaks after each impact (with a microphone).
    pattern : str
        Impact pattern (``"no impact"``, ``"1/1"``, ``"1/n"``, ``"several per cycle"``,
        ``"irregular"``; ``""`` without an excitation frequency).
    pattern_n : int
        ``n`` of a 1/n pattern.
    cycle_counts : ndarray
        Impacts per forcing cycle.
    acoustic_delay_s : float
        Impact-to-sound delay by cross-correlation over the run, s.
    expected_delay_s : float
        ``mic_distance_m / speed_of_sound``, s.
    spl_rms_db, spl_rms_a_db : float
        RMS sound pressure level of the run, unweighted and A-weighted, dB re 20 uPa.
    threshold : Threshold or None
        Ramp threshold (ramp runs with a base accelerometer).
    acoustics : RunAcoustics or None
        LAeq, LAFmax, LCpeak, third-octave bands, loudness, sharpness and the
        microphone's calibration (:func:`rattle_lab.acoustics.run_acoustics`).
    chain_flags : tuple of str
        Named data-quality flags of the run's measurement chain
        (:func:`~rattle_lab.detect.run_chain_flags`).
    shocks : tuple of dict
        Transient runs: the shock found on each channel, the cause first
        (:func:`~rattle_lab.detect.transient_shocks`); empty otherwise.
    """

    input_key: str
    run_id: str
    protocol: str
    status: str
    reason: str = ""
    freq_hz: float = float("nan")
    channels_used: tuple[str, ...] = ()
    impacts: ImpactLog | None = None
    peaks: SoundPeaks | None = None
    pattern: str = ""
    pattern_n: int = 0
    cycle_counts: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    acoustic_delay_s: float = float("nan")
    expected_delay_s: float = float("nan")
    spl_rms_db: float = float("nan")
    spl_rms_a_db: float = float("nan")
    threshold: Threshold | None = None
    acoustics: Any = None  # [issue 17] RunAcoustics (levels, loudness) with a microphone
    chain_flags: tuple[str, ...] = ()
    shocks: tuple[dict[str, Any], ...] = ()



def _analyse_transient(run: Any, detect: DetectParams, base: dict[str, Any]) -> RunResult:
    """One event per transient run: the shock on the cause channel (see :func:`transient_shocks`)."""
    rows = transient_shocks(run, on=float(detect.on), channel=detect.channel)
    if not rows:
        return RunResult(status="skipped", reason="transient run without a channel to find its "
                         "shock in (" + ", ".join(SHOCK_QUANTITIES) + ")", **base)
    cause = rows[0]
    ch = run.channel(cause["channel"])
    t = np.array([cause["onset_s"]]) if cause["found"] else np.zeros(0)
    nan = np.full(t.size, np.nan)
    log = ImpactLog(t_s=t, onset_s=t.copy(), v_in_m_s=nan, v_out_m_s=nan.copy(), e=nan.copy(),
                    strength=np.array([cause["strength"]])[:t.size], channels=(ch.name,),
                    fs_hz=_fs_of(run, ch))
    return RunResult(status="ok", channels_used=tuple(r["channel"] for r in rows), impacts=log,
                     pattern="single shock" if t.size else "no shock", pattern_n=int(t.size),
                     shocks=tuple(rows), **base)


def _by_quantity(run: Any) -> dict[str, Any]:
    """The run's first channel of each quantity."""
    by_q: dict[str, Any] = {}
    for ch in run.channels:
        by_q.setdefault(ch.quantity, ch)
    return by_q


@dataclass(frozen=True)
class _Plan:
    """What :func:`analyse_run` decides before reading samples: the run's identity and chain
    flags (``base``), the plate channels, the forced-mode frequency of the velocity fits,
    whether the vibrometer's delay is declared, and the segments (None: whole)."""

    base: dict[str, Any]
    vel: str | None
    acc: str | None
    f_fit: float | None
    delay_declared: bool
    spans: list[Span] | None

    def plate(self, run: Any) -> tuple[Any, Any]:
        return tuple(run.channel(n) if n is not None else None  # type: ignore[return-value]
                     for n in (self.vel, self.acc))


def _plan(input_key: str, run: Any, detect: DetectParams) -> _Plan | RunResult:
    by_q = _by_quantity(run)
    freq = float(run.excitation_freq_hz) if run.excitation_freq_hz else float("nan")
    vel, acc = by_q.get("plate_velocity"), by_q.get("plate_acceleration")
    base = dict(input_key=input_key, run_id=run.run_id, protocol=run.protocol, freq_hz=freq,
                chain_flags=tuple(run_chain_flags(run)))
    if run.protocol == "transient":
        return _analyse_transient(run, detect, base)
    wanted = detect.channel or getattr(run, "detect_channel", None)
    if wanted is not None:
        named = next((c for c in run.channels if c.name == wanted), None)
        if named is None:
            return RunResult(status="skipped", reason=f"no channel {wanted!r} to detect on",
                             **base)
        if named.quantity not in ("plate_velocity", "plate_acceleration"):
            return RunResult(status="skipped", reason=f"channel {wanted!r} measures "
                             f"{named.quantity}: impacts are detected on a plate_velocity or "
                             "plate_acceleration", **base)
        vel, acc = (named, None) if named.quantity == "plate_velocity" else (None, named)
    if vel is None and acc is None:
        return RunResult(status="skipped", reason="no plate_velocity or plate_acceleration channel",
                         **base)
    used = [c for c in (vel, acc) if c is not None]
    # a constant excitation frequency lets the velocity fits use the forced-mode basis
    f_end = getattr(run, "freq_end_hz", None)
    fs_plate = max(_fs_of(run, c) for c in used)   # the pair's grid (paired_plate_channels)
    f_fit = freq if (math.isfinite(freq) and 0 < freq < fs_plate / 2
                     and (f_end is None or f_end == freq)) else None
    delay_declared = vel is not None and declared_delay_s(vel) is not None
    return _Plan(base, vel.name if vel is not None else None,
                 acc.name if acc is not None else None, f_fit, delay_declared,
                 segment_spans(run, detect, *used))


def analyse_run(input_key: str, run: Any, *, detect: DetectParams | Mapping[str, Any] | None,
                fit: Mapping[str, Any], mic_distance_m: float | None = None,
                reuse: RunResult | None = None) -> RunResult:
    """Detection results of one :class:`~rattle_lab.records.Run`.

    Parameters
    ----------
    input_key : str
        The run's record in the store.
    run : Run
    detect : DetectParams or mapping
        The ``[detect]`` parameters (a mapping is read with :meth:`DetectParams.from_mapping`).
    fit : mapping
        The ``[fit]`` parameters the per-run analysis reads: ``speed_of_sound_m_s``,
        ``n_confirm``, ``sound_field``, ``loudness`` and ``ecma418_s``.
    mic_distance_m : float, optional
        The rig's microphone distance (the expected acoustic delay).
    reuse : RunResult, optional
        This run's result from an earlier call with the same ``fit`` and the same
        ``[detect]`` parameters but for the velocity model's (``velocity_model``,
        ``ring_modes``, ``ring_modes_runs``; the caller's to ensure: the campaign's ringing
        passes, :func:`rattle_lab.workflow.detect_runs`).  Where the impacts come out at the
        same times, bit for bit, what follows from their times alone (the sound peaks,
        acoustic delay, levels and acoustics, pattern and threshold) is taken from it
        instead of being computed again; otherwise it is ignored.

    Raises
    ------
    ParameterError
        For an unknown ``[detect]`` key or a value out of range.
    """
    detect = DetectParams.from_mapping(detect)
    plan = _plan(input_key, run, detect)
    if isinstance(plan, RunResult):
        return plan
    if plan.spans is not None:
        return _analyse_segments(input_key, run, plan, detect, fit, mic_distance_m, reuse)
    by_q = _by_quantity(run)
    freq, base = plan.base["freq_hz"], dict(plan.base)
    vel, acc = plan.plate(run)
    used = [c for c in (vel, acc) if c is not None]
    f_fit, delay_declared = plan.f_fit, plan.delay_declared
    # issue 15: each channel's time base less its declared filter delay; two channels at
    # different rates or offsets are brought onto the grid of the faster one before pairing
    recognised = None
    if (reuse is not None and reuse.impacts is not None
            and (reuse.input_key, reuse.run_id) == (input_key, run.run_id)):
        # the first pass's impacts: only the velocity model is applied again
        recognised = reuse.impacts.recognition
    log, fs, t0, duration, flags = _impact_log(run, by_q, vel, acc, detect, f_fit,
                                               delay_declared, recognised)
    base["chain_flags"] = _with_log_flags(base["chain_flags"], log, delay_declared, flags)
    reused = reused_result(reuse, input_key, run.run_id, log, base["chain_flags"])
    if reused is not None:
        # the same impact times: the same sound, pattern and threshold (issue 29: the
        # ringing passes detect again for the velocities only)
        return reused
    names = tuple(c.name for c in used)
    pattern, pattern_n, counts = _pattern(run, log, freq, t0, duration)
    peaks, delay, expected, spl, spl_a = None, np.nan, np.nan, np.nan, np.nan
    acoustic = None  # [issue 17]
    mic = by_q.get("sound_pressure")
    if mic is not None:
        fs_mic = _fs_of(run, mic)
        p = mic.read()
        t0_mic = _t0_of(run, mic)
        names = names + (mic.name,)
        peaks = _peaks(p, fs_mic, t0_mic, log.t_s, detect, fit, mic_distance_m, f_fit)
        spl = rms_spl_db(p)
        spl_a = rms_spl_db(p, fs_mic, a_weighted=True)
        if log.n_impacts:
            train = impulse_train(log.t_s, p.size, fs_mic, t0_mic)
            delay = cross_correlation_delay(train, p, fs_mic, max_lag_s=detect.max_lag_s)
        if mic_distance_m:
            expected = mic_distance_m / float(fit.get("speed_of_sound_m_s", 343.0))
        # [issue 17 acoustics hook] levels, bands, loudness, calibration of the microphone
        acoustic = _acoustics(run, mic, p, fs_mic, log.t_s, t0_mic, fit)
    threshold, names = _threshold(run, log, freq, fit, names)
    return RunResult(status="ok", channels_used=names, impacts=log, peaks=peaks, pattern=pattern,
                     pattern_n=pattern_n, cycle_counts=counts, acoustic_delay_s=delay,
                     expected_delay_s=expected, spl_rms_db=spl, spl_rms_a_db=spl_a,
                     threshold=threshold, acoustics=acoustic, **base)


def _threshold(run: Any, log: ImpactLog, freq: float, fit: Mapping[str, Any],
               names: tuple[str, ...]) -> tuple[Threshold | None, tuple[str, ...]]:
    """The ramp threshold of an ``amplitude_ramp_up/down`` run with a base accelerometer
    (read whole: one channel), and the channels used with it."""
    if run.protocol not in ("amplitude_ramp_up", "amplitude_ramp_down") \
            or not math.isfinite(freq):
        return None, names
    b = next((c for c in run.channels if c.quantity == "base_acceleration"), None)
    if b is None:
        return None, names
    return (ramp_threshold(run.run_id, b.read(), _fs_of(run, b), freq, log.t_s,
                           "up" if run.protocol.endswith("up") else "down",
                           start_time_s=_t0_of(run, b), n_confirm=int(fit.get("n_confirm", 3))),
            names + (b.name,))


def _impact_log(run: Any, by_q: Mapping[str, Any], vel: Any, acc: Any, detect: DetectParams,
                f_fit: float | None, delay_declared: bool, recognised: Recognition | None = None
                ) -> tuple[ImpactLog, float, float, float, tuple[str, ...] | None]:
    """The impacts of a run (or a segment's view of it): ``(log, fs, t0, duration, flags)``,
    the log relative to the striker where the vibrometer is absolute (declared or inferred),
    ``flags`` those of an inferred measurand (None where it was not inferred)."""
    fs, t0, v_si, a_si = paired_plate_channels(run, vel, acc)
    log = detect_impacts(fs, velocity_m_s=v_si, accel_ms2=a_si, params=detect.impact_params(),
                         start_time_s=t0, excitation_freq_hz=f_fit,
                         velocity_delay_declared=delay_declared, recognised=recognised,
                         level_held=run.protocol == "sine_dwell")
    flags: tuple[str, ...] | None = None
    # issue 28: the vibrometer's measurand, when the record does not say, inferred from
    # the data
    measurand = getattr(vel, "measurand", None) if vel is not None else None
    if vel is not None and measurand is None and v_si is not None:
        log, flags = infer_measurand(run, log, v_si, fs, t0, by_q.get("base_acceleration"),
                                     f_fit, if_undetermined=detect.measurand_if_undetermined)
    if vel is not None and measurand == "panel_absolute":
        log = relative_to_striker(run, log, by_q.get("base_acceleration"), f_fit)
    duration = (v_si if v_si is not None else a_si).size / fs  # type: ignore[union-attr]
    return log, fs, t0, duration, flags


#: Data-quality flag: with ringing modes carried on, the impacts' instants from the flights
#: were not applied (the velocities are read at the accelerometer's, plus any delay).
FLAG_FLIGHT_INSTANTS = "flight_instants_not_applied"


def _with_log_flags(flags: tuple[str, ...], log: ImpactLog, delay_declared: bool,
                    measurand_flags: tuple[str, ...] | None) -> tuple[str, ...]:
    """The run's chain flags with those of its impact log: the vibrometer's delay
    measured from the impacts (issue 28), an inferred measurand, the flight model's note."""
    flags = flags + velocity_delay_flags(log, delay_declared)
    if measurand_flags is not None:
        flags = tuple(f for f in flags if f != FLAG_MEASURAND_UNDECLARED) + measurand_flags
    if log.velocity_delay_note:   # the flights' own impact instants were not applied
        flags = flags + (f"{FLAG_FLIGHT_INSTANTS}: {log.velocity_delay_note}",)
    if log.velocity_note:   # the flight model gave no ringing share, or used some impacts only
        what = "ringing_velocities_missing" if log.ring_modes else "ringing_share_missing"
        flags = flags + (f"{what}: {log.velocity_note}",)
    return flags


def reused_result(reuse: RunResult | None, input_key: str, run_id: str, log: ImpactLog,
                  chain_flags: tuple[str, ...]) -> RunResult | None:
    """``reuse`` with ``log`` and ``chain_flags`` where it is this run's result with the same
    impact times, bit for bit (what follows from the times alone is then the same); None
    otherwise (:func:`analyse_run`'s ``reuse``)."""
    if (reuse is not None and reuse.status == "ok" and reuse.impacts is not None
            and (reuse.input_key, reuse.run_id) == (input_key, run_id)
            and np.array_equal(reuse.impacts.t_s, log.t_s)):
        return replace(reuse, impacts=log, chain_flags=chain_flags)
    return None


def _pattern(run: Any, log: ImpactLog, freq: float, t0: float, duration: float
             ) -> tuple[str, int, np.ndarray]:
    if not (math.isfinite(freq) and freq > 0 and duration * freq >= 1):
        return "", 0, np.zeros(0, dtype=int)
    lo, hi = t0, t0 + duration
    if run.protocol.startswith("amplitude_ramp") and log.n_impacts:
        # a ramp: the pattern while impacting (from the first to the last impact's cycle)
        lo = t0 + np.floor((log.t_s[0] - t0) * freq) / freq
        hi = min(t0 + duration, t0 + (np.floor((log.t_s[-1] - t0) * freq) + 1) / freq)
    pr = impact_pattern(log.t_s, freq, lo, hi)
    return pr.pattern, pr.n, pr.counts


def _peaks(p: np.ndarray, fs_mic: float, t0_mic: float, t_s: np.ndarray, detect: DetectParams,
           fit: Mapping[str, Any], mic_distance_m: float | None, f_fit: float | None
           ) -> SoundPeaks:
    # issue 15: each sound paired with its impact through the declared propagation delay
    d_prop = mic_distance_m / float(fit.get("speed_of_sound_m_s", 343.0)) \
        if mic_distance_m else 0.0
    return sound_peaks(p, fs_mic, t_s, window_s=detect.window_s, delay_s=d_prop,
                       first_fraction=detect.first_fraction, start_time_s=t0_mic,
                       excitation_freq_hz=f_fit if f_fit is not None and f_fit < fs_mic / 2
                       else None)


def _acoustics(run: Any, mic: Any, p: np.ndarray, fs_mic: float, t_s: np.ndarray, t0: float,
               fit: Mapping[str, Any], *, ecma418_s: float | None = None,
               keep_curve: bool = False) -> Any:
    return run_acoustics(p, fs_mic, t_s, start_time_s=t0, channel=mic,
                         field_type=run.extra.get("x_sound_field",
                                                  fit.get("sound_field", "free")),
                         with_loudness=bool(fit.get("loudness", True)),
                         ecma418_s=float(fit.get("ecma418_s", 0.0)) if ecma418_s is None
                         else ecma418_s,  # [issue 26]
                         keep_loudness_curve=keep_curve)


#: A long run's part of the campaign's ringing search (``ImpactLog.ringing_problem``) is
#: taken from its first segments only (the first of these that has one): the samples of one
#: segment describe a steady run's ringing, and keeping every segment's would grow with the
#: run's length.
PROBLEM_SEGMENTS = 4


@dataclass(frozen=True)
class SegmentImpacts:
    """One segment's impacts (:func:`segment_impacts`): its span, its log, and the flags of
    an inferred measurand (None where it was not inferred)."""

    span: Span
    log: ImpactLog
    measurand_flags: tuple[str, ...] | None


@dataclass(frozen=True)
class SegmentSound:
    """One segment's sound (:func:`segment_sound`): the peaks of its impacts, its acoustic
    delay (NaN without impacts), the sums of squares of its core's pressure, plain and
    A-weighted, and their sample count, and its acoustics (loudness curve kept; None where the
    microphone does not reach the segment's core)."""

    peaks: SoundPeaks
    delay_s: float
    sum_sq: float
    sum_sq_a: float
    n_core: int
    acoustics: Any


def run_segments(input_key: str, run: Any,
                 detect: DetectParams | Mapping[str, Any] | None) -> list[Span] | None:
    """The segments :func:`analyse_run` cuts ``run`` into (None: analysed whole)."""
    plan = _plan(input_key, run, DetectParams.from_mapping(detect))
    return None if isinstance(plan, RunResult) else plan.spans


def _segment_plan(input_key: str, run: Any, detect: DetectParams) -> _Plan:
    plan = _plan(input_key, run, detect)
    if isinstance(plan, RunResult) or plan.spans is None:
        raise ParameterError(f"run {run.run_id!r} is not analysed in segments")
    return plan


def segment_impacts(input_key: str, run: Any, index: int,
                    detect: DetectParams | Mapping[str, Any] | None) -> SegmentImpacts:
    """The impacts of segment ``index`` of a long run (:func:`run_segments`): the first half
    of its analysis, a task of its own on a cluster."""
    detect = DetectParams.from_mapping(detect)
    plan = _segment_plan(input_key, run, detect)
    span = plan.spans[index]  # type: ignore[index]
    view = segment_view(run, span)
    v_by_q = _by_quantity(view)
    vel, acc = plan.plate(view)
    log, _, _, _, flags = _impact_log(view, v_by_q, vel, acc, detect, plan.f_fit,
                                      plan.delay_declared)
    if index >= PROBLEM_SEGMENTS:
        # the run's part of the campaign's ringing search comes from its first segments
        # (merge_logs keeps the first): the others' samples are not kept
        log = replace(log, ringing_problem=None)
    return SegmentImpacts(span, log, flags)


def merge_segment_impacts(input_key: str, run: Any, parts: list[SegmentImpacts],
                          detect: DetectParams | Mapping[str, Any] | None
                          ) -> tuple[ImpactLog, tuple[str, ...]]:
    """The run's impact log and chain flags from its segments' (:func:`segment_impacts`, in
    order): every impact once (:func:`~rattle_lab.detect._segments.merge_logs`), each
    flag once."""
    detect = DetectParams.from_mapping(detect)
    plan = _segment_plan(input_key, run, detect)
    measurand: dict[str, str] = {}
    for part in parts:   # each flag once, as the first segment that raised it put it
        for f in part.measurand_flags or ():
            measurand.setdefault(f.split(":")[0], f)
    inferred = any(p.measurand_flags is not None for p in parts)
    log, _ = merge_logs([(p.span, p.log) for p in parts], float(detect.min_separation_s))
    flags = _with_log_flags(plan.base["chain_flags"], log, plan.delay_declared,
                            tuple(measurand.values()) if inferred else None)
    return log, flags


def _ecma_budget(fit: Mapping[str, Any], spans: list[Span], index: int) -> float:
    """Segment ``index``'s share of the run's ECMA-418-2 seconds: the run's budget spent in
    time order, each segment at most its own duration (a share fixed before any segment is
    analysed, so that segments can run side by side)."""
    used = sum(s.core_hi_s - s.core_lo_s for s in spans[:index])
    own = spans[index].core_hi_s - spans[index].core_lo_s
    return min(own, max(0.0, float(fit.get("ecma418_s", 0.0)) - used))


def segment_sound(input_key: str, run: Any, index: int, t_s: np.ndarray,
                  detect: DetectParams | Mapping[str, Any] | None, fit: Mapping[str, Any],
                  mic_distance_m: float | None = None) -> SegmentSound:
    """The sound of segment ``index`` of a long run with a microphone, given the run's
    impact times ``t_s`` (:func:`merge_segment_impacts`): the second half of its analysis."""
    detect = DetectParams.from_mapping(detect)
    plan = _segment_plan(input_key, run, detect)
    spans = plan.spans
    span = spans[index]  # type: ignore[index]
    mic = next(c for c in run.channels if c.quantity == "sound_pressure")
    view_mic = segment_view(run, span).channel(mic.name)
    fs_mic, t0_view = _fs_of(run, view_mic), _t0_of(run, view_mic)
    p = view_mic.read()
    t_s = np.asarray(t_s, dtype=float)
    t_core = t_s[core_mask(t_s, span)]
    if p.size == 0:
        # the microphone does not reach this segment (shorter than the plate's channels, or
        # starting later): its impacts get no sound, as those of a whole run beyond its end
        nan = np.full(t_core.size, np.nan)
        return SegmentSound(SoundPeaks(*(nan.copy() for _ in dataclasses.fields(SoundPeaks))),
                            float("nan"), 0.0, 0.0, 0, None)
    peaks = _peaks(p, fs_mic, t0_view, t_core, detect, fit, mic_distance_m, plan.f_fit)
    delay = (cross_correlation_delay(impulse_train(t_core, p.size, fs_mic, t0_view), p, fs_mic,
                                     max_lag_s=detect.max_lag_s) if t_core.size else np.nan)
    start = float(view_mic.start_time_s or 0.0)
    i0 = max(0, math.ceil((span.core_lo_s - start) * fs_mic - 1e-9))
    i1 = min(p.size, math.ceil((span.core_hi_s - start) * fs_mic - 1e-9))
    core = p[i0:i1]
    part = (_acoustics(run, mic, core, fs_mic, t_core, t0_view + i0 / fs_mic, fit,
                       ecma418_s=_ecma_budget(fit, spans, index),  # type: ignore[arg-type]
                       keep_curve=True) if core.size >= 2 else None)
    return SegmentSound(peaks, float(delay), float(np.sum(np.square(core, dtype=float))),
                        float(np.sum(np.square(a_weight(p, fs_mic)[i0:i1]))), int(core.size),
                        part)


def assemble_segments(input_key: str, run: Any, log: ImpactLog, chain_flags: tuple[str, ...],
                      sounds: list[SegmentSound] | None,
                      detect: DetectParams | Mapping[str, Any] | None,
                      fit: Mapping[str, Any], mic_distance_m: float | None = None
                      ) -> RunResult:
    """A long run's :class:`RunResult` from its merged impacts and its segments' sound (None
    without a microphone)."""
    detect = DetectParams.from_mapping(detect)
    plan = _segment_plan(input_key, run, detect)
    base = {**plan.base, "chain_flags": chain_flags}
    names = tuple(n for n in (plan.vel, plan.acc) if n is not None)
    # the pattern over the stretch the detection channels share (as paired_plate_channels
    # cuts a whole run)
    plate = [c for c in plan.plate(run) if c is not None]
    t0 = max(_t0_of(run, c) for c in plate)
    t1 = min(_t0_of(run, c) + c.n_samples / _fs_of(run, c) for c in plate)
    pattern, pattern_n, counts = _pattern(run, log, base["freq_hz"], t0, t1 - t0)
    peaks, delay, expected, spl, spl_a, acoustic = None, np.nan, np.nan, np.nan, np.nan, None
    if sounds:
        mic = next(c for c in run.channels if c.quantity == "sound_pressure")
        names = names + (mic.name,)
        peaks = merge_arrays([x.peaks for x in sounds])
        n_core = sum(x.n_core for x in sounds)
        if n_core:
            spl = float(spl_db(np.sqrt(sum(x.sum_sq for x in sounds) / n_core)))
            spl_a = float(spl_db(np.sqrt(sum(x.sum_sq_a for x in sounds) / n_core)))
        delays = [x.delay_s for x in sounds if math.isfinite(x.delay_s)]
        delay = float(np.median(delays)) if delays else np.nan
        if mic_distance_m:
            expected = mic_distance_m / float(fit.get("speed_of_sound_m_s", 343.0))
        heard = [x.acoustics for x in sounds if x.acoustics is not None]
        acoustic = joined_acoustics(heard) if heard else None
    threshold, names = _threshold(run, log, base["freq_hz"], fit, names)
    return RunResult(status="ok", channels_used=names, impacts=log, peaks=peaks, pattern=pattern,
                     pattern_n=pattern_n, cycle_counts=counts, acoustic_delay_s=delay,
                     expected_delay_s=expected, spl_rms_db=spl, spl_rms_a_db=spl_a,
                     threshold=threshold, acoustics=acoustic, **base)


def _analyse_segments(input_key: str, run: Any, plan: _Plan, detect: DetectParams,
                      fit: Mapping[str, Any], mic_distance_m: float | None,
                      reuse: RunResult | None) -> RunResult:
    """:func:`analyse_run` of a long run, one segment at a time (:mod:`._segments`): at
    most one segment's samples and its margins are in memory at once.  The same steps as
    the pipeline's segment tasks (:func:`rattle_lab.workflow.detect_runs`)."""
    parts = [segment_impacts(input_key, run, index, detect)
             for index in range(len(plan.spans or ()))]
    log, flags = merge_segment_impacts(input_key, run, parts, detect)
    reused = reused_result(reuse, input_key, run.run_id, log, flags)
    if reused is not None:
        return reused
    has_mic = any(c.quantity == "sound_pressure" for c in run.channels)
    sounds = ([segment_sound(input_key, run, i, log.t_s, detect, fit, mic_distance_m)
               for i in range(len(plan.spans or ()))] if has_mic else None)
    return assemble_segments(input_key, run, log, flags, sounds, detect, fit, mic_distance_m)


__all__ = ["RunResult", "SegmentImpacts", "SegmentSound", "analyse_run", "assemble_segments",
           "merge_segment_impacts", "reused_result", "run_segments", "segment_impacts",
           "segment_sound"]
