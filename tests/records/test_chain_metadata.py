"""Issue 15, part A: the measurement chain a record declares (schema v2), edge order, participation.

The modal participation ``Q1/Q2`` enters the gap of the eq. (3.4) fit as ``h / q``: a fit
that assumes 1.0 on a plate with 1.2 reports a gap 1.2 times too small.  The record's rig
metadata (schema v2 ``modal_participation``, or the plate geometry) carries it; ``fit
--participation`` overrides it; when neither exists 1.0 is assumed and the output says so
with the data-quality flag ``participation_assumed``.
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import h5py
import pytest

from rattle_lab.rig._handbuilt import synthetic_campaign
from rattle_lab.exceptions import SchemaError
from rattle_lab.store import ingest
from rattle_lab.model.plate import EDGE_ORDER
from rattle_lab.records import read, write_record
from rattle_lab.records._chain import (FLAG_PARTICIPATION_ASSUMED, FLAG_POISSON_ASSUMED,
                                       participation_from_plate, resolve_participation,
                                       rig_participation)
from rattle_lab.records._model import Rig
from rattle_lab.store import read_results
from record_factory import make_record, run_command

ROOT = Path(__file__).resolve().parents[2]
THESIS_PLATE = ["--a", "0.254", "--b", "0.2286", "--h", "0.001", "--E", "7e10", "--nu", "0.34",
                "--rho", "2710"]


# ----------------------------------------------------------------------------- edge order
def test_thesis_plate_is_105_5_hz_with_the_thesis_edges_through_the_cli():
    # Thesis sec. 5.1: a = 0.254 m (clamped), b = 0.2286 m (free), 1 mm aluminium, E = 7e10,
    # nu = 0.34, rho = 2710; Table 2.1 (CFCF, "length a sides clamped", b/a = 0.9) lambda =
    # 27.4 (Leissa), which gives f1 = 105.5 Hz by eq. 2.25 (the thesis rounds to 105 Hz).
    # Tolerance 0.5 %: Leissa's lambda has three digits and, like every beam-function Ritz
    # value with a free edge, sits above the converged value: the converged Ritz solver gives
    # 27.31 (0.33 % below 27.4; issue 13).  The other edge reading is 20 % away.
    proc = run_command("model", "plate", *THESIS_PLATE, "--edges", "CFCF", "--modes", "1", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["edge_order"] == list(EDGE_ORDER)
    assert out["modes"][0]["lambda"] == pytest.approx(27.4, rel=5e-3)
    assert out["modes"][0]["f_hz"] == pytest.approx(105.5, rel=5e-3)
    # the other reading of the four letters (length-b sides clamped) is another plate
    other = json.loads(run_command("model", "plate", *THESIS_PLATE, "--edges", "FCFC", "--modes",
                               "1", "--json").stdout)
    assert other["modes"][0]["f_hz"] < 90.0


def test_schema_and_its_readme_spell_the_plate_models_edge_order():
    order = ", ".join(e.replace("x=a", "x=length").replace("y=b", "y=width") for e in EDGE_ORDER)
    schema = (ROOT / "rattle_lab/data/schema/rattle_record.v1.schema.json").read_text()
    readme = (ROOT / "data_schema/README.md").read_text()
    assert order == "y=0, x=length, y=width, x=0"
    assert f"for the edges {order}" in schema
    assert f"for the edges {order}" in readme
    # the version-1 order is named once, as the order of version-1 files (issue 28)
    v1 = "x=0, y=0, x=length, y=width"
    assert v1 not in schema and readme.count(v1) == 1
    assert "The version-1 text listed them for the edges x=0, y=0, x=length, y=width" in \
        " ".join(readme.split())


def test_rig_participation_from_the_plate_geometry_matches_model_scale():
    # The record's CFCF geometry goes through the same plate model as `model scale`.
    rig = Rig("plate_striker", plate_length_m=0.254, plate_width_m=0.2286, edge_conditions="CFCF",
              plate_poisson_ratio=0.34)
    proc = run_command("model", "scale", *THESIS_PLATE, "--edges", "CFCF", "--gap", "0.001",
                   "--accel", "1.0", "--json")
    assert proc.returncode == 0, proc.stderr
    expected = json.loads(proc.stdout)["participation"]
    got = rig_participation(rig)
    assert got is not None and got.flags == ()
    assert got.value == pytest.approx(expected, rel=1e-12)
    # Table 2.1 (b/a = 0.9, FEM): Q1 = 0.500, Q2 = 0.402 -> 1.244.  Three digits give 0.25 %;
    # the converged Ritz mode (issue 13) gives 1.234, 0.8 % from the thesis's FEM mesh: 1 %.
    assert got.value == pytest.approx(0.500 / 0.402, rel=1e-2)
    no_nu = rig_participation(dataclasses.replace(rig, plate_poisson_ratio=None))
    assert no_nu is not None and no_nu.flags == (FLAG_POISSON_ASSUMED,)


def test_participation_closed_form_for_ssss():
    # SSSS: Q1 = (b/a)/(pi^2) * 4 (eq. 2.23, m = n = 1), Q2 = b/(4a) (eq. 2.24): Q1/Q2 = 16/pi^2
    import math
    assert participation_from_plate(0.3, 0.2, "SSSS", 0.3) == pytest.approx(16 / math.pi**2,
                                                                           rel=1e-12)


def test_resolve_participation_order_and_disagreement():
    from rattle_lab.exceptions import ParameterError
    a = Rig("other", description="x", modal_participation=1.3)
    b = Rig("other", description="y", modal_participation=1.1)
    assert resolve_participation([a], 2.0, "command line").value == 2.0
    assert resolve_participation([a], None, "pipeline").value == 1.3
    none = resolve_participation([Rig("other", description="z")], None, "pipeline")
    assert (none.value, none.flags) == (1.0, (FLAG_PARTICIPATION_ASSUMED,))
    with pytest.raises(ParameterError, match="disagree"):
        resolve_participation([a, b], None, "pipeline")
    with pytest.raises(ParameterError, match="participation"):
        resolve_participation([a], -1.0, "command line")


# ----------------------------------------------------------------------------- schema v2
def test_v2_attributes_round_trip_and_v1_files_keep_reading(tmp_path):
    rec = make_record()
    v1 = write_record(tmp_path / "v1.h5", rec)
    with h5py.File(v1, "r") as fh:
        assert fh.attrs["schema_version"] == 1
    assert read(v1).rig.modal_participation is None
    runs = []
    for run in rec.runs:
        chans = tuple(dataclasses.replace(c, measurand="panel_relative_to_striker",
                                          sign_convention="toward_striker_positive",
                                          group_delay_s=18e-6)
                      if c.quantity == "plate_velocity" else c for c in run.channels)
        runs.append(dataclasses.replace(run, channels=chans))
    rec2 = dataclasses.replace(rec, runs=tuple(runs),
                               rig=dataclasses.replace(rec.rig, modal_participation=1.244,
                                                       plate_poisson_ratio=0.33))
    assert any(c.quantity == "plate_velocity" for c in rec2.runs[0].channels)
    v2 = write_record(tmp_path / "v2.h5", rec2)
    with h5py.File(v2, "r") as fh:
        assert fh.attrs["schema_version"] == 2
    back = read(v2)
    assert back.rig.modal_participation == 1.244 and back.rig.plate_poisson_ratio == 0.33
    vel = [c for c in back.runs[0].channels if c.quantity == "plate_velocity"][0]
    assert (vel.measurand, vel.sign_convention, vel.group_delay_s) == (
        "panel_relative_to_striker", "toward_striker_positive", 18e-6)


def test_v2_attribute_in_a_v1_file_and_unknown_measurand_are_refused(tmp_path):
    path = write_record(tmp_path / "v1.h5", make_record())
    with h5py.File(path, "r+") as fh:
        fh["rig"].attrs["modal_participation"] = 1.2
    with pytest.raises(SchemaError, match=r"/rig: attribute 'modal_participation': needs "
                                          r"schema_version 2"):
        read(path)
    with h5py.File(path, "r+") as fh:
        fh.attrs["schema_version"] = 2
        vel = next(n for n, d in fh["runs/dwell_094/channels"].items()
                   if d.attrs["quantity"] == "plate_velocity")
        fh[f"runs/dwell_094/channels/{vel}"].attrs["measurand"] = "striker_absolute"
    with pytest.raises(SchemaError, match=r"channels/.*measurand"):
        read(path)


# ----------------------------------------------------------------------------- fit
@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    d = tmp_path_factory.mktemp("participation")
    record, truth = synthetic_campaign(up_freq_hz=(85.0, 93.0, 95.5, 96.0, 96.5, 99.0, 106.0),
                                       down_freq_hz=(106.0, 112.0), duration_s=0.6)
    assert truth.participation == 1.2
    out = {}
    for name, rig in (("declared", dataclasses.replace(record.rig,
                                                       modal_participation=truth.participation)),
                      ("bare", Rig("other", description="no plate described",
                                   mic_distance_m=record.rig.mic_distance_m))):
        path = write_record(d / f"{name}.h5", dataclasses.replace(record, rig=rig))
        store = d / f"{name}_store.h5"
        ingest([path], store, quiet=True)
        out[name] = store
    pipeline = d / "p.toml"
    pipeline.write_text('[fit]\nrestitution_method = "quasi-static"\n')
    return out, pipeline, truth


def test_fit_takes_the_participation_from_the_record(stores):
    out, pipeline, truth = stores
    proc = run_command("fit", str(out["declared"]), "--pipeline", str(pipeline), "--json")
    assert proc.returncode == 0, proc.stderr
    res = json.loads(proc.stdout)
    assert res["participation"] == {"value": 1.2, "source": "rig modal_participation"}
    # (the hand-built record does not say what its vibrometer measures: flagged per run;
    # issue 28: inferred from the data where it can be, its delay measured where undeclared)
    assert not [f for f in res["data_quality"] if "participation" in f]
    assert res["data_quality"] and all(
        re.match(r"\S+: (velocity_measurand_undeclared|measurand_inferred: |"
                 r"measurand_undetermined: |channel_delay_estimated: )", f)
        for f in res["data_quality"]), res["data_quality"]
    # the synthetic thresholds follow eq. 3.4 with 1 % noise: the gap to 2 % (issue target)
    assert res["fits"]["grazing"]["gap_m"]["value"] == pytest.approx(truth.gap_m, rel=0.02)


def test_fit_without_participation_assumes_one_and_flags_it(stores):
    out, pipeline, truth = stores
    proc = run_command("fit", str(out["bare"]), "--pipeline", str(pipeline))
    assert proc.returncode == 0, proc.stderr
    assert "data-quality flag: participation_assumed" in proc.stdout
    assert re.search(r"participation Q1/Q2 = 1 \(assumed\)", proc.stdout)
    # what that fit wrote to the store (what --json prints: test_fit_summary)
    res = read_results(out["bare"]).summary
    assert res["data_quality"][0] == FLAG_PARTICIPATION_ASSUMED
    assert not [f for f in res["data_quality"][1:] if "participation" in f]
    # what the flag warns of: only gap/participation is identified, the gap is 1/1.2 of truth
    assert res["fits"]["grazing"]["gap_m"]["value"] == pytest.approx(truth.gap_m / 1.2, rel=0.02)
    # the command line overrides and removes the flag
    over = json.loads(run_command("fit", str(out["bare"]), "--pipeline", str(pipeline),
                              "--participation", "1.2", "--json").stdout)
    assert over["participation"] == {"value": 1.2, "source": "command line"}
    assert not [f for f in over["data_quality"] if "participation" in f]
    assert over["fits"]["grazing"]["gap_m"]["value"] == pytest.approx(truth.gap_m, rel=0.02)


def test_fit_rejects_a_bad_participation_on_the_command_line(stores):
    out, _, _ = stores
    proc = run_command("fit", str(out["bare"]), "--participation", "0")
    assert proc.returncode == 2
    assert "participation" in proc.stderr and "Traceback" not in proc.stderr


# ----------------------------------------------------------------------------- bad metadata
def test_group_delay_longer_than_a_forcing_period_is_refused(tmp_path):
    path = write_record(tmp_path / "v1.h5", make_record())
    with h5py.File(path, "r+") as fh:
        fh.attrs["schema_version"] = 2
        vel = next(n for n, d in fh["runs/dwell_094/channels"].items()
                   if d.attrs["quantity"] == "plate_velocity")
        fh[f"runs/dwell_094/channels/{vel}"].attrs["group_delay_s"] = 0.018   # 18 ms, not us
    with pytest.raises(SchemaError, match=r"attribute 'group_delay_s': 0\.018 s is not less than "
                                          r"a forcing period of the run \(0\.0106383 s\)"):
        read(path)
    proc = run_command("ingest", str(path), "-o", str(tmp_path / "s.h5"))
    assert proc.returncode == 2 and "group_delay_s" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_sample_rate_contradicting_the_time_vector_is_refused(tmp_path):
    import numpy as np

    from rattle_lab.records._errors import MappingError

    t = np.arange(1000) / 25600.0
    np.save(tmp_path / "rec.npy", np.vstack([t, np.sin(2 * np.pi * 100 * t)]))
    mapping = tmp_path / "m.toml"
    mapping.write_text(
        '[mapping]\nversion = 1\nformat = "npy"\n\n[campaign]\ncampaign_id = "c-{stem}"\n'
        'source = "measured"\n\n[rig]\napparatus = "other"\ndescription = "x"\n\n'
        '[[runs]]\nrun_id = "r"\nprotocol = "transient"\n\n[runs.timestamps.t]\nindex = 0\n\n'
        '[[runs.channels]]\nname = "a"\nindex = 1\nquantity = "plate_acceleration"\n'
        'units = "m/s^2"\ntimestamps = "t"\nsample_rate_hz = 51200.0\n')
    with pytest.raises(MappingError, match=r"sample_rate_hz 51200 Hz contradicts the channel's "
                                           r"time vector \(median step 3\.90625e-05 s = 25600 Hz\)"):
        read(tmp_path / "rec.npy", mapping=mapping)
    # agreeing to 1e-3: accepted
    mapping.write_text(mapping.read_text().replace("51200.0", "25600.0"))
    assert read(tmp_path / "rec.npy", mapping=mapping).runs[0].channel("a").n_samples == 1000
