"""Scenes of the synthetic rig: TOML files, parsed and validated strictly.

A scene names the plate (or direct modal parameters), the gap and the
restitution, the acoustic law, the sensors, the protocol (runs), artefacts and a
seed.  Every key is checked: an unknown key or a value of the wrong type raises
:class:`SceneError` naming the file, the TOML key path and the value.  See
``synthetic/thesis_cfcf_1p3mm.toml`` for a commented example of every table.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from typing import Any, Literal

from rattle_lab._resources import find_resource, resolve_resource
from rattle_lab.exceptions import ParameterError
from ._chain_spec import ChainSpec, parse_chain
from ._modal_spec import ModalRigSpec, parse_modal

__all__ = ["SceneError", "Scene", "PlateSpec", "ModelSpec", "AcousticSpec", "SensorSpec",
           "RunSpec", "ArtefactSpec", "SimulationSpec", "load_scene", "parse_scene",
           "SENSOR_QUANTITIES", "RUN_PROTOCOLS"]


class SceneError(ParameterError):
    """A scene file is invalid: names the file, the TOML key path and the value."""


#: Sensor name -> the record quantity it measures (channel names are the sensor names).
SENSOR_QUANTITIES: dict[str, str] = {
    "base": "base_acceleration",
    "plate": "plate_acceleration",
    "velocity": "plate_velocity",
    "mic": "sound_pressure",
    "drive": "drive_signal",
}
#: SI unit stored when a sensor gives no sensitivity.
_SI_UNITS = {"base": "m/s^2", "plate": "m/s^2", "velocity": "m/s", "mic": "Pa", "drive": "V"}

RunProtocol = Literal["sine_dwell", "amplitude_ramp_up", "amplitude_ramp_down",
                      "stepped_frequency", "swept_frequency"]
RUN_PROTOCOLS: tuple[str, ...] = ("sine_dwell", "amplitude_ramp_up", "amplitude_ramp_down",
                                  "stepped_frequency", "swept_frequency")


@dataclass(frozen=True)
class PlateSpec:
    """The plate (thesis chapter 2); its Ritz modes give f_s, participation and ringing."""

    length_m: float
    width_m: float
    thickness_m: float
    E_pa: float
    nu: float
    rho_kg_m3: float
    edges: str = "CFCF"
    material: str = "aluminium"


@dataclass(frozen=True)
class ModelSpec:
    """Modal model of the plate/striker: ``f_s_hz``, ``zeta``, ``participation``, ``gap_m``, ``e``.

    ``f_s_hz`` and ``participation`` default to the plate's first mode; ``ringing_freqs_hz``
    defaults to the plate's modes 2-4 (or none without a plate).  ``contact_s`` is the
    duration of the half-sine contact pulse, centred on the simulated (rigid) impact time,
    that spreads the velocity jump in the plate accelerometer and the vibrometer alike;
    ``ringing_m_s2_per_m_s`` the ringing
    amplitude per m/s of impact velocity; ``ringing_decay_s`` its time constant.

    ``kind = "modal"`` (opt-in) simulates the plate with the multi-mode model instead
    (``modal``: :class:`rattle_lab.rig._modal_spec.ModalRigSpec`; needs a [plate]).
    """

    gap_m: float
    e: float
    zeta: float
    f_s_hz: float | None = None
    participation: float | None = None
    ringing_freqs_hz: tuple[float, ...] | None = None
    ringing_m_s2_per_m_s: float = 2000.0
    ringing_decay_s: float = 0.004
    contact_s: float = 0.0002
    kind: str = "sdf"
    modal: ModalRigSpec | None = None    # when kind == "modal"


@dataclass(frozen=True)
class AcousticSpec:
    """The thesis's linear acoustic law: ``p_peak_pa = pa_per_m_s * v_in_m_s + intercept_pa``.

    The pulse starts ``distance_m / c_m_s + radiation_lag_s`` after the impact and rings
    as ``exp(-t / ring_decay_s) cos(2 pi ring_freq_hz t)``; with probability
    ``second_peak_probability`` a second pulse ``second_peak_ratio`` times larger follows
    ``second_peak_delay_s`` later (thesis Fig. 6-6).  The main mode radiates
    ``mode_pa_per_m_s2`` Pa per m/s^2 of modal acceleration.
    """

    pa_per_m_s: float
    intercept_pa: float = 0.0
    distance_m: float = 0.3
    c_m_s: float = 343.0
    radiation_lag_s: float = 0.0003
    ring_freq_hz: float = 1200.0
    ring_decay_s: float = 0.0015
    second_peak_probability: float = 0.0
    second_peak_ratio: float = 1.3
    second_peak_delay_s: float = 0.0015
    mode_pa_per_m_s2: float = 0.0002

    @property
    def delay_s(self) -> float:
        """``distance_m / c_m_s + radiation_lag_s``, s: impact to the start of the sound pulse."""
        return self.distance_m / self.c_m_s + self.radiation_lag_s

    def law_text(self) -> str:
        """The law as text (``/truth`` attribute ``acoustic_law``)."""
        return (f"p_peak_pa = {self.pa_per_m_s!r} * v_in_m_s + {self.intercept_pa!r}, starting "
                f"{self.distance_m!r} m / {self.c_m_s!r} m/s + {self.radiation_lag_s!r} s after "
                f"the impact, ringing exp(-t/{self.ring_decay_s!r} s) cos(2 pi "
                f"{self.ring_freq_hz!r} Hz t); second peak x{self.second_peak_ratio!r} after "
                f"{self.second_peak_delay_s!r} s with probability {self.second_peak_probability!r}")


@dataclass(frozen=True)
class SensorSpec:
    """One sensor; the channel of the same name measures ``SENSOR_QUANTITIES[name]``.

    ``noise_rms`` is in SI units (m/s^2, m/s, Pa, V).  With ``sensitivity`` the channel is
    stored in volts, else in SI units.  ``range`` is the +- input range in stored units.
    ``band_hz`` low-pass filters the vibrometer; ``volts_per_m_s2`` scales the drive.
    """

    name: str
    noise_rms: float
    sensitivity: float | None = None
    sensitivity_units: str | None = None
    range: float | None = None
    model: str | None = None
    band_hz: float | None = None
    volts_per_m_s2: float = 0.05

    @property
    def quantity(self) -> str:
        """The record quantity."""
        return SENSOR_QUANTITIES[self.name]

    @property
    def units(self) -> str:
        """Stored units: ``"V"`` with a sensitivity, else the SI unit."""
        return "V" if self.sensitivity is not None else _SI_UNITS[self.name]


@dataclass(frozen=True)
class RunSpec:
    """One run of the protocol (levels are base-acceleration amplitudes, m/s^2)."""

    run_id: str
    protocol: RunProtocol
    freq_hz: float
    level_m_s2: float
    duration_s: float
    level_end_m_s2: float | None = None
    freq_end_hz: float | None = None
    freq_step_hz: float | None = None
    sample_rate_hz: float | None = None
    notes: str = ""


@dataclass(frozen=True)
class ArtefactSpec:
    """Rig artefacts: cooling-fan tone, shaker harmonics that grow with impacts, a dropout.

    ``harmonics[k]`` is the (k+2)-th harmonic's amplitude over the fundamental without
    impacts; ``harmonics_impact[k]`` with impacts in every forcing period, approached
    with time constant ``harmonics_tau_s``.  ``dropout_s`` > 0 zeroes that long a stretch
    of every run's microphone (ingest flags it as a fatal dropout).
    """

    fan_hz: float = 88.0
    fan_m_s2: float = 0.0
    fan_pa: float = 0.0
    harmonics: tuple[float, ...] = ()
    harmonics_impact: tuple[float, ...] = ()
    harmonics_tau_s: float = 0.05
    dropout_s: float = 0.0


@dataclass(frozen=True)
class SimulationSpec:
    """How the rig drives the simulator: ramps and sweeps change F or omega every
    ``piece_periods`` forcing periods; runs starting above grazing first settle for
    ``settle_time_constants`` modal time constants ``1 / (zeta omega_s)``."""

    piece_periods: int = 1
    settle_time_constants: float = 8.0


@dataclass(frozen=True)
class Scene:
    """A validated scene.  ``source`` is the file it came from (for messages)."""

    campaign_id: str
    description: str
    seed: int
    start_iso: str
    sample_rate_hz: float
    model: ModelSpec
    runs: tuple[RunSpec, ...]
    sensors: tuple[SensorSpec, ...]
    plate: PlateSpec | None = None
    acoustic: AcousticSpec | None = None
    artefacts: ArtefactSpec = field(default_factory=ArtefactSpec)
    simulation: SimulationSpec = field(default_factory=SimulationSpec)
    mic_distance_m: float = 0.3
    source: str = "<scene>"
    chain: ChainSpec | None = None    # the measurement chain ([chain]); None: ideal

    def sensor(self, name: str) -> SensorSpec | None:
        """The sensor called ``name``, or None when the scene does not record it."""
        for s in self.sensors:
            if s.name == name:
                return s
        return None


# ----------------------------------------------------------------------------- parsing
class _Reader:
    """Pops typed keys from one TOML table and complains precisely."""

    def __init__(self, source: str, path: str, table: Any) -> None:
        self.source, self.path = source, path
        if not isinstance(table, dict):
            self.fail(path, table, "must be a table")
        self.table = dict(table)

    def fail(self, key_path: str, value: Any, why: str) -> None:
        raise SceneError(f"{self.source}: `{key_path}` {why}, was {value!r}")

    def key(self, name: str) -> str:
        return f"{self.path}.{name}" if self.path else name

    def _get(self, name: str, required: bool) -> Any:
        if name not in self.table:
            if required:
                raise SceneError(f"{self.source}: missing key `{self.key(name)}`")
            return None
        return self.table.pop(name)

    def number(self, name: str, default: Any = None, *, required: bool = False,
               low: float | None = None, high: float | None = None, strict_low: bool = False) -> Any:
        v = self._get(name, required)
        if v is None:
            return default
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(self.key(name), v, "must be a number")
        v = float(v)
        if not math.isfinite(v):
            self.fail(self.key(name), v, "must be finite")
        if low is not None and (v <= low if strict_low else v < low):
            self.fail(self.key(name), v, f"must be {'>' if strict_low else '>='} {low}")
        if high is not None and v > high:
            self.fail(self.key(name), v, f"must be <= {high}")
        return v

    def positive(self, name: str, default: Any = None, *, required: bool = False) -> Any:
        return self.number(name, default, required=required, low=0.0, strict_low=True)

    def integer(self, name: str, default: Any = None, *, required: bool = False, low: int = 0) -> Any:
        v = self._get(name, required)
        if v is None:
            return default
        if isinstance(v, bool) or not isinstance(v, int):
            self.fail(self.key(name), v, "must be an integer")
        if v < low:
            self.fail(self.key(name), v, f"must be >= {low}")
        return int(v)

    def string(self, name: str, default: Any = None, *, required: bool = False,
               choices: tuple[str, ...] | None = None) -> Any:
        v = self._get(name, required)
        if v is None:
            return default
        if not isinstance(v, str):
            self.fail(self.key(name), v, "must be a string")
        if choices is not None and v not in choices:
            self.fail(self.key(name), v, f"must be one of {list(choices)}")
        return v

    def numbers(self, name: str, default: Any = None) -> Any:
        v = self._get(name, False)
        if v is None:
            return default
        if not isinstance(v, list) or any(isinstance(x, bool) or not isinstance(x, (int, float))
                                          or not math.isfinite(x) or x < 0 for x in v):
            self.fail(self.key(name), v, "must be a list of finite numbers >= 0")
        return tuple(float(x) for x in v)

    def sub(self, name: str, *, required: bool = False) -> _Reader | None:
        v = self._get(name, required)
        return None if v is None else _Reader(self.source, self.key(name), v)

    def done(self) -> None:
        if self.table:
            name = sorted(self.table)[0]
            self.fail(self.key(name), self.table[name], "is not a known key")


def parse_scene(data: dict[str, Any], source: str = "<scene>") -> Scene:
    """Validate a scene given as a TOML-like dict; see :func:`load_scene`.

    Raises
    ------
    SceneError
        On an unknown key, a missing key, a wrong type or an out-of-range value.
    """
    top = _Reader(source, "", data)
    head = top.sub("scene", required=True)
    assert head is not None
    campaign_id = head.string("campaign_id", required=True)
    description = head.string("description", "synthetic plate/striker campaign")
    seed = head.integer("seed", 0)
    start_iso = head.string("start_iso", "2024-03-01T14:00:00Z")
    sample_rate_hz = head.positive("sample_rate_hz", required=True)
    mic_distance_m = head.positive("mic_distance_m", 0.3)
    head.done()

    plate = None
    pr = top.sub("plate")
    if pr is not None:
        plate = PlateSpec(length_m=pr.positive("length_m", required=True),
                          width_m=pr.positive("width_m", required=True),
                          thickness_m=pr.positive("thickness_m", required=True),
                          E_pa=pr.positive("E_pa", 7.0e10), nu=pr.number("nu", 0.33, low=-0.99, high=0.49),
                          rho_kg_m3=pr.positive("rho_kg_m3", 2700.0),
                          edges=pr.string("edges", "CFCF"), material=pr.string("material", "aluminium"))
        if len(plate.edges) != 4 or set(plate.edges) - set("CSF"):
            pr.fail(pr.key("edges"), plate.edges, "must be four letters of C, S, F")
        pr.done()

    mr = top.sub("model", required=True)
    assert mr is not None
    model = ModelSpec(gap_m=mr.positive("gap_m", required=True),
                      e=mr.number("e", required=True, low=0.0, high=1.0),
                      zeta=mr.number("zeta", required=True, low=0.0, high=0.99),
                      f_s_hz=mr.positive("f_s_hz"), participation=mr.positive("participation"),
                      ringing_freqs_hz=mr.numbers("ringing_freqs_hz"),
                      ringing_m_s2_per_m_s=mr.number("ringing_m_s2_per_m_s", 2000.0, low=0.0),
                      ringing_decay_s=mr.positive("ringing_decay_s", 0.004),
                      contact_s=mr.positive("contact_s", 0.0002))
    kind = mr.string("kind", "sdf", choices=("sdf", "modal"))
    if kind == "modal":
        for name in ("f_s_hz", "participation", "ringing_freqs_hz"):
            if getattr(model, name) is not None:   # the plate's modes give them
                mr.fail(mr.key(name), getattr(model, name), 'must not be given with kind = "modal"')
        if plate is None:
            mr.fail(mr.key("kind"), kind, "needs a [plate] table")
        model = ModelSpec(**{**model.__dict__, "kind": kind, "modal": parse_modal(mr)})
    if plate is None:
        for name in ("f_s_hz", "participation"):
            if getattr(model, name) is None:
                raise SceneError(f"{source}: `model.{name}` is required when the scene has no "
                                 f"[plate], was None")
    mr.done()

    acoustic = None
    ar = top.sub("acoustic")
    if ar is not None:
        acoustic = AcousticSpec(
            pa_per_m_s=ar.number("pa_per_m_s", required=True, low=0.0),
            intercept_pa=ar.number("intercept_pa", 0.0),
            distance_m=ar.positive("distance_m", mic_distance_m), c_m_s=ar.positive("c_m_s", 343.0),
            radiation_lag_s=ar.number("radiation_lag_s", 0.0003, low=0.0),
            ring_freq_hz=ar.positive("ring_freq_hz", 1200.0),
            ring_decay_s=ar.positive("ring_decay_s", 0.0015),
            second_peak_probability=ar.number("second_peak_probability", 0.0, low=0.0, high=1.0),
            second_peak_ratio=ar.positive("second_peak_ratio", 1.3),
            second_peak_delay_s=ar.positive("second_peak_delay_s", 0.0015),
            mode_pa_per_m_s2=ar.number("mode_pa_per_m_s2", 0.0002, low=0.0))
        if model.kind == "modal":   # the modal model radiates its own sound
            ar.fail("acoustic", "[acoustic]", 'must not be given with `model.kind` = "modal"')
        ar.done()

    sensors = []
    sr = top.sub("sensors", required=True)
    assert sr is not None
    for name in list(sr.table):
        if name not in SENSOR_QUANTITIES:
            sr.fail(sr.key(name), sr.table[name], f"is not a known sensor (known: {list(SENSOR_QUANTITIES)})")
        s = sr.sub(name)
        assert s is not None
        spec = SensorSpec(name=name, noise_rms=s.number("noise_rms", required=True, low=0.0),
                          sensitivity=s.positive("sensitivity"),
                          sensitivity_units=s.string("sensitivity_units"),
                          range=s.positive("range"), model=s.string("model"),
                          band_hz=s.positive("band_hz"), volts_per_m_s2=s.positive("volts_per_m_s2", 0.05))
        if (spec.sensitivity is None) != (spec.sensitivity_units is None) or (
                name == "drive" and spec.sensitivity is not None):
            s.fail(s.key("sensitivity"), spec.sensitivity,
                   "must come with `sensitivity_units` (and not for the drive)")
        if spec.noise_rms == 0.0 and name in ("mic", "plate", "velocity", "base"):
            s.fail(s.key("noise_rms"), 0.0, "must be > 0 (exact zeros are read as dropouts)")
        s.done()
        sensors.append(spec)
    sr.done()
    if acoustic is None and model.kind != "modal" and any(s.name == "mic" for s in sensors):
        raise SceneError(f"{source}: `sensors.mic` needs an [acoustic] table, was None")
    if not sensors:
        raise SceneError(f"{source}: `sensors` must name at least one sensor, was {{}}")

    runs = []
    raw_runs = top._get("runs", True)
    if not isinstance(raw_runs, list) or not raw_runs:
        top.fail("runs", raw_runs, "must be a non-empty array of tables ([[runs]])")
    seen: set[str] = set()
    for i, raw in enumerate(raw_runs):
        r = _Reader(source, f"runs[{i}]", raw)
        run = RunSpec(run_id=r.string("run_id", required=True),
                      protocol=r.string("protocol", required=True, choices=RUN_PROTOCOLS),
                      freq_hz=r.positive("freq_hz", required=True),
                      level_m_s2=r.number("level_m_s2", required=True, low=0.0),
                      duration_s=r.positive("duration_s", required=True),
                      level_end_m_s2=r.number("level_end_m_s2", None, low=0.0),
                      freq_end_hz=r.positive("freq_end_hz"), freq_step_hz=r.positive("freq_step_hz"),
                      sample_rate_hz=r.positive("sample_rate_hz"), notes=r.string("notes", ""))
        ramp = run.protocol.startswith("amplitude_ramp")
        freq = run.protocol in ("stepped_frequency", "swept_frequency")
        if ramp != (run.level_end_m_s2 is not None):
            r.fail(r.key("level_end_m_s2"), run.level_end_m_s2,
                   "is required for ramps and only for ramps")
        if freq != (run.freq_end_hz is not None):
            r.fail(r.key("freq_end_hz"), run.freq_end_hz,
                   "is required for stepped/swept runs and only for them")
        if (run.protocol == "stepped_frequency") != (run.freq_step_hz is not None):
            r.fail(r.key("freq_step_hz"), run.freq_step_hz, "is required for stepped runs and only for them")
        if run.run_id.lower() in seen:
            r.fail(r.key("run_id"), run.run_id, "is a duplicate")
        seen.add(run.run_id.lower())
        r.done()
        runs.append(run)

    art = ArtefactSpec()
    tr = top.sub("artefacts")
    if tr is not None:
        art = ArtefactSpec(fan_hz=tr.positive("fan_hz", 88.0), fan_m_s2=tr.number("fan_m_s2", 0.0, low=0.0),
                           fan_pa=tr.number("fan_pa", 0.0, low=0.0), harmonics=tr.numbers("harmonics", ()),
                           harmonics_impact=tr.numbers("harmonics_impact", ()),
                           harmonics_tau_s=tr.positive("harmonics_tau_s", 0.05),
                           dropout_s=tr.number("dropout_s", 0.0, low=0.0))
        if art.harmonics_impact and len(art.harmonics_impact) != len(art.harmonics):
            tr.fail(tr.key("harmonics_impact"), list(art.harmonics_impact),
                    f"must have as many entries as `harmonics` ({len(art.harmonics)})")
        tr.done()
    chain = None
    cr = top.sub("chain")
    if cr is not None:
        chain = parse_chain(cr)
        if model.kind == "modal" and chain.ring_velocity_per_m_s:   # the modes ring by themselves
            cr.fail(cr.key("ring_velocity_per_m_s"), chain.ring_velocity_per_m_s,
                    'must be 0 with `model.kind` = "modal" (the plate\'s modes ring physically)')
    sim = SimulationSpec()
    smr = top.sub("simulation")
    if smr is not None:
        sim = SimulationSpec(piece_periods=smr.integer("piece_periods", 1, low=1),
                             settle_time_constants=smr.number("settle_time_constants", 8.0, low=0.0))
        smr.done()
    top.done()
    return Scene(campaign_id=campaign_id, description=description, seed=seed, start_iso=start_iso,
                 sample_rate_hz=sample_rate_hz, model=model, runs=tuple(runs), sensors=tuple(sensors),
                 plate=plate, acoustic=acoustic, artefacts=art, simulation=sim,
                 mic_distance_m=mic_distance_m, source=source, chain=chain)


def load_scene(scene: str | os.PathLike[str]) -> Scene:
    """Read and validate a scene: a TOML file path, or ``"default"`` for the embedded scene.

    Raises
    ------
    SceneError
        If the file is missing, is not TOML, or is not a valid scene.

    Examples
    --------
    >>> load_scene("default").campaign_id
    'demo-cfcf'
    """
    # "default": the embedded scene (whatever the folder holds); else a file, or a scene
    # shipped with rattle_lab, by name
    embedded = find_resource("scenes", "default") if str(scene) == "default" else None
    path = embedded or resolve_resource("scenes", scene, SceneError, "cannot read the scene")
    source = "default" if embedded else str(path)
    try:
        text = path.read_text("utf-8")
    except OSError as exc:
        raise SceneError(f"{source}: cannot read the scene: {exc.strerror}") from exc
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{source}: not valid TOML: {exc}") from exc
    return parse_scene(data, source)
