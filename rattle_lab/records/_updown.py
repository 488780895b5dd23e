"""A run that ramps up then down, split by the reader into its up and down parts (schema v2).

Protocols ``amplitude_ramp_up_down`` (level ``nominal_level`` -> ``level_peak`` ->
``level_end`` at ``excitation_freq_hz``) and ``swept_frequency_up_down`` (frequency
``excitation_freq_hz`` -> ``freq_peak_hz`` -> ``freq_end_hz``) are read as two runs,
``{run_id}_up`` and ``{run_id}_down``, with the ordinary protocols (``amplitude_ramp_up`` /
``amplitude_ramp_down``; ``swept_frequency`` twice) so that every later step (ingest, fit,
report) sees one-directional runs.  The turn is the run attribute ``turn_time_s`` (channel
time, s) when the file declares it, else it is found on the ``drive_signal`` channel: the
drive's RMS (amplitude) or its zero-crossing rate (frequency) per block of whole forcing
periods, a straight line fitted to each side of the largest block, and the turn where the
two lines meet.  Every channel is cut at its own first sample at or after the turn (channels
at different sample rates, or sampled irregularly, each keep their own clock); the down part
keeps the run's time origin (its ``start_time_s`` is the time of its first sample).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from rattle_lab.exceptions import SchemaError
from ._model import ArraySource, Channel

#: Protocols split by the reader, and the protocols of their (up, down) parts.
UP_DOWN_PROTOCOLS: dict[str, tuple[str, str]] = {
    "amplitude_ramp_up_down": ("amplitude_ramp_up", "amplitude_ramp_down"),
    "swept_frequency_up_down": ("swept_frequency", "swept_frequency"),
}
#: Forcing periods per block of the drive's envelope when the turn is found on the drive.
PERIODS_PER_BLOCK = 8


class SliceSource:
    """Samples ``start:stop`` of another source (lazy)."""

    def __init__(self, source: ArraySource, start: int, stop: int) -> None:
        self.source, self.start = source, int(start)
        self.n_samples = int(stop) - int(start)
        self.dtype = source.dtype

    def read(self, start: int, stop: int) -> np.ndarray:
        return self.source.read(self.start + start, self.start + stop)


def _line_meet(t: np.ndarray, y: np.ndarray, t_lo: float, t_hi: float) -> float:
    """Where lines fitted to the points before ``t_lo`` and after ``t_hi`` meet (clipped to
    ``[t_lo, t_hi]``; its middle when a side has too few points or the lines do not make a
    peak)."""
    left, right = t < t_lo, t > t_hi
    if np.count_nonzero(left) < 2 or np.count_nonzero(right) < 2:
        return 0.5 * (t_lo + t_hi)
    b1, a1 = np.polyfit(t[left], y[left], 1)
    b2, a2 = np.polyfit(t[right], y[right], 1)
    if not b1 > 0 > b2:
        return 0.5 * (t_lo + t_hi)
    return float(np.clip((a2 - a1) / (b1 - b2), t_lo, t_hi))


def turn_from_drive(drive: np.ndarray, fs_hz: float, start_time_s: float, f_low_hz: float,
                    what: str) -> float:
    """Time of the drive's turn (s).

    The drive's RMS (``what="amplitude"``) per block of :data:`PERIODS_PER_BLOCK` periods at
    ``f_low_hz``, or its frequency (``"frequency"``) from each half period between zero
    crossings interpolated to a fraction of a sample; the largest block brackets the turn,
    and the turn is where straight lines fitted to the points on either side of that block
    meet (a linear ramp up, then down).
    """
    x = np.asarray(drive, dtype=float)
    x = x - float(np.mean(x))
    n_block = max(4, int(round(PERIODS_PER_BLOCK * fs_hz / f_low_hz)))
    n = x.size // n_block
    if n < 3:
        raise ValueError(f"the drive has {x.size} samples, fewer than three blocks of "
                         f"{PERIODS_PER_BLOCK} forcing periods")
    if what == "amplitude":
        blocks = x[:n * n_block].reshape(n, n_block)
        y = np.sqrt(np.mean(blocks ** 2, axis=1))
        tk = (np.arange(n) + 0.5) * n_block
        yk = y
    else:
        k = np.flatnonzero(np.signbit(x[1:]) != np.signbit(x[:-1]))
        tc = k + x[k] / (x[k] - x[k + 1])
        t_half = 0.5 * (tc[1:] + tc[:-1])
        f_half = 0.5 * fs_hz / np.diff(tc)
        which = np.minimum((t_half // n_block).astype(int), n - 1)
        # per block the medians (noise adds close pairs of crossings: a few huge rates)
        tk, yk = np.full(n, np.nan), np.full(n, np.nan)
        for b in range(n):
            sel = which == b
            if np.count_nonzero(sel):
                tk[b], yk[b] = np.median(t_half[sel]), np.median(f_half[sel])
        ok = np.isfinite(yk)
        tk, yk = tk[ok], yk[ok]
        y = np.where(ok, np.nan, 0.0)
        y[ok] = yk
    peak = int(np.nanargmax(y))
    t_samples = _line_meet(tk, yk, peak * n_block, (peak + 1) * n_block)
    return start_time_s + t_samples / fs_hz


def _cut_index(ch: Channel, timestamps: Mapping[str, np.ndarray], turn_s: float) -> int:
    if ch.timestamps is not None:
        return int(np.searchsorted(timestamps[ch.timestamps], turn_s, side="left"))
    assert ch.sample_rate_hz is not None  # a channel has timestamps or a sample rate
    k = int(np.ceil((turn_s - float(ch.start_time_s or 0.0)) * float(ch.sample_rate_hz) - 1e-9))
    return min(max(k, 0), ch.n_samples)


def split_up_down(run_id: str, attrs: Mapping[str, Any], channels: list[Channel],
                  timestamps: Mapping[str, ArraySource], label: str
                  ) -> tuple[float, list[tuple[str, dict[str, Any], list[Channel],
                                               dict[str, ArraySource]]]]:
    """The turn (s) and the up and down parts: ``[(run_id, attrs, channels, timestamps)]``.

    ``attrs`` are the run's known attributes (``protocol`` one of :data:`UP_DOWN_PROTOCOLS`,
    ``level_peak`` or ``freq_peak_hz``, optional ``turn_time_s``).

    Raises
    ------
    SchemaError
        Naming the file and run: no ``turn_time_s`` and no regularly sampled
        ``drive_signal`` channel to find the turn on, or a turn outside the record.
    """
    where = f"{label}: /runs/{run_id}"
    attrs = dict(attrs)
    protocol = attrs.pop("protocol")
    up_protocol, down_protocol = UP_DOWN_PROTOCOLS[protocol]
    turn_s = attrs.pop("turn_time_s", None)
    level_peak, freq_peak = attrs.pop("level_peak", None), attrs.pop("freq_peak_hz", None)
    ts_arrays = {name: np.asarray(src.read(0, src.n_samples), dtype=float)
                 for name, src in timestamps.items()}
    if turn_s is None:
        drive = next((c for c in channels if c.quantity == "drive_signal"
                      and c.sample_rate_hz is not None), None)
        if drive is None:
            raise SchemaError(f"{where}: attribute 'turn_time_s': an {protocol} run needs the "
                              "time of its turn, or a drive_signal channel (sampled regularly) "
                              "to find it on")
        f_low = float(attrs["excitation_freq_hz"]) if protocol.startswith("amplitude") else \
            min(float(attrs["excitation_freq_hz"]), float(attrs["freq_end_hz"]))
        try:
            assert drive.sample_rate_hz is not None  # chosen above for its sample rate
            turn_s = turn_from_drive(drive.read(), float(drive.sample_rate_hz),
                                     float(drive.start_time_s or 0.0), f_low,
                                     "amplitude" if protocol.startswith("amplitude")
                                     else "frequency")
        except ValueError as exc:
            raise SchemaError(f"{where}/channels/{drive.name}: cannot find the turn of the "
                              f"{protocol} run: {exc}") from None
    parts: list[tuple[str, dict[str, Any], list[Channel], dict[str, ArraySource]]] = []
    for suffix, proto in (("_up", up_protocol), ("_down", down_protocol)):
        up = suffix == "_up"
        run_attrs = dict(attrs, protocol=proto)
        if protocol.startswith("amplitude"):
            run_attrs["nominal_level" if not up else "level_end"] = level_peak
            if not up:
                run_attrs["level_end"] = attrs["level_end"]
        else:
            run_attrs["freq_end_hz" if up else "excitation_freq_hz"] = freq_peak
            if not up:
                run_attrs["freq_end_hz"] = attrs["freq_end_hz"]
        cut: list[Channel] = []
        for ch in channels:
            k = _cut_index(ch, ts_arrays, float(turn_s))
            if k <= 0 or k >= ch.n_samples:
                raise SchemaError(f"{where}/channels/{ch.name}: the turn at {float(turn_s):.6g} s "
                                  "is not inside the channel (attribute 'turn_time_s', or the "
                                  "drive's largest level/frequency at an end of the record)")
            lo, hi = (0, k) if up else (k, ch.n_samples)
            new: dict[str, Any] = {"data": SliceSource(ch.data, lo, hi)}
            if ch.timestamps is None and not up:
                assert ch.sample_rate_hz is not None  # no timestamps: regularly sampled
                new["start_time_s"] = float(ch.start_time_s or 0.0) + k / float(ch.sample_rate_hz)
            cut.append(_replace(ch, **new))
        ts_cut: dict[str, ArraySource] = {}
        for name, src in timestamps.items():
            k = int(np.searchsorted(ts_arrays[name], float(turn_s), side="left"))
            ts_cut[name] = SliceSource(src, 0, k) if up else SliceSource(src, k, src.n_samples)
        run_attrs["x_split_from"] = run_id
        run_attrs["x_turn_time_s"] = float(turn_s)
        parts.append((run_id + suffix, run_attrs, cut, ts_cut))
    return float(turn_s), parts


def _replace(ch: Channel, **changes: Any) -> Channel:
    import dataclasses
    return dataclasses.replace(ch, **changes)


__all__ = ["PERIODS_PER_BLOCK", "SliceSource", "UP_DOWN_PROTOCOLS", "split_up_down",
           "turn_from_drive"]
