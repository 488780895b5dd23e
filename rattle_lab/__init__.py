"""rattle_lab: rattle-noise engineering, from exact impact models to shaker-lab data."""

from ._version import __version__
from .exceptions import RattleLabError

__all__ = ["__version__", "RattleLabError"]
