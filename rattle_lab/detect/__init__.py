"""Event detection in shaker-lab records: impacts, sound peaks, SPL and impact patterns.

Parameters are in seconds and SI units; samples are derived with
:func:`n_samples_of` (``round``).
"""

from ._common import n_samples_of, parabolic_peak, robust_sigma
from ._flights import RingingProblem, campaign_ring_modes
from ._impacts import ImpactLog, ImpactParams, detect_impacts
from ._ringing import RINGING_RESIDUAL_RATIO
from ._trigger import trigger_onsets
from ._pairing import base_velocity_at, onto_grid
from ._shock import detect_shock
from ._timing import DelayEstimate, delay_contradicted, measurand_share
from ._patterns import PatternResult, impact_pattern, impacts_per_cycle
from ._sound import SoundPeaks, cross_correlation_delay, impulse_train, sound_peaks
from ._spl import P_REF_PA, a_weight, a_weighting_db, rms_spl_db, spl_db

__all__ = [
    "ImpactLog", "ImpactParams", "P_REF_PA", "PatternResult", "RingingProblem", "SoundPeaks",
    "a_weight", "a_weighting_db", "campaign_ring_modes", "cross_correlation_delay", "detect_impacts", "impact_pattern",
    "impulse_train", "n_samples_of", "parabolic_peak", "rms_spl_db", "robust_sigma",
    "sound_peaks", "spl_db", "trigger_onsets", "impacts_per_cycle",
    "RINGING_RESIDUAL_RATIO", "base_velocity_at", "onto_grid", "detect_shock",
    "DelayEstimate", "delay_contradicted", "measurand_share",
]
