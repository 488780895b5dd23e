"""Errors and warnings of the record layer.

They subclass the classes of :mod:`rattle_lab.exceptions` and are kept here,
in one place, so that they can be moved into that module as a block.

Data-quality findings come in pairs: by default a finding that makes the data
unusable for analysis raises its ``...Error`` (a :class:`DataQualityError`,
hence a :class:`~rattle_lab.exceptions.DataError`); with ``allow_flagged=True``
(CLI ``--allow-flagged``) the data are ingested unchanged, the finding is
written to the catalogue as a flag and reported as the matching
``...Warning``.  Findings that the input itself declares (uncalibrated
amplitude, assumed units) are never fatal: they are flagged and warned.
"""

from __future__ import annotations

from rattle_lab.exceptions import DataError, DataQualityWarning, SchemaError


class MappingError(SchemaError):
    """A mapping file (TOML) is invalid or does not fit the input it is applied to."""


class DuplicateRunError(SchemaError):
    """Two runs share one ``(campaign_id, run_id)`` within a file, a call or a store."""


class DataQualityError(DataError):
    """A data-quality finding that is fatal unless flagged data are allowed.

    Attributes
    ----------
    finding : rattle_lab.records.Finding
        The finding: flag, file, HDF5 path, field and first sample index.
    """

    def __init__(self, message: str, finding: object | None = None) -> None:
        super().__init__(message)
        self.finding = finding


class NaNGapError(DataQualityError):
    """A channel or timestamp dataset holds NaN samples."""


class InfValueError(DataQualityError):
    """A channel holds infinite samples."""


class ClippingError(DataQualityError):
    """A channel has flat runs at its range limit (the ADC clipped)."""


class DropoutError(DataQualityError):
    """A channel has a run of identical samples (stuck or zero-filled), or a timestamp gap."""


class SampleRateMismatchError(DataQualityError):
    """Channels of one run have different sample rates."""


class NonMonotonicTimestampsError(DataQualityError):
    """Timestamps are not strictly increasing."""


class EmptyChannelError(DataQualityError):
    """A channel has zero samples."""


class NaNGapWarning(DataQualityWarning):
    """Flagged data: a channel holds NaN samples."""


class InfValueWarning(DataQualityWarning):
    """Flagged data: a channel holds infinite samples."""


class ClippingWarning(DataQualityWarning):
    """Flagged data: a channel clipped at its range limit."""


class DropoutWarning(DataQualityWarning):
    """Flagged data: a run of identical samples or a timestamp gap."""


class SampleRateMismatchWarning(DataQualityWarning):
    """Flagged data: channels of one run have different sample rates."""


class NonMonotonicTimestampsWarning(DataQualityWarning):
    """Flagged data: timestamps are not strictly increasing."""


class EmptyChannelWarning(DataQualityWarning):
    """Flagged data: a channel has zero samples."""


class UncalibratedWarning(DataQualityWarning):
    """A channel's amplitude is not traceable to a calibration (units '1', or units assumed)."""


__all__ = [
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
]
