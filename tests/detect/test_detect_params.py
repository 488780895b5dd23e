"""DetectParams: every [detect] key, checked in one place, given back as it was given.

The pipeline's content key of the detect stage and ``/results``'s provenance hash the
``[detect]`` table as the user wrote it; :meth:`DetectParams.to_dict` must give back exactly
that (the same keys, the same values of the same types), or every existing store's cache
would go stale.
"""

from __future__ import annotations

import dataclasses
import json
import tomllib
from pathlib import Path

import pytest

from rattle_lab.detect import MEASURAND_KEYS, SEGMENT_KEYS, SOUND_KEYS, DetectParams, ImpactParams
from rattle_lab.exceptions import ParameterError
from rattle_lab.fit import load_pipeline
from rattle_lab.workflow.pipeline import parse_pipeline

PIPELINES = Path(__file__).resolve().parents[2] / "pipelines"


def test_every_detect_key_is_a_field() -> None:
    fields = {f.name for f in dataclasses.fields(DetectParams)} - {"given"}
    assert fields == ({f.name for f in dataclasses.fields(ImpactParams)} | set(SOUND_KEYS)
                      | set(SEGMENT_KEYS) | set(MEASURAND_KEYS))
    # the defaults are ImpactParams', SOUND_KEYS', SEGMENT_KEYS' and MEASURAND_KEYS'
    d = DetectParams()
    assert d.impact_params() == ImpactParams()
    assert {k: getattr(d, k) for k in SOUND_KEYS} == SOUND_KEYS
    assert {k: getattr(d, k) for k in SEGMENT_KEYS} == SEGMENT_KEYS
    assert {k: getattr(d, k) for k in MEASURAND_KEYS} == MEASURAND_KEYS


def test_to_dict_is_the_table_as_given() -> None:
    table = {"window_s": 0.005, "on": 12, "ring_modes": [[512.0, 30.0]], "channel": "plate",
             "fit_basis": "poly"}
    p = DetectParams.from_mapping(table)
    out = p.to_dict()
    assert out == table
    assert list(out) == list(table)                       # the order too
    assert json.dumps(out) == json.dumps(table)           # 12 stays an int, lists stay lists
    assert DetectParams.from_mapping({}).to_dict() == {}
    # the typed values the detection reads
    assert p.impact_params().ring_modes == ((512.0, 30.0),)
    assert p.impact_params().on == 12.0 and p.channel == "plate"


def test_replace_adds_what_it_changed() -> None:
    p = DetectParams.from_mapping({"on": 10.0})
    q = dataclasses.replace(p, velocity_model="flights")
    assert q.to_dict() == {"on": 10.0, "velocity_model": "flights"}
    assert p.to_dict() == {"on": 10.0}                    # frozen: p is unchanged
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.on = 3.0  # type: ignore[misc]


@pytest.mark.parametrize(("table", "message"), [
    ({"onn": 12.0}, r"\[detect\]: unknown key 'onn' \(known: .*channel"),
    ({"on": 3.0}, r"\[detect\]: `on` must be > `off`"),
    ({"first_fraction": 0.0}, r"`first_fraction` must be a number > 0"),
    ({"first_fraction": 1.5}, r"`first_fraction` must be in \(0, 1\]"),
    ({"window_s": "5 ms"}, r"`window_s` must be a number > 0, was '5 ms'"),
    ({"channel": 3}, r"`channel` must be a channel name"),
    ({"ring_modes": [[100.0, -1.0]]}, r"`ring_modes`: each frequency and decay rate"),
])
def test_bad_tables_are_refused_naming_the_key(table, message) -> None:
    with pytest.raises(ParameterError, match=message):
        DetectParams.from_mapping(table, "p.toml: [detect]: ")


def test_pipeline_files_are_checked_by_it(tmp_path) -> None:
    f = tmp_path / "p.toml"
    f.write_text("[detect]\non = 2.0\n")
    with pytest.raises(ParameterError, match=r"p.toml: \[detect\]: `on` must be > `off`"):
        load_pipeline(f)
    with pytest.raises(ParameterError, match=r"\[detect\]: unknown key 'x'"):
        parse_pipeline({"detect": {"x": 1}}, str(f))


@pytest.mark.parametrize("path", sorted(PIPELINES.glob("*.toml")), ids=lambda p: p.stem)
def test_shipped_pipelines_round_trip(path: Path) -> None:
    table = tomllib.loads(path.read_text()).get("detect", {})
    assert load_pipeline(path)["detect"] == table
    assert DetectParams.from_mapping(table).to_dict() == table
