"""Validation of a record's node tree against the JSON Schema, plus the checks JSON Schema cannot do.

The JSON Schema (``rattle_lab/data/schema/rattle_record.v1.schema.json``)
checks names, attributes and units.  This module adds what needs the datasets
or cross references: dtypes and shapes, timestamp and sensor references,
range limits, truth tables of equal length, and run ids that differ only by
case.  Every error names the file, the HDF5 path and the field.
"""

from __future__ import annotations

import functools
import json
import math
import re
from collections.abc import Iterable, Sequence
from typing import Any

import jsonschema

from rattle_lab._resources import find_resource
from rattle_lab.exceptions import SchemaError
from ._chain import check_filter
from ._errors import DuplicateRunError

#: The schema's file among the resources of kind "schema" (:mod:`rattle_lab._resources`).
SCHEMA_FILE = "rattle_record.v1.schema.json"

#: dtypes (numpy kind + item size) a channel may have.
CHANNEL_DTYPES = frozenset({"f4", "f8", "i1", "i2", "i4", "i8", "u1", "u2", "u4"})

#: Attributes that layout version 2 adds (the measurement chain), by group.
V2_RIG_ATTRS = ("modal_participation", "plate_poisson_ratio")
V2_CHANNEL_ATTRS = ("measurand", "sign_convention", "group_delay_s", "adc_gain", "adc_offset",
                    "filter_type", "filter_order", "filter_cutoff_hz", "filter_sample_rate_hz")
V2_RUN_ATTRS = ("detect_channel", "level_peak", "freq_peak_hz", "turn_time_s")


@functools.lru_cache(maxsize=1)
def load_schema() -> dict[str, Any]:
    """The rattle record v1 JSON Schema, as shipped in the package."""
    path = find_resource("schema", SCHEMA_FILE)
    if path is None:  # a broken installation: the wheel ships it
        raise FileNotFoundError(f"the record schema {SCHEMA_FILE} is not installed with rattle_lab")
    return json.loads(path.read_text("utf-8"))


@functools.lru_cache(maxsize=1)
def _validator() -> jsonschema.protocols.Validator:
    schema = load_schema()
    # The schema itself is checked by the test suite (check_schema costs ~60 ms per process).
    return jsonschema.validators.validator_for(schema)(schema)


#: Among errors at one depth, a missing or unexpected name explains the others.
_PRIORITY = {"required": 0, "additionalProperties": 1}

#: Longest excerpt of a value quoted in an error message.
MAX_QUOTE = 80


def _quote(value: object) -> str:
    text = repr(value)
    return text if len(text) <= MAX_QUOTE else text[:MAX_QUOTE] + f"... ({len(text)} characters)"


def _locate(path: Sequence[Any]) -> tuple[str, str | None, str]:
    """Map a JSON path in the node tree to (HDF5 path, field, container kind)."""
    parts: list[str] = []
    field: str | None = None
    container = "node"
    i = 0
    while i < len(path):
        key = path[i]
        if key == "members":
            container = "members"
            if i + 1 < len(path):
                parts.append(str(path[i + 1]))
                container = "node"
            i += 2
        elif key == "attrs":
            container = "attrs"
            if i + 1 < len(path):
                field = str(path[i + 1])
            i += 2
        else:
            field = str(key)
            i += 1
    return "/" + "/".join(parts), field, container


def _message(error: jsonschema.ValidationError) -> str:
    h5path, field, container = _locate(list(error.absolute_path))
    extra = error.schema.get("x-message") if isinstance(error.schema, dict) else None
    validator = error.validator
    if validator == "required":
        missing = [name for name in error.validator_value if name not in error.instance]
        name = missing[0] if missing else "?"
        what = "attribute" if container == "attrs" else "group or dataset"
        text = f"{h5path}: missing {what} '{name}'"
    elif validator == "additionalProperties" and isinstance(error.instance, dict):
        known = set(error.schema.get("properties", {}))
        patterns = list(error.schema.get("patternProperties", {}))
        unexpected = sorted(k for k in error.instance if k not in known
                            and not any(re.search(p, k) for p in patterns))
        what = "attribute" if container == "attrs" else "group or dataset"
        hint = " (extra attributes must start with 'x_')" if container == "attrs" else ""
        name = unexpected[0] if unexpected else "?"
        text = f"{h5path}: unexpected {what} '{name}'{hint}"
        if extra:
            text += f": {extra}"
            extra = None
    elif validator == "propertyNames" or (error.relative_schema_path
                                           and "propertyNames" in error.relative_schema_path):
        text = f"{h5path}: invalid name {_quote(error.instance)}"
    elif validator in ("minProperties", "maxProperties"):
        text = f"{h5path}: {'is empty' if validator == 'minProperties' else 'has unexpected members'}"
    elif validator == "oneOf":
        text = f"{h5path}: attributes do not fit"
    elif validator == "maxLength":
        text = (f"{h5path}: attribute '{field}': text of {len(error.instance)} characters is "
                f"longer than {error.validator_value}")
    else:
        label = f"attribute '{field}'" if container == "attrs" or field not in (None, "kind") else "node"
        if field == "kind":
            label = "node type"
        message = error.message
        if len(message) > 4 * MAX_QUOTE:
            message = f"{_quote(error.instance)} does not fit ({validator} {_quote(error.validator_value)})"
        text = f"{h5path}: {label}: {message}"
    if extra:
        text += f" ({extra})"
    return text


def validate_tree(tree: dict[str, Any], file_label: str) -> None:
    """Validate a record's node tree against the schema, then the in-code rules.

    Parameters
    ----------
    tree : dict
        The node tree (see :func:`rattle_lab.records._h5.node_tree`).
    file_label : str
        The file named in error messages.

    Raises
    ------
    SchemaError
        Naming ``file: /hdf5/path: attribute 'field': reason``.
    DuplicateRunError
        If two run ids differ only by letter case.
    """
    errors = sorted(_validator().iter_errors(tree),
                    key=lambda e: (len(e.absolute_path), _PRIORITY.get(str(e.validator), 2),
                                   [str(p) for p in e.absolute_path]))
    if errors:
        # The shallowest error is reported: a missing group explains the errors below it.
        first = errors[0]
        more = f" (and {len(errors) - 1} more schema errors)" if len(errors) > 1 else ""
        raise SchemaError(f"{file_label}: {_message(first)}{more}")
    _check_in_code(tree, file_label)


def _members(node: dict[str, Any]) -> dict[str, Any]:
    return node.get("members", {})


def _check_version(tree: dict[str, Any], label: str) -> None:
    """Version-2 attributes in a file that says version 1 are refused (a v1 reader ignores them)."""
    if tree["attrs"].get("schema_version") != 1:
        return
    members = _members(tree)
    found = [("/rig", k) for k in V2_RIG_ATTRS if k in members["rig"]["attrs"]]
    for run_id, run in _members(members["runs"]).items():
        found += [(f"/runs/{run_id}", k) for k in V2_RUN_ATTRS if k in run["attrs"]]
        if str(run["attrs"].get("protocol", "")).endswith("_up_down"):
            found.append((f"/runs/{run_id}", "protocol"))
        for name, channel in _members(_members(run)["channels"]).items():
            found += [(f"/runs/{run_id}/channels/{name}", k) for k in V2_CHANNEL_ATTRS
                      if k in channel["attrs"]]
    if found:
        path, key = found[0]
        raise SchemaError(f"{label}: {path}: attribute {key!r}: needs schema_version 2 "
                          "(the file says 1)")


def _check_in_code(tree: dict[str, Any], label: str) -> None:
    _check_version(tree, label)
    members = _members(tree)
    sensors = set(_members(_members(members["rig"]).get("sensors", {"members": {}})))
    runs = _members(members["runs"])
    _check_case_duplicates(runs, label, "/runs")
    for run_id, run in runs.items():
        run_path = f"/runs/{run_id}"
        timestamps = _members(_members(run).get("timestamps", {"members": {}}))
        for ts_name, ts in timestamps.items():
            ts_path = f"{run_path}/timestamps/{ts_name}"
            _check_dataset(ts, label, ts_path, kinds=("f8",), what="timestamps dataset")
        channels = _members(_members(run)["channels"])
        _check_case_duplicates(channels, label, f"{run_path}/channels")
        for name, channel in channels.items():
            path = f"{run_path}/channels/{name}"
            _check_dataset(channel, label, path, kinds=None, what="channel")
            attrs = channel["attrs"]
            _check_finite(attrs, label, path)
            ts_name = attrs.get("timestamps")
            if ts_name is not None:
                if ts_name not in timestamps:
                    raise SchemaError(f"{label}: {path}: attribute 'timestamps': no dataset "
                                      f"{run_path}/timestamps/{ts_name}")
                if timestamps[ts_name]["shape"] != channel["shape"]:
                    raise SchemaError(f"{label}: {path}: attribute 'timestamps': "
                                      f"{run_path}/timestamps/{ts_name} has shape "
                                      f"{timestamps[ts_name]['shape']}, the channel {channel['shape']}")
            delay = attrs.get("group_delay_s")
            f_exc = run["attrs"].get("excitation_freq_hz")
            if delay is not None and f_exc and delay * max(f_exc, run["attrs"].get(
                    "freq_end_hz") or f_exc) >= 1.0:
                raise SchemaError(f"{label}: {path}: attribute 'group_delay_s': {delay!r} s is "
                                  f"not less than a forcing period of the run "
                                  f"({1.0 / max(f_exc, run['attrs'].get('freq_end_hz') or f_exc):.6g} s); "
                                  "a filter delay is microseconds to milliseconds (was it given "
                                  "in another unit?)")
            problem = check_filter(attrs.get("filter_type"), attrs.get("filter_order"),
                                   attrs.get("filter_cutoff_hz"),
                                   attrs.get("filter_sample_rate_hz"))
            if problem is not None:
                raise SchemaError(f"{label}: {path}: the declared filter: {problem}")
            if "measurand" in attrs and attrs.get("quantity") != "plate_velocity":
                raise SchemaError(f"{label}: {path}: attribute 'measurand': only a plate_velocity "
                                  f"channel has one (this is {attrs.get('quantity')!r})")
            _check_adc(channel, label, path)
            sensor_id = attrs.get("sensor_id")
            if sensor_id is not None and sensor_id not in sensors:
                raise SchemaError(f"{label}: {path}: attribute 'sensor_id': no sensor "
                                  f"/rig/sensors/{sensor_id}")
            lo, hi = attrs.get("range_min"), attrs.get("range_max")
            if (lo is None) != (hi is None):
                raise SchemaError(f"{label}: {path}: attribute 'range_min': range_min and "
                                  "range_max go together")
            if lo is not None and not lo < hi:
                raise SchemaError(f"{label}: {path}: attribute 'range_max': must be > range_min "
                                  f"({lo}), was {hi}")
        detect_channel = run["attrs"].get("detect_channel")
        if detect_channel is not None and detect_channel not in channels:
            raise SchemaError(f"{label}: {run_path}: attribute 'detect_channel': no channel "
                              f"{detect_channel!r} (has: {', '.join(sorted(channels))})")
        _check_finite(run["attrs"], label, run_path)
    _check_finite(members["rig"]["attrs"], label, "/rig")
    truth = members.get("truth")
    if truth is not None:
        _check_truth(truth, set(runs), label)


def _check_adc(channel: dict[str, Any], label: str, path: str) -> None:
    """Raw ADC counts: ``adc_gain`` needs an integer dataset; ``adc_offset`` needs ``adc_gain``."""
    attrs = channel["attrs"]
    if "adc_offset" in attrs and "adc_gain" not in attrs:
        raise SchemaError(f"{label}: {path}: attribute 'adc_offset': needs 'adc_gain' (counts "
                          "are converted as adc_gain * count + adc_offset)")
    kind = str(channel["dtype"]).lstrip("<>|=")[:1]
    if "adc_gain" in attrs and kind not in ("i", "u"):
        raise SchemaError(f"{label}: {path}: attribute 'adc_gain': raw ADC counts are integers; "
                          f"this dataset is {channel['dtype']!r} (store engineering units without "
                          "adc_gain, or the counts as an integer dataset)")


def _check_case_duplicates(names: Iterable[str], label: str, where: str) -> None:
    seen: dict[str, str] = {}
    for name in names:
        key = name.casefold()
        if key in seen:
            raise DuplicateRunError(f"{label}: {where}: duplicated id: {seen[key]!r} and {name!r} "
                                    "differ only by letter case")
        seen[key] = name


def _check_finite(attrs: dict[str, Any], label: str, path: str) -> None:
    for key, value in attrs.items():
        values = value if isinstance(value, list) else [value]
        for v in values:
            if isinstance(v, float) and not math.isfinite(v):
                raise SchemaError(f"{label}: {path}: attribute '{key}': must be finite, was {v}")


def _check_dataset(node: dict[str, Any], label: str, path: str, *, kinds: tuple[str, ...] | None,
                   what: str) -> None:
    dtype = str(node["dtype"]).lstrip("<>|=")
    allowed = CHANNEL_DTYPES if kinds is None else frozenset(kinds)
    if dtype not in allowed:
        raise SchemaError(f"{label}: {path}: dataset 'dtype': a {what} must be one of "
                          f"{', '.join(sorted(allowed))} (numpy codes), got {node['dtype']!r}")
    shape = node["shape"]
    if len(shape) != 1:
        raise SchemaError(f"{label}: {path}: dataset 'shape': a {what} must be 1-D, got {tuple(shape)}")


def _check_truth(truth: dict[str, Any], run_ids: set[str], label: str) -> None:
    _check_finite(truth["attrs"], label, "/truth")
    impacts = _members(_members(truth)["impacts"])
    for run_id, table in impacts.items():
        path = f"/truth/impacts/{run_id}"
        if run_id not in run_ids:
            raise SchemaError(f"{label}: {path}: group name: no run /runs/{run_id}")
        _check_table(_members(table), label, path, ("t_s", "v_in_m_s", "v_out_m_s"))
    _check_table(_members(_members(truth)["thresholds"]), label, "/truth/thresholds",
                 ("freq_hz", "onset_level", "disappearance_level"))


def _check_table(columns: dict[str, Any], label: str, path: str, names: tuple[str, ...]) -> None:
    lengths = {}
    for name in names:
        node = columns[name]
        _check_dataset(node, label, f"{path}/{name}", kinds=("f8", "f4"), what="table column")
        lengths[name] = node["shape"][0]
    if len(set(lengths.values())) > 1:
        raise SchemaError(f"{label}: {path}: dataset 'shape': columns differ in length: "
                          + ", ".join(f"{k}={v}" for k, v in lengths.items()))
