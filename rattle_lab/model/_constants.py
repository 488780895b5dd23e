"""Constants shared by the model packages."""

from __future__ import annotations

import math

__all__ = ["TWO_PI"]

TWO_PI = 2.0 * math.pi
