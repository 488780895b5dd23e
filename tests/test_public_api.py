"""The public surface is a decision: this test pins it."""

from __future__ import annotations

import subprocess
import sys

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
