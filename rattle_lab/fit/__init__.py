"""Fits of measured thresholds and events: grazing curve, restitution, SPL law (lmfit/scipy).

Ramp thresholds are modelled either quasi-statically (eq. 3.4 grazing, eq. 3.11
saddle-node) or by replaying the measured ramp through the exact simulator
(:func:`model_threshold`; :func:`fit_zeta_ramp`, ``fit_restitution_down(method="ramp")``).
"""

from typing import TYPE_CHECKING

from rattle_lab._lazy import lazy_names

if TYPE_CHECKING:
    from ._bands import (SIGNIFICANCE_K, band_quantile, grazing_band_ms2, hysteresis_uncertainty_ms2,
                         linear_law_band, negative_hysteresis, student_t_ci, threshold_hysteresis)
    from ._damping import fit_zeta_ramp
    from ._grazing import fit_grazing
    from ._grazing_ramp import fit_grazing_ramp
    from ._ramp_model import ModelThreshold, RampSpec, model_threshold
    from ._restitution import (RestitutionStats, fit_restitution_down,
                               pooled_ringing_share, ratios_of_runs, restitution_from_ratios,
                               ringing_corrected_ratios, saddle_node_threshold_ms2)
    from ._results import RunResult, StoreFit  # noqa: F401  (RunResult: see _LAZY)
    from ._spl_law import DbLaw, LinearLaw, fit_db_law, fit_linear_law
    from ._params import FIT_KEYS, SOUND_KEYS, check_fit_params, load_pipeline
    from ._store import analyse_run, fit_runs, json_ready, summarise_fits  # noqa: F401
    from ._estimates import (DbLawSummary, DownRestitution, Estimate, Fits, GrazingParameter,
                             GrazingSummary, LinearLawSummary, RampDamping, RampGrazing,
                             RatioRestitution, SplLawSummary)
    from ._summary import (SUMMARY_SCHEMA_VERSION, FitSummary, ParticipationInfo, RunRow,
                           SkippedRun, TableRow, ThresholdTable, TransientRun)

#: public name -> submodule that defines it; loaded on first use, so that a command that needs
#: the parameter names only (``rattle-lab run`` checking its pipeline file) does not import
#: lmfit, SciPy and the compiled kernels
_LAZY: dict[str, str] = {
    "SIGNIFICANCE_K": "_bands",
    "band_quantile": "_bands",
    "grazing_band_ms2": "_bands",
    "hysteresis_uncertainty_ms2": "_bands",
    "linear_law_band": "_bands",
    "negative_hysteresis": "_bands",
    "student_t_ci": "_bands",
    "threshold_hysteresis": "_bands",
    "fit_zeta_ramp": "_damping",
    "fit_grazing": "_grazing",
    "fit_grazing_ramp": "_grazing_ramp",
    "ModelThreshold": "_ramp_model",
    "RampSpec": "_ramp_model",
    "model_threshold": "_ramp_model",
    "RestitutionStats": "_restitution",
    "fit_restitution_down": "_restitution",
    "pooled_ringing_share": "_restitution",
    "ratios_of_runs": "_restitution",
    "restitution_from_ratios": "_restitution",
    "ringing_corrected_ratios": "_restitution",
    "saddle_node_threshold_ms2": "_restitution",
    # moved to rattle_lab.detect (issue 29), still read from here (and old caches name
    # rattle_lab.fit._results.RunResult)
    "RunResult": "_results",
    "StoreFit": "_results",
    "DbLaw": "_spl_law",
    "LinearLaw": "_spl_law",
    "fit_db_law": "_spl_law",
    "fit_linear_law": "_spl_law",
    "FIT_KEYS": "_params",
    "SOUND_KEYS": "_params",
    "check_fit_params": "_params",
    "load_pipeline": "_params",
    "analyse_run": "_store",   # moved to rattle_lab.detect (issue 29), still read from here
    "fit_runs": "_store",
    "json_ready": "_store",
    "summarise_fits": "_store",
    "DbLawSummary": "_estimates",
    "DownRestitution": "_estimates",
    "Estimate": "_estimates",
    "Fits": "_estimates",
    "GrazingParameter": "_estimates",
    "GrazingSummary": "_estimates",
    "LinearLawSummary": "_estimates",
    "RampDamping": "_estimates",
    "RampGrazing": "_estimates",
    "RatioRestitution": "_estimates",
    "SplLawSummary": "_estimates",
    "SUMMARY_SCHEMA_VERSION": "_summary",
    "FitSummary": "_summary",
    "ParticipationInfo": "_summary",
    "RunRow": "_summary",
    "SkippedRun": "_summary",
    "TableRow": "_summary",
    "ThresholdTable": "_summary",
    "TransientRun": "_summary",
}

__all__ = [
    "DbLaw", "check_fit_params", "fit_runs", "json_ready",
    "load_pipeline",
    "summarise_fits", "LinearLaw", "RestitutionStats",
    "fit_db_law", "fit_grazing", "fit_linear_law", "fit_restitution_down",
    "pooled_ringing_share", "ratios_of_runs", "restitution_from_ratios", "ringing_corrected_ratios",
    "saddle_node_threshold_ms2",
    "ModelThreshold", "RampSpec", "fit_zeta_ramp", "model_threshold", "fit_grazing_ramp",
    "StoreFit",
    "SUMMARY_SCHEMA_VERSION", "FitSummary", "Fits", "Estimate", "GrazingParameter",
    "GrazingSummary", "RatioRestitution", "RampDamping", "DownRestitution", "SplLawSummary",
    "LinearLawSummary", "DbLawSummary", "RampGrazing", "RunRow", "SkippedRun", "TableRow",
    "ThresholdTable", "TransientRun", "ParticipationInfo",
    "band_quantile", "grazing_band_ms2", "linear_law_band", "student_t_ci",
    "threshold_hysteresis", "negative_hysteresis", "hysteresis_uncertainty_ms2", "SIGNIFICANCE_K",
    "FIT_KEYS", "SOUND_KEYS",
]


__getattr__, __dir__ = lazy_names(__name__, globals(), _LAZY)
