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

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from rattle_lab.acoustics import run_acoustics  # [issue 17, 26]
from rattle_lab.records import FLAG_MEASURAND_UNDECLARED, declared_delay_s
from ._chain import (SHOCK_QUANTITIES, _fs_of, _t0_of, infer_measurand, paired_plate_channels,
                     relative_to_striker, run_chain_flags, transient_shocks,
                     velocity_delay_flags)
from ._impacts import ImpactLog, detect_impacts
from ._params import DetectParams
from ._patterns import impact_pattern
from ._sound import SoundPeaks, cross_correlation_delay, impulse_train, sound_peaks
from ._spl import rms_spl_db
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
    by_q: dict[str, Any] = {}
    for ch in run.channels:
        by_q.setdefault(ch.quantity, ch)
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
    # issue 15: each channel's time base less its declared filter delay; two channels at
    # different rates or offsets are brought onto the grid of the faster one before pairing
    fs, t0, v_si, a_si = paired_plate_channels(run, vel, acc)
    params = detect.impact_params()
    # a constant excitation frequency lets the velocity fits use the forced-mode basis
    f_end = getattr(run, "freq_end_hz", None)
    f_fit = freq if (math.isfinite(freq) and 0 < freq < fs / 2
                     and (f_end is None or f_end == freq)) else None
    delay_declared = vel is not None and declared_delay_s(vel) is not None
    log = detect_impacts(fs, velocity_m_s=v_si, accel_ms2=a_si, params=params,
                         start_time_s=t0, excitation_freq_hz=f_fit,
                         velocity_delay_declared=delay_declared)
    # issue 28: the vibrometer's delay measured from the impacts; its measurand, when the
    # record does not say, inferred from the data
    base["chain_flags"] = base["chain_flags"] + velocity_delay_flags(log, delay_declared)
    measurand = getattr(vel, "measurand", None) if vel is not None else None
    if vel is not None and measurand is None and v_si is not None:
        log, flags = infer_measurand(run, log, v_si, fs, t0, by_q.get("base_acceleration"),
                                     f_fit)
        base["chain_flags"] = tuple(f for f in base["chain_flags"]
                                    if f != FLAG_MEASURAND_UNDECLARED) + flags
    if vel is not None and measurand == "panel_absolute":
        log = relative_to_striker(run, log, by_q.get("base_acceleration"), f_fit)
    if log.velocity_note:   # the flight model gave no ringing share, or used some impacts only
        what = "ringing_velocities_missing" if log.ring_modes else "ringing_share_missing"
        base["chain_flags"] = base["chain_flags"] + (f"{what}: {log.velocity_note}",)
    if (reuse is not None and reuse.status == "ok" and reuse.impacts is not None
            and (reuse.input_key, reuse.run_id) == (input_key, run.run_id)
            and np.array_equal(reuse.impacts.t_s, log.t_s)):
        # the same impact times: the same sound, pattern and threshold (issue 29: the
        # ringing passes detect again for the velocities only)
        return replace(reuse, impacts=log, chain_flags=base["chain_flags"])
    names = tuple(c.name for c in used)
    duration = (v_si if v_si is not None else a_si).size / fs  # type: ignore[union-attr]
    pattern, pattern_n, counts = "", 0, np.zeros(0, dtype=int)
    if math.isfinite(freq) and freq > 0 and duration * freq >= 1:
        lo, hi = t0, t0 + duration
        if run.protocol.startswith("amplitude_ramp") and log.n_impacts:
            # a ramp: the pattern while impacting (from the first to the last impact's cycle)
            lo = t0 + np.floor((log.t_s[0] - t0) * freq) / freq
            hi = min(t0 + duration, t0 + (np.floor((log.t_s[-1] - t0) * freq) + 1) / freq)
        pr = impact_pattern(log.t_s, freq, lo, hi)
        pattern, pattern_n, counts = pr.pattern, pr.n, pr.counts
    peaks, delay, expected, spl, spl_a = None, np.nan, np.nan, np.nan, np.nan
    acoustic = None  # [issue 17]
    mic = by_q.get("sound_pressure")
    if mic is not None:
        fs_mic = _fs_of(run, mic)
        p = mic.read()
        t0_mic = _t0_of(run, mic)
        names = names + (mic.name,)
        # issue 15: each sound paired with its impact through the declared propagation delay
        d_prop = mic_distance_m / float(fit.get("speed_of_sound_m_s", 343.0)) \
            if mic_distance_m else 0.0
        peaks = sound_peaks(p, fs_mic, log.t_s, window_s=detect.window_s, delay_s=d_prop,
                            first_fraction=detect.first_fraction, start_time_s=t0_mic,
                            excitation_freq_hz=f_fit if f_fit is not None and f_fit < fs_mic / 2
                            else None)
        spl = rms_spl_db(p)
        spl_a = rms_spl_db(p, fs_mic, a_weighted=True)
        if log.n_impacts:
            train = impulse_train(log.t_s, p.size, fs_mic, t0_mic)
            delay = cross_correlation_delay(train, p, fs_mic, max_lag_s=detect.max_lag_s)
        if mic_distance_m:
            expected = mic_distance_m / float(fit.get("speed_of_sound_m_s", 343.0))
        # [issue 17 acoustics hook] levels, bands, loudness, calibration of the microphone
        acoustic = run_acoustics(p, fs_mic, log.t_s, start_time_s=t0_mic, channel=mic,
                                 field_type=run.extra.get("x_sound_field",
                                                          fit.get("sound_field", "free")),
                                 with_loudness=bool(fit.get("loudness", True)),
                                 ecma418_s=float(fit.get("ecma418_s", 0.0)))  # [issue 26]
    threshold = None
    if run.protocol in ("amplitude_ramp_up", "amplitude_ramp_down") and math.isfinite(freq):
        b = by_q.get("base_acceleration")
        if b is not None:
            threshold = ramp_threshold(run.run_id, b.read(), _fs_of(run, b), freq, log.t_s,
                                       "up" if run.protocol.endswith("up") else "down",
                                       start_time_s=_t0_of(run, b),
                                       n_confirm=int(fit.get("n_confirm", 3)))
            names = names + (b.name,)
    return RunResult(status="ok", channels_used=names, impacts=log, peaks=peaks, pattern=pattern,
                     pattern_n=pattern_n, cycle_counts=counts, acoustic_delay_s=delay,
                     expected_delay_s=expected, spl_rms_db=spl, spl_rms_a_db=spl_a,
                     threshold=threshold, acoustics=acoustic, **base)


__all__ = ["RunResult", "analyse_run"]
