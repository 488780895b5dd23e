"""The infinite plate's point impedance and a model's band-averaged point mobility, shared by
the multi-mode model's tests against independent references (issue 24)."""

from __future__ import annotations

import math

import numpy as np


def z_inf(plate: object) -> float:
    """``Z = 8 sqrt(D m'')`` of the plate (Cremer, Heckl & Petersson), from its material and
    thickness."""
    D = plate.E_pa * plate.h_p_m**3 / (12.0 * (1.0 - plate.nu**2))   # type: ignore[attr-defined]
    return 8.0 * math.sqrt(D * plate.rho_kg_m3 * plate.h_p_m)         # type: ignore[attr-defined]


def band_means(system: object, centres_hz: tuple[float, ...]) -> np.ndarray:
    """Mean of ``Re(Y)`` of ``system.point_mobility`` on 20001 frequencies across each octave."""
    out = []
    for fc in centres_hz:
        f = np.linspace(fc / math.sqrt(2.0), fc * math.sqrt(2.0), 20001)
        out.append(float(np.mean(system.point_mobility(2.0 * math.pi * f).real)))  # type: ignore[attr-defined]
    return np.array(out)
