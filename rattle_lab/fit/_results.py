"""Results of ``rattle-lab fit``: the frozen result classes.

Their place in the store (``/results``), :func:`write_results` and
:func:`read_results` belong to :mod:`rattle_lab.store` and are re-exported here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rattle_lab.detect import ImpactLog, SoundPeaks
from rattle_lab.store import (RESULTS_VERSION, StoredResults, read_results,  # noqa: F401
                              write_results)
from rattle_lab.detect.thresholds import Threshold, ThresholdCurve
from ._summary import FitSummary


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
        (:func:`rattle_lab.fit._chain.run_chain_flags`).
    shocks : tuple of dict
        Transient runs: the shock found on each channel, the cause first
        (:func:`rattle_lab.fit._chain.transient_shocks`); empty otherwise.
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


@dataclass(frozen=True)
class StoreFit:
    """Everything ``rattle-lab fit`` derives from a store.

    Attributes
    ----------
    runs : tuple of RunResult
    thresholds : ThresholdCurve
    summary : FitSummary
        The fits with units and uncertainties, run counts, skipped runs
        (:meth:`FitSummary.to_dict` is what ``/results`` stores and ``--json`` prints).
    provenance : dict
        Function, parameters, package version and the inputs' SHA-256.
    """

    runs: tuple[RunResult, ...]
    thresholds: ThresholdCurve
    summary: FitSummary
    provenance: dict[str, Any]


__all__ = ["RunResult", "StoreFit", "StoredResults", "read_results", "write_results"]
