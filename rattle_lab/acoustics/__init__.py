"""NVH acoustics: calibrated levels (IEC 61672-1), third-octave bands (IEC 61260-1), loudness
(ISO 532-1) and sharpness (DIN 45692), calibration from calibrator records.

It depends only on NumPy, SciPy and numba (compiled loudness), not on the rest of the
package apart from its exceptions, so that every stage after ``records`` may use it.
"""

from ._filters import (NOMINAL_THIRD_OCTAVE_HZ, apply_weighting, band_edges_hz, band_gain,
                       band_mean_squares, weighting_db, weighting_response)
from ._levels import (P_REF_PA, SoundLevels, energy_mean_db, fast_time_weighted, rattle_episodes,
                      sound_levels)
from ._loudness import Loudness, loudness
from ._run import RunAcoustics, channel_calibration, run_acoustics

__all__ = [
    "Loudness", "NOMINAL_THIRD_OCTAVE_HZ", "P_REF_PA", "RunAcoustics", "SoundLevels",
    "apply_weighting", "band_edges_hz", "band_gain", "band_mean_squares", "channel_calibration",
    "fast_time_weighted", "loudness", "rattle_episodes", "run_acoustics", "sound_levels",
    "weighting_db", "weighting_response", "energy_mean_db",
]
