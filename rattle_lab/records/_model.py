"""Domain objects of a rattle record: Record, Rig, Run, Channel, Truth.

They are frozen dataclasses.  Channel samples are not held in memory: each
channel has a *source* (anything with ``n_samples``, ``dtype`` and
``read(start, stop)``) and reads slices on demand, so a one-hour record is
never loaded whole.  ``Channel.read`` returns SI values by default
(``scale_to_si * stored``).

Equality (``==``) compares metadata only; compare samples with
``channel.read()``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._units import scale_to_si

Protocol_ = Literal["sine_dwell", "amplitude_ramp_up", "amplitude_ramp_down", "stepped_frequency",
                    "swept_frequency", "transient", "unspecified"]

#: Default number of samples read at a time when streaming a channel.
DEFAULT_CHUNK_SAMPLES = 1 << 20


@runtime_checkable
class ArraySource(Protocol):
    """Lazy 1-D samples: ``n_samples``, ``dtype`` and ``read(start, stop)``."""

    n_samples: int
    dtype: np.dtype[Any]

    def read(self, start: int, stop: int) -> np.ndarray: ...


class ArrayData:
    """An in-memory array as a source (what writers and tests pass)."""

    def __init__(self, array: Any) -> None:
        arr = np.asarray(array)
        if arr.ndim != 1:
            raise ParameterError(f"channel data must be 1-D, got shape {arr.shape}")
        self.array = arr
        self.n_samples = int(arr.shape[0])
        self.dtype = arr.dtype

    def read(self, start: int, stop: int) -> np.ndarray:
        return self.array[start:stop]


class GeneratedData:
    """Samples made on demand by ``func(start, stop) -> array`` (for long synthetic records).

    Parameters
    ----------
    n_samples : int
        Length of the channel.
    dtype : numpy dtype
        dtype of the arrays ``func`` returns.
    func : callable
        ``func(start, stop)`` returns samples ``start:stop``; it must be a pure
        function of its arguments (use ``np.random.default_rng((seed, start))``
        for noise) so that reads are repeatable.
    """

    def __init__(self, n_samples: int, dtype: Any, func: Callable[[int, int], np.ndarray]) -> None:
        if n_samples < 0:
            raise ParameterError(f"`n_samples` must be >= 0, was {n_samples}")
        self.n_samples = int(n_samples)
        self.dtype = np.dtype(dtype)
        self.func = func

    def read(self, start: int, stop: int) -> np.ndarray:
        out = np.asarray(self.func(start, stop), dtype=self.dtype)
        if out.shape != (stop - start,):
            raise ParameterError(f"generator returned shape {out.shape} for samples {start}:{stop}")
        return out


def as_source(data: Any) -> ArraySource:
    """Wrap arrays as :class:`ArrayData`; pass sources through."""
    if isinstance(data, ArraySource) and not isinstance(data, np.ndarray):
        return data
    return ArrayData(data)


def si_dtype(dtype: np.dtype[Any]) -> np.dtype[Any]:
    """dtype of SI values: float64 for float64 and wide integers, float32 otherwise.

    float32 holds a 24-bit ADC word exactly; int32/int64 need float64.
    """
    dtype = np.dtype(dtype)
    if dtype.kind == "f" and dtype.itemsize >= 8:
        return np.dtype("f8")
    if dtype.kind in "iu" and dtype.itemsize >= 4:
        return np.dtype("f8")
    return np.dtype("f4")


@dataclass(frozen=True)
class Sensor:
    """A sensor of the rig.

    Attributes
    ----------
    sensor_id : str
        Name, referenced by channels' ``sensor_id``.
    position_m : tuple of 3 floats
        ``(x, y, z)`` in metres from the plate corner at x=0, y=0; x along the
        plate length, y along its width, z normal to the plate, up.
    mounted_on : str
        ``"base"``, ``"plate"``, ``"striker"``, ``"stand"`` or ``"other"``.
    description : str
        Free text.
    """

    sensor_id: str
    position_m: tuple[float, float, float]
    mounted_on: Literal["base", "plate", "striker", "stand", "other"]
    description: str = ""
    extra: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Rig:
    """The test rig of a campaign (``/rig`` attributes).

    Attributes
    ----------
    apparatus : str
        ``"plate_striker"`` (the rattle rig; plate, striker and microphone
        fields required) or ``"other"`` (a foreign record; ``description`` required).
    plate_length_m, plate_width_m, plate_thickness_m : float
        Plate dimensions, m.
    plate_material : str
        E.g. ``"aluminium 6061"``.
    edge_conditions : str
        Four letters C/S/F for the edges y=0, x=length, y=width, x=0 (the order of
        :data:`rattle_lab.model.plate.EDGE_ORDER`; ``"CFCF"`` clamps the two edges of length
        ``plate_length_m``, the thesis plate).
    striker_x_m, striker_y_m : float
        Striker position in plate coordinates, m.
    gap_m : float or None
        Measured static gap between plate and striker, m, when known.
    mic_distance_m : float
        Microphone distance from the plate, m.
    modal_participation : float or None
        Modal participation factor ``Q1/Q2`` of the fitted mode at the measurement point
        (thesis eq. 2.27), when known (schema v2).
    plate_poisson_ratio : float or None
        Poisson's ratio of the plate, for the plate model's ``Q1/Q2`` (schema v2).
    sensors : tuple of Sensor
        Sensor positions.
    """

    apparatus: Literal["plate_striker", "other"]
    description: str = ""
    plate_length_m: float | None = None
    plate_width_m: float | None = None
    plate_thickness_m: float | None = None
    plate_material: str | None = None
    edge_conditions: str | None = None
    striker_x_m: float | None = None
    striker_y_m: float | None = None
    gap_m: float | None = None
    mic_distance_m: float | None = None
    modal_participation: float | None = None
    plate_poisson_ratio: float | None = None
    sensors: tuple[Sensor, ...] = ()
    extra: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Channel:
    """One recorded signal (an HDF5 dataset ``/runs/{run_id}/channels/{name}``).

    Attributes
    ----------
    name : str
        Channel name.
    quantity : str
        ``base_acceleration``, ``plate_acceleration``, ``plate_velocity``,
        ``sound_pressure``, ``drive_signal`` or ``excitation_force``.
    units : str
        Units of the stored samples (see ``rattle_lab.records._units``); ``"V"``
        for raw volts of a transducer, ``"1"`` for uncalibrated full-scale values.
    data : ArraySource
        The stored samples (lazy).  Not compared by ``==``.
    sample_rate_hz, start_time_s : float or None
        Regular sampling: t_k = start_time_s + k / sample_rate_hz, s.
    timestamps : str or None
        Irregular sampling: name of a dataset in ``/runs/{run_id}/timestamps``.
    sensitivity, sensitivity_units : float, str or None
        Transducer sensitivity for raw volts.
    sensor_id, sensor_model, sensor_serial, calibration_date : str or None
        Sensor identity; ``calibration_date`` is ISO 8601 (``YYYY-MM-DD``).
    range_min, range_max : float or None
        Input range of the acquisition in stored units (used to detect clipping).
    units_assumed : bool
        True when the units were not stated by the source but assumed.
    description : str
        Free text.
    measurand : str or None
        Plate velocity only (schema v2): ``"panel_absolute"`` (the panel alone) or
        ``"panel_relative_to_striker"`` (differential vibrometer, two beams subtracted).
    sign_convention : str or None
        ``"toward_striker_positive"`` or ``"away_from_striker_positive"`` (schema v2).
    group_delay_s : float or None
        Known group delay of the channel's filters (vibrometer decoder, anti-alias), s:
        an event shows ``group_delay_s`` late; compensated before channels are paired.
    filter_type, filter_order, filter_cutoff_hz, filter_sample_rate_hz : str, int, float, float or None
        The channel's low-pass filter where its delay is not known (schema v2): family
        (``"butterworth"`` or ``"bessel"``), order, -3 dB cut-off in Hz and, for a digital
        filter, the rate it runs at (absent: analog).  Its low-frequency group delay
        (:func:`~rattle_lab.records.filter_group_delay_s`) is compensated like
        ``group_delay_s``, which takes precedence when both are given.
    adc_gain, adc_offset : float or None
        Raw ADC counts (schema v2): the stored integers are counts, and
        ``adc_gain * count + adc_offset`` is the value in :attr:`units` (``adc_gain`` > 0, in
        units per count; ``adc_offset`` in units, default 0).  :meth:`read` applies them, then
        the conversion of :attr:`units` to SI; ``range_min``/``range_max`` stay in counts.
    """

    name: str
    quantity: str
    units: str
    data: ArraySource = field(compare=False, repr=False)
    sample_rate_hz: float | None = None
    start_time_s: float | None = None
    timestamps: str | None = None
    sensitivity: float | None = None
    sensitivity_units: str | None = None
    sensor_id: str | None = None
    sensor_model: str | None = None
    sensor_serial: str | None = None
    calibration_date: str | None = None
    range_min: float | None = None
    range_max: float | None = None
    units_assumed: bool = False
    description: str = ""
    measurand: str | None = None
    sign_convention: str | None = None
    group_delay_s: float | None = None
    adc_gain: float | None = None
    adc_offset: float | None = None
    filter_type: str | None = None
    filter_order: int | None = None
    filter_cutoff_hz: float | None = None
    filter_sample_rate_hz: float | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "data", as_source(self.data))
        from ._chain import check_filter

        problem = check_filter(self.filter_type, self.filter_order, self.filter_cutoff_hz,
                               self.filter_sample_rate_hz)
        if problem is not None:
            raise ParameterError(f"channel {self.name!r}: {problem}")
        if self.adc_gain is not None and not (np.isfinite(self.adc_gain) and self.adc_gain > 0):
            raise ParameterError(f"channel {self.name!r}: `adc_gain` must be finite and > 0, "
                                 f"was {self.adc_gain}")
        if self.adc_offset is not None and self.adc_gain is None:
            raise ParameterError(f"channel {self.name!r}: `adc_offset` needs `adc_gain`")

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.data.n_samples)

    @property
    def si_units(self) -> str:
        """SI unit of :meth:`read` (``"1"`` for uncalibrated data)."""
        return scale_to_si(self.quantity, self.units, self.sensitivity, self.sensitivity_units)[1]

    @property
    def scale_to_si(self) -> float:
        """Factor from the stored numbers (ADC counts when :attr:`adc_gain` is set) to :attr:`si_units`."""
        scale = scale_to_si(self.quantity, self.units, self.sensitivity, self.sensitivity_units)[0]
        return scale * self.adc_gain if self.adc_gain is not None else scale

    @property
    def offset_si(self) -> float:
        """Offset added after :attr:`scale_to_si`, SI units (``adc_offset`` converted; else 0)."""
        if self.adc_offset is None:
            return 0.0
        return scale_to_si(self.quantity, self.units, self.sensitivity,
                           self.sensitivity_units)[0] * self.adc_offset

    @property
    def uncalibrated(self) -> bool:
        """True when the amplitude is not traceable to a calibration."""
        return self.units == "1" or self.units_assumed

    def read(self, start: int = 0, stop: int | None = None, *, si: bool = True) -> np.ndarray:
        """Samples ``start:stop``, in SI units unless ``si=False``.

        Examples
        --------
        >>> import numpy as np
        >>> ch = Channel("acc", "plate_acceleration", "g", np.array([0.0, 1.0, 2.0]),
        ...              sample_rate_hz=1000.0, start_time_s=0.0)
        >>> bool(np.allclose(ch.read(), [0.0, 9.80665, 19.6133], rtol=1e-15))   # g0 = 9.80665 m/s^2
        True
        >>> ch.read(si=False).tolist()
        [0.0, 1.0, 2.0]

        Raw 16-bit counts of a +-10 V ADC, 100 mV/g accelerometer, -2 mV offset:

        >>> adc = Channel("acc", "plate_acceleration", "V", np.array([0, 3277], dtype="i2"),
        ...               sample_rate_hz=1000.0, start_time_s=0.0, sensitivity=100.0,
        ...               sensitivity_units="mV/g", adc_gain=10.0 / 32768, adc_offset=-0.002)
        >>> [round(float(x), 4) for x in adc.read()]    # m/s^2: (gain * count + offset) / 0.1 V/g * g0
        [-0.1961, 97.8764]
        """
        stop = self.n_samples if stop is None else stop
        if not 0 <= start <= stop <= self.n_samples:
            raise ParameterError(f"`start`:`stop` must lie in 0:{self.n_samples}, was {start}:{stop}")
        raw = self.data.read(start, stop)
        if not si:
            return raw
        out = to_si(raw, self.scale_to_si)
        offset = self.offset_si
        if offset != 0.0:
            out = out + out.dtype.type(offset)
        return out

    def iter_chunks(self, n_chunk_samples: int = DEFAULT_CHUNK_SAMPLES, *,
                    si: bool = True) -> Iterator[tuple[int, np.ndarray]]:
        """Yield ``(start, samples)`` for consecutive chunks of at most ``n_chunk_samples``."""
        if n_chunk_samples < 1:
            raise ParameterError(f"`n_chunk_samples` must be >= 1, was {n_chunk_samples}")
        for start in range(0, self.n_samples, n_chunk_samples):
            stop = min(self.n_samples, start + n_chunk_samples)
            yield start, self.read(start, stop, si=si)


def to_si(raw: np.ndarray, scale: float) -> np.ndarray:
    """``scale * raw`` in :func:`si_dtype` (no copy when nothing changes)."""
    dtype = si_dtype(raw.dtype)
    if scale == 1.0:
        return raw if raw.dtype == dtype else raw.astype(dtype)
    return np.multiply(raw, dtype.type(scale), dtype=dtype)


@dataclass(frozen=True)
class Run:
    """One run of a campaign (``/runs/{run_id}``).

    Attributes
    ----------
    run_id : str
        Unique within the campaign.
    protocol : str
        ``sine_dwell``; ``amplitude_ramp_up`` / ``amplitude_ramp_down`` (level
        from ``nominal_level`` to ``level_end`` at ``excitation_freq_hz``);
        ``stepped_frequency`` / ``swept_frequency`` (from ``excitation_freq_hz``
        to ``freq_end_hz``); ``transient`` (a single shock, for foreign records);
        ``unspecified`` (a foreign file that does not say).
    channels : tuple of Channel
        The channels.
    excitation_freq_hz, freq_end_hz, freq_step_hz : float or None
        Excitation frequency (start), end and step, Hz.
    nominal_level, level_end : float or None
        Nominal excitation level (start, end) in ``nominal_level_units``.
    nominal_level_units : str or None
        ``m/s^2``, ``g``, ``V``, ``mV``, ``N`` or ``1``.
    start_time_iso : str or None
        Start of the run, ISO 8601 (local time unless it carries an offset).
    notes : str
        Free text.
    detect_channel : str or None
        The channel events are detected on, when the record says (schema v2); else
        chosen by what each channel measures.
    timestamps : mapping of str to ArraySource
        Explicit time bases referenced by channels, in s.  Not compared by ``==``.
    """

    run_id: str
    protocol: Protocol_
    channels: tuple[Channel, ...]
    excitation_freq_hz: float | None = None
    freq_end_hz: float | None = None
    freq_step_hz: float | None = None
    nominal_level: float | None = None
    level_end: float | None = None
    nominal_level_units: str | None = None
    start_time_iso: str | None = None
    notes: str = ""
    detect_channel: str | None = None
    timestamps: Mapping[str, ArraySource] = field(default_factory=dict, compare=False, repr=False)
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "channels", tuple(self.channels))
        object.__setattr__(self, "timestamps",
                           {k: as_source(v) for k, v in dict(self.timestamps).items()})

    def channel(self, name: str) -> Channel:
        """The channel called ``name``."""
        for ch in self.channels:
            if ch.name == name:
                return ch
        raise ParameterError(f"run {self.run_id!r} has no channel {name!r} "
                             f"(has: {', '.join(c.name for c in self.channels)})")


@dataclass(frozen=True, eq=False)
class ImpactTable:
    """True impacts of one synthetic run: times (s) and normal velocities (m/s) in and out."""

    t_s: np.ndarray
    v_in_m_s: np.ndarray
    v_out_m_s: np.ndarray

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ImpactTable) and all(
            np.array_equal(getattr(self, k), getattr(other, k), equal_nan=True)
            for k in ("t_s", "v_in_m_s", "v_out_m_s"))


@dataclass(frozen=True, eq=False)
class ThresholdTable:
    """True impact thresholds against frequency.

    ``onset_level``: excitation level at which impacts appear on an increasing
    ramp; ``disappearance_level``: level at which they vanish on a decreasing
    ramp (NaN where not reached); both in ``level_units``.
    """

    freq_hz: np.ndarray
    onset_level: np.ndarray
    disappearance_level: np.ndarray
    level_units: str

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ThresholdTable) and self.level_units == other.level_units and all(
            np.array_equal(getattr(self, k), getattr(other, k), equal_nan=True)
            for k in ("freq_hz", "onset_level", "disappearance_level"))


@dataclass(frozen=True)
class Truth:
    """Ground truth of a synthetic record (``/truth``).

    Attributes
    ----------
    gap_m : float
        Gap between plate and striker, m.
    f_s_hz : float
        Natural frequency of the plate mode, Hz.
    zeta : float
        Modal damping ratio, nondimensional.
    e : float
        Coefficient of restitution, nondimensional.
    participation : float
        Modal participation factor of the base excitation, nondimensional.
    acoustic_law : str
        The law that made the sound pressure from the impacts (free text or formula).
    impacts : mapping of run_id to ImpactTable
        Every impact's time and velocities.
    thresholds : ThresholdTable
        Onset and disappearance levels against frequency.
    extra : mapping
        Further model parameters (scalars), names carrying their units.
    """

    gap_m: float
    f_s_hz: float
    zeta: float
    e: float
    participation: float
    acoustic_law: str
    impacts: Mapping[str, ImpactTable]
    thresholds: ThresholdTable
    extra: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Skipped:
    """A column or channel of a foreign file that was not ingested, and why."""

    source: str
    reason: str


@dataclass(frozen=True)
class Origin:
    """Where a record was read from."""

    path: Path
    format: str
    skipped: tuple[Skipped, ...] = ()
    closer: Callable[[], None] | None = field(default=None, repr=False, compare=False)


@dataclass(frozen=True)
class Record:
    """A campaign: its rig, its runs and, for synthetic records, the truth.

    Use as a context manager (or call :meth:`close`) to release the file.

    Attributes
    ----------
    campaign_id : str
        Campaign name.
    source : str
        ``"measured"`` or ``"synthetic"``.
    rig : Rig
        The rig.
    runs : tuple of Run
        The runs.
    truth : Truth or None
        Ground truth (synthetic records only).
    description, operator, created_iso, writer : str or None
        Free text; creation time (ISO 8601); the program that wrote the file.
    origin : Origin or None
        File and format read from, and skipped columns.  Not compared.
    """

    campaign_id: str
    source: Literal["measured", "synthetic"]
    rig: Rig
    runs: tuple[Run, ...]
    truth: Truth | None = None
    description: str = ""
    operator: str | None = None
    created_iso: str | None = None
    writer: str | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    origin: Origin | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "runs", tuple(self.runs))

    def run(self, run_id: str) -> Run:
        """The run called ``run_id``."""
        for run in self.runs:
            if run.run_id == run_id:
                return run
        raise ParameterError(f"campaign {self.campaign_id!r} has no run {run_id!r} "
                             f"(has: {', '.join(r.run_id for r in self.runs)})")

    def close(self) -> None:
        """Release the file behind the lazy channels (reads after this reopen it)."""
        if self.origin is not None and self.origin.closer is not None:
            self.origin.closer()

    def __enter__(self) -> Record:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def duration_s(channel: Channel) -> float:
    """Duration covered by a regularly sampled channel, ``n_samples / sample_rate_hz``, s."""
    if channel.sample_rate_hz is None:
        return math.nan
    return channel.n_samples / channel.sample_rate_hz
