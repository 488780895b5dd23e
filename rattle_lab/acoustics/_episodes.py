"""Rattle as a listener hears it, per run and per rattle episode (issue 26).

An *episode* is a stretch of impacts (:func:`~rattle_lab.acoustics.rattle_episodes`);
the *background* is the rest of the run.  Per episode:

* ``n_impacts`` and ``impacts_per_s`` -- the repetition rate ``(n - 1) / (t_last - t_first)``
  of its impacts (None with one impact);
* ISO 532-1 loudness ``loudness_n5_sone`` / ``loudness_max_sone`` of the episode's sound:
  the 95th percentile and the largest of the run's ``N(t)`` over the episode, as a sound
  level meter running through the run reads a stretch of it (the ear does not restart at
  the first impact; without the run's ``N(t)``, the public
  :func:`~rattle_lab.acoustics.loudness` of the episode from rest at its start);
* impulsiveness (:mod:`._impulsiveness`): the most prominent onset of ``L_AF`` (computed once
  over the whole run, so that an episode's first onset rises from its background) that
  starts inside the episode, ``impulse_prominence`` ``P`` and ``impulse_penalty_db`` ``K_I``;
* ECMA-418-2 loudness, tonality and roughness when asked (:mod:`._ecma418`).

Per run: ``impacts_per_s`` over the episodes together (``sum(n - 1) / sum(t_last - t_first)``),
the most prominent onset of the run, the episodes' duration-weighted ECMA-418-2 values and
``rattle_loudness_n5_sone``, their duration-weighted N5.  The background stretches
(at least :data:`MIN_BACKGROUND_S` long) get their own N5, of their central
:data:`MAX_BACKGROUND_S` at most, from rest (read off the run's ``N(t)``, a stretch's N5
would carry the decay of the impact before it).

The loudness *above background* compares the rattle with the background stretches of the
whole campaign (all runs of one fit, runs without impacts included),
:func:`campaign_background`: ``dN = N5_rattle - mean(N5_background)``.  A single stretch of
background varies about that mean by the spread ``s`` of the campaign's stretches, so the
difference is judged against ``u = s sqrt(1 + 1/n)`` (prediction of one new stretch from
``n``): the rattle is flagged ``background_too_close`` when ``dN < 2 u`` (not above the
background at about 97.7 %, one-sided, for normal spread), ``background_spread_unknown``
with one background stretch, ``no_background`` with none.

Loudness needs a calibrated microphone: with an uncalibrated one (calibration source
``"none"``), every loudness of this module is None and the run is flagged
``uncalibrated_no_loudness``; impacts per second and ``P``, ``K_I`` (level differences and
rates) do not depend on the sensitivity and are kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from rattle_lab.exceptions import RattleLabError
from ._ecma418 import FLAG_UNAVAILABLE, MIN_ECMA_S, ecma418, ecma418_available
from ._impulsiveness import ONSET_STEP_S, Onsets, find_onsets
from ._loudness import FieldType, loudness

#: Background stretches shorter than this get no loudness (ISO 532-1's temporal
#: integration and the N5 percentile need a few hundred 2 ms values), s.
MIN_BACKGROUND_S = 0.5
#: A background stretch's loudness is that of its central this many seconds at most (the
#: background is steady; this bounds the cost of a long quiet run), s.
MAX_BACKGROUND_S = 2.0
#: Episodes shorter than this get no ISO 532-1 loudness (the function's own minimum), s.
MIN_EPISODE_LOUDNESS_S = 0.1
#: Coverage factor of the background test (one-sided, about 97.7 % for normal spread).
K_BACKGROUND = 2.0

FLAG_UNCALIBRATED = "uncalibrated_no_loudness"
FLAG_TOO_CLOSE = "background_too_close"
FLAG_SPREAD_UNKNOWN = "background_spread_unknown"
FLAG_NO_BACKGROUND = "no_background"

_NAN = float("nan")
_ECMA_KEYS = ("loudness_ecma_sone", "tonality_tu", "roughness_asper")


def _n5(p: np.ndarray, fs_hz: float, field_type: FieldType) -> tuple[float, float]:
    try:
        ld = loudness(p, fs_hz, field_type=field_type)
    except RattleLabError:
        return _NAN, _NAN
    return ld.n5_sone, ld.nmax_sone


#: Step of the ISO 532-1 ``N(t)`` curve, s.
_CURVE_STEP_S = 0.002


def _curve_n5(curve: np.ndarray, t0_s: float, t1_s: float) -> tuple[float, float]:
    """N5 and Nmax of the stretch ``[t0_s, t1_s)`` (s from the curve's start) of ``N(t)``."""
    k0 = max(0, math.floor(t0_s / _CURVE_STEP_S))
    k1 = min(curve.size, math.ceil(t1_s / _CURVE_STEP_S))
    if k1 <= k0:
        return _NAN, _NAN
    part = curve[k0:k1]
    return float(np.percentile(part, 95.0)), float(np.max(part))


def _rate(t: np.ndarray) -> tuple[int, float]:
    """(intervals, span) of sorted impact times."""
    return (t.size - 1, float(t[-1] - t[0])) if t.size >= 2 else (0, 0.0)


def _weighted(values: Sequence[float], weights: Sequence[float]) -> float:
    v, w = np.asarray(values, dtype=float), np.asarray(weights, dtype=float)
    ok = np.isfinite(v) & (w > 0)
    return float(np.sum(v[ok] * w[ok]) / np.sum(w[ok])) if ok.any() else _NAN


def episode_psychoacoustics(pressure_pa: np.ndarray, fs_hz: float, impact_t_s: object,
                            episodes: Sequence[tuple[float, float]],
                            background: Sequence[tuple[int, int]], *,
                            start_time_s: float = 0.0, field_type: FieldType = "free",
                            calibrated: bool = True, with_loudness: bool = True,
                            ecma418_s: float = 0.0, fast_a_ms: np.ndarray | None = None,
                            loudness_curve: np.ndarray | None = None
                            ) -> tuple[dict[str, Any],
                                                             list[dict[str, Any]],
                                                             list[dict[str, Any]]]:
    """Run-level keys, per-episode entries and background stretches (see the module).

    Parameters
    ----------
    pressure_pa : ndarray
        Sound pressure of the run, Pa (full-scale units when not ``calibrated``).
    fs_hz : float
        Sampling rate, Hz.
    impact_t_s : array_like
        Detected impact times, s.
    episodes : sequence of (t_start_s, t_end_s)
        The rattle episodes, s on the record's time axis.
    background : sequence of (i0, i1)
        Sample ranges of the background stretches.
    start_time_s : float
        Time of the first sample, s.
    field_type : {"free", "diffuse"}
        Sound field of the loudness.
    calibrated : bool
        Whether the pressure is in Pa; without it no loudness is computed.
    with_loudness : bool
        Compute ISO 532-1 loudness per episode and per background stretch.
    ecma418_s : float
        Seconds of episode sound per run to rate with ECMA-418-2 (0: none).
    fast_a_ms : ndarray, optional
        The record's F-weighted A mean square per sample, when already computed (for
        its ``L_AF``).
    loudness_curve : ndarray, optional
        The record's ISO 532-1 ``N(t)`` (sone every 2 ms from its first sample, in the
        ``field_type`` asked for): the episodes' loudness is read off it.

    Returns
    -------
    run : dict
        The run-level keys.
    episode_entries : list of dict
        One per episode, in time order.
    background_entries : list of dict
        ``t_start_s``, ``t_end_s``, ``loudness_n5_sone`` of each background stretch.
    """
    p = np.asarray(pressure_pa, dtype=float)
    t_imp = np.sort(np.asarray(impact_t_s, dtype=float).ravel())
    t_imp = t_imp[np.isfinite(t_imp)]
    flags: list[str] = []
    loud_ok = with_loudness and calibrated
    if not calibrated:
        flags.append(FLAG_UNCALIBRATED)
    onsets = (find_onsets(p, fs_hz, start_time_s=start_time_s, step_s=ONSET_STEP_S,
                          fast_a_ms=fast_a_ms)
              if p.size >= 0.2 * fs_hz else Onsets(*(np.zeros(0) for _ in range(5))))
    want_ecma = ecma418_s > 0 and calibrated
    if want_ecma and not ecma418_available():
        flags.append(FLAG_UNAVAILABLE)
        want_ecma = False
    budget = float(ecma418_s)
    entries: list[dict[str, Any]] = []
    intervals, span = 0, 0.0
    for a, b in episodes:
        i0 = max(0, round((a - start_time_s) * fs_hz))
        i1 = min(p.size, round((b - start_time_s) * fs_hz))
        t_in = t_imp[(t_imp >= a) & (t_imp <= b)]
        k, s = _rate(t_in)
        intervals, span = intervals + k, span + s
        seg = p[i0:i1]
        if not (loud_ok and seg.size >= MIN_EPISODE_LOUDNESS_S * fs_hz):
            n5, nmax = _NAN, _NAN
        elif loudness_curve is not None:
            n5, nmax = _curve_n5(loudness_curve, i0 / fs_hz, i1 / fs_hz)
        else:
            n5, nmax = _n5(seg, fs_hz, field_type)
        e: dict[str, Any] = {"t_start_s": a, "t_end_s": b, "n_impacts": int(t_in.size),
                             "impacts_per_s": k / s if s > 0 else None,
                             "loudness_n5_sone": n5, "loudness_max_sone": nmax,
                             # an onset starts at the L_AF sample before the rise: up to
                             # one step (10 ms) before the episode's first impact
                             **onsets.within(a - ONSET_STEP_S - 1.0 / fs_hz, b).rating()}
        e.update(dict.fromkeys(_ECMA_KEYS, None))
        e["ecma418_s"] = 0.0
        if want_ecma and min(budget, seg.size / fs_hz) >= MIN_ECMA_S:
            use = seg[:int(min(budget, seg.size / fs_hz) * fs_hz)]
            try:
                e.update(ecma418(use, fs_hz, field_type=field_type).to_dict())
                e["ecma418_s"] = use.size / fs_hz
                budget -= use.size / fs_hz
            except (RattleLabError, ValueError, RuntimeError, FloatingPointError) as exc:
                # the package's own checks: keep the run, say why this episode has none
                flags.append(f"ecma418_failed: {type(exc).__name__}: {exc}"[:200])
        entries.append(e)
    backgrounds = []
    for i0, i1 in background:
        half = (i1 - i0 - round(MAX_BACKGROUND_S * fs_hz)) // 2
        c0, c1 = (i0 + half, i1 - half) if half > 0 else (i0, i1)
        n5 = (_n5(p[c0:c1], fs_hz, field_type)[0]
              if loud_ok and (i1 - i0) >= MIN_BACKGROUND_S * fs_hz else _NAN)
        backgrounds.append({"t_start_s": start_time_s + i0 / fs_hz,
                            "t_end_s": start_time_s + i1 / fs_hz, "loudness_n5_sone": n5})
    dur = [e["t_end_s"] - e["t_start_s"] for e in entries]
    rated = [e["ecma418_s"] for e in entries]
    run: dict[str, Any] = {
        "impacts_per_s": intervals / span if span > 0 else None,
        **onsets.rating(),
        "rattle_loudness_n5_sone": _weighted([e["loudness_n5_sone"] for e in entries], dur),
        **{key: (_weighted([_nan(e[key]) for e in entries], rated) if sum(rated) else None)
           for key in _ECMA_KEYS},
        "ecma418_s": float(sum(rated)),
        "psychoacoustic_flags": flags,
    }
    return run, entries, backgrounds


def _nan(x: Any) -> float:
    return _NAN if x is None else float(x)


def _finite(x: Any) -> float | None:
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


def campaign_background(summaries: Sequence[dict[str, Any] | None]) -> list[dict[str, Any] | None]:
    """Each run's and episode's loudness above the campaign's background (see the module).

    ``summaries`` are :meth:`RunAcoustics.summary` dicts (None for a run without a
    microphone) of one campaign; returned are copies with ``acoustics`` gaining
    ``background_loudness_n5_sone`` (mean over the campaign's stretches),
    ``background_loudness_spread_sone`` (``u``), ``loudness_above_background_sone``, and
    the flags; each episode gains ``loudness_above_background_sone`` and its flag.
    """
    values = [v for s in summaries if s is not None
              for b in s["acoustics"].get("background_stretches", [])
              if (v := _finite(b.get("loudness_n5_sone"))) is not None]
    n = len(values)
    mean = float(np.mean(values)) if n else None
    u = float(np.std(values, ddof=1) * math.sqrt(1.0 + 1.0 / n)) if n >= 2 else None

    def judge(rattle: Any) -> tuple[float | None, list[str]]:
        r = _finite(rattle)
        if r is None:
            return None, []
        if mean is None:
            return None, [FLAG_NO_BACKGROUND]
        d = r - mean
        if u is None:
            return d, [FLAG_SPREAD_UNKNOWN]
        return d, [FLAG_TOO_CLOSE] if d < K_BACKGROUND * u else []

    out: list[dict[str, Any] | None] = []
    for s in summaries:
        if s is None:
            out.append(None)
            continue
        ac = dict(s["acoustics"])
        d, flags = judge(ac.get("rattle_loudness_n5_sone"))
        ac.update(background_loudness_n5_sone=mean, background_loudness_spread_sone=u,
                  loudness_above_background_sone=d,
                  psychoacoustic_flags=list(ac.get("psychoacoustic_flags", [])) + flags)
        eps = []
        for e in ac.get("episodes", []):
            de, fe = judge(e.get("loudness_n5_sone"))
            eps.append({**e, "loudness_above_background_sone": de, "flags": fe})
        ac["episodes"] = eps
        out.append({**s, "acoustics": ac})
    return out


__all__ = ["FLAG_NO_BACKGROUND", "FLAG_SPREAD_UNKNOWN", "FLAG_TOO_CLOSE", "FLAG_UNCALIBRATED",
           "K_BACKGROUND", "MAX_BACKGROUND_S", "MIN_BACKGROUND_S", "campaign_background",
           "episode_psychoacoustics"]
