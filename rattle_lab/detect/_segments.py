"""Long runs analysed in segments: memory bounded whatever the run's length (issue 29).

A run whose detection channel holds more than 1.5 ``segment_samples``
(:class:`~rattle_lab.detect.DetectParams`) is cut into ``k = round(n / segment_samples)``
segments of equal duration.  Each segment is a view of the run (:func:`segment_view`): its
channels read only the segment's *core* and ``segment_margin_s`` of the record either side,
so that the detector has the same context at a segment's edges as in the middle of the run.
A segment keeps the impacts it finds within ``min_separation_s`` of its core; where two
adjacent segments found the same impact (within ``min_separation_s`` of each other near
their common edge) the earlier segment's is kept (:func:`merge_logs`): every impact is
counted once, including one that straddles an edge.

What is estimated per run from its impacts (the vibrometer's offset and delay, the ringing
share) is estimated per segment and applied there, as for a run of the segment's length; the
merged :class:`~rattle_lab.detect.ImpactLog` reports their combination (:func:`merge_logs`).
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from rattle_lab.records import Run

#: Protocols never cut: a transient's one shock is found in the whole run.  (A ramp is cut
#: like any run; its threshold reads the base accelerometer whole, one channel.)
UNSEGMENTED_PROTOCOLS = ("transient",)


@dataclass(frozen=True)
class Span:
    """One segment of a run, on the record's time axis, s.

    ``core_lo_s``/``core_hi_s``: what the segment answers for; ``read_lo_s``/``read_hi_s``:
    what it reads (the core and the margins, within the record).  ``index`` and ``count``:
    its place among the run's segments.
    """

    index: int
    count: int
    core_lo_s: float
    core_hi_s: float
    read_lo_s: float
    read_hi_s: float


class _Slice:
    """Samples ``start:stop`` of another source (a lazy view: nothing is read here)."""

    def __init__(self, source: Any, start: int, stop: int) -> None:
        self.source, self.start = source, int(start)
        self.n_samples = int(stop - start)
        self.dtype = source.dtype

    def read(self, start: int, stop: int) -> np.ndarray:
        return self.source.read(self.start + start, self.start + stop)


def _extent(ch: Any) -> tuple[float, float, float]:
    """``(start_s, fs_hz, duration_s)`` of a regularly sampled channel."""
    start = float(ch.start_time_s) if ch.start_time_s is not None else 0.0
    fs = float(ch.sample_rate_hz)
    return start, fs, ch.n_samples / fs


def segment_spans(run: Run, detect: Any, *channels: Any) -> list[Span] | None:
    """The segments of ``run`` (None where it is analysed whole).

    Parameters
    ----------
    run : Run
    detect : DetectParams
        ``segment_samples`` and ``segment_margin_s``.
    *channels : Channel
        The channels the impacts are detected on (one, or the velocity and the
        acceleration): the stretch they share, in samples of the fastest, decides.

    A run is analysed whole where it is short enough, where it is a transient
    (:data:`UNSEGMENTED_PROTOCOLS`), or where a channel has no regular sampling.  The
    segments divide the stretch the detection channels share; the first and the last reach
    out to the run's ends.
    """
    used = [c for c in channels if c is not None]
    if run.protocol in UNSEGMENTED_PROTOCOLS or not used:
        return None
    if any(ch.sample_rate_hz is None or ch.timestamps is not None for ch in run.channels):
        return None
    extents = [_extent(ch) for ch in used]
    start = max(e[0] for e in extents)
    duration = min(e[0] + e[2] for e in extents) - start
    n = duration * max(e[1] for e in extents)
    if duration <= 0 or n <= 1.5 * detect.segment_samples:
        return None
    count = int(round(n / detect.segment_samples))
    lo_run = min(_extent(ch)[0] for ch in run.channels)
    hi_run = max(sum(_extent(ch)[::2]) for ch in run.channels)
    edges = start + duration * np.arange(count + 1) / count
    edges[0], edges[-1] = min(edges[0], lo_run), max(edges[-1], hi_run)
    m = float(detect.segment_margin_s)
    return [Span(i, count, float(edges[i]), float(edges[i + 1]),
                 max(lo_run, float(edges[i]) - m), min(hi_run, float(edges[i + 1]) + m))
            for i in range(count)]


def segment_view(run: Run, span: Span) -> Run:
    """``run`` with every channel cut to ``span``'s read range (a lazy view; empty for a
    channel that does not reach it)."""
    channels = []
    for ch in run.channels:
        start, fs, _ = _extent(ch)
        i0 = min(ch.n_samples, max(0, math.floor((span.read_lo_s - start) * fs)))
        i1 = min(ch.n_samples, max(i0, math.ceil((span.read_hi_s - start) * fs)))
        channels.append(replace(ch, data=_Slice(ch.data, i0, i1), start_time_s=start + i0 / fs))
    return replace(run, channels=tuple(channels))


def core_mask(t_s: np.ndarray, span: Span, slack_s: float = 0.0) -> np.ndarray:
    """Which times lie in ``span``'s core, widened by ``slack_s`` where it meets another
    segment (the run's own ends are not widened: nothing lies beyond them)."""
    lo = span.core_lo_s - (slack_s if span.index > 0 else math.inf)
    hi = span.core_hi_s + (slack_s if span.index < span.count - 1 else math.inf)
    return (t_s >= lo) & (t_s < hi)


def _owned(parts: list[tuple[Span, Any]], sep_s: float) -> list[np.ndarray]:
    """Per part, the impacts it keeps: those within ``sep_s`` of its core, less those an
    earlier segment found already (within ``sep_s`` of one of its kept impacts)."""
    keep: list[np.ndarray] = []
    previous = np.zeros(0)
    for span, log in parts:
        t = np.asarray(log.t_s, dtype=float)
        k = core_mask(t, span, sep_s)
        if previous.size and t.size:
            near = previous[previous >= span.core_lo_s - 2 * sep_s]
            if near.size:
                j = np.clip(np.searchsorted(near, t), 1, near.size) - 1
                d = np.minimum(np.abs(t - near[j]),
                               np.abs(t - near[np.minimum(j + 1, near.size - 1)]))
                k &= ~(d <= sep_s)
        keep.append(k)
        previous = t[k]
    return keep


def _weighted(values: list[float], weights: list[int]) -> float:
    v, w = np.asarray(values, float), np.asarray(weights, float)
    ok = np.isfinite(v) & (w > 0)
    return float(np.sum(v[ok] * w[ok]) / np.sum(w[ok])) if ok.any() else float("nan")


def _median(values: list[float]) -> float:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(np.median(v)) if v.size else float("nan")


def _delay(logs: list[Any]) -> tuple[float, float, int]:
    """The segments' vibrometer delays combined: inverse-variance mean; its standard error
    widened by the segments' scatter where that exceeds their stated errors (Birge ratio)."""
    d = np.array([x.velocity_delay_s for x in logs], float)
    se = np.array([x.velocity_delay_stderr_s for x in logs], float)
    n = sum(int(x.velocity_delay_n) for x in logs)
    ok = np.isfinite(d) & np.isfinite(se) & (se > 0)
    if not ok.any():
        finite = d[np.isfinite(d)]
        return (float(finite[0]) if finite.size else float("nan"),
                float(se[np.isfinite(d)][0]) if finite.size else float("nan"), n)
    w = 1.0 / se[ok] ** 2
    mean = float(np.sum(w * d[ok]) / np.sum(w))
    err = float(1.0 / np.sqrt(np.sum(w)))
    if ok.sum() > 1:
        birge = float(np.sum(w * (d[ok] - mean) ** 2) / (ok.sum() - 1))
        err *= math.sqrt(max(1.0, birge))
    return mean, err, n


_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?")
_COUNT = re.compile(r"(\d+) of (\d+) impacts")


def merged_notes(notes: list[str]) -> str:
    """The segments' notes, each kind once: notes that differ in their numbers only are one,
    their ``"N of M impacts"`` summed over the segments (else the first segment's numbers,
    with how many segments said it)."""
    groups: dict[str, list[str]] = {}
    for note in notes:
        if note:
            groups.setdefault(_NUMBER.sub("#", note), []).append(note)
    out = []
    for same in groups.values():
        first = same[0]
        counts = [_COUNT.search(x) for x in same]
        if len(set(same)) == 1:
            out.append(first)
        elif all(counts):
            a = sum(int(m.group(1)) for m in counts if m)
            b = sum(int(m.group(2)) for m in counts if m)
            out.append(_COUNT.sub(f"{a} of {b} impacts", first, count=1))
        else:
            out.append(f"{first} (the first of {len(same)} segments that said so)")
    return "; ".join(out)


def merge_logs(parts: list[tuple[Span, Any]], sep_s: float) -> tuple[Any, list[np.ndarray]]:
    """The run's :class:`~rattle_lab.detect.ImpactLog` from its segments' logs.

    Parameters
    ----------
    parts : list of (Span, ImpactLog)
        Each segment's log, in time order.
    sep_s : float
        The detector's ``min_separation_s``: two impacts of adjacent segments closer than
        this are one.

    Returns
    -------
    log : ImpactLog
        The impacts every segment kept, sorted by time.  Per-run estimates: the offset, the
        delay actually applied, the measurand's difference -- impact-weighted means; the
        ringing share and ratio, ``d e / d delay`` -- medians over the segments; the
        vibrometer's delay -- the inverse-variance mean of the segments' with the scatter's
        Birge ratio; the guards and window effects -- the largest; the notes -- each kind
        once (:func:`merged_notes`);
        the ringing problem -- the first segment's that has one.
    kept : list of ndarray of bool
        Per segment, which of its impacts the log holds.
    """
    keep = _owned(parts, sep_s)
    logs = [log for _, log in parts]
    first = logs[0]
    arrays = {f.name: np.concatenate([np.asarray(getattr(log, f.name))[k]
                                      for log, k in zip(logs, keep)])
              for f in dataclasses.fields(first)
              if isinstance(getattr(first, f.name), np.ndarray)}
    # in time order: an impact only the later segment found, just before the edge, can
    # precede one the earlier segment kept just after it
    order = np.argsort(arrays["t_s"], kind="stable")
    arrays = {k: v[order] for k, v in arrays.items()}
    n = [int(k.sum()) for k in keep]
    delay, delay_se, delay_n = _delay(logs)
    alt = np.array([x.e_measurand_alt_se for x in logs], float)
    alt = alt[np.isfinite(alt) & (alt > 0)]
    merged = replace(
        first, **arrays,
        velocity_note=merged_notes([x.velocity_note for x in logs]),
        velocity_offset_m_s=_weighted([x.velocity_offset_m_s for x in logs], n) if sum(n) else
        first.velocity_offset_m_s,
        ringing_share=_median([x.ringing_share for x in logs]),
        ringing_ratio=_median([x.ringing_ratio for x in logs]),
        ring_modes=next((x.ring_modes for x in logs if x.ring_modes), ()),
        ringing_problem=next((x.ringing_problem for x in logs if x.ringing_problem is not None),
                             None),
        velocity_delay_s=delay, velocity_delay_stderr_s=delay_se, velocity_delay_n=delay_n,
        velocity_delay_applied_s=_weighted([x.velocity_delay_applied_s for x in logs], n)
        if sum(n) else first.velocity_delay_applied_s,
        step_guard_s=max(x.step_guard_s for x in logs),
        velocity_delay_window_s=max((x.velocity_delay_window_s for x in logs
                                     if math.isfinite(x.velocity_delay_window_s)),
                                    key=abs, default=float("nan")),
        e_per_delay_s=_median([x.e_per_delay_s for x in logs]),
        e_window_change=max(x.e_window_change for x in logs),
        e_measurand_diff=_weighted([x.e_measurand_diff for x in logs], n) if sum(n) else 0.0,
        e_measurand_alt_se=float(1.0 / np.sqrt(np.sum(1.0 / alt ** 2))) if alt.size
        else float("nan"),
        decoder=merged_notes([getattr(x, "decoder", "") for x in logs]))
    return merged, keep


def merge_arrays(parts: list[Any]) -> Any:
    """Dataclasses of per-impact arrays (sound peaks) concatenated, field by field."""
    first = parts[0]
    return replace(first, **{f.name: np.concatenate([getattr(p, f.name) for p in parts])
                             for f in dataclasses.fields(first)})


__all__ = ["Span", "UNSEGMENTED_PROTOCOLS", "core_mask", "merge_arrays", "merge_logs",
           "merged_notes",
           "segment_spans", "segment_view"]
