"""The public surface is a decision: this test pins it."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

import pytest

import rattle_lab


def test_all_is_pinned():
    assert rattle_lab.__all__ == [
        "__version__", "RattleLabError",
        "SDFParams", "SDFState", "simulate",
        "Plate", "ritz_modes", "table_modes", "SDFScaling",
        "grazing_F", "grazing_omegas", "linear_impact_velocity",
        "one_over_n_orbits", "bifurcation_sets", "sweep", "sweep_up_down",
        "lyapunov_exponent", "regime_map",
        "read", "write_record", "Record", "ingest", "read_catalogue", "open_stored_record",
        "load_scene", "synthesize", "write_synthetic",
        "detect_impacts", "sound_peaks", "fit_grazing", "fit_store", "read_results",
        "write_report", "load_pipeline_file", "run_pipeline",
    ]


def test_every_public_name_resolves():
    for name in rattle_lab.__all__:
        assert getattr(rattle_lab, name) is not None


def test_import_is_light():
    code = ("import sys, rattle_lab; "
            "print(','.join(m for m in ('numba', 'scipy', 'h5py', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_unknown_attribute_raises():
    try:
        rattle_lab.no_such_thing  # noqa: B018
    except AttributeError as exc:
        assert "no_such_thing" in str(exc)
    else:
        raise AssertionError("expected AttributeError")


# The public names of every package, in the order ``__all__`` lists them.  Changing one is an
# API decision: update this table in the same commit.
PACKAGES: dict[str, list[str]] = {
    "rattle_lab.acoustics": [
        "Loudness", "NOMINAL_THIRD_OCTAVE_HZ", "P_REF_PA", "RunAcoustics", "SoundLevels",
        "apply_weighting", "band_edges_hz", "band_gain", "band_mean_squares",
        "channel_calibration", "fast_time_weighted", "loudness", "rattle_episodes",
        "run_acoustics", "sound_levels", "weighting_db", "weighting_response", "energy_mean_db",
        # issue 26: impulsiveness, ECMA-418-2, episodes against the campaign's background
        "Ecma418", "Onsets", "adjustment_db", "campaign_background", "ecma418", "ecma418_available",
        "episode_psychoacoustics", "find_onsets", "laf_db", "prominence",
        # issue 26 item 5: ISO 532-1 stationary loudness from third-octave levels (annex B.2)
        "stationary_loudness",
        # issue 29: a long run's acoustics joined from its segments'
        "joined_acoustics",
    ],
    "rattle_lab.exchange": ["UFF_TYPE_OF_QUANTITY", "export_uff", "uff_sets"],
    "rattle_lab.model.analysis": [
        "OneOverNOrbit", "BranchEvent", "PeriodicOrbit", "BifurcationSets", "BoundaryCurve",
        "one_over_n_orbits", "impact_quadratic", "impact_velocities", "orbit_forcing",
        "floquet_multipliers", "orbit_clearance", "grazing_forcing", "saddle_node_forcing",
        "branch_events", "impact_map", "find_periodic_orbit", "periodic_orbit_from_impacts",
        "bifurcation_sets", "Regime", "SweepPoint", "Sweep",
        "LyapunovResult", "AttractorMap", "DisturbanceMap", "classify_impacts", "sweep_values",
        "sweep", "sweep_up_down", "write_sweeps_csv", "lyapunov_exponent",
        "lyapunov_from_result", "tangent_log_growth", "regime_map", "basin_map",
        "disturbance_threshold", "disturbance_map", "SweepThresholds", "sweep_thresholds",
        "SWEEP_PARAMS", "LYAPUNOV_MODES"
    ],
    "rattle_lab.cli": [
        "COMMAND_MODULES", "build_parser", "main"
    ],
    "rattle_lab.detect": [
        "ImpactLog", "ImpactParams", "P_REF_PA", "PatternResult", "Recognition", "RingingProblem",
        "SoundPeaks",
        "a_weight", "a_weighting_db", "campaign_ring_modes", "cross_correlation_delay",
        "detect_impacts", "impact_pattern", "CampaignRinging", "campaign_ringing_model",
        "impulse_train", "n_samples_of", "parabolic_peak", "rms_spl_db", "robust_sigma",
        "sound_peaks", "spl_db", "trigger_onsets", "impacts_per_cycle",
        # issue 25: what the fit imports from detect
        "RINGING_RESIDUAL_RATIO", "base_velocity_at", "onto_grid", "detect_shock",
        # issue 28: the channel timing the fit checks
        "DelayEstimate", "delay_contradicted", "measurand_share",
        # issue 29: detection in one room
        "DetectParams", "SEGMENT_KEYS", "SOUND_KEYS", "RunResult", "analyse_run", "campaign_ringing",
        "campaign_measurand", "MEASURAND_KEYS",
        "CAUSE_QUANTITIES", "FLAG_DELAY_CONTRADICTED", "FLAG_DELAY_ESTIMATED",
        "FLAG_FILTER_IDENTIFIED", "FLAG_MEASURAND_INFERRED", "FLAG_MEASURAND_UNDETERMINED", "SHOCK_QUANTITIES",
        "infer_measurand", "median_and_error", "paired_plate_channels", "relative_to_striker",
        "run_chain_flags", "transient_shocks", "velocity_delay_flags",
        # the kernels compiled after installing (rattle_lab._warmup) or at a first fit
        "kernels_cold", "warm_cache",
        # issue 29: a long run in segments
        "SegmentImpacts", "SegmentSound", "assemble_segments", "merge_segment_impacts",
        "reused_result", "run_segments", "segment_impacts", "segment_sound",
    ],
    "rattle_lab.explorer": [
        "Explorer", "Histories", "compute_histories", "save_histories", "impacts_path",
        "display_available", "HISTORY_COLUMNS", "IMPACT_COLUMNS", "DATA_SUFFIXES",
        "DEFAULT_SAVE_PATH"
    ],
    "rattle_lab.fit": [
        "DbLaw", "check_fit_params", "fit_runs", "json_ready",
        "load_pipeline",
        "summarise_fits", "LinearLaw", "RestitutionStats",
        "fit_db_law", "fit_grazing", "fit_linear_law", "fit_restitution_down",
        "pooled_ringing_share", "ratios_of_runs", "restitution_from_ratios",
        "ringing_corrected_ratios", "saddle_node_threshold_ms2",
        "ModelThreshold", "RampSpec", "fit_zeta_ramp", "model_threshold", "fit_grazing_ramp",
        "StoreFit",
        "SUMMARY_SCHEMA_VERSION", "FitSummary", "Fits", "Estimate", "GrazingParameter",
        "GrazingSummary", "RatioRestitution", "RampDamping", "DownRestitution", "SplLawSummary",
        "LinearLawSummary", "DbLawSummary", "RampGrazing", "RunRow", "SkippedRun",
        "TableRow", "ThresholdTable", "TransientRun", "ParticipationInfo",
        "band_quantile", "grazing_band_ms2", "linear_law_band", "student_t_ci",
        "threshold_hysteresis", "negative_hysteresis", "hysteresis_uncertainty_ms2", "SIGNIFICANCE_K",
        "FIT_KEYS", "SOUND_KEYS"
    ],
    "rattle_lab.model.modal": [
        "CONTACT_NAMES", "MIC_CORNER_HZ", "THESIS_HERTZ_N_M15", "THESIS_PLATE",
        "THESIS_STRIKER_STIFFNESS_N_M",
        "ContactLog", "EpisodeLog", "HertzContact", "KelvinVoigtContact", "ModalChannels",
        "ModalResult", "ModalState", "ModalSystem", "RadiatingSurface", "RigidContact",
        "contact_from_name", "infinite_plate_impedance", "measured_peak", "microphone",
        "modal_channels", "plate_surface", "plate_system",
        "predicted_spl_slope", "rayleigh_pressure", "rayleigh_zeta", "residual_pressure",
        "simulate_modal", "C_AIR_M_S", "Contact", "peak_per_impact"
    ],
    "rattle_lab.model.plate": [
        "Plate", "PlateMode", "PlateModes", "TableMode", "EDGE_ORDER", "DEFAULT_N_TERMS",
        "TABLE_ASPECT_RATIOS", "simply_supported_mode", "simply_supported_modes", "table_modes",
        "ritz_modes"
    ],
    "rattle_lab.model": [],
    "rattle_lab.plot": [
        "FIGURE_SUFFIXES", "check_figure_path", "save_figure", "plot_time_history", "plot_sweeps",
        "plot_bifurcation_sets", "plot_attractor_map", "plot_disturbance_map",
        "smooth_region", "db_slope_guide", "power_law_guide", "BIFURCATION_LINESTYLES"
    ],
    "rattle_lab.workflow": [
        "STAGES", "Pipeline", "PipelineRun", "load_pipeline_file", "parse_pipeline", "run_pipeline",
        "detect_runs", "fit_store", "write_report", "build_report_content", "build_pages",
        "gather", "ReportData", "SECTIONS", "shock_lines"
    ],
    "rattle_lab.records": [
        "read", "write_record", "detect_format", "load_schema", "validate_tree", "load_mapping",
        "MappingSpec", "Record", "Rig", "Sensor", "Run", "Channel", "Truth", "ImpactTable",
        "ThresholdTable", "Skipped", "Origin", "ArraySource", "ArrayData", "GeneratedData",
        "Finding", "QualityLimits", "FLAGS", "FATAL_FLAGS", "SI_UNITS", "scale_to_si",
        # StoreError moved to rattle_lab.store (issue 25)
        "MappingError", "DuplicateRunError", "DataQualityError", "NaNGapError",
        "InfValueError", "ClippingError", "DropoutError", "SampleRateMismatchError",
        "NonMonotonicTimestampsError", "EmptyChannelError", "NaNGapWarning", "InfValueWarning",
        "ClippingWarning", "DropoutWarning", "SampleRateMismatchWarning",
        "NonMonotonicTimestampsWarning", "EmptyChannelWarning", "UncalibratedWarning",
        # issue 25: what the store and the fit import from records
        "write_tree", "record_to_tree", "record_from_tree", "load_group", "as_source",
        "DEFAULT_CHUNK_SAMPLES", "LinkPolicy", "link_policy", "ChannelChecker", "TimestampChecker",
        "Participation", "PlateF1", "plate_model_f1", "resolve_participation",
        "channel_time_offset_s", "declared_delay_s", "filter_group_delay_s", "FILTER_TYPES",
        "FLAG_PARTICIPATION_ASSUMED", "FLAG_MEASURAND_UNDECLARED",
        "FLAG_MEASURAND_ABSOLUTE"
    ],
    "rattle_lab.report": [
        "write_pdf", "render_pages", "ReportResult", "ReportContent", "PAGES",
        "RigContent", "RecordInfo", "ChannelInfo", "ThresholdContent", "GrazingCurve",
        "PatternContent", "SplContent", "SplCurve", "WaveformContent", "WaveformColumn",
        "Trace", "WAVEFORM_QUANTITIES", "AcousticsContent", "ListenerMetrics", "ModelContent", "SweepComparison",
        "Field", "ShockContent", "ShockRun", "ShockTrace",
        "TEXT_WIDTH", "fmt", "wrapped", "pdf_output"
    ],
    "rattle_lab.rig": [
        "load_scene", "parse_scene", "synthesize", "write_synthetic", "Scene", "SceneError",
        "StageCounter", "Synthesis", "RunSummary", "Modal", "Piece", "RunMotion", "schedule",
        "simulate_run", "true_thresholds", "resolve_modal"
    ],
    "rattle_lab.model.scaling": [
        "flexural_rigidity_nm", "omega_s_rad_s", "f_s_hz", "lam_from_f_s",
        "participation_factor", "pressure_pa_from_accel", "accel_ms2_from_pressure",
        "F_es_from_pressure", "F_es_from_accel", "F_from_F_es", "F_es_from_F", "F_from_accel",
        "accel_ms2_from_F", "F_from_pressure", "pressure_pa_from_F", "omega_from_freq",
        "freq_hz_from_omega", "tau_from_time", "time_s_from_tau", "x_from_displacement",
        "displacement_m_from_x", "impact_velocity_ms", "v_im_from_velocity", "inv_F_from_gap",
        "gap_m_from_inv_F", "v_im_over_F_from_velocity", "velocity_ms_from_v_im_over_F",
        "NondimensionalExcitation", "PhysicalExcitation", "SDFScaling", "angular_rad_s_from_freq"
    ],
    "rattle_lab.model.sdf": [
        "SDFParams", "SDFState", "SimImpacts", "Crossings", "DenseSamples", "SimResult",
        "simulate", "flow", "particular_coeffs", "particular_state", "homogeneous_transition",
        "simulate_pieces", "jit_kernel", "signals_deferred", "KERNELS", "cold_kernels", "warm_cache"
    ],
    "rattle_lab.store": [
        "ingest", "read_catalogue", "open_stored_record", "IngestReport", "InputResult",
        "CATALOGUE_COLUMNS", "file_hash", "input_key", "MappingIgnoredWarning", "STORE_FORMAT",
        "STORE_VERSION", "READABLE_VERSIONS", "open_store", "edit_store", "store_lock",
        "has_path", "read_results", "write_results", "StoredResults", "CACHE_GROUP",
        "read_cache_keys", "record_cache_keys", "read_cached", "write_cached", "output_digest",
        "input_hashes", "provenance_log", "verify_store", "check_linked_inputs", "Mismatch",
        "record_attrs_count", "REINGEST_ADVICE", "reingest_advice",
        "StoreError", "RESULTS_VERSION", "record_attrs"
    ],
}


def _public_packages() -> list[str]:
    """Every package under rattle_lab whose dotted name has no private (``_``) part."""
    found = []
    for info in pkgutil.walk_packages(rattle_lab.__path__, "rattle_lab."):
        if info.ispkg and not any(part.startswith("_") for part in info.name.split(".")):
            found.append(info.name)
    return sorted(found)


def test_every_public_package_is_pinned():
    assert _public_packages() == sorted(PACKAGES)


@pytest.mark.parametrize("name", sorted(PACKAGES))
def test_package_all_is_pinned(name: str):
    module = importlib.import_module(name)
    assert module.__all__ == PACKAGES[name]


@pytest.mark.parametrize("name", sorted(PACKAGES))
def test_package_public_names_resolve_and_are_unique(name: str):
    module = importlib.import_module(name)
    assert len(set(module.__all__)) == len(module.__all__)
    for attr in module.__all__:
        assert hasattr(module, attr), f"{name}.{attr}"
