"""Impact detection (ObsPy trigger design: characteristic function, on/off, back-track).

1. Characteristic functions, each in units of its own robust noise (1.4826 MAD):
   the velocity jump ``|dv - smooth(dv)|`` (smooth: a local cubic) between consecutive samples of the
   vibrometer, placed at the later sample, and the spike ``|a - smooth(a)|``
   of the plate accelerometer.  With both channels the mean of the two is
   used (a true impact shows in both; a glitch in one channel is halved).
2. Trigger on where the function exceeds ``on``, off where it falls below
   ``off``; a trigger closer than ``min_separation_s`` to the previous peak
   is merged into it.
3. Back-track from the peak to the onset (the last sample above ``off``).
4. Sub-sample time: the centroid of the velocity jump, from the normalised step
   between the fits either side (5.); with a plate accelerometer, the centroid of its
   contact pulse (less noisy).  Without velocity: the centroid of the spike.
6. Physics (with a velocity): an impact reverses the plate's velocity.  A trigger whose
   velocity jump does not take back at least ``min_reversal`` of the approach velocity
   (``-(v_out - v_in) / v_in < 1 + e`` for an impact; ``0`` for no impact, ``1`` for a
   plastic one, ``2`` for an elastic one) is ringing, hum or a glitch, not an impact, and
   so is one that approaches from the side opposite the striker (the side most triggers
   that do reverse approach from).  This, not a longer dead time, keeps the plate's
   ringing from re-triggering the detector.  With a plate accelerometer, a trigger that fails
   this at the impact time is judged again by the velocity fits at its contact pulse's
   ends (first touch and separation), provided its pulse has the kept impacts' sign: a
   contact lasting ``T`` adds the free flight's ``a T`` to the jump, so a slow impact of
   a long contact shows no reversal at its centroid (:func:`_reversed_at_ends`).  Last, one
   that the fits reject either way is judged by the velocity samples just outside its contact
   pulse, the side and polarity taken from the triggers whose samples reverse: on a plate
   ringing in many lightly damped modes the fits read the ringing
   (:func:`_reversed_by_samples`; such impacts keep no velocities).
5. Incoming and rebound velocities: fits to the velocity over a window before and
   after the jump, clear of it by its half-height width plus a guard (a finite contact
   and a band-limited vibrometer spread a jump over several samples), each evaluated at
   the impact time; ``e = -v_out / v_in``.  With the excitation frequency the fits are
   the local forced-mode solution (:class:`~rattle_lab.detect._local_fits._LocalFit`), else
   polynomials.
7. With an excitation frequency (a shaker run), the vibrometer's DC offset is taken off
   both velocities: the plate is at the gap at every impact, so its velocity integrates
   to zero from the first impact to the last (:func:`velocity_offset`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from rattle_lab.exceptions import ParameterError
from ._common import as_signal, n_samples_of
from ._decoder import DecoderFit, equalise, identify_decoder
from ._flights import FlightFit, RingingProblem, flight_velocities, ringing_problem
from ._local_fits import _fit_rows, _fit_windows, _fits_at, _jump_fits_all, _JumpFits
from ._offset import _reversed_at_ends, _reversed_by_samples, _reverses, velocity_offset
from ._ringing import (MIN_SHARE_IMPACTS, QUIET_LEVEL, RINGING_RESIDUAL_RATIO, _residual_level,
                       _ringing_residual_ratio)
from ._trigger import _centroid, _half_region, characteristic, trigger_onsets
from ._timing import (MAX_COARSE_LAG_S, MAX_EXTRA_GUARD_S, DelayEstimate, channel_delay,
                      coarse_lag, delay_significant, settled_span, shift_earlier, step_error)


#: Least share of the triggers that reverse with the velocity read at the accelerometer's
#: time that must still reverse with it read at a measured delay, for that delay to be
#: applied (:func:`_delay_keeps_reversals`).
DELAY_REVERSAL_SHARE = 0.9


def _delay_keeps_reversals(jfits: list[_JumpFits], rows: np.ndarray, d_new: float,
                           d_old: float, min_reversal: float) -> bool:
    """Whether reading the velocity fits at the contact pulses plus ``d_new`` samples keeps
    at least :data:`DELAY_REVERSAL_SHARE` as many reversing triggers (:func:`_reverses`) as
    reading them at ``d_old``.  Without the pulses' times, or no trigger reversing at
    ``d_old``: True.  ``rows``: the fits' rows (:func:`_fit_rows`)."""
    t_a = np.array([jf.t_a for jf in jfits], dtype=float)
    ok = np.isfinite(t_a)
    if min_reversal == 0.0 or not ok.any():
        return True
    counts = []
    for d in (d_old, d_new):
        vv = _fits_at(rows, t_a + d)[ok]
        counts.append(int(_reverses(vv[:, 0], vv[:, 1], min_reversal).sum()))
    return counts[0] == 0 or counts[1] >= DELAY_REVERSAL_SHARE * counts[0]


@dataclass(frozen=True)
class ImpactParams:
    """Parameters of :func:`detect_impacts` (seconds and SI units).

    Attributes
    ----------
    on, off : float
        Trigger on / off levels of the characteristic function, in robust
        noise units (``on > off > 0``).
    min_separation_s : float
        Triggers closer than this to the previous peak belong to it, s.
    detrend_window_s : float
        Window of the local cubic (Savitzky-Golay) removed from the characteristic
        functions, s; must span several samples more than a contact pulse.
    fit_window_s : float
        Length of the polynomial velocity fits on either side of an impact, s.
    guard_s : float
        Extra time left out between the jump's half-height region and each polynomial fit
        window, s.
    poly_degree : int
        Degree of the polynomial velocity fits (0 to 3).
    sigma_floor_rel : float
        Lower bound of the noise unit, relative to the largest ``|sample|`` of the
        channel, so that noiseless records do not trigger on rounding and
        curvature residue (>= 0).
    fit_basis : {"sine", "poly"}
        ``"sine"``: with a known excitation frequency the velocity fits are the local
        solution of a mode forced near resonance (see :class:`_LocalFit`) over
        ``sine_window_s`` with an envelope of degree ``sine_degree``; ``"poly"``, or no
        frequency: polynomials (``fit_window_s``, ``poly_degree``).
    sine_window_s : float
        Length of the forced-mode velocity fits on either side of an impact, s.
    sine_degree : int
        Degree of the envelope polynomial of the forced-mode fits (0 to 2).
    sine_guard_s : float
        Extra time left out between the jump's half-height region and each forced-mode fit
        window, s: a band-limited vibrometer rings for a few periods of its band around a
        jump (0.3 ms covers a zero-phase 4th-order Butterworth at 5 kHz).
    min_reversal : float
        With a velocity: the least velocity change, as a fraction of the approach velocity
        and opposite to it, that an impact makes (``1 + e``: 1 for a plastic impact, 2 for
        an elastic one; 0 without an impact).  The default 0.5 lies halfway between no
        impact and the most plastic one.  0 keeps every trigger.
    velocity_model : {"auto", "local", "flights"}
        How the plate's higher modes ringing in the vibrometer are dealt with.
        ``"flights"`` (needs the velocity and a constant excitation frequency): a model of
        the whole run that also fits the modes ringing after each impact
        (:func:`rattle_lab.detect._flights.flight_velocities`).  Modes that die out within
        a flight give the ringing's share of each measured velocity jump
        (:attr:`ImpactLog.ringing_share`; ``v_in``/``v_out`` stay the local fits', and the
        fit pools the runs' shares and takes it off the ratios,
        :func:`rattle_lab.fit.ratios_of_runs`).  The run also keeps its part of a
        campaign-wide search (:attr:`ImpactLog.ringing_problem`): ``rattle-lab fit`` finds
        the modes across the runs, each impact's ringing carried on over the later
        flights, and detects again with them (``ring_modes``), which supersedes the
        runs' shares; lightly damped modes that ring on past the next impact have their
        tails in ``v_in`` too, and only this finds them.  Where no mode is found, the
        runs' shares stand, or, without any, the fit names the bias
        (``e_ratio_ringing_uncorrected``).
        ``"auto"`` (default): the same where the local fits' residual after the impacts
        is at least :data:`RINGING_RESIDUAL_RATIO` times that before them (ringing is
        there), the local fits otherwise; ``"local"``: the local fits.
    ring_modes : tuple of (f_hz, s_1_s)
        The plate's lightly damped higher modes (frequency, Hz, and decay rate, 1/s), as
        the campaign's search found them (:func:`rattle_lab.detect.campaign_ring_modes`,
        run by ``rattle-lab fit`` and the pipeline where runs ring and no run's flight
        model measured a share) or as a modal test gives them.  With a velocity channel
        and a constant excitation frequency, ``v_in`` and ``v_out`` then come from the
        flight model with these modes fixed and each impact's ringing carried on over the
        later flights; impacts the model cannot give velocities keep none (NaN: their
        local fits read the tails).  Given, it is used whatever ``velocity_model`` says.
        Empty (default): not used.
    ring_modes_runs : int
        How many runs ``ring_modes`` were found from (0: given; the fit names a search
        that had one run only).
    identify_decoder : bool
        With a velocity and a plate acceleration and no delay declared, where the first
        pass shows a decoder's response in the steps (unsettled at the fits' near ends, or
        its two delay estimators more than :data:`IDENTIFY_METHOD_ERR` apart): identify the
        vibrometer's decoder from the impacts' velocity steps (Butterworth or Bessel
        low-pass, order, cut-off, extra delay; :func:`rattle_lab.detect._decoder.identify_decoder`)
        and, where one explains them, replace it by a zero-phase, non-ringing low-pass
        before the velocities are read (:func:`rattle_lab.detect._decoder.equalise`;
        :attr:`ImpactLog.decoder`).  Default True.
    ring_fundamental : (f_hz, s_1_s) or empty
        With ``ring_modes``: the plate's fundamental mode (frequency, Hz, and decay rate,
        1/s) that the campaign's search found with them
        (:func:`rattle_lab.detect.campaign_ringing_model`: all the runs together, where one
        run in periodic motion does not determine it); the flight model then uses it
        instead of searching each run's own.  Empty (default): each run's own.
    """

    on: float = 12.0
    off: float = 4.0
    min_separation_s: float = 2e-3
    detrend_window_s: float = 1e-3
    fit_window_s: float = 1e-3
    guard_s: float = 0.0
    poly_degree: int = 2
    sigma_floor_rel: float = 1e-4
    fit_basis: Literal["sine", "poly"] = "sine"
    sine_window_s: float = 3e-3
    sine_degree: int = 1
    sine_guard_s: float = 3e-4
    min_reversal: float = 0.5
    velocity_model: Literal["auto", "local", "flights"] = "auto"
    ring_modes: tuple[tuple[float, float], ...] = ()
    ring_modes_runs: int = 0
    ring_fundamental: tuple[float, ...] = ()
    identify_decoder: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.identify_decoder, (bool, np.bool_)):
            raise ParameterError(f"`identify_decoder` must be true or false, was "
                                 f"{self.identify_decoder!r}")
        if isinstance(self.ring_modes_runs, bool) or not (
                isinstance(self.ring_modes_runs, (int, np.integer)) and self.ring_modes_runs >= 0):
            raise ParameterError(f"`ring_modes_runs` must be an integer >= 0, was "
                                 f"{self.ring_modes_runs!r}")
        try:
            modes = tuple((float(f), float(s)) for f, s in self.ring_modes)
        except (TypeError, ValueError):
            raise ParameterError("`ring_modes` must be pairs [frequency_hz, decay_1_s], was "
                                 f"{self.ring_modes!r}") from None
        if not all(np.isfinite(f) and f > 0 and np.isfinite(s) and s > 0 for f, s in modes):
            raise ParameterError(f"`ring_modes`: each frequency and decay rate must be > 0, "
                                 f"was {self.ring_modes!r}")
        object.__setattr__(self, "ring_modes", modes)
        try:
            fund = tuple(float(x) for x in self.ring_fundamental)
        except (TypeError, ValueError):
            fund = (float("nan"),)
        if fund and not (len(fund) == 2 and all(np.isfinite(x) and x > 0 for x in fund)):
            raise ParameterError("`ring_fundamental` must be empty or [frequency_hz, "
                                 f"decay_1_s], each > 0, was {self.ring_fundamental!r}")
        object.__setattr__(self, "ring_fundamental", fund)
        if not (np.isfinite(self.off) and self.off > 0):
            raise ParameterError(f"`off` must be > 0, was {self.off}")
        if not (np.isfinite(self.on) and self.on > self.off):
            raise ParameterError(f"`on` must be > `off` ({self.off}), was {self.on}")
        for name in ("min_separation_s", "detrend_window_s", "fit_window_s", "guard_s",
                     "sigma_floor_rel", "sine_window_s", "sine_guard_s", "min_reversal"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"`{name}` must be >= 0, was {value}")
        if self.fit_basis not in ("sine", "poly"):
            raise ParameterError(f"`fit_basis` must be 'sine' or 'poly', was {self.fit_basis!r}")
        if self.velocity_model not in ("auto", "local", "flights"):
            raise ParameterError("`velocity_model` must be 'auto', 'local' or 'flights', was "
                                 f"{self.velocity_model!r}")
        if self.sine_degree not in (0, 1, 2):
            raise ParameterError(f"`sine_degree` must be 0, 1 or 2, was {self.sine_degree}")
        if self.poly_degree not in (0, 1, 2, 3):
            raise ParameterError(f"`poly_degree` must be 0, 1, 2 or 3, was {self.poly_degree}")


@dataclass(frozen=True)
class Recognition:
    """What :func:`detect_impacts` found before its velocity model (steps 1-7): a run's
    triggers, their local-fit velocities (after the offset), which are impacts, the
    vibrometer's delay.  A detection pass that changes only the velocity model
    (``velocity_model``, ``ring_modes``: the campaign's ringing passes) starts from it
    instead of finding the impacts again (``recognised``).  Per trigger arrays, small
    beside the record; not kept in caches."""

    key: tuple[object, ...]           # what it depends on (:func:`_recognition_key`)
    lag: int                          # the velocity's coarse lag, samples
    names: tuple[str, ...]            # channels used
    t_idx: np.ndarray                 # per trigger: impact time, samples
    onsets: np.ndarray
    strength: np.ndarray
    pads: np.ndarray                  # the flight model's pads (with a velocity)
    spans: np.ndarray                 # per trigger (j_lo, j_hi, lo_lim, hi_lim), int64 (n, 4)
    keep: np.ndarray                  # which triggers are impacts
    v_in: np.ndarray                  # local fits, offset taken off
    v_out: np.ndarray
    e: np.ndarray
    offset: float
    d_use: float                      # the delay the fits were read at, samples
    delay: DelayEstimate
    delay_first: float
    method_err: float
    step_guard_s: float
    e_slope: float
    e_window: float
    n_fit: int
    n_guard: int
    degree: int
    omega: float | None
    ratio: float | None = None        # the ringing test's ratio, once computed
    declared: bool = False            # the velocity's delay was declared (taken off before)
    guard_wanted: int = 0             # samples the step had not settled at the fits' near
    # ends (before the guard's limits)
    decoder: DecoderFit | None = None  # the decoder identified and equalised (the velocity
    # the rest of the recognition read is the equalised one)
    decoder_shaped: bool = True       # replaced by a non-ringing low-pass (else only advanced
    # by its delay: for the flight model)


@dataclass(frozen=True)
class ImpactLog:
    """Impacts found in one run (arrays of equal length, one entry per impact).

    Attributes
    ----------
    t_s : ndarray
        Impact time (sub-sample), s from the first sample of the input (plus ``start_time_s``).
    onset_s : ndarray
        Back-tracked onset (first sample above ``off``), s.
    v_in_m_s : ndarray
        Incoming velocity: velocity fit before the impact evaluated at ``t_s``, m/s (NaN without velocity).
    v_out_m_s : ndarray
        Rebound velocity: fit after the impact at ``t_s``, m/s (NaN without velocity).
    e : ndarray
        Coefficient of restitution per impact, ``-v_out / v_in``, nondimensional.
    strength : ndarray
        Peak of the characteristic function, in noise units.
    channels : tuple of str
        Channels used: ``("velocity",)``, ``("acceleration",)`` or both.
    params : ImpactParams
        The parameters used.
    fs_hz : float
        Sample rate, Hz.
    velocity_note : str
        Why the flight model gave no ringing share, or used only some impacts (empty
        when it used all, or was not run).
    velocity_offset_m_s : float
        The velocity channel's DC offset taken off ``v_in`` and ``v_out``
        (:func:`velocity_offset`; 0 without an excitation frequency or where it cannot be
        measured), m/s.
    ringing_share : float
        The higher modes' share of each measured velocity jump ``v_out - v_in`` from the
        flight model (the median over its impacts of ``1 - jump_flight / jump_local``);
        NaN where it was not run or not determined (see ``velocity_model``).
    ringing_ratio : float
        The local fits' median residual after the impacts over that before them, the
        ``velocity_model = "auto"`` test for ringing (NaN where not computed).
    ring_modes : tuple of (f_hz, s_1_s)
        The ringing modes whose tails were carried on (``ImpactParams.ring_modes``):
        ``v_in`` and ``v_out`` are then the flight model's; empty otherwise.
    ringing_problem : RingingProblem or None
        Where the run's flight model ran: its part of the campaign's search for ringing
        modes (not compared, not kept in caches).
    velocity_delay_s, velocity_delay_stderr_s : float
        The vibrometer's delay after the accelerometer measured from the impacts (median
        over them of the velocity step's centroid less the contact pulse's) and its
        standard error, s; what remains after any declared ``group_delay_s``.  NaN without
        both channels or with fewer than 5 impacts.
    velocity_delay_n : int
        Impacts it was measured from.
    velocity_delay_applied_s : float
        The part of it the velocity fits were evaluated with (0 where the declared delay
        stands), s.
    step_guard_s : float
        Extra guard the velocity fits kept from each jump because the chain's step response
        (pooled over the impacts, :func:`rattle_lab.detect._timing.step_error`) had not
        settled at their near ends, s (0: it had).
    velocity_delay_window_s : float
        How far the delay estimate moved when the fits moved out by ``step_guard_s`` (the
        centroids' dependence on their windows: a systematic error of the estimate), s.
    e_per_delay_s : float
        Median over the impacts of ``d e / d delay`` at the instant used, 1/s (NaN where the
        delay was declared or not measured): what an error of the delay does to ``e``.
    e_window_change : float
        ``|median change of e|`` over the impacts when the fits moved out by
        ``step_guard_s`` (0 when they did not): how much of the chain's step response the
        nearer fits read, a measure of what the moved fits may still read.
    e_measurand_diff : float
        Where the vibrometer's measurand is neither declared nor established from the data
        and the relative reading is kept: the mean ``e`` of the absolute reading (the base
        velocity taken off) less the relative reading's (0 elsewhere).  The fit widens e's
        interval by it (:func:`rattle_lab.fit._chain.measurand_systematic`).
    e_measurand_alt_se : float
        The standard error of the absolute reading's median e there (NaN elsewhere).
    velocity_delay_method : str
        How ``velocity_delay_s`` was measured: ``"steps"`` (the velocity steps' centroids
        against the contact pulses') or ``"flights"`` (with ringing modes carried on, the
        instants where the flight model's displacements either side of each impact meet,
        :func:`rattle_lab.detect._flights._continuity_lag`; the velocities were then read
        there where the delay is not declared, and ``velocity_delay_applied_s`` is all of
        it; a declared delay stands and is checked against it).
    velocity_delay_note : str
        With ringing modes carried on, why the flights' instants were not applied (empty
        where they were, or not tried).
    decoder : str
        The vibrometer's decoder identified from the impacts and equalised before the
        velocities were read (``identify_decoder``; empty where none was).  Its delay is
        included in ``velocity_delay_s`` and ``velocity_delay_applied_s``.
    recognition : Recognition or None
        What the detector found before its velocity model, for a pass that changes only
        that (:func:`detect_impacts`' ``recognised``; not compared, not kept in caches).
    """

    t_s: np.ndarray
    onset_s: np.ndarray
    v_in_m_s: np.ndarray
    v_out_m_s: np.ndarray
    e: np.ndarray
    strength: np.ndarray
    channels: tuple[str, ...]
    params: ImpactParams = field(default_factory=ImpactParams)
    fs_hz: float = float("nan")
    velocity_note: str = ""
    velocity_offset_m_s: float = 0.0
    ringing_share: float = float("nan")
    ringing_ratio: float = float("nan")
    ring_modes: tuple[tuple[float, float], ...] = ()
    ringing_problem: RingingProblem | None = field(default=None, compare=False, repr=False)
    velocity_delay_s: float = float("nan")
    velocity_delay_stderr_s: float = float("nan")
    velocity_delay_n: int = 0
    velocity_delay_applied_s: float = 0.0
    step_guard_s: float = 0.0
    velocity_delay_window_s: float = float("nan")
    e_per_delay_s: float = float("nan")
    e_window_change: float = 0.0
    e_measurand_diff: float = 0.0
    e_measurand_alt_se: float = float("nan")
    velocity_delay_method: str = "steps"
    velocity_delay_note: str = ""
    decoder: str = ""
    recognition: Recognition | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:   # (pairs come back from a cache as lists)
        object.__setattr__(self, "ring_modes",
                           tuple((float(f), float(s)) for f, s in self.ring_modes))

    @property
    def n_impacts(self) -> int:
        """Number of impacts."""
        return int(self.t_s.size)


def detect_impacts(fs_hz: float, *, velocity_m_s: object = None, accel_ms2: object = None,
                   params: ImpactParams | None = None, start_time_s: float = 0.0,
                   excitation_freq_hz: float | None = None,
                   velocity_delay_declared: bool = False,
                   recognised: Recognition | None = None, level_held: bool = False
                   ) -> ImpactLog:
    """Find impacts in a vibrometer velocity and/or plate acceleration record.

    Parameters
    ----------
    fs_hz : float
        Sample rate of both channels, Hz.
    velocity_m_s : array, optional
        Plate velocity, m/s.
    accel_ms2 : array, optional
        Plate acceleration, m/s^2 (same length as ``velocity_m_s`` when both are given).
    params : ImpactParams, optional
        Detector parameters.
    start_time_s : float
        Time of the first sample, s.
    excitation_freq_hz : float, optional
        Excitation frequency, Hz.  With ``params.fit_basis == "sine"`` the velocity fits on
        either side of an impact use the forced-mode basis at this frequency (see
        :func:`jump_velocities`); without it they are polynomials.
    velocity_delay_declared : bool
        Whether the velocity's time base already has its declared filter delay taken off
        (``group_delay_s``).  With both channels the vibrometer's delay relative to the
        accelerometer is measured from the impacts (:func:`rattle_lab.detect._timing.channel_delay`):
        undeclared, it is applied where it is beyond its uncertainty
        (:func:`rattle_lab.detect._timing.delay_significant`: the velocity fits are evaluated
        at the impact time plus it) and left at zero otherwise; declared, the declaration
        stands and the measurement only checks it (the fit flags a contradiction,
        :func:`rattle_lab.fit._chain.velocity_delay_flags`).  Either way it is in
        :attr:`ImpactLog.velocity_delay_s`.
    recognised : Recognition, optional
        An earlier call's :attr:`ImpactLog.recognition` on the same record: where it was
        made with the same channels' lengths, rate, excitation frequency, declared delay and
        parameters but for the velocity model's (``velocity_model``, ``ring_modes``,
        ``ring_modes_runs``), steps 1-7 are taken from it and only the velocity model is
        applied (the same log as without it, bit for bit; the caller's to ensure that it
        was made from the same samples).  Otherwise it is ignored.
    level_held : bool
        The run holds its excitation level (a sine dwell): the flight model's forced
        amplitude is then one over up to 10 s (:data:`rattle_lab.detect._flights.HELD_KNOT_S`),
        not free to change every second.

    Returns
    -------
    ImpactLog
        Possibly empty (a run without impacts is a valid result).

    Raises
    ------
    ParameterError
        Without any channel, with channels of different lengths, or non-finite samples.

    Examples
    --------
    >>> import numpy as np
    >>> v = np.r_[np.full(100, -0.1), np.full(100, 0.08)]
    >>> log = detect_impacts(10000.0, velocity_m_s=v)
    >>> log.n_impacts, bool(np.isclose(log.t_s[0], 0.00995)), bool(np.isclose(log.e[0], 0.8))
    (1, True, True)
    """
    params = params if params is not None else ImpactParams()
    key = _recognition_key(fs_hz, velocity_m_s, accel_ms2, params, excitation_freq_hz,
                           velocity_delay_declared)
    if recognised is not None and recognised.key == key and not (
            recognised.decoder is not None and recognised.decoder_shaped and params.ring_modes):
        # the same record and recognition parameters: only the velocity model is applied
        # (the campaign's ringing passes, issue 29)
        rec, v = recognised, None
        if velocity_m_s is not None:
            v = as_signal(velocity_m_s, "velocity_m_s")
            if rec.decoder is not None:
                v = equalise(v, fs_hz, rec.decoder, shape=rec.decoder_shaped)
            if rec.lag:
                v = shift_earlier(v, rec.lag)
    elif recognised is not None and recognised.key == key:
        # an equalised run the campaign found ringing modes in: found again for the flight
        # model (:func:`_for_flights`)
        assert recognised.decoder is not None
        rec, v = _for_flights(recognised.decoder, fs_hz, velocity_m_s, accel_ms2, params,
                              excitation_freq_hz, key)
    else:
        rec, v = _recognise(fs_hz, velocity_m_s, accel_ms2, params, excitation_freq_hz,
                            velocity_delay_declared, key)
        if (params.identify_decoder and velocity_m_s is not None and accel_ms2 is not None
                and not velocity_delay_declared and rec.delay.n
                and (rec.guard_wanted > 0 or not rec.delay.resolved
                     or rec.method_err > IDENTIFY_METHOD_ERR)):
            # issue 28: where the step had not settled at the fits' near ends or its two
            # delay estimators disagree (a decoder's response the fits read), the decoder is
            # identified from the impacts' steps and, where one of the families searched
            # explains them, replaced by a zero-phase,
            # non-ringing low-pass, and the impacts are found again in the equalised
            # velocity.  Where the plate's higher modes ring in the vibrometer the flight
            # model reads another version (:func:`_for_flights`)
            raw = as_signal(velocity_m_s, "velocity_m_s")
            at = np.asarray(rec.t_idx, dtype=float)[rec.keep]
            fit = identify_decoder(raw, at[np.isfinite(at)], fs_hz, float(rec.delay.value))
            if fit is not None:
                # its delay, which the equaliser takes off, stands as if declared: the step
                # centroids only check it (the plate's higher modes ringing in the
                # vibrometer move them)
                first = rec, v
                rec, v = _recognise(fs_hz, equalise(raw, fs_hz, fit), accel_ms2, params,
                                    excitation_freq_hz, True, key, identified=True)
                ratio = level = None
                if params.velocity_model != "local" and excitation_freq_hz is not None \
                        and v is not None:
                    spans = [(a, b, c, d) for a, b, c, d in rec.spans.tolist()]
                    ratio = _ringing_residual_ratio(v, spans, rec.keep, rec.n_fit, rec.n_guard,
                                                    rec.degree, rec.omega)
                    level = _residual_level(v, spans, rec.keep, rec.v_out - rec.v_in, rec.n_fit,
                                            rec.n_guard, rec.degree, rec.omega)
                rec = replace(rec, decoder=fit, ratio=ratio)
                ringing = ratio is not None and level is not None and (
                    ratio >= RINGING_RESIDUAL_RATIO or level >= QUIET_LEVEL)
                if params.ring_modes or ringing:
                    # the plate's higher modes ring in the vibrometer (after each impact, or,
                    # lightly damped, through every flight alike): the flight model's record
                    rec, v = _for_flights(fit, fs_hz, raw, accel_ms2, params,
                                          excitation_freq_hz, key, first)
    return _with_velocity_model(rec, v, fs_hz, params, start_time_s, excitation_freq_hz,
                                level_held)


#: The decoder is identified where the short-flank and long-fit delay estimators disagree by
#: more than this, samples (as where the step has not settled at the fits' near ends): on the
#: independent generator's chains 0.008-0.02 where the delay estimate was right, 0.13-2.9
#: where it erred by 0.15-0.8 sample.  Elsewhere the identification (about 0.4 s a run) is
#: not needed.
IDENTIFY_METHOD_ERR = 0.05


def _for_flights(fit: DecoderFit, fs_hz: float, velocity_m_s: object, accel_ms2: object,
                 params: ImpactParams, excitation_freq_hz: float | None, key: tuple[object, ...],
                 first: tuple[Recognition, np.ndarray | None] | None = None
                 ) -> tuple[Recognition, np.ndarray | None]:
    """The recognition the flight model reads where the plate's higher modes ring in the
    vibrometer and its decoder was identified.

    The flight model was built on records as the decoder gives them; on the equalised ones
    7 of the 14 undeclared light-ringing campaigns of ``benchmarks/chain_timing.py`` moved
    by 2-8 % (their steady dwells' velocities rest on a nearly flat direction of the
    model).  So: a decoder whose step settles within
    :data:`~rattle_lab.detect._timing.MAX_EXTRA_GUARD_S`, which the first pass's guards
    handle, the record as it is and its delay measured as without the identification
    (``first``, else found again); a slower one, the record only advanced by the
    identified delay, as a declared delay is taken off (its own guards would leave the
    decoder's ringing in the fits: -57 % on one campaign).
    """
    if fit.settle_samples <= MAX_EXTRA_GUARD_S * fs_hz:
        if first is not None:
            return first
        return _recognise(fs_hz, velocity_m_s, accel_ms2, params, excitation_freq_hz, False,
                          key)
    raw = as_signal(velocity_m_s, "velocity_m_s")
    rec, v = _recognise(fs_hz, equalise(raw, fs_hz, fit, shape=False), accel_ms2, params,
                        excitation_freq_hz, True, key, identified=True)
    return replace(rec, decoder=fit, decoder_shaped=False), v


def _recognition_key(fs_hz: float, velocity_m_s: object, accel_ms2: object,
                     params: ImpactParams, excitation_freq_hz: float | None,
                     velocity_delay_declared: bool) -> tuple[object, ...]:
    """What a :class:`Recognition` depends on: the channels' presence and length, the rate,
    the excitation frequency, the declared delay and the parameters but for the velocity
    model's (``velocity_model``, ``ring_modes``, ``ring_modes_runs``,
    ``ring_fundamental``)."""
    def size(x: Any) -> int | None:
        return None if x is None else int(np.size(x))

    return (float(fs_hz), size(velocity_m_s), size(accel_ms2),
            None if excitation_freq_hz is None else float(excitation_freq_hz),
            bool(velocity_delay_declared),
            replace(params, velocity_model="auto", ring_modes=(), ring_modes_runs=0,
                    ring_fundamental=()))


def _recognise(fs_hz: float, velocity_m_s: object, accel_ms2: object, params: ImpactParams,
               excitation_freq_hz: float | None, velocity_delay_declared: bool,
               key: tuple[object, ...], identified: bool = False
               ) -> tuple[Recognition, np.ndarray | None]:
    """Steps 1-7 of :func:`detect_impacts` (everything but the velocity model): the
    recognition, and the velocity shifted by the coarse lag (None without one).
    ``identified``: the velocity was equalised after its decoder was identified; its delay
    stands as declared, and e's dependence on it is measured as for a measured one."""
    if velocity_m_s is None and accel_ms2 is None:
        raise ParameterError("detect_impacts needs `velocity_m_s` or `accel_ms2` (got neither)")
    n_detrend = n_samples_of(params.detrend_window_s, fs_hz, name="detrend_window_s")
    cfs: list[np.ndarray] = []
    names: list[str] = []
    v = a = None
    if velocity_m_s is not None:
        v = as_signal(velocity_m_s, "velocity_m_s")
        floor = params.sigma_floor_rel * float(np.max(np.abs(v), initial=0.0))
        cfs.append(characteristic(v, floor, n_detrend, jump=True))
        names.append("velocity")
    if accel_ms2 is not None:
        a = as_signal(accel_ms2, "accel_ms2")
        if v is not None and a.size != v.size:
            raise ParameterError(f"`accel_ms2` has {a.size} samples, `velocity_m_s` {v.size}")
        floor = params.sigma_floor_rel * float(np.max(np.abs(a), initial=0.0))
        cfs.append(characteristic(a, floor, n_detrend, jump=False))
        names.append("acceleration")
    lag, step_guard_s, e_slope, e_window = 0, 0.0, float("nan"), 0.0
    wanted = 0   # the guard the step response wanted at the fits' near ends, samples
    if v is not None and a is not None:
        # issue 28: a decoder can delay the velocity by many samples; its events are brought
        # onto the accelerometer's (whole samples) before the two are paired
        lag = coarse_lag(cfs[0], cfs[1], int(round(MAX_COARSE_LAG_S * fs_hz)), params.off)
        # (a velocity jump's characteristic function sits on the later of its two samples:
        # a lag of one is that, or a delay the centroids measure without the shift)
        lag = lag if abs(lag) > 1 else 0
        if lag:
            v = shift_earlier(v, lag)
            floor = params.sigma_floor_rel * float(np.max(np.abs(v), initial=0.0))
            cfs[0] = characteristic(v, floor, n_detrend, jump=True)
    cf = cfs[0] if len(cfs) == 1 else 0.5 * (cfs[0] + cfs[1])
    n_sep = n_samples_of(params.min_separation_s, fs_hz, name="min_separation_s")
    trig = trigger_onsets(cf, params.on, params.off, n_sep)
    n_fit = max(n_samples_of(params.fit_window_s, fs_hz, name="fit_window_s"), params.poly_degree + 1)
    degree = params.poly_degree
    n_guard = n_samples_of(params.guard_s, fs_hz, name="guard_s")
    omega = None
    if excitation_freq_hz is not None and params.fit_basis == "sine":
        if not (np.isfinite(excitation_freq_hz) and 0 < excitation_freq_hz < fs_hz / 2):
            raise ParameterError(f"`excitation_freq_hz` must be in (0, fs_hz/2 = {fs_hz / 2}), "
                                 f"was {excitation_freq_hz}")
        omega = 2.0 * np.pi * excitation_freq_hz / fs_hz
        degree = params.sine_degree
        n_fit = max(n_samples_of(params.sine_window_s, fs_hz, name="sine_window_s"),
                    2 * degree + 3)
        n_guard = n_samples_of(params.sine_guard_s, fs_hz, name="sine_guard_s")
    t_idx, onsets, v_in, v_out, strength, pads = [], [], [], [], [], []
    spans: list[tuple[int, int, int, int]] = []
    jfits: list[_JumpFits] = []
    for j, (start, peak, end) in enumerate(trig):
        j_lo, j_hi = start, end
        if v is not None:
            # The jump of v[k-1] -> v[k] is at cf index k, i.e. between samples k-1 and k.
            pk = start + int(np.argmax(cfs[0][start:end + 1]))
            t_k = _centroid(cfs[0], pk, -0.5)
            j_lo, j_hi = _half_region(cfs[0], pk)
        else:
            t_k = _centroid(cf, peak, 0.0)
        t_idx.append(t_k)
        onsets.append(start)
        strength.append(float(cf[peak]))
        if v is None:
            v_in.append(np.nan)
            v_out.append(np.nan)
            continue
        pads.append(max((j_hi - j_lo + 1) * 1.5 + n_guard + 1, 5e-4 * fs_hz))
        lo_lim = trig[j - 1][2] + 1 if j > 0 else 0
        hi_lim = trig[j + 1][0] - 1 if j + 1 < len(trig) else v.size - 1
        spans.append((j_lo, j_hi, lo_lim, hi_lim))
    rows = np.zeros((0, 2, 1))
    if v is not None:
        jfits = _jump_fits_all(v, spans, n_fit=n_fit, n_guard=n_guard, degree=degree,
                               omega_per_sample=omega, accel=a)
        rows = _fit_rows(jfits)
    # issue 28: the velocity steps' centroids against the contact pulses' measure what is
    # left of the vibrometer's delay after the declared one (the first moment of any
    # filter's impulse response is its low-frequency group delay): the fits are evaluated
    # at the impact time plus it, the impact time stays the accelerometer's.  The steps'
    # centroids are taken between short flanks (:func:`_short_flank_centroid`): the long
    # fits cannot follow the plate's higher modes ringing after an impact and put every
    # step late alike (up to 7 samples, with a standard error of 0.01)
    delay = channel_delay([j.t_s for j in jfits], [j.t_a for j in jfits]) \
        if v is not None and a is not None else DelayEstimate(float("nan"), float("nan"), 0)
    method_err = 0.0
    if v is not None and a is not None:
        # the same delay between the long fits: where the two estimators disagree (the
        # ringing moves one, a decoder's long step response the other) the difference is
        # an error of the method that the per-impact scatter does not show.  It is reported
        # with the delay's standard error (and so widens e's interval), but does not decide
        # whether the delay is applied: reading at zero errs by the whole delay
        alt = channel_delay([j.t_v for j in jfits], [j.t_a for j in jfits])
        if np.isfinite(alt.value) and np.isfinite(delay.value):
            method_err = abs(delay.value - alt.value)
    delay = replace(delay, value=delay.value + lag)
    delay_first = delay.value
    # the velocity is read at the impact time plus d_use in the shifted velocity's samples
    # (plus lag in its own): -lag where the declared delay stands
    d_use = -float(lag)
    # measured and undeclared: applied only where it is beyond its uncertainty and the
    # per-impact values agree to under a sample (a delay the data cannot tell from zero, or
    # centroids scattered by the sampling or by the plate's higher modes ringing in the
    # vibrometer, moved 5-12 samples on the independent generator, is left at zero; the fit
    # still carries its uncertainty into e's interval,
    # :func:`rattle_lab.fit._chain.delay_systematic`)
    measured = bool(np.isfinite(delay.value)) and not velocity_delay_declared
    applied = measured and delay.resolved and delay_significant(delay)
    if applied and not _delay_keeps_reversals(jfits, rows, delay.value - lag, -float(lag),
                                              params.min_reversal):
        # an impact reverses the velocity whatever the chain: a delay under which fewer
        # triggers do than without it is not the chain's (a slow decoder and the plate's
        # ringing together bias the steps' centroids alike at every impact: 2-3.5 samples
        # on the independent generator, and 44 of 77 impacts lost)
        applied = False
    if applied:
        d_use = delay.value - lag
    def t_eval_of(jf: _JumpFits) -> float:
        if np.isfinite(jf.t_a):
            return jf.t_a + d_use
        return jf.t_v if np.isfinite(jf.t_v) else jf.t_half

    if v is not None and jfits:
        # issue 28: the chain's step response as the record shows it: where it has not
        # settled at the fit windows' near ends (a decoder's overshoot and ringing), the
        # fits move out by what it needs
        t_ev = np.array([t_eval_of(jf) for jf in jfits])
        n_pad0 = max(hi - lo + 1 for lo, hi, _, _ in spans) + n_guard
        n_extra_max = int(round(MAX_EXTRA_GUARD_S * fs_hz))
        taus, med, noise = step_error(v, t_ev, rows,
                                      [(lo_l, hi_l) for _, _, lo_l, hi_l in spans],
                                      n_pad0 + n_extra_max)
        first, last = settled_span(taus, med, noise)
        need = []
        for te, (j_lo, j_hi, lo_l, hi_l) in zip(t_ev, spans):
            _, pre_hi, post_lo, _ = _fit_windows(j_lo, j_hi, lo_l, hi_l, n_fit, n_guard)
            if np.isfinite(te):
                need.append(max(0.0, pre_hi - (te + first) + 1, (te + last) - post_lo + 1))
        extra = int(np.ceil(np.median(need))) if need else 0
        wanted = extra
        if not applied:
            # a declared chain, or a delay the data cannot tell from zero, keeps the fits
            # where they were (the plate's higher modes ringing in the vibrometer also leave
            # the step unsettled, and the flight model that deals with them was tuned on
            # these windows)
            extra = 0
        if extra > n_extra_max:
            # not settled within MAX_EXTRA_GUARD_S: not a decoder's step response but the
            # plate's higher modes ringing in the vibrometer (the flight model's business)
            extra = 0
        first_fits, first_rows = jfits, rows
        if extra > 0:
            wide = [replace(w, t_a=jf.t_a, a_lo=jf.a_lo, a_hi=jf.a_hi, a_sign=jf.a_sign)
                    for w, jf in zip(_jump_fits_all(v, spans, n_fit=n_fit,
                                                    n_guard=n_guard + extra, degree=degree,
                                                    omega_per_sample=omega, accel=None),
                                     jfits)]
            # the step's centroid over the wider span holds more of a ringing decoder's tail.
            # A decoder's step response is the same at every impact, so its centroids agree
            # there; where they scatter by a sample or more (unresolved) what kept the step
            # from settling is the plate's higher modes ringing in the vibrometer, which
            # differ from impact to impact: the first fits and estimate stand (applying the
            # wide estimate moved the delay by 2-20 samples and lost most impacts' velocities
            # on the independent generator's undeclared chains with ringing)
            est = channel_delay([j.t_v for j in wide], [j.t_a for j in wide])
            if np.isfinite(est.value) and est.resolved:
                jfits = wide
                step_guard_s = extra / fs_hz
                pads = [pd + extra for pd in pads]
                delay = replace(est, value=est.value + lag)
                d_use = est.value
                method_err = 0.0   # its change from the first is the window term
                rows = _fit_rows(jfits)
        t_ev = np.array([t_eval_of(jf) for jf in jfits])
        if measured or identified:
            # how much e moves per sample of delay: the fits read a quarter sample either
            # side of the instant used (the median over the impacts)
            v1, v0 = _fits_at(rows, t_ev + 0.25), _fits_at(rows, t_ev - 0.25)
            with np.errstate(divide="ignore", invalid="ignore"):
                sl = (-v1[:, 1] / v1[:, 0] + v0[:, 1] / v0[:, 0]) / 0.5
            sl = sl[np.isfinite(sl)]
            e_slope = float(np.median(sl)) * fs_hz if sl.size else float("nan")
        if first_fits is not jfits:
            # what moving the fits out of the unsettled step changed in e: the part of the
            # chain's step response the first fits read (a systematic error of their own)
            v0, v1 = _fits_at(first_rows, t_ev), _fits_at(rows, t_ev)
            with np.errstate(divide="ignore", invalid="ignore"):
                mv = -v1[:, 1] / v1[:, 0] + v0[:, 1] / v0[:, 0]
            mv = mv[np.isfinite(mv)]
            e_window = abs(float(np.median(mv))) if mv.size else float("nan")
        t_at = np.empty(len(jfits))
        for i, jf in enumerate(jfits):
            if np.isfinite(jf.t_a):
                t_idx[i], t_at[i] = jf.t_a, jf.t_a + d_use
            elif np.isfinite(jf.t_v):
                t_idx[i], t_at[i] = jf.t_v - d_use, jf.t_v
            else:
                t_at[i] = jf.t_half
        vv = _fits_at(rows, t_at)
        v_in.extend(vv[:, 0].tolist())
        v_out.extend(vv[:, 1].tolist())
    vin = np.asarray(v_in, dtype=float)
    vout = np.asarray(v_out, dtype=float)
    keep = _reverses(vin, vout, params.min_reversal) if v is not None else np.ones(vin.size, bool)
    if v is not None and jfits and not keep.all():
        # issue 24: a contact that lasts many samples (a compliant striker on a many-mode
        # plate, ~0.2-0.8 ms) changes the free flight's velocity by a (t_end - t_start) while
        # it lasts; read at the centroid, a slow one's fits then show no reversal.  Those are
        # judged again by the fits at the contact pulse's ends, first touch and separation.
        # Their velocities stay the centroid's (the rigid impact's that the SDF model has)
        pulse_lo = np.array([jf.a_lo for jf in jfits]) + d_use   # in the velocity's samples
        pulse_hi = np.array([jf.a_hi for jf in jfits]) + d_use
        vin_e = _fits_at(rows, pulse_lo)[:, 0]
        vout_e = _fits_at(rows, pulse_hi)[:, 1]
        sign_a = np.array([jf.a_sign for jf in jfits])
        keep = keep | _reversed_at_ends(vin, vout, keep, vin_e, vout_e, sign_a,
                                        params.min_reversal)
        # issue 24: on a plate ringing in many lightly damped modes the fits read the ringing;
        # the velocity samples just outside the contact pulse show the impact.  Those impacts
        # keep no velocities (their fits read the ringing, not the approach and rebound)
        by_samples = _reversed_by_samples(v, keep, pulse_lo, pulse_hi, sign_a,
                                          params.min_reversal)
        if by_samples.any():
            vin = np.where(by_samples, np.nan, vin)
            vout = np.where(by_samples, np.nan, vout)
            keep = keep | by_samples
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.where(vin != 0, -vout / vin, np.nan)
    offset = 0.0
    if v is not None and excitation_freq_hz is not None:
        # a shaker run: the plate meets the striker at the gap, cycle after cycle
        speed = float(np.nanmedian(np.abs(vin[keep]))) if keep.any() else float("nan")
        offset = velocity_offset(v, np.asarray(t_idx, dtype=float)[keep] + d_use, fs_hz, speed)
        vin, vout = vin - offset, vout - offset
        with np.errstate(divide="ignore", invalid="ignore"):
            e = np.where(vin != 0, -vout / vin, np.nan)
    return Recognition(
        key=key, lag=int(lag), names=tuple(names), t_idx=np.asarray(t_idx, dtype=float),
        onsets=np.asarray(onsets, dtype=float), strength=np.asarray(strength, dtype=float),
        pads=np.asarray(pads, dtype=float),
        spans=np.asarray(spans, dtype=np.int64).reshape(-1, 4), keep=keep, v_in=vin,
        v_out=vout, e=e, offset=float(offset), d_use=float(d_use), delay=delay,
        delay_first=float(delay_first), method_err=float(method_err),
        step_guard_s=float(step_guard_s), e_slope=float(e_slope), e_window=float(e_window),
        n_fit=int(n_fit), n_guard=int(n_guard), degree=int(degree), omega=omega,
        declared=bool(velocity_delay_declared), guard_wanted=int(wanted)), v


def _with_velocity_model(rec: Recognition, v: np.ndarray | None, fs_hz: float,
                         params: ImpactParams, start_time_s: float,
                         excitation_freq_hz: float | None, level_held: bool = False
                         ) -> ImpactLog:
    """The last step of :func:`detect_impacts`: the velocity model (``velocity_model``,
    ``ring_modes``) applied to a recognition, and the log."""
    t_idx, onsets, strength, pads = rec.t_idx, rec.onsets, rec.strength, rec.pads
    spans = [(a, b, c, d) for a, b, c, d in rec.spans.tolist()]
    keep, vin, vout, e, offset, d_use = rec.keep, rec.v_in, rec.v_out, rec.e, rec.offset, \
        rec.d_use
    delay, n_fit, n_guard, degree, omega = rec.delay, rec.n_fit, rec.n_guard, rec.degree, \
        rec.omega

    def ratio_of() -> float:
        # the local fits' residual after the impacts over that before (once per recognition)
        nonlocal rec
        assert v is not None   # (called with a velocity only)
        if rec.ratio is None:
            rec = replace(rec, ratio=_ringing_residual_ratio(v, spans, keep, n_fit, n_guard,
                                                             degree, omega))
        return float(rec.ratio)   # type: ignore[arg-type]
    note, share, ratio = "", float("nan"), float("nan")
    problem: RingingProblem | None = None
    model = params.velocity_model
    k_keep = np.asarray(t_idx, dtype=float)[keep] + d_use     # in the velocity's time
    pad_keep = np.asarray(pads, dtype=float)[keep] if v is not None else np.zeros(0)
    carried = False   # ImpactParams.ring_modes applied
    timed: FlightFit | None = None   # the flights' own impact instants applied
    lag_note = ""                     # why they were not
    if params.ring_modes and v is not None and excitation_freq_hz is not None:
        carried = True
        model = "local"
        ratio = ratio_of()
        # every trigger with a jump bounds a flight and starts a tail, also one whose
        # reversal test failed (an absolute vibrometer's velocities carry the base's): a
        # missing impact would leave its jump and its ringing out of the run-wide model
        src = np.isfinite(vin) & np.isfinite(vout)
        flights = flight_velocities(v, fs_hz, excitation_freq_hz,
                                    np.asarray(t_idx, dtype=float)[src] + d_use,
                                    np.asarray(pads, dtype=float)[src], vin[src], vout[src],
                                    list(params.ring_modes), carried=True,
                                    instants_given=rec.declared,
                                    fundamental_given=(
                                        (params.ring_fundamental[0], params.ring_fundamental[1])
                                        if params.ring_fundamental else None),
                                    held=level_held)
        got = np.zeros(vin.size, dtype=bool)
        got[src] = flights.from_flights
        vin, vout = np.full(vin.size, np.nan), np.full(vin.size, np.nan)
        vin[got] = flights.v_in_m_s[flights.from_flights]
        vout[got] = flights.v_out_m_s[flights.from_flights]
        with np.errstate(divide="ignore", invalid="ignore"):
            e = np.where(vin != 0, -vout / vin, np.nan)
        n_out = int((~got[keep]).sum())
        if n_out:
            why = flights.note.removeprefix("local fits kept: ").removeprefix(
                "local fits kept for ") or "the flight model gave none"
            why = re.sub(r"^\d+ of \d+ impacts \((.*)\)$", r"\1", why)
            note = (f"no velocities for {n_out} of {int(keep.sum())} impacts, left out (their "
                    f"local fits read the ringing modes' tails): {why}")
        if np.isfinite(flights.lag_samples):
            timed = flights
        lag_note = flights.lag_note
    elif model != "local" and v is not None and excitation_freq_hz is not None:
        ratio = ratio_of()
        if model == "auto":
            model = "flights" if ratio >= RINGING_RESIDUAL_RATIO else "local"
    if model == "flights" and v is not None:
        if excitation_freq_hz is None:
            note = "no ringing share: the flight model needs a constant excitation frequency"
        else:
            flights = flight_velocities(v, fs_hz, excitation_freq_hz, k_keep, pad_keep,
                                        vin[keep], vout[keep], held=level_held)
            note = flights.note
            m = flights.from_flights
            if m.sum() >= MIN_SHARE_IMPACTS:
                with np.errstate(divide="ignore", invalid="ignore"):
                    jumps = (flights.v_out_m_s[m] - flights.v_in_m_s[m]) / (vout[keep][m]
                                                                             - vin[keep][m])
                share = float(np.median(1.0 - jumps[np.isfinite(jumps)]))
            elif not note:
                note = (f"no ringing share: {int(m.sum())} impacts from the flight model, "
                        f"needs >= {MIN_SHARE_IMPACTS}")
            # the campaign's runs together find the modes better than one run alone (and
            # find lightly damped ones, which ring on past the next impact, at all)
            problem = ringing_problem(v, fs_hz, excitation_freq_hz, k_keep, pad_keep,
                                      vin[keep], vout[keep], searched=flights.searched,
                                      held=level_held)
    # an equalised decoder's delay was taken off the velocity before the rest: it is the
    # vibrometer's delay too
    d_dec = rec.decoder.delay_samples if rec.decoder is not None else 0.0
    delay_fields: dict[str, Any] = dict(
        velocity_delay_s=(delay.value + d_dec) / fs_hz if delay.n else float("nan"),
        velocity_delay_stderr_s=math.hypot(delay.stderr, rec.method_err) / fs_hz
        if delay.n else float("nan"),
        velocity_delay_n=delay.n, velocity_delay_applied_s=(d_use + rec.lag + d_dec) / fs_hz,
        velocity_delay_window_s=abs(delay.value - rec.delay_first) / fs_hz
        if delay.n else float("nan"),
        e_per_delay_s=rec.e_slope, e_window_change=rec.e_window, velocity_delay_note=lag_note)
    if timed is not None:
        # the impacts' instants in the velocity's own record, from the flights: the delay
        # is measured there, and (undeclared) the velocities were read there; a declared
        # delay stands and is checked against them
        total = (d_use + rec.lag + d_dec + timed.lag_samples) / fs_hz
        delay_fields = dict(
            velocity_delay_s=total, velocity_delay_stderr_s=timed.lag_stderr_samples / fs_hz,
            velocity_delay_n=timed.lag_n,
            velocity_delay_applied_s=total if timed.lag_applied
            else (d_use + rec.lag + d_dec) / fs_hz,
            velocity_delay_window_s=0.0, e_per_delay_s=timed.e_per_lag * fs_hz,
            e_window_change=0.0, velocity_delay_method="flights")
    return ImpactLog(t_s=start_time_s + np.asarray(t_idx, dtype=float)[keep] / fs_hz,
                     onset_s=start_time_s + np.asarray(onsets, dtype=float)[keep] / fs_hz,
                     v_in_m_s=vin[keep], v_out_m_s=vout[keep], e=e[keep],
                     strength=np.asarray(strength, dtype=float)[keep],
                     channels=rec.names, params=params, fs_hz=float(fs_hz),
                     velocity_note=note, velocity_offset_m_s=offset, ringing_share=share,
                     ringing_ratio=ratio, ring_modes=params.ring_modes if carried else (),
                     ringing_problem=problem,
                     step_guard_s=rec.step_guard_s, **delay_fields,
                     decoder="" if rec.decoder is None else rec.decoder.describe(fs_hz) + (
                         "; replaced by a zero-phase low-pass without overshoot"
                         if rec.decoder_shaped else "; its delay taken off (the plate's higher "
                         "modes ring in the vibrometer: the flight model reads the decoder's "
                         "own step)"),
                     recognition=rec)
