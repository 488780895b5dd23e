"""What the report draws: frozen, plain data, one dataclass per page and one for the report.

These types are all the report knows of the rest of the package.  They hold arrays,
numbers and strings that were computed before drawing (by
:func:`rattle_lab.workflow.build_report_content`, from a store); a page module reads
their fields and draws, and nothing here computes.  A test builds each of them by hand
and renders every page without a store.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

# --- rig -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ChannelInfo:
    """Rig/calibration facts of one stored channel (first run in which it appears)."""

    input_key: str
    name: str
    quantity: str
    units: str
    source_units: str
    scale_to_si: float
    sensitivity: str
    sample_rate_hz: float
    sensor_model: str
    sensor_serial: str
    calibration_date: str
    range_si: str
    position_m: str


@dataclass(frozen=True)
class RecordInfo:
    """Rig facts of one ingested input."""

    input_key: str
    campaign_id: str
    source: str
    rig: dict[str, Any]
    channels: tuple[ChannelInfo, ...]
    runs: dict[str, dict[str, Any]]  # run_id -> protocol, freq_hz, level, level_end, units


@dataclass(frozen=True)
class RigContent:
    """The records whose rig facts and channels the rig page tabulates."""

    records: tuple[RecordInfo, ...]


# --- thresholds ------------------------------------------------------------------------------

@dataclass(frozen=True)
class GrazingCurve:
    """Eq. (3.4) at the fitted parameters on a frequency grid, with its 95 % band."""

    grid_hz: np.ndarray
    accel_ms2: np.ndarray
    band_ms2: tuple[np.ndarray, np.ndarray] | None  # lower and upper edge (None: no band)
    dof: int | None             # Student t degrees of freedom of the band (None: normal)
    gap_m: float
    f_s_hz: float
    zeta: float
    outlier_freq_hz: np.ndarray | None  # None: the fit left no threshold out
    outlier_up_ms2: np.ndarray | None
    #: measured onset less the curve, at the measured frequencies (None: not computed)
    residual_freq_hz: np.ndarray | None = None
    residual_ms2: np.ndarray | None = None
    #: what the curve is ("eq. (3.4) fit", "eq. (3.4) at the ramp-corrected ...")
    label: str = "eq. (3.4) fit"


@dataclass(frozen=True)
class ThresholdContent:
    """Measured thresholds, their hysteresis and the eq. (3.4) fit curve (None: not fitted)."""

    freq_hz: np.ndarray
    up_ms2: np.ndarray
    down_ms2: np.ndarray
    hysteresis_ms2: np.ndarray
    negative: np.ndarray        # bool: disappearance above onset beyond its uncertainty
    both: np.ndarray            # bool: onset and disappearance measured
    bar_width_hz: float
    curve: GrazingCurve | None
    missing: tuple[tuple[str, str], ...] = ()  # parts left out (name, why)
    #: eq. (3.4) at the ramp-corrected parameters (None: no ramp-corrected fit); its
    #: ``residual_ms2`` is this curve less the eq. (3.4) fit's, at the measured frequencies
    corrected: GrazingCurve | None = None
    #: index ranges ``(i, j)`` (``j`` exclusive) into the frequencies where both thresholds
    #: are measured, over which the hysteresis is shaded: neighbours on the measured grid
    #: only (no shading across a frequency without a run)
    hysteresis_segments: tuple[tuple[int, int], ...] = ()


# --- impact patterns -------------------------------------------------------------------------

@dataclass(frozen=True)
class PatternContent:
    """One point per forcing cycle of each analysed run, and one marker per dwell and class.

    ``points`` columns: frequency (Hz, ramps shifted -0.12 up / +0.12 down), nominal level,
    impacts in the cycle, 1.0 for a dwell (else 0.0).  ``dwell_shares``: ``(class, freq,
    level, share of the dwell's cycles in the class)``, class 3 meaning >= 3 impacts.
    """

    points: np.ndarray
    level_units: tuple[str, ...]
    dwell_shares: tuple[tuple[int, float, float, float], ...]


# --- SPL law ---------------------------------------------------------------------------------

@dataclass(frozen=True)
class SplCurve:
    """One fitted SPL law with its measured points and the 95 % band of its mean."""

    name: str                     # "first", "max" or "rms"
    v_m_s: np.ndarray
    p_pa: np.ndarray
    slope: float
    intercept: float
    r2: float
    grid_m_s: np.ndarray
    line_pa: np.ndarray               # the law on the grid
    band_pa: tuple[np.ndarray, np.ndarray] | None  # 95 % band of the mean (None: < 3 points
    #                                                or no spread in v)
    #: per point: True where a later peak of the impact is larger than its first peak
    #: (None: not known); the maximum-peak and RMS clouds split along it
    later_max: np.ndarray | None = None


@dataclass(frozen=True)
class SplContent:
    """The SPL laws in drawing order (RMS, maximum, first peak)."""

    curves: tuple[SplCurve, ...]


# --- waveforms -------------------------------------------------------------------------------

WAVEFORM_QUANTITIES = (("plate_acceleration", "plate acceleration (m/s^2)"),
                       ("plate_velocity", "plate velocity (m/s)"),
                       ("sound_pressure", "sound pressure (Pa)"))


@dataclass(frozen=True)
class Trace:
    """A window of one stored channel with the detected events inside it.

    ``impact_t_s``: impacts in the window; ``impact_y``: the trace at those times;
    ``peaks``: for the sound pressure, ``(which, t_s, y)`` of the first and maximum
    peaks (empty where the run has no sound peaks).
    """

    t_s: np.ndarray
    y: np.ndarray
    impact_t_s: np.ndarray
    impact_y: np.ndarray
    peaks: tuple[tuple[str, np.ndarray, np.ndarray], ...] = ()


@dataclass(frozen=True)
class WaveformColumn:
    """One example run: its facts and one trace per quantity (None: no such channel)."""

    run_id: str
    protocol: str
    freq_hz: float
    pattern: str
    traces: tuple[Trace | None, ...]  # in WAVEFORM_QUANTITIES order


@dataclass(frozen=True)
class WaveformContent:
    """The example runs, steady (dwell) runs first."""

    columns: tuple[WaveformColumn, ...]


# --- acoustics -------------------------------------------------------------------------------

@dataclass(frozen=True)
class AcousticsContent:
    """Per-run acoustic results against the run's RMS impact velocity.

    ``rows``: the summary rows of the runs with acoustics (``RunRow.to_dict()``) with
    ``v_rms_m_s`` added.  ``band_traces``: ``("rattle" | "background", f_hz, level_db)``
    per run; ``band_means``: the energy mean over runs of each (None: no bands).
    ``level_guide`` / ``loudness_guide``: 20 dB per decade and ``N ~ v^0.602`` through
    the points (None: no finite point).  ``calibration_note``: how the microphones were
    calibrated, one line; ``sound_fields``: the sound fields the loudness assumed.
    """

    rows: tuple[dict[str, Any], ...]
    band_traces: tuple[tuple[str, np.ndarray, np.ndarray], ...]
    band_means: Mapping[str, tuple[np.ndarray, np.ndarray] | None]
    v_rms_m_s: np.ndarray
    laeq_db: np.ndarray
    lafmax_db: np.ndarray
    n5_sone: np.ndarray
    nmax_sone: np.ndarray
    level_guide: tuple[np.ndarray, np.ndarray] | None
    loudness_guide: tuple[np.ndarray, np.ndarray] | None
    calibration_note: str
    sound_fields: tuple[str, ...]
    listener: ListenerMetrics | None = None


@dataclass(frozen=True)
class ListenerMetrics:
    """What a listener judges, per run against its RMS impact velocity (the acoustics
    section's second page; NaN where a run has no value).

    ``impulse_prominence`` (P) and ``impulse_penalty_db`` (K_I, dB) of ISO/PAS 1996-3;
    ``impacts_per_s`` over the run's rattle episodes; ``above_background_sone`` the rattle's
    ISO 532-1 N5 less the background's, with ``background_spread_sone`` the spread of the
    background stretches' N5; ``loudness_ecma_sone``, ``tonality_tu``, ``roughness_asper``
    of ECMA-418-2 (NaN unless computed); ``ecma_note``: why they are absent, else "";
    ``flags``: the runs' psychoacoustic flags, each once.
    """

    impulse_prominence: np.ndarray
    impulse_penalty_db: np.ndarray
    impacts_per_s: np.ndarray
    above_background_sone: np.ndarray
    background_spread_sone: np.ndarray
    loudness_ecma_sone: np.ndarray
    tonality_tu: np.ndarray
    roughness_asper: np.ndarray
    ecma_note: str
    flags: tuple[str, ...]


# --- model predictions -----------------------------------------------------------------------

Field = tuple[np.ndarray, np.ndarray, np.ndarray]  # omega, F, smoothed 0/1 field


@dataclass(frozen=True)
class SweepComparison:
    """The model's onset and disappearance from F sweeps at the measured frequencies, m/s^2."""

    freq_hz: np.ndarray          # the swept frequencies
    onset_ms2: np.ndarray        # NaN: no impacts on the grid
    disappearance_ms2: np.ndarray
    half_step_ms2: float         # the resolution (half the sweep step)
    F_max_ms2: float             # the highest amplitude swept
    n_sweep: int
    measured_freq_hz: np.ndarray
    measured_up_ms2: np.ndarray
    measured_down_ms2: np.ndarray


@dataclass(frozen=True)
class ModelContent:
    """The bifurcation sets at the fitted zeta and e with the measured thresholds in (omega, F).

    ``sets``: a :class:`rattle_lab.model.analysis.BifurcationSets` (frozen; the page reads
    its grids, curves and grazing line).  ``exists_fields`` / ``stable_fields``: per ``n``
    of ``sets.ns`` the smoothed region (None: empty); ``both_field``: where the first two
    orbits coexist (None: nowhere).
    """

    sets: Any
    exists_fields: tuple[Field | None, ...]
    stable_fields: tuple[Field | None, ...]
    both_field: Field | None
    omega_up: np.ndarray
    F_up: np.ndarray
    omega_down: np.ndarray
    F_down: np.ndarray
    zeta: float
    zeta_source: str
    e: float
    sweeps: SweepComparison | None


# --- the whole report ------------------------------------------------------------------------

@dataclass(frozen=True)
class ReportContent:
    """Everything the report draws, computed.

    Attributes
    ----------
    store_name : str
        The store's file name (the PDF's title and every page's footer).
    summary_lines : tuple of str
        The summary page's text (parameters, flags, provenance), before the section list.
    sections : tuple of (str, object)
        The sections present, in page order, with their page content (one of the
        ``*Content`` types of :data:`rattle_lab.report.PAGES`' section).
    missing : Mapping of str to str
        Sections (or parts) left out and why: the gathering's, then the sections'.
    title : str
        The summary page's title: what the report is (fitted rattle parameters, or the
        shocks of transient records).
    """

    store_name: str
    summary_lines: tuple[str, ...]
    sections: tuple[tuple[str, Any], ...]
    missing: Mapping[str, str]
    title: str = "rattle_lab report: fitted gap, zeta, f_s, e and SPL law"


# --- transient records (shocks) --------------------------------------------------------------

@dataclass(frozen=True)
class ShockTrace:
    """One channel of a transient run around its shock, on its own clock.

    ``t_ms``: time from the channel's own onset, ms by its own sample rate (NaN-free);
    ``y``: the samples, in ``units``; ``peak_t_ms``: the peak on the same axis (None: no
    shock found, the trace is then centred on the cause's onset sample).
    """

    channel: str
    quantity: str
    units: str
    role: str
    clock: str
    fs_hz: float
    found: bool
    t_ms: np.ndarray
    y: np.ndarray
    peak_t_ms: float | None


@dataclass(frozen=True)
class ShockRun:
    """A transient run: its rows as text (one per channel, then its clocks) and its traces."""

    input_key: str
    run_id: str
    lines: tuple[str, ...]
    traces: tuple[ShockTrace, ...]


@dataclass(frozen=True)
class ShockContent:
    """The transient runs of the store (single shocks), each on its own page."""

    runs: tuple[ShockRun, ...]
