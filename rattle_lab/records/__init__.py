"""Rattle records: the v1 layout, its readers and its writer.

Layers (as xarray layers its I/O): raw file access (``_h5``, ``_readers``)
-> schema validation and units (``_schema``, ``_units``) -> domain objects
(``_model``).  One :func:`read` detects the format; one :func:`write_record`
writes valid files atomically.  See ``data_schema/README.md`` for the layout.
"""

from ._errors import (ClippingError, ClippingWarning, DataQualityError, DropoutError,
                      DropoutWarning, DuplicateRunError, EmptyChannelError, EmptyChannelWarning,
                      InfValueError, InfValueWarning, MappingError, NaNGapError, NaNGapWarning,
                      NonMonotonicTimestampsError, NonMonotonicTimestampsWarning,
                      SampleRateMismatchError, SampleRateMismatchWarning, UncalibratedWarning)
from ._chain import (FILTER_TYPES, FLAG_MEASURAND_ABSOLUTE, FLAG_MEASURAND_UNDECLARED,
                     FLAG_PARTICIPATION_ASSUMED, Participation, PlateF1, channel_time_offset_s,
                     declared_delay_s, filter_group_delay_s, plate_model_f1,
                     resolve_participation)
from ._convert import record_from_tree, record_to_tree
from ._h5 import LinkPolicy, link_policy
from ._model import (DEFAULT_CHUNK_SAMPLES, ArrayData, ArraySource, Channel, GeneratedData,
                     ImpactTable, Origin, Record, Rig, Run, Sensor, Skipped, ThresholdTable, Truth,
                     as_source)
from ._quality import FATAL_FLAGS, FLAGS, ChannelChecker, Finding, QualityLimits, TimestampChecker
from ._read import detect_format, read
from ._readers.mapping import MappingSpec, load_mapping
from ._readers.native import load_group
from ._schema import load_schema, validate_tree
from ._units import SI_UNITS, scale_to_si
from ._write import write_record, write_tree

__all__ = [
    "read",
    "write_record",
    "detect_format",
    "load_schema",
    "validate_tree",
    "load_mapping",
    "MappingSpec",
    "Record",
    "Rig",
    "Sensor",
    "Run",
    "Channel",
    "Truth",
    "ImpactTable",
    "ThresholdTable",
    "Skipped",
    "Origin",
    "ArraySource",
    "ArrayData",
    "GeneratedData",
    "Finding",
    "QualityLimits",
    "FLAGS",
    "FATAL_FLAGS",
    "SI_UNITS",
    "scale_to_si",
    "MappingError",
    "DuplicateRunError",
    "DataQualityError",
    "NaNGapError",
    "InfValueError",
    "ClippingError",
    "DropoutError",
    "SampleRateMismatchError",
    "NonMonotonicTimestampsError",
    "EmptyChannelError",
    "NaNGapWarning",
    "InfValueWarning",
    "ClippingWarning",
    "DropoutWarning",
    "SampleRateMismatchWarning",
    "NonMonotonicTimestampsWarning",
    "EmptyChannelWarning",
    "UncalibratedWarning",
    # for the store and the fit (issue 25: packages import each other's public names only)
    "write_tree",
    "record_to_tree",
    "record_from_tree",
    "load_group",
    "as_source",
    "DEFAULT_CHUNK_SAMPLES",
    "LinkPolicy",
    "link_policy",
    "ChannelChecker",
    "TimestampChecker",
    "Participation",
    "PlateF1",
    "plate_model_f1",
    "resolve_participation",
    "channel_time_offset_s", "declared_delay_s", "filter_group_delay_s", "FILTER_TYPES",
    "FLAG_PARTICIPATION_ASSUMED",
    "FLAG_MEASURAND_UNDECLARED",
    "FLAG_MEASURAND_ABSOLUTE",
]
