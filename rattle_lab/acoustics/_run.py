"""The acoustics of one run with a microphone: levels of the run, of its rattle episodes and of
its background, loudness and sharpness, and the calibration used.

This is what ``rattle-lab fit --json`` reports per run as ``acoustics`` and
``calibration`` (:meth:`RunAcoustics.summary`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from rattle_lab.exceptions import RattleLabError
from ._episodes import episode_psychoacoustics
from ._levels import (P_REF_PA, SoundLevels, levels_and_bands, levels_bands_fast,
                      rattle_episodes)
from ._loudness import FieldType, Loudness, joined_loudness, loudness

#: Loudness needs ISO 532-1's 0.1 s at least; shorter stretches get none.
_MIN_LOUDNESS_S = 0.1


@dataclass(frozen=True)
class RunAcoustics:
    """Acoustic results of one run.

    Attributes
    ----------
    levels : SoundLevels
        LAeq, LAFmax, LCpeak, third-octave levels of the whole run.
    loudness : Loudness or None
        N5, Nmax (sone) and sharpness (acum) of the whole run (None when too short).
    episodes : tuple of dict
        Rattle episodes: ``t_start_s``, ``t_end_s`` (s, on the record's time axis) and
        their levels (the keys of :meth:`SoundLevels.to_dict`).  Plain dicts, so that the
        pipeline's detection cache stores them as JSON.
    rattle_bands_db, background_bands_db : dict of str to float
        Third-octave levels of the rattle episodes together and of the rest of the run
        (duration-weighted mean square of the pieces), dB; empty when there is none.
    calibration : dict
        ``sensitivity``, ``sensitivity_units``, ``source`` ("calibrator", "declared",
        "none"), ``drift_db`` (None without a pre- and a post-calibration), ``flags`` of the
        microphone channel.
    psychoacoustics : dict
        Issue 26's run-level keys (impacts per second, impulse prominence and adjustment,
        ECMA-418-2 values, the rattle's loudness, flags) and ``background_stretches``
        (:func:`~rattle_lab.acoustics._episodes.episode_psychoacoustics`); each episode's
        dict holds its own.
    """

    levels: SoundLevels
    loudness: Loudness | None
    episodes: tuple[dict[str, Any], ...]
    rattle_bands_db: dict[str, float]
    background_bands_db: dict[str, float]
    calibration: dict[str, Any]
    psychoacoustics: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """``{"acoustics": {...}, "calibration": {...}}`` as ``fit --json`` prints them."""
        lv, ld = self.levels, self.loudness
        nan = float("nan")
        acoustics = {
            "laeq_db": lv.laeq_db, "lafmax_db": lv.lafmax_db, "lcpeak_db": lv.lcpeak_db,
            "third_octave_db": dict(lv.third_octave_db),
            "loudness_n5_sone": ld.n5_sone if ld else nan,
            "loudness_max_sone": ld.nmax_sone if ld else nan,
            "sharpness_acum": ld.sharpness_acum if ld else nan,
            "sound_field": ld.field_type if ld else None,
            "episodes": [dict(e) for e in self.episodes],
            "rattle_third_octave_db": dict(self.rattle_bands_db),
            "background_third_octave_db": dict(self.background_bands_db),
            **self.psychoacoustics,  # [issue 26]
        }
        return {"acoustics": acoustics, "calibration": dict(self.calibration)}


def _finite_or_none(x: Any) -> float | None:
    """``float(x)``, or None for an absent or non-finite value (JSON-ready, and equal to itself)."""
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def channel_calibration(channel: Any) -> dict[str, Any]:
    """The calibration facts of a stored channel (``ingest_calibration_*`` provenance).

    A channel ingested before calibration was recorded has no provenance: its
    declared sensitivity was used (``source = "declared"``; ``"none"`` when uncalibrated).
    """
    ex = channel.extra
    default = "none" if channel.uncalibrated else "declared"
    flags = str(ex.get("ingest_calibration_flags", "") or "")
    return {"sensitivity": channel.sensitivity, "sensitivity_units": channel.sensitivity_units,
            "units": channel.units,
            "source": str(ex.get("ingest_calibration_source", default)),
            "drift_db": _finite_or_none(ex.get("ingest_calibration_drift_db")),
            "flags": [f for f in flags.split(",") if f]}


def _pooled_bands(pieces: list[np.ndarray], fs_hz: float,
                  known: list[dict[str, float]] | None = None) -> dict[str, float]:
    """Third-octave levels of ``pieces`` together: each band's mean square weighted by the
    pieces' lengths (``known``: the pieces' band mean squares, already computed)."""
    from ._filters import band_mean_squares

    total: dict[str, float] = {}
    dur: dict[str, float] = {}
    for i, x in enumerate(pieces):
        for k, ms in (known[i] if known is not None else band_mean_squares(x, fs_hz)).items():
            total[k] = total.get(k, 0.0) + ms * x.size
            dur[k] = dur.get(k, 0.0) + x.size
    return {k: float(10 * np.log10(total[k] / dur[k] / P_REF_PA**2)) if total[k] > 0
            else float("-inf") for k in total}


def run_acoustics(pressure_pa: np.ndarray, fs_hz: float, impact_t_s: object, *,
                  start_time_s: float = 0.0, channel: Any = None,
                  field_type: FieldType = "free", with_loudness: bool = True,
                  episode_gap_s: float = 0.5, ecma418_s: float = 0.0,
                  keep_loudness_curve: bool = False) -> RunAcoustics:
    """Levels, loudness and band spectra of a run's sound pressure (Pa) and its episodes.

    Parameters
    ----------
    pressure_pa : ndarray
        Calibrated sound pressure of the run, Pa.
    fs_hz : float
        Its sampling rate, Hz.
    impact_t_s : array_like
        Detected impact times, s (episodes: :func:`~rattle_lab.acoustics.rattle_episodes`).
    start_time_s : float
        Time of the first sample, s.
    channel : Channel, optional
        The microphone channel, for its calibration provenance.
    field_type : {"free", "diffuse"}
        Sound field of the loudness.
    with_loudness : bool
        Compute ISO 532-1 loudness (compiled; see docs/explanation/throughput.md for its rate).
    episode_gap_s : float
        Impacts further apart than this start a new episode, s.
    ecma418_s : float
        Seconds of rattle episodes to rate with ECMA-418-2 (0, the default: none; it
        costs about 7 s of CPU per second of sound, :mod:`._ecma418`).
    keep_loudness_curve : bool
        Keep the run's ``N(t)`` on its loudness, for :func:`joined_acoustics`.
    """
    p = np.asarray(pressure_pa, dtype=float)
    lv, _, fast_a = levels_bands_fast(p, fs_hz)
    ld = None
    if with_loudness and p.size >= _MIN_LOUDNESS_S * fs_hz:
        try:
            ld = loudness(p, fs_hz, field_type=field_type, keep_curve=True)
        except RattleLabError:
            ld = None
    eps = rattle_episodes(impact_t_s, start_time_s=start_time_s, duration_s=p.size / fs_hz,
                          gap_s=episode_gap_s)
    episodes = []
    kept = []
    inside = np.zeros(p.size, dtype=bool)
    rattle_pieces = []
    rattle_ms: list[dict[str, float]] = []   # their band mean squares (pooled below)
    for a, b in eps:
        i0 = max(0, round((a - start_time_s) * fs_hz))
        i1 = min(p.size, round((b - start_time_s) * fs_hz))
        if i1 - i0 < 2:
            continue
        inside[i0:i1] = True
        rattle_pieces.append(p[i0:i1])
        kept.append((a, b))
        lv_episode, ms = levels_and_bands(p[i0:i1], fs_hz)
        rattle_ms.append(ms)
        episodes.append({"t_start_s": a, "t_end_s": b, **lv_episode.to_dict()})
    edges = np.flatnonzero(np.diff(np.concatenate([[1], inside.astype(int), [1]])))
    spans = [(int(edges[i]), int(edges[i + 1])) for i in range(0, edges.size - 1, 2)
             if edges[i + 1] - edges[i] >= 2]
    background = [p[i0:i1] for i0, i1 in spans]
    calib = channel_calibration(channel) if channel is not None else {
        "sensitivity": None, "sensitivity_units": None, "units": "Pa", "source": "declared",
        "drift_db": None, "flags": []}
    # [issue 26] impacts per second, impulsiveness, loudness per episode, ECMA-418-2
    run, per_episode, per_background = episode_psychoacoustics(
        p, fs_hz, impact_t_s, kept, spans, start_time_s=start_time_s, field_type=field_type,
        calibrated=calib.get("source") != "none", with_loudness=with_loudness,
        ecma418_s=ecma418_s, fast_a_ms=fast_a,
        loudness_curve=ld.curve[0] if ld is not None and ld.curve is not None else None)
    if ld is not None and not keep_loudness_curve:
        ld = replace(ld, curve=None)
    episodes = [{**e, **x} for e, x in zip(episodes, per_episode)]
    run["background_stretches"] = per_background
    return RunAcoustics(lv, ld, tuple(episodes), _pooled_bands(rattle_pieces, fs_hz, rattle_ms),
                        _pooled_bands(background, fs_hz), calib, run)


def _energy_mean(levels_db: list[float], weights: list[float]) -> float:
    lv, w = np.asarray(levels_db, float), np.asarray(weights, float)
    ok = ~np.isnan(lv) & (w > 0)
    if not ok.any():
        return float("nan")
    ms = np.sum(w[ok] * 10.0 ** (lv[ok] / 10.0)) / np.sum(w[ok])
    return float(10 * np.log10(ms)) if ms > 0 else float("-inf")


def _joined_bands(bands: list[dict[str, float]], weights: list[float]) -> dict[str, float]:
    keys = list(dict.fromkeys(k for b in bands for k in b))
    return {k: _energy_mean([b.get(k, float("nan")) for b in bands], weights) for k in keys}


def _max(values: list[Any]) -> float:
    v = [float(x) for x in values if x is not None and not math.isnan(float(x))]
    return max(v) if v else float("nan")


def joined_acoustics(parts: list[RunAcoustics]) -> RunAcoustics:
    """The acoustics of consecutive stretches of one run (its segments) joined.

    Levels: LAeq and third-octave levels the duration-weighted energy mean, LAFmax and
    LCpeak the largest.  Loudness: N5 and Nmax of the stretches' ``N(t)`` end to end
    (:func:`~rattle_lab.acoustics._loudness.joined_loudness`; each stretch's loudness
    starts from rest).  Episodes and background stretches: each stretch's, in order (an
    episode that crosses from one stretch into the next is two).  Rattle and background
    bands: energy means weighted by the episodes' and the rest's durations.  Run-level
    psychoacoustics: impacts per second over the episodes together, the most prominent
    onset of any stretch, the episodes' duration-weighted N5 and ECMA-418-2 values, the
    flags once each.
    """
    dur = [a.levels.duration_s for a in parts]
    lv = SoundLevels(_energy_mean([a.levels.laeq_db for a in parts], dur),
                     _max([a.levels.lafmax_db for a in parts]),
                     _max([a.levels.lcpeak_db for a in parts]),
                     _joined_bands([dict(a.levels.third_octave_db) for a in parts], dur),
                     float(sum(dur)))
    louds = [a.loudness for a in parts]
    ld = (joined_loudness([x for x in louds if x is not None])
          if any(x is not None for x in louds) and all(x is None or x.curve is not None
                                                        for x in louds) else None)
    episodes = tuple(e for a in parts for e in a.episodes)
    rattle_s = [sum(e["t_end_s"] - e["t_start_s"] for e in a.episodes) for a in parts]
    psy = _joined_psychoacoustics([a.psychoacoustics for a in parts], episodes)
    return RunAcoustics(lv, ld, episodes,
                        _joined_bands([a.rattle_bands_db for a in parts], rattle_s),
                        _joined_bands([a.background_bands_db for a in parts],
                                      [d - r for d, r in zip(dur, rattle_s)]),
                        parts[0].calibration, psy)


def _joined_psychoacoustics(parts: list[dict[str, Any]],
                            episodes: tuple[dict[str, Any], ...]) -> dict[str, Any]:
    if not parts or not parts[0]:
        return {}
    out = dict(parts[0])
    intervals, span = 0.0, 0.0
    for e in episodes:
        rate, n = e.get("impacts_per_s"), e.get("n_impacts", 0)
        if rate:
            intervals, span = intervals + (n - 1), span + (n - 1) / rate
    out["impacts_per_s"] = intervals / span if span > 0 else None
    prom = [float("nan") if p.get("impulse_prominence") is None
            else float(p["impulse_prominence"]) for p in parts]
    ok = [i for i, x in enumerate(prom) if math.isfinite(x)]
    best = parts[max(ok, key=lambda i: prom[i])] if ok else parts[0]
    for key in ("impulse_prominence", "impulse_penalty_db", "impulse_level_difference_db",
                "impulse_onset_rate_db_s"):
        if key in best:
            out[key] = best[key]
    if "impulse_onsets" in out:
        out["impulse_onsets"] = int(sum(p.get("impulse_onsets", 0) for p in parts))
    dur = [e["t_end_s"] - e["t_start_s"] for e in episodes]
    if "rattle_loudness_n5_sone" in out:
        out["rattle_loudness_n5_sone"] = _weighted_or_nan(
            [e.get("loudness_n5_sone") for e in episodes], dur)
    rated = [float(e.get("ecma418_s") or 0.0) for e in episodes]
    for key in ("loudness_ecma_sone", "tonality_tu", "roughness_asper"):
        if key in out:
            out[key] = _weighted_or_nan([e.get(key) for e in episodes], rated) \
                if sum(rated) else None
    if "ecma418_s" in out:
        out["ecma418_s"] = float(sum(rated))
    out["psychoacoustic_flags"] = list(dict.fromkeys(
        f for p in parts for f in p.get("psychoacoustic_flags", [])))
    out["background_stretches"] = [b for p in parts for b in p.get("background_stretches", [])]
    return out


def _weighted_or_nan(values: list[Any], weights: list[float]) -> float:
    v = np.array([float("nan") if x is None else float(x) for x in values], float)
    w = np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    return float(np.sum(v[ok] * w[ok]) / np.sum(w[ok])) if ok.any() else float("nan")


__all__ = ["RunAcoustics", "channel_calibration", "joined_acoustics", "run_acoustics"]
