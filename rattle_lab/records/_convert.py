"""Between the validated node tree (+ data sources) and the Record objects.

Both directions live here so that the attribute names are written down once:
readers build a tree, validate it, then call :func:`record_from_tree`;
:func:`~rattle_lab.records.write_record` calls :func:`record_to_tree`,
validates the result and writes it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ._model import (ArraySource, Channel, ImpactTable, Origin, Record, Rig, Run, Sensor,
                     ThresholdTable, Truth)
from ._schema import _check_case_duplicates
from ._updown import UP_DOWN_PROTOCOLS, split_up_down

ROOT_FIELDS = ("campaign_id", "source", "description", "operator", "created_iso", "writer")
RIG_FIELDS = ("apparatus", "description", "plate_length_m", "plate_width_m", "plate_thickness_m",
              "plate_material", "edge_conditions", "striker_x_m", "striker_y_m", "gap_m",
              "mic_distance_m", "modal_participation", "plate_poisson_ratio")
RUN_FIELDS = ("protocol", "excitation_freq_hz", "freq_end_hz", "freq_step_hz", "nominal_level",
              "level_end", "nominal_level_units", "start_time_iso", "notes", "detect_channel")
CHANNEL_FIELDS = ("quantity", "units", "sample_rate_hz", "start_time_s", "timestamps",
                  "sensitivity", "sensitivity_units", "sensor_id", "sensor_model", "sensor_serial",
                  "calibration_date", "range_min", "range_max", "units_assumed", "description",
                  "measurand", "sign_convention", "group_delay_s", "adc_gain", "adc_offset",
                  "filter_type", "filter_order", "filter_cutoff_hz", "filter_sample_rate_hz")
#: Run attributes of an up-down run (schema v2), consumed when the reader splits it.
UP_DOWN_FIELDS = ("level_peak", "freq_peak_hz", "turn_time_s")
TRUTH_FIELDS = ("gap_m", "f_s_hz", "zeta", "e", "participation", "acoustic_law")
SCHEMA_NAME = "rattle_record"
SCHEMA_VERSION = 1
#: Layout version written when a record uses the measurement-chain attributes of version 2.
SCHEMA_VERSION_CHAIN = 2
#: Layout version 1 listed ``edge_conditions`` for the edges x=0, y=0, x=length, y=width;
#: version 2 (and every :class:`Rig` in memory) uses :data:`rattle_lab.model.plate.EDGE_ORDER`
#: (y=0, x=length, y=width, x=0).
V1_EDGE_ORDER = ("x=0", "y=0", "x=a", "y=b")


def edges_from_v1(edges: Any) -> Any:
    """A version-1 file's ``edge_conditions`` (x=0, y=0, x=a, y=b) in ``EDGE_ORDER``.

    Anything but a 4-character string is returned unchanged (the schema refuses it).

    >>> edges_from_v1("CFCF")   # v1: clamped at x=0 and x=length
    'FCFC'
    """
    if not isinstance(edges, str) or len(edges) != 4:
        return edges
    return edges[1] + edges[2] + edges[3] + edges[0]


def edges_to_v1(edges: Any) -> Any:
    """``EDGE_ORDER`` letters in the order a version-1 file lists them (inverse of
    :func:`edges_from_v1`)."""
    if not isinstance(edges, str) or len(edges) != 4:
        return edges
    return edges[3] + edges[0] + edges[1] + edges[2]


def schema_version_of(record: Record) -> int:
    """1, or 2 when ``record`` uses an attribute that layout version 2 adds."""
    rig = record.rig
    if rig.modal_participation is not None or rig.plate_poisson_ratio is not None:
        return SCHEMA_VERSION_CHAIN
    for run in record.runs:
        if run.detect_channel is not None:
            return SCHEMA_VERSION_CHAIN
        for ch in run.channels:
            if ch.measurand is not None or ch.sign_convention is not None or \
                    ch.group_delay_s is not None or ch.adc_gain is not None or \
                    ch.adc_offset is not None or ch.filter_type is not None or \
                    ch.filter_sample_rate_hz is not None:
                return SCHEMA_VERSION_CHAIN
    return SCHEMA_VERSION


def _split(attrs: Mapping[str, Any], fields: tuple[str, ...]) -> tuple[dict[str, Any], dict[str, Any]]:
    known = {k: v for k, v in attrs.items() if k in fields}
    extra = {k: v for k, v in attrs.items() if k not in fields}
    return known, extra


def _members(node: Mapping[str, Any], name: str) -> dict[str, Any]:
    child = node.get("members", {}).get(name)
    return {} if child is None else child.get("members", {})


def record_from_tree(tree: Mapping[str, Any], sources: Mapping[str, ArraySource],
                     origin: Origin | None = None, *, store: bool = False) -> Record:
    """Build a :class:`Record` from a validated tree and its dataset sources (keyed by HDF5 path).

    A version-1 file's ``edge_conditions`` are read in the version-1 order (x=0, y=0,
    x=length, y=width) and turned into ``EDGE_ORDER``.  ``store=True``: the tree is a record
    of an ingest store, whose ``edge_conditions`` are always in ``EDGE_ORDER``.
    """
    root_attrs = {k: v for k, v in tree["attrs"].items() if k not in ("schema", "schema_version")}
    root_known, root_extra = _split(root_attrs, ROOT_FIELDS)
    members = tree["members"]

    rig_known, rig_extra = _split(members["rig"]["attrs"], RIG_FIELDS)
    if not store and tree["attrs"].get("schema_version") == SCHEMA_VERSION \
            and "edge_conditions" in rig_known:
        rig_known["edge_conditions"] = edges_from_v1(rig_known["edge_conditions"])
    sensors = []
    for sensor_id, node in _members(members["rig"], "sensors").items():
        attrs = dict(node["attrs"])
        sensors.append(Sensor(sensor_id=sensor_id, position_m=tuple(attrs.pop("position_m")),
                              mounted_on=attrs.pop("mounted_on"),
                              description=attrs.pop("description", ""), extra=attrs))
    rig = Rig(**rig_known, sensors=tuple(sensors), extra=rig_extra)

    runs = []
    turns: dict[str, float] = {}
    for run_id, run_node in members["runs"]["members"].items():
        run_known, run_extra = _split(run_node["attrs"], RUN_FIELDS + UP_DOWN_FIELDS)
        channels = []
        for name, ch_node in _members(run_node, "channels").items():
            ch_known, ch_extra = _split(ch_node["attrs"], CHANNEL_FIELDS)
            channels.append(Channel(name=name, data=sources[f"/runs/{run_id}/channels/{name}"],
                                    **ch_known, extra=ch_extra))
        timestamps = {name: sources[f"/runs/{run_id}/timestamps/{name}"]
                      for name in _members(run_node, "timestamps")}
        if run_known["protocol"] in UP_DOWN_PROTOCOLS:
            # a run that ramps up then down is read as its two parts
            label = str(origin.path) if origin is not None else "record"
            turns[run_id], parts = split_up_down(run_id, run_known, channels, timestamps, label)
            for part_id, attrs, chans, ts in parts:
                runs.append(Run(run_id=part_id, channels=tuple(chans), timestamps=ts, **{
                    k: v for k, v in attrs.items() if not k.startswith("x_")},
                    extra={**run_extra, **{k: v for k, v in attrs.items() if k.startswith("x_")}}))
            continue
        runs.append(Run(run_id=run_id, channels=tuple(channels), timestamps=timestamps,
                        **run_known, extra=run_extra))

    if turns:   # the parts' ids must not collide with the file's other runs
        _check_case_duplicates([r.run_id for r in runs],
                               str(origin.path) if origin is not None else "record", "/runs")
    truth = None
    if "truth" in members:
        truth = _truth_from_tree(members["truth"], sources, turns)
    return Record(**root_known, rig=rig, runs=tuple(runs), truth=truth, extra=root_extra,
                  origin=origin)


def _read_all(source: ArraySource) -> np.ndarray:
    return np.asarray(source.read(0, source.n_samples), dtype=np.float64)


def _truth_from_tree(node: Mapping[str, Any], sources: Mapping[str, ArraySource],
                     turns: Mapping[str, float]) -> Truth:
    known, extra = _split(node["attrs"], TRUTH_FIELDS)
    impacts = {}
    for run_id in _members(node, "impacts"):
        base = f"/truth/impacts/{run_id}"
        cols = [_read_all(sources[f"{base}/{k}"]) for k in ("t_s", "v_in_m_s", "v_out_m_s")]
        if run_id in turns:   # an up-down run read as two: its impacts split at the turn
            up = cols[0] < turns[run_id]
            impacts[run_id + "_up"] = ImpactTable(*(c[up] for c in cols))
            impacts[run_id + "_down"] = ImpactTable(*(c[~up] for c in cols))
            continue
        impacts[run_id] = ImpactTable(*cols)
    th_node = node["members"]["thresholds"]
    freq, onset, disappearance = (_read_all(sources[f"/truth/thresholds/{k}"])
                                  for k in ("freq_hz", "onset_level", "disappearance_level"))
    thresholds = ThresholdTable(freq, onset, disappearance,
                                level_units=th_node["attrs"]["level_units"])
    return Truth(**known, impacts=impacts, thresholds=thresholds, extra=extra)


def _attrs(obj: Any, fields: tuple[str, ...], extra: Mapping[str, Any]) -> dict[str, Any]:
    out = {}
    for name in fields:
        value = getattr(obj, name)
        if value is None or (name in ("description", "notes") and value == ""):
            continue
        if name == "units_assumed" and value is False:
            continue
        out[name] = _plain(value)
    out.update({k: _plain(v) for k, v in extra.items()})
    return out


def _plain(value: Any) -> Any:
    if isinstance(value, (np.generic,)):
        return value.item()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _dataset_node(source: ArraySource, attrs: dict[str, Any]) -> dict[str, Any]:
    return {"kind": "dataset", "attrs": attrs, "dtype": np.dtype(source.dtype).str,
            "shape": [int(source.n_samples)]}


def record_to_tree(record: Record, *, store: bool = False
                   ) -> tuple[dict[str, Any], dict[str, ArraySource]]:
    """The node tree and dataset sources (keyed by HDF5 path) that represent ``record``.

    In a version-1 tree ``edge_conditions`` are written in the version-1 order (see
    :func:`record_from_tree`); ``store=True`` (a record of an ingest store) keeps
    ``EDGE_ORDER``.
    """
    from ._model import ArrayData

    sources: dict[str, ArraySource] = {}
    version = schema_version_of(record)
    root_attrs = {"schema": SCHEMA_NAME, "schema_version": version,
                  **_attrs(record, ROOT_FIELDS, record.extra)}
    sensors = {s.sensor_id: {"kind": "group", "members": {},
                             "attrs": _attrs(s, ("position_m", "mounted_on", "description"), s.extra)}
               for s in record.rig.sensors}
    rig_members = {"sensors": {"kind": "group", "attrs": {}, "members": sensors}} if sensors else {}
    rig_attrs = _attrs(record.rig, RIG_FIELDS, record.rig.extra)
    if not store and version == SCHEMA_VERSION and "edge_conditions" in rig_attrs:
        rig_attrs["edge_conditions"] = edges_to_v1(rig_attrs["edge_conditions"])
    rig = {"kind": "group", "attrs": rig_attrs, "members": rig_members}
    runs: dict[str, Any] = {}
    for run in record.runs:
        channels = {}
        for ch in run.channels:
            path = f"/runs/{run.run_id}/channels/{ch.name}"
            sources[path] = ch.data
            channels[ch.name] = _dataset_node(ch.data, _attrs(ch, CHANNEL_FIELDS, ch.extra))
        run_members: dict[str, Any] = {"channels": {"kind": "group", "attrs": {}, "members": channels}}
        if run.timestamps:
            ts_nodes = {}
            for name, src in run.timestamps.items():
                sources[f"/runs/{run.run_id}/timestamps/{name}"] = src
                ts_nodes[name] = _dataset_node(src, {"units": "s"})
            run_members["timestamps"] = {"kind": "group", "attrs": {}, "members": ts_nodes}
        runs[run.run_id] = {"kind": "group", "attrs": _attrs(run, RUN_FIELDS, run.extra),
                            "members": run_members}
    members: dict[str, Any] = {"rig": rig, "runs": {"kind": "group", "attrs": {}, "members": runs}}
    if record.truth is not None:
        truth = record.truth
        impacts = {}
        for run_id, table in truth.impacts.items():
            cols = {}
            for k in ("t_s", "v_in_m_s", "v_out_m_s"):
                src = ArrayData(np.asarray(getattr(table, k), dtype=np.float64))
                sources[f"/truth/impacts/{run_id}/{k}"] = src
                cols[k] = _dataset_node(src, {})
            impacts[run_id] = {"kind": "group", "attrs": {}, "members": cols}
        th_cols = {}
        for k in ("freq_hz", "onset_level", "disappearance_level"):
            src = ArrayData(np.asarray(getattr(truth.thresholds, k), dtype=np.float64))
            sources[f"/truth/thresholds/{k}"] = src
            th_cols[k] = _dataset_node(src, {})
        members["truth"] = {
            "kind": "group", "attrs": _attrs(truth, TRUTH_FIELDS, truth.extra),
            "members": {
                "impacts": {"kind": "group", "attrs": {}, "members": impacts},
                "thresholds": {"kind": "group", "attrs": {"level_units": truth.thresholds.level_units},
                               "members": th_cols},
            },
        }
    return {"kind": "group", "attrs": root_attrs, "members": members}, sources
