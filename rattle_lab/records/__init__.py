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
                      SampleRateMismatchError, SampleRateMismatchWarning, StoreError,
                      UncalibratedWarning)
from ._model import (ArrayData, ArraySource, Channel, GeneratedData, ImpactTable, Origin, Record,
                     Rig, Run, Sensor, Skipped, ThresholdTable, Truth)
from ._quality import FATAL_FLAGS, FLAGS, Finding, QualityLimits
from ._read import detect_format, read
from ._readers.mapping import MappingSpec, load_mapping
from ._schema import load_schema, validate_tree
from ._units import SI_UNITS, scale_to_si
from ._write import write_record

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
    "StoreError",
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
]
