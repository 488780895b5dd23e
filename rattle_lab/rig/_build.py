"""From a scene to a synthetic rattle record: simulate every run, synthesise the channels
the scene records (and only those), and collect everything the rig knows in ``/truth``."""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from datetime import datetime, timedelta

import numpy as np

from rattle_lab._progress import progress
from rattle_lab._version import __version__
from rattle_lab._atomic import check_output_path
from rattle_lab.model.plate import Plate
from rattle_lab.records import (Channel, ImpactTable, Record, Rig, Run, Sensor, ThresholdTable,
                                Truth, as_source, scale_to_si, write_record)
from rattle_lab.model.modal import C_AIR_M_S
from . import _chain as cc
from . import _modal as md
from . import _channels as ch
from ._counter import StageCounter
from ._motion import Modal, RunMotion, simulate_run, true_thresholds
from ._scene import SENSOR_QUANTITIES, RunSpec, Scene, SceneError, SensorSpec, load_scene

#: Seconds between the end of one run and the start of the next (start_time_iso).
RUN_GAP_S = 1.0


@dataclass(frozen=True)
class RunSummary:
    """What one synthetic run produced.

    Attributes
    ----------
    run_id, protocol : str
        As in the record.
    freq_hz : float
        Excitation (start) frequency, Hz.
    duration_s : float
        Run duration, s.
    n_impacts : int
        Number of impacts (chatter included).
    max_v_in_m_s : float
        Largest impact speed, m/s (NaN without impacts).
    onset_m_s2, disappearance_m_s2 : float
        Threshold levels of a ramp run, m/s^2 (NaN where not seen).
    """

    run_id: str
    protocol: str
    freq_hz: float
    duration_s: float
    n_impacts: int
    max_v_in_m_s: float
    onset_m_s2: float
    disappearance_m_s2: float

    def line(self) -> str:
        """One human line."""
        text = (f"{self.run_id}: {self.protocol} {self.freq_hz:g} Hz, {self.duration_s:g} s, "
                f"{self.n_impacts} impacts")
        if self.n_impacts:
            text += f" (max {self.max_v_in_m_s:.3g} m/s)"
        if not math.isnan(self.onset_m_s2):
            text += f", onset {self.onset_m_s2:.4g} m/s^2"
        if not math.isnan(self.disappearance_m_s2):
            text += f", disappearance {self.disappearance_m_s2:.4g} m/s^2"
        return text


@dataclass(frozen=True)
class Synthesis:
    """A synthetic record and the per-run summaries.

    Attributes
    ----------
    record : Record
        The record (in memory; write it with :func:`rattle_lab.records.write_record`).
    runs : tuple of RunSummary
        One per run, in order.
    modal : Modal
        The modal model simulated (physical units).
    """

    record: Record
    runs: tuple[RunSummary, ...]
    modal: Modal


def resolve_modal(scene: Scene) -> tuple[Modal, tuple[float, ...]]:
    """The modal model and the ringing frequencies (Hz) of a scene.

    Without explicit values, ``f_s_hz`` and ``participation`` come from the plate's first
    Ritz mode and the ringing frequencies from modes 2-4, scaled by ``f_s_hz / f_1``
    when ``f_s_hz`` is given (a measured resonance shifts the whole plate).
    """
    m = scene.model
    f_s, part, ring = m.f_s_hz, m.participation, m.ringing_freqs_hz
    if scene.plate is not None and (f_s is None or part is None or ring is None):
        p = scene.plate
        plate = Plate(a_m=p.length_m, b_m=p.width_m, h_p_m=p.thickness_m, E_pa=p.E_pa, nu=p.nu,
                      rho_kg_m3=p.rho_kg_m3, edges=p.edges)
        modes = plate.modes(4)
        freqs = np.asarray(plate.frequency_hz(modes.lam), dtype=float)
        part = float(modes.Q1[0] / modes.Q2[0]) if part is None else part
        ratio = 1.0 if f_s is None else f_s / float(freqs[0])
        f_s = float(freqs[0]) if f_s is None else f_s
        ring = tuple(float(f) * ratio for f in freqs[1:4]) if ring is None else ring
    assert f_s is not None and part is not None
    return Modal(f_s_hz=f_s, zeta=m.zeta, participation=part, gap_m=m.gap_m, e=m.e), tuple(ring or ())


def _rig(scene: Scene, participation: float) -> Rig:
    p = scene.plate
    if p is None:
        return Rig("other", description="synthetic rig from direct modal parameters (no plate)",
                   mic_distance_m=scene.mic_distance_m, modal_participation=participation)
    cx, cy = p.length_m / 2, p.width_m / 2
    where = {"base": ((cx, cy, -0.02), "base"), "plate": ((cx, cy, 0.0), "plate"),
             "velocity": ((cx, cy, 0.5), "stand"), "mic": ((cx, cy, scene.mic_distance_m), "stand")}
    sensors = tuple(Sensor(s.name, where[s.name][0], where[s.name][1])  # type: ignore[arg-type]
                    for s in scene.sensors if s.name in where)
    return Rig("plate_striker", plate_length_m=p.length_m, plate_width_m=p.width_m,
               plate_thickness_m=p.thickness_m, plate_material=p.material, edge_conditions=p.edges,
               striker_x_m=cx, striker_y_m=cy, mic_distance_m=scene.mic_distance_m,
               modal_participation=participation, plate_poisson_ratio=p.nu, sensors=sensors)


def _rng(seed: int, run_index: int, stream: int) -> np.random.Generator:
    # one independent stream per (run, sensor/stage): adding a sensor changes no other channel
    return np.random.default_rng([seed, run_index, stream])


def _store(sensor: SensorSpec, si: np.ndarray, noise_rng: np.random.Generator, fs_hz: float,
           with_id: bool) -> Channel:
    """SI samples plus sensor noise, in stored units, clipped at the input range like an ADC."""
    si = si + sensor.noise_rms * noise_rng.standard_normal(si.size)
    scale = scale_to_si(sensor.quantity, sensor.units, sensor.sensitivity, sensor.sensitivity_units)[0]
    stored = si / scale
    if sensor.range is not None:
        stored = np.clip(stored, -sensor.range, sensor.range)   # the ADC saturates (ingest flags it)
    return Channel(sensor.name, sensor.quantity, sensor.units, as_source(stored.astype(np.float32)),
                   sample_rate_hz=fs_hz, start_time_s=0.0, sensitivity=sensor.sensitivity,
                   sensitivity_units=sensor.sensitivity_units,
                   sensor_id=sensor.name if with_id else None, sensor_model=sensor.model,
                   range_min=-sensor.range if sensor.range is not None else None,
                   range_max=sensor.range if sensor.range is not None else None)


def _channels(scene: Scene, run_index: int, seed: int, motion: RunMotion, fs_hz: float,
              ring: tuple[float, ...], counter: StageCounter, with_ids: bool,
              modal_mic_pa: np.ndarray | None = None) -> list[Channel]:
    """The channels of one run.  With ``[model] kind = "modal"`` the motion already holds
    the plate's physical ringing and ``modal_mic_pa`` the radiated sound, so the canned
    contact pulses, ringing and acoustic law of the SDF rig are not added."""
    modal = scene.model.kind == "modal"
    art = scene.artefacts
    chain = scene.chain
    fan_phase = float(_rng(seed, run_index, 200).uniform(0.0, 2.0 * math.pi))
    a_base = None
    out: list[Channel] = []
    stream = {name: k for k, name in enumerate(SENSOR_QUANTITIES)}
    for sensor in scene.sensors:
        noise = _rng(seed, run_index, stream[sensor.name])
        if sensor.name in ("base", "plate") and a_base is None:
            a_base = ch.base_acceleration(motion, art, fs_hz, fan_phase)
        if sensor.name == "base":
            counter.add("base")
            si = a_base
        elif sensor.name == "plate":
            counter.add("plate")
            assert a_base is not None
            assert motion.a_rel_m_s2 is not None
            si = (a_base + motion.a_rel_m_s2 if modal
                  else ch.plate_acceleration(motion, a_base, scene.model, ring, fs_hz))
        elif sensor.name == "velocity":
            counter.add("velocity")
            si = ch.vibrometer_velocity(motion, sensor.band_hz, fs_hz, 0.0 if modal else scene.model.contact_s)
            if chain is not None and not modal:
                si = si + cc.velocity_ringing(motion, scene.model, ring,
                                              chain.ring_velocity_per_m_s, si.size, fs_hz)
            if chain is not None and chain.vibrometer == "absolute":
                si = si + cc.base_velocity(motion, fs_hz)
        elif sensor.name == "mic":
            counter.add("mic")
            if modal:
                assert modal_mic_pa is not None
                si = modal_mic_pa + art.fan_pa * np.sin(2.0 * math.pi * art.fan_hz * np.arange(modal_mic_pa.size)
                                                        / fs_hz + fan_phase)
                if chain is not None:
                    si = cc.floor_reflection(si, chain, C_AIR_M_S, fs_hz)
            else:
                counter.add("acoustic")
                assert scene.acoustic is not None
                si, _ = ch.sound_pressure(motion, scene.acoustic, art, fs_hz, _rng(seed, run_index, 100),
                                          fan_phase)
                if chain is not None:
                    si = cc.floor_reflection(si, chain, scene.acoustic.c_m_s, fs_hz)
        else:
            counter.add("drive")
            assert motion.theta is not None and motion.level_m_s2 is not None
            si = -sensor.volts_per_m_s2 * motion.level_m_s2 * np.cos(motion.theta)
        assert si is not None
        if chain is not None:
            si = cc.hum_and_offset(si, sensor.name, chain, fs_hz)
        chan = _store(sensor, si, noise, fs_hz, with_ids and sensor.name != "drive")
        if chain is not None and sensor.name == "velocity" and chain.decoder_delay_s:
            data = cc.fractional_delay(chan.data.read(0, chan.n_samples).astype(np.float64),
                                       fs_hz, chain.decoder_delay_s)
            chan = dataclasses.replace(chan, data=as_source(data.astype(np.float32)),
                                       group_delay_s=chain.decoder_delay_s)
        if chain is not None and chain.adc_bits:
            data = cc.quantise(chan.data.read(0, chan.n_samples).astype(np.float64),
                               sensor.range, chain.adc_bits)
            chan = dataclasses.replace(chan, data=as_source(
                data.astype(np.float64 if chain.adc_bits > 16 else np.float32)))
        if sensor.name == "velocity":   # what the vibrometer measures, declared (schema v2)
            chan = dataclasses.replace(chan, measurand=chain.measurand if chain is not None
                                       else "panel_relative_to_striker",
                                       sign_convention="toward_striker_positive")
        if sensor.name == "mic" and art.dropout_s > 0:
            data = chan.data.read(0, chan.n_samples).copy()
            lo = data.size // 2
            data[lo:lo + ch.n_samples(art.dropout_s, fs_hz)] = 0.0
            chan = dataclasses.replace(chan, data=as_source(data))
        out.append(chan)
    return out


def synthesize(scene: Scene | str | os.PathLike[str], *, seed: int | None = None,
               counter: StageCounter | None = None, quiet: bool = True) -> Synthesis:
    """Simulate a scene's runs and synthesise its record.

    Parameters
    ----------
    scene : Scene, path or ``"default"``
        The scene (a path is read with :func:`load_scene`).
    seed : int, optional
        Overrides the scene's seed.
    counter : StageCounter, optional
        Counts the stages evaluated (simulator calls, dense motion, each channel, the
        acoustic model).  Stages a scene does not need are never evaluated: without a
        plate accelerometer, vibrometer or microphone the motion is not sampled at all.
    quiet : bool
        No progress bar (drawn only on a terminal anyway).

    Returns
    -------
    Synthesis

    Raises
    ------
    SceneError
        If the scene is invalid.
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    seed = scene.seed if seed is None else int(seed)
    if seed < 0:
        raise SceneError(f"`seed` must be >= 0, was {seed}")
    counter = counter if counter is not None else StageCounter()
    system = contact = None
    if scene.model.kind == "modal":
        system, contact = md.build_system(scene)
        ring: tuple[float, ...] = ()
        modal = md.truth_modal(scene, system)
    else:
        modal, ring = resolve_modal(scene)
    e_mode1: list[tuple[np.ndarray, np.ndarray]] = []
    names = {s.name for s in scene.sensors}
    want_v = "velocity" in names
    want_a = "plate" in names or ("mic" in names and scene.acoustic is not None
                                  and scene.acoustic.mode_pa_per_m_s2 > 0)
    try:
        start = datetime.fromisoformat(scene.start_iso)
    except ValueError as exc:
        raise SceneError(f"{scene.source}: `scene.start_iso` is not ISO 8601, was "
                         f"{scene.start_iso!r}") from exc
    runs, summaries, impacts = [], [], {}
    onsets: dict[float, list[float]] = {}
    gones: dict[float, list[float]] = {}
    rig = _rig(scene, modal.participation)
    if system is not None:
        rig = md.place_striker(rig, system)
    for i, spec in enumerate(progress(scene.runs, total=len(scene.runs), desc="simulate",
                                      quiet=quiet, unit="run")):
        fs_hz = spec.sample_rate_hz or scene.sample_rate_hz
        mic_pa = None
        if system is not None:
            assert contact is not None
            motion, mic_pa, episodes = md.simulate_run_modal(scene, system, contact, spec, fs_hz, counter)
            e_mode1.extend((e.e_mode1, e.v_in_m_s) for e in episodes)
        else:
            motion = simulate_run(modal, spec, piece_periods=scene.simulation.piece_periods,
                                  settle_time_constants=scene.simulation.settle_time_constants,
                                  sample_rate_hz=fs_hz, want_v=want_v, want_a=want_a, counter=counter)
        chans = _channels(scene, i, seed, motion, fs_hz, ring, counter, rig.apparatus == "plate_striker",
                          mic_pa)
        runs.append(_run(spec, chans, start))
        start += timedelta(seconds=spec.duration_s + RUN_GAP_S)
        onset, gone = true_thresholds(spec, motion)
        if spec.protocol == "amplitude_ramp_up":
            onsets.setdefault(spec.freq_hz, []).append(onset)
        if spec.protocol == "amplitude_ramp_down":
            gones.setdefault(spec.freq_hz, []).append(gone)
        if motion.impact_t_s.size:
            impacts[spec.run_id] = ImpactTable(motion.impact_t_s, motion.impact_v_in_m_s,
                                               motion.impact_v_out_m_s)
        summaries.append(RunSummary(spec.run_id, spec.protocol, spec.freq_hz, spec.duration_s,
                                    int(motion.impact_t_s.size),
                                    float(motion.impact_v_in_m_s.max()) if motion.impact_t_s.size else math.nan,
                                    onset, gone))
    freqs = sorted(set(onsets) | set(gones))
    table = ThresholdTable(
        np.array(freqs, dtype=float),
        np.array([np.nanmean(onsets[f]) if f in onsets and not np.all(np.isnan(onsets[f])) else math.nan
                  for f in freqs]),
        np.array([np.nanmean(gones[f]) if f in gones and not np.all(np.isnan(gones[f])) else math.nan
                  for f in freqs]),
        "m/s^2")
    extra: dict[str, float | str] = {"omega_s_rad_s": modal.omega_s_rad_s, "seed": float(seed),
                                     "contact_s": scene.model.contact_s}
    if scene.acoustic is not None:
        a = scene.acoustic
        extra.update(acoustic_pa_per_m_s=a.pa_per_m_s, acoustic_intercept_pa=a.intercept_pa,
                     acoustic_delay_s=a.delay_s, radiation_lag_s=a.radiation_lag_s,
                     mic_distance_m=a.distance_m, sound_speed_m_s=a.c_m_s,
                     second_peak_probability=a.second_peak_probability)
    law = scene.acoustic.law_text() if scene.acoustic is not None else "none (no acoustic model in the scene)"
    e_truth = modal.e
    if system is not None:
        assert contact is not None
        law, e_truth = md.truth_extra(scene, system, contact, e_mode1, extra)
    truth = Truth(gap_m=modal.gap_m, f_s_hz=modal.f_s_hz, zeta=modal.zeta, e=e_truth,
                  participation=modal.participation, acoustic_law=law, impacts=impacts,
                  thresholds=table, extra=extra)
    record = Record(scene.campaign_id, "synthetic", rig, tuple(runs), truth=truth,
                    description=scene.description, writer=f"rattle_lab {__version__} rig")
    return Synthesis(record, tuple(summaries), modal)


def _run(spec: RunSpec, chans: list[Channel], start: datetime) -> Run:
    iso = start.isoformat().replace("+00:00", "Z")
    return Run(spec.run_id, spec.protocol, tuple(chans), excitation_freq_hz=spec.freq_hz,
               freq_end_hz=spec.freq_end_hz, freq_step_hz=spec.freq_step_hz,
               nominal_level=spec.level_m_s2, level_end=spec.level_end_m_s2,
               nominal_level_units="m/s^2", start_time_iso=iso, notes=spec.notes)


def write_synthetic(scene: Scene | str | os.PathLike[str], output: str | os.PathLike[str], *,
                    seed: int | None = None, counter: StageCounter | None = None,
                    quiet: bool = True) -> Synthesis:
    """:func:`synthesize` a scene and write the record to ``output`` (validated, atomically).

    Returns
    -------
    Synthesis
        With ``record`` as written.

    Raises
    ------
    SceneError
        If the scene is invalid.
    OutputError
        If the output directory does not exist, the output is a directory (both refused
        before simulating), or the file cannot be written.
    """
    check_output_path(output)   # fail before simulating, not after
    result = synthesize(scene, seed=seed, counter=counter, quiet=quiet)
    write_record(output, result.record)
    return result
