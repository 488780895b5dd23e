"""Event detection in shaker-lab records: impacts, sound peaks, SPL and impact patterns.

Parameters are in seconds and SI units; samples are derived with
:func:`n_samples_of` (``round``).
"""

from typing import TYPE_CHECKING

from rattle_lab._lazy import lazy_names

if TYPE_CHECKING:
    from ._campaign import campaign_measurand, campaign_ringing
    from ._chain import (CAUSE_QUANTITIES, FLAG_DELAY_CONTRADICTED, FLAG_DELAY_ESTIMATED,
                         FLAG_FILTER_IDENTIFIED, FLAG_MEASURAND_INFERRED, FLAG_MEASURAND_UNDETERMINED, SHOCK_QUANTITIES,
                         infer_measurand, median_and_error, paired_plate_channels,
                         relative_to_striker, run_chain_flags, transient_shocks,
                         velocity_delay_flags)
    from ._common import n_samples_of, parabolic_peak, robust_sigma
    from ._params import MEASURAND_KEYS, SEGMENT_KEYS, SOUND_KEYS, DetectParams
    from ._run import (RunResult, SegmentImpacts, SegmentSound, analyse_run, assemble_segments,
                       merge_segment_impacts, reused_result, run_segments, segment_impacts,
                       segment_sound)
    from ._flights import (CampaignRinging, RingingProblem, campaign_ring_modes,
                           campaign_ringing_model)
    from ._impacts import ImpactLog, ImpactParams, Recognition, detect_impacts
    from ._ringing import RINGING_RESIDUAL_RATIO
    from ._trigger import trigger_onsets
    from ._pairing import base_velocity_at, onto_grid
    from ._shock import detect_shock
    from ._timing import DelayEstimate, delay_contradicted, measurand_share
    from ._patterns import PatternResult, impact_pattern, impacts_per_cycle
    from ._sound import SoundPeaks, cross_correlation_delay, impulse_train, sound_peaks
    from ._spl import P_REF_PA, a_weight, a_weighting_db, rms_spl_db, spl_db
    from ._warm import kernels_cold, warm_cache

#: public name -> submodule that defines it; loaded on first use (SciPy's signal package, the
#: flight model and the trigger only when detection runs)
_LAZY: dict[str, str] = {
    "campaign_ringing": "_campaign",
    "campaign_measurand": "_campaign",
    **dict.fromkeys(("CAUSE_QUANTITIES", "FLAG_DELAY_CONTRADICTED", "FLAG_DELAY_ESTIMATED",
                     "FLAG_FILTER_IDENTIFIED", "FLAG_MEASURAND_INFERRED", "FLAG_MEASURAND_UNDETERMINED",
                     "SHOCK_QUANTITIES", "infer_measurand", "median_and_error",
                     "paired_plate_channels", "relative_to_striker", "run_chain_flags",
                     "transient_shocks", "velocity_delay_flags"), "_chain"),
    "DetectParams": "_params",
    "SOUND_KEYS": "_params",
    "SEGMENT_KEYS": "_params",
    "MEASURAND_KEYS": "_params",
    "RunResult": "_run",
    "analyse_run": "_run",
    **dict.fromkeys(("SegmentImpacts", "SegmentSound", "assemble_segments",
                     "merge_segment_impacts", "reused_result", "run_segments", "segment_impacts",
                     "segment_sound"), "_run"),
    "n_samples_of": "_common",
    "parabolic_peak": "_common",
    "robust_sigma": "_common",
    "RingingProblem": "_flights",
    "campaign_ring_modes": "_flights",
    "CampaignRinging": "_flights",
    "campaign_ringing_model": "_flights",
    "ImpactLog": "_impacts",
    "ImpactParams": "_impacts",
    "Recognition": "_impacts",
    "detect_impacts": "_impacts",
    "RINGING_RESIDUAL_RATIO": "_ringing",
    "trigger_onsets": "_trigger",
    "base_velocity_at": "_pairing",
    "onto_grid": "_pairing",
    "detect_shock": "_shock",
    "DelayEstimate": "_timing",
    "delay_contradicted": "_timing",
    "measurand_share": "_timing",
    "PatternResult": "_patterns",
    "impact_pattern": "_patterns",
    "impacts_per_cycle": "_patterns",
    "SoundPeaks": "_sound",
    "cross_correlation_delay": "_sound",
    "impulse_train": "_sound",
    "sound_peaks": "_sound",
    "P_REF_PA": "_spl",
    "a_weight": "_spl",
    "a_weighting_db": "_spl",
    "rms_spl_db": "_spl",
    "spl_db": "_spl",
    "kernels_cold": "_warm",
    "warm_cache": "_warm",
}

__all__ = [
    "ImpactLog", "ImpactParams", "P_REF_PA", "PatternResult", "Recognition", "RingingProblem",
    "SoundPeaks",
    "a_weight", "a_weighting_db", "campaign_ring_modes", "cross_correlation_delay", "detect_impacts", "impact_pattern",
    "CampaignRinging", "campaign_ringing_model",
    "impulse_train", "n_samples_of", "parabolic_peak", "rms_spl_db", "robust_sigma",
    "sound_peaks", "spl_db", "trigger_onsets", "impacts_per_cycle",
    "RINGING_RESIDUAL_RATIO", "base_velocity_at", "onto_grid", "detect_shock",
    "DelayEstimate", "delay_contradicted", "measurand_share",
    # issue 29: detection in one room (the [detect] parameters, the per-run analysis, the
    # measurement chain of a run, the campaign's ringing search)
    "DetectParams", "SEGMENT_KEYS", "SOUND_KEYS", "RunResult", "analyse_run", "campaign_ringing",
    "campaign_measurand", "MEASURAND_KEYS",
    "CAUSE_QUANTITIES", "FLAG_DELAY_CONTRADICTED", "FLAG_DELAY_ESTIMATED", "FLAG_FILTER_IDENTIFIED",
    "FLAG_MEASURAND_INFERRED", "FLAG_MEASURAND_UNDETERMINED", "SHOCK_QUANTITIES",
    "infer_measurand", "median_and_error", "paired_plate_channels", "relative_to_striker",
    "run_chain_flags", "transient_shocks", "velocity_delay_flags",
    # the kernels compiled after installing (rattle_lab._warmup) or at a first fit
    "kernels_cold", "warm_cache",
    # issue 29: a long run in segments, each segment's impacts and sound a task of its own
    "SegmentImpacts", "SegmentSound", "assemble_segments", "merge_segment_impacts",
    "reused_result", "run_segments", "segment_impacts", "segment_sound",
]


__getattr__, __dir__ = lazy_names(__name__, globals(), _LAZY)
