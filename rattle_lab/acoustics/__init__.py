"""NVH acoustics: calibrated levels (IEC 61672-1), third-octave bands (IEC 61260-1), loudness
(ISO 532-1: time-varying, and stationary from third-octave levels) and sharpness (DIN 45692),
calibration from calibrator records; impulsiveness (ISO/PAS 1996-3), ECMA-418-2 loudness,
tonality and roughness (optional package) and the rattle per episode against the campaign's
background (issue 26).

It depends only on NumPy, SciPy and numba (compiled loudness), not on the rest of the
package apart from its exceptions, so that every stage after ``records`` may use it.
"""

from typing import TYPE_CHECKING

from rattle_lab._lazy import lazy_names

if TYPE_CHECKING:
    from ._ecma418 import Ecma418, ecma418, ecma418_available
    from ._episodes import campaign_background, episode_psychoacoustics
    from ._filters import (NOMINAL_THIRD_OCTAVE_HZ, apply_weighting, band_edges_hz, band_gain,
                           band_mean_squares, weighting_db, weighting_response)
    from ._impulsiveness import Onsets, adjustment_db, find_onsets, laf_db, prominence
    from ._iso532 import stationary_loudness
    from ._levels import (P_REF_PA, SoundLevels, energy_mean_db, fast_time_weighted, rattle_episodes,
                          sound_levels)
    from ._loudness import Loudness, loudness
    from ._run import RunAcoustics, channel_calibration, joined_acoustics, run_acoustics

#: public name -> submodule that defines it; loaded on first use, so that a stage that needs
#: one corner of the package (ingest reads microphone calibrations) does not import SciPy's
#: signal package (about a second) with the filters
_LAZY: dict[str, str] = {
    "Ecma418": "_ecma418",
    "ecma418": "_ecma418",
    "ecma418_available": "_ecma418",
    "campaign_background": "_episodes",
    "episode_psychoacoustics": "_episodes",
    "NOMINAL_THIRD_OCTAVE_HZ": "_filters",
    "apply_weighting": "_filters",
    "band_edges_hz": "_filters",
    "band_gain": "_filters",
    "band_mean_squares": "_filters",
    "weighting_db": "_filters",
    "weighting_response": "_filters",
    "Onsets": "_impulsiveness",
    "adjustment_db": "_impulsiveness",
    "find_onsets": "_impulsiveness",
    "laf_db": "_impulsiveness",
    "prominence": "_impulsiveness",
    "P_REF_PA": "_levels",
    "SoundLevels": "_levels",
    "energy_mean_db": "_levels",
    "fast_time_weighted": "_levels",
    "rattle_episodes": "_levels",
    "sound_levels": "_levels",
    "stationary_loudness": "_iso532",
    "Loudness": "_loudness",
    "loudness": "_loudness",
    "RunAcoustics": "_run",
    "channel_calibration": "_run",
    "run_acoustics": "_run",
    "joined_acoustics": "_run",
}

__all__ = [
    "Loudness", "NOMINAL_THIRD_OCTAVE_HZ", "P_REF_PA", "RunAcoustics", "SoundLevels",
    "apply_weighting", "band_edges_hz", "band_gain", "band_mean_squares", "channel_calibration",
    "fast_time_weighted", "loudness", "rattle_episodes", "run_acoustics", "sound_levels",
    "weighting_db", "weighting_response", "energy_mean_db",
    "Ecma418", "Onsets", "adjustment_db", "campaign_background", "ecma418", "ecma418_available",
    "episode_psychoacoustics", "find_onsets", "laf_db", "prominence", "stationary_loudness",
    "joined_acoustics",
]


__getattr__, __dir__ = lazy_names(__name__, globals(), _LAZY)
