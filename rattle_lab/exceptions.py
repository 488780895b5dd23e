"""Errors and warnings raised by rattle_lab.

Every error a user can cause is a :class:`RattleLabError`.  Each subclass also
subclasses the builtin exception it means, so ``except ValueError`` keeps
working for callers who do not know this package.  The CLI turns any
``RattleLabError`` into one line on stderr and exit status 2.

Messages name the place: the file, the HDF5 path and the field, or the
argument and the value, e.g. ``"`omega` must be > 0, was -1.0"``.
"""

from __future__ import annotations


class RattleLabError(Exception):
    """Base class of every error rattle_lab raises on purpose."""


class ParameterError(RattleLabError, ValueError):
    """A function or CLI argument has an invalid value."""


class SimulationError(RattleLabError, RuntimeError):
    """The simulator could not honour its contract (e.g. an event budget ran out)."""


class ConvergenceError(RattleLabError, RuntimeError):
    """An iterative solver (Rayleigh-Ritz, orbit Newton, fit) did not converge."""


class DataError(RattleLabError, ValueError):
    """Input data are unusable: wrong, truncated, NaN, clipped or mismatched."""


class SchemaError(DataError):
    """A record does not conform to the rattle record schema."""


class FileFormatError(DataError):
    """A file is not of the format it claims to be, or cannot be read."""


class OutputError(RattleLabError, OSError):
    """An output could not be written (the previous result is left intact)."""


class RattleLabWarning(UserWarning):
    """Base class of data-quality and numerical warnings from rattle_lab."""


class DataQualityWarning(RattleLabWarning):
    """A data-quality finding (NaN run, clipping, dropout, ...)."""


class NumericalWarning(RattleLabWarning):
    """A numerical result holds with reduced accuracy; the message says why."""


class SummaryFormatError(DataError):
    """A fit summary (``rattle-lab fit``'s ``/results`` or ``--json``) is malformed."""


class SummaryVersionError(SummaryFormatError):
    """A fit summary has no ``schema_version``, or one this release does not read."""


__all__ = [
    "RattleLabError",
    "ParameterError",
    "SimulationError",
    "ConvergenceError",
    "DataError",
    "SchemaError",
    "FileFormatError",
    "OutputError",
    "SummaryFormatError",
    "SummaryVersionError",
    "RattleLabWarning",
    "DataQualityWarning",
    "NumericalWarning",
]

