"""Data-quality checks that stream over a channel chunk by chunk.

Findings and their flags (catalogue column ``flags``):

========================== ======= =======================================================
flag                       fatal   what
========================== ======= =======================================================
``nan``                    yes     NaN samples (in a channel or its timestamps)
``inf``                    yes     infinite samples
``clipping``               yes     a flat run of >= ``n_clip_min`` samples at the range
                                   limit: the declared ``range_min``/``range_max``, the
                                   limits of an integer dtype, or else the channel's own
                                   minimum or maximum (not its rest level: flat runs at
                                   an extreme that hold most of the samples, as a gated
                                   pulse or a command signal sits at 0; and, for a
                                   quantised signal, only a run longer than ``SHORT_FLAT``
                                   samples or several stepped onto sharply: a smooth or
                                   noisy peak repeats its top sample a few times too)
``dropout``                yes     a flat run of >= ``max(n_dropout_min, dropout_min_s*fs)``
                                   identical samples not at a range limit (stuck or
                                   zero-filled acquisition), a constant channel, or a
                                   timestamp step over ``gap_factor`` times the nominal step
``rate_mismatch``          yes     channels of one run with different sample rates
``nonmonotonic_timestamps`` yes    timestamps not strictly increasing
``empty``                  yes     a zero-length channel
``uncalibrated``           no      amplitude in full-scale units ("1")
``units_assumed``          no      units not stated by the source, assumed by the mapping
========================== ======= =======================================================

"Fatal" findings raise their :class:`~rattle_lab.records.DataQualityError`
unless flagged data are allowed; nothing is ever dropped or clamped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ._scan import flat_runs
from ._errors import (ClippingError, ClippingWarning, DataQualityError, DropoutError,
                      DropoutWarning, EmptyChannelError, EmptyChannelWarning, InfValueError,
                      InfValueWarning, NaNGapError, NaNGapWarning, NonMonotonicTimestampsError,
                      NonMonotonicTimestampsWarning, SampleRateMismatchError,
                      SampleRateMismatchWarning, UncalibratedWarning)
from rattle_lab.exceptions import DataQualityWarning

Flag = Literal["nan", "inf", "clipping", "dropout", "rate_mismatch", "nonmonotonic_timestamps",
               "empty", "uncalibrated", "units_assumed"]

FLAGS: tuple[str, ...] = ("nan", "inf", "clipping", "dropout", "rate_mismatch",
                          "nonmonotonic_timestamps", "empty", "uncalibrated", "units_assumed")
FATAL_FLAGS = frozenset({"nan", "inf", "clipping", "dropout", "rate_mismatch",
                         "nonmonotonic_timestamps", "empty"})

ERROR_CLASSES: dict[str, type[DataQualityError]] = {
    "nan": NaNGapError, "inf": InfValueError, "clipping": ClippingError, "dropout": DropoutError,
    "rate_mismatch": SampleRateMismatchError, "nonmonotonic_timestamps": NonMonotonicTimestampsError,
    "empty": EmptyChannelError,
}
WARNING_CLASSES: dict[str, type[DataQualityWarning]] = {
    "nan": NaNGapWarning, "inf": InfValueWarning, "clipping": ClippingWarning,
    "dropout": DropoutWarning, "rate_mismatch": SampleRateMismatchWarning,
    "nonmonotonic_timestamps": NonMonotonicTimestampsWarning, "empty": EmptyChannelWarning,
    "uncalibrated": UncalibratedWarning, "units_assumed": UncalibratedWarning,
}


@dataclass(frozen=True)
class QualityLimits:
    """Thresholds of the checks.

    Attributes
    ----------
    n_clip_min : int
        Shortest flat run at a range limit that counts as clipping, samples.
    n_dropout_min : int
        Shortest flat run that counts as a dropout, samples (at least).
    dropout_min_s : float
        Shortest flat run that counts as a dropout, s (``round(dropout_min_s * fs)``
        samples when that is more than ``n_dropout_min``).
    gap_factor : float
        A timestamp step longer than ``gap_factor`` times the nominal step is a dropout.
    rate_rtol : float
        Relative tolerance when comparing sample rates of one run.
    """

    n_clip_min: int = 3
    n_dropout_min: int = 16
    dropout_min_s: float = 0.001
    gap_factor: float = 1.5
    rate_rtol: float = 1e-6

    def n_dropout(self, sample_rate_hz: float | None) -> int:
        """Dropout length in samples for a channel sampled at ``sample_rate_hz``."""
        if sample_rate_hz is None or not math.isfinite(sample_rate_hz):
            return self.n_dropout_min
        return max(self.n_dropout_min, round(self.dropout_min_s * sample_rate_hz))


@dataclass(frozen=True)
class Finding:
    """One data-quality finding.

    Attributes
    ----------
    flag : str
        One of :data:`FLAGS`.
    file : str
        The input file.
    path : str
        HDF5 path (or the foreign file's equivalent) of the dataset.
    field : str
        ``"data"``, ``"timestamps"``, ``"sample_rate_hz"`` or ``"units"``.
    detail : str
        What was found, with counts.
    sample_index : int or None
        First affected sample.
    n_samples : int
        Number of affected samples.
    """

    flag: str
    file: str
    path: str
    field: str
    detail: str
    sample_index: int | None = None
    n_samples: int = 0

    @property
    def fatal(self) -> bool:
        """True when the finding raises unless flagged data are allowed."""
        return self.flag in FATAL_FLAGS

    @property
    def message(self) -> str:
        """``file: path: field: flag: detail`` on one line."""
        return f"{self.file}: {self.path}: {self.field}: {self.flag}: {self.detail}"

    def error(self) -> DataQualityError:
        """The exception for this finding."""
        return ERROR_CLASSES[self.flag](self.message, self)

    @property
    def warning_class(self) -> type[DataQualityWarning]:
        """The warning class for this finding."""
        return WARNING_CLASSES[self.flag]


@dataclass
class _Acc:
    """Flat runs of one kind: count, samples, first one."""

    n_runs: int = 0
    n_samples: int = 0
    first_start: int | None = None
    first_len: int = 0
    value: float = math.nan
    n_long: int = 0       # runs longer than SHORT_FLAT (quantised data: evidence of clipping)
    n_steep: int = 0      # shorter runs stepped onto or off by more than SHARP_QUANTA quanta

    def add(self, starts: np.ndarray, lens: np.ndarray, values: np.ndarray) -> None:
        if starts.size == 0:
            return
        self.n_runs += int(starts.size)
        self.n_samples += int(lens.sum())
        i = int(np.argmin(starts))
        if self.first_start is None or starts[i] < self.first_start:
            self.first_start, self.first_len, self.value = int(starts[i]), int(lens[i]), float(values[i])


#: Without a declared range, flat runs at a quantised channel's own extreme are clipping if
#: one is longer than SHORT_FLAT samples, or more than one is stepped onto or off by more
#: than SHARP_QUANTA of the channel's smallest steps.
SHARP_QUANTA = 3.0
SHORT_FLAT = 4


class ChannelChecker:
    """Streaming checks of one channel: feed chunks in order to :meth:`update`, then :meth:`finish`.

    Parameters
    ----------
    dtype : numpy dtype
        dtype of the stored samples (integer dtypes are clipped at their limits).
    range_min, range_max : float or None
        Declared input range, stored units.
    n_dropout : int
        Dropout length in samples (see :meth:`QualityLimits.n_dropout`).
    limits : QualityLimits
        The other thresholds.
    """

    def __init__(self, dtype: np.dtype, *, range_min: float | None = None,
                 range_max: float | None = None, n_dropout: int = 16,
                 limits: QualityLimits = QualityLimits()) -> None:
        dtype = np.dtype(dtype)
        self.is_float = dtype.kind == "f"
        self.range_source = "declared range"
        if range_min is None and dtype.kind in "iu":
            info = np.iinfo(dtype)
            range_min, range_max = float(info.min), float(info.max)
            self.range_source = f"{dtype.name} limit"
        self.range_min, self.range_max = range_min, range_max
        self.n_clip_min = limits.n_clip_min
        self.n_dropout = n_dropout
        self.pos = 0
        self.n_nan = 0
        self.nan_runs = 0
        self.first_nan: int | None = None
        self._prev_nan = False
        self.n_inf = 0
        self.first_inf: int | None = None
        self.vmin = math.inf
        self.vmax = -math.inf
        # Flat runs shorter than this cannot be clipping or a dropout: not reported by the scan.
        self._min_len = max(2, min(self.n_clip_min, self.n_dropout))
        self._tail = np.empty(0, dtype=dtype.newbyteorder("="))  # last sample seen
        self._open_start = 0  # the run of identical samples that reaches the last sample seen
        self._open_len = 0
        self._runs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None  # scan output buffers
        self.clip = _Acc()
        self.dropout = _Acc()
        # Without a known range: flat runs at the highest / lowest value seen so far.
        self._hi = _Acc(value=-math.inf)
        self._lo = _Acc(value=math.inf)
        # the smallest step between neighbouring samples seen: the ADC's quantum, if any
        self._quantum = math.inf
        self._quantised: bool | None = None
        self._open_entry = math.nan   # the step onto the open run
        # Without a known range, dropouts may turn out to be at an extreme: kept apart.
        self._dropouts: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def update(self, x: np.ndarray) -> None:
        """Check the next chunk ``x`` (1-D, stored units)."""
        n = int(x.shape[0])
        if n == 0:
            return
        if not x.dtype.isnative:  # the compiled scan reads native byte order only
            x = x.astype(x.dtype.newbyteorder("="))
        start = self.pos
        # min and max propagate NaN and show +-inf: finite extremes prove every sample finite.
        lo, hi = float(x.min()), float(x.max())
        if not (math.isfinite(lo) and math.isfinite(hi)):
            mask = np.isfinite(x)
            self._nonfinite(x, mask, start)
            finite = x[mask]
            lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (math.inf, -math.inf)
        else:
            self._prev_nan = False
        self.vmin = min(self.vmin, lo)
        self.vmax = max(self.vmax, hi)
        if self.range_min is None and n > 1 and self._quantised is not False:
            d = np.abs(np.diff(x.astype(np.float64)))
            d = d[(d > 0) & np.isfinite(d)]
            if d.size:
                q = min(self._quantum, float(d.min()))
                # quantised: the steps are whole multiples of the smallest one
                off = np.abs(d[:2000] / q - np.round(d[:2000] / q))
                if d.size >= 50:
                    self._quantised = bool(np.mean(off < 1e-3) > 0.9)
                self._quantum = q
        self._flat_runs(x, start)
        self.pos += n

    def _nonfinite(self, x: np.ndarray, mask: np.ndarray, start: int) -> None:
        isnan = np.isnan(x)
        n_nan = int(isnan.sum())
        if n_nan:
            if self.first_nan is None:
                self.first_nan = start + int(np.argmax(isnan))
            self.n_nan += n_nan
            self.nan_runs += int(isnan[0] and not self._prev_nan)
            self.nan_runs += int(np.count_nonzero(isnan[1:] & ~isnan[:-1]))
        self._prev_nan = bool(isnan[-1])
        isinf = ~mask & ~isnan
        n_inf = int(isinf.sum())
        if n_inf:
            if self.first_inf is None:
                self.first_inf = start + int(np.argmax(isinf))
            self.n_inf += n_inf

    def _flat_runs(self, x: np.ndarray, start: int) -> None:
        n = int(x.shape[0])
        cap = n // self._min_len + 2  # each reported run but the first lies inside the chunk
        if self._runs is None or self._runs[0].shape[0] < cap:
            self._runs = (np.empty(cap, dtype=np.int64), np.empty(cap, dtype=np.int64),
                          np.empty(cap, dtype=np.float64))
        starts, lens, values = self._runs
        prev_open_entry = self._open_entry
        k, self._open_start, self._open_len = flat_runs(
            x, self._tail, start, self._open_start, self._open_len, self._min_len,
            starts, lens, values)
        xf = x.astype(np.float64)
        before = float(self._tail[0]) if self._tail.shape[0] else math.nan

        def entry_step(rel: np.ndarray, value: np.ndarray, continued: float) -> np.ndarray:
            # the step onto each run: from the sample before it (the previous chunk's last
            # for a run starting this chunk; a run that began in an earlier chunk keeps the
            # step it was entered with)
            prev = np.where(rel >= 1, xf[np.clip(rel - 1, 0, n - 1)], before)
            return np.where(rel >= 0, np.abs(prev - value), continued)

        if k:
            # every run reported here ends inside the chunk: the sample after it is known
            rel = starts[:k] - start
            exit_ = np.abs(xf[np.minimum(rel + lens[:k], n - 1)] - values[:k])
            entry = entry_step(rel, values[:k], prev_open_entry)
            self._classify(starts[:k].copy(), lens[:k].copy(), values[:k].copy(),
                           np.fmax(np.nan_to_num(entry, nan=0.0), np.nan_to_num(exit_, nan=0.0)))
        if self._open_len:
            rel_open = np.array([self._open_start - start])
            self._open_entry = float(entry_step(rel_open, np.array([xf[-1]]),
                                                prev_open_entry)[0])
        self._tail = x[-1:].copy()

    def _close_open(self) -> None:
        if self._open_len >= self._min_len:
            # a run that reaches the end of the record: only its entry step is known
            self._classify(np.array([self._open_start]), np.array([self._open_len]),
                           self._tail.astype(np.float64),
                           np.array([np.nan_to_num(self._open_entry, nan=0.0)]))
        self._open_len = 0

    def _classify(self, starts: np.ndarray, lens: np.ndarray, values: np.ndarray,
                  steps: np.ndarray) -> None:
        if starts.size == 0:
            return
        long_enough = lens >= self.n_clip_min
        if self.range_min is not None and self.range_max is not None:
            at_limit = (values >= self.range_max) | (values <= self.range_min)
            clip = long_enough & at_limit
            self.clip.add(starts[clip], lens[clip], values[clip])
            drop = (lens >= self.n_dropout) & ~at_limit
            self.dropout.add(starts[drop], lens[drop], values[drop])
            return
        # Without a declared range, a flat run at the channel's own extreme of a quantised
        # signal is clipping only where the signal steps into (or out of) it by more than a
        # few quanta: a smooth peak also repeats its top sample a few times, stepping on and
        # off it by one quantum (16 bits at 25.6 kHz: 3 samples at a 0.8 m/s peak).
        # (every run at the extreme still counts towards its rest level)
        cand = long_enough
        if cand.any():
            cs, cl, cv = starts[cand], lens[cand], values[cand]
            # evidence of clipping: a long flat run (a smooth top that long needs a curvature
            # its neighbours would show), or more than one run stepped onto or off sharply
            # (one short run, however steep its sides, may be a noisy top: 16 bits at
            # 25.6 kHz repeat a 0.8 m/s peak 3 times between steps of 6 and 9 quanta)
            if self._quantised:
                long_ = cl > SHORT_FLAT
                steep = (steps[cand] > SHARP_QUANTA * self._quantum) & ~long_
            else:
                long_ = np.ones(cl.size, dtype=bool)
                steep = np.zeros(cl.size, dtype=bool)
            for acc, best, better in ((self._hi, cv.max(), np.greater),
                                      (self._lo, cv.min(), np.less)):
                if better(best, acc.value):
                    acc.n_runs, acc.n_samples, acc.first_start, acc.value = 0, 0, None, float(best)
                    acc.n_long, acc.n_steep = 0, 0
                if best == acc.value:
                    sel = cv == best
                    acc.add(cs[sel], cl[sel], cv[sel])
                    acc.n_long += int((sel & long_).sum())
                    acc.n_steep += int((sel & steep).sum())
        drop = lens >= self.n_dropout
        if drop.any():
            self._dropouts.append((starts[drop], lens[drop], values[drop]))

    def finish(self) -> list[tuple[str, int | None, int, str]]:
        """Findings as ``(flag, sample_index, n_samples, detail)``."""
        self._close_open()
        n = self.pos
        out: list[tuple[str, int | None, int, str]] = []
        if n == 0:
            return [("empty", None, 0, "zero-length channel (0 samples)")]
        if self.n_nan:
            out.append(("nan", self.first_nan, self.n_nan,
                        f"{self.n_nan} NaN sample(s) in {self.nan_runs} run(s), first at sample "
                        f"{self.first_nan}"))
        if self.n_inf:
            out.append(("inf", self.first_inf, self.n_inf,
                        f"{self.n_inf} infinite sample(s), first at sample {self.first_inf}"))
        constant = self.vmin == self.vmax
        if self.range_min is None:
            sides = ((self._hi, "maximum"), (self._lo, "minimum"))
            flat = {side: bool(acc.n_runs) and acc.value == (self.vmax if side == "maximum"
                                                              else self.vmin)
                    for acc, side in sides}
            for acc, side in sides:
                # Without a declared range, a signal that rests at one of its extremes (a
                # gated pulse, a command that is 0 between shots) is not clipped there: a
                # clipped signal leaves its rail again and spends most of its time inside.
                rest_level = flat[side] and 2 * acc.n_samples > n
                evidence = acc.n_long > 0 or acc.n_steep > 1
                if flat[side] and not rest_level and not constant and evidence:
                    self.clip.add(np.array([acc.first_start]), np.array([acc.first_len]),
                                  np.array([acc.value]))
                    self.clip.n_runs += acc.n_runs - 1
                    self.clip.n_samples += acc.n_samples - acc.first_len
            for starts, lens, values in self._dropouts:
                keep = constant | ((values != self.vmax) & (values != self.vmin))
                self.dropout.add(starts[keep], lens[keep], values[keep])
            where = "at the channel's own extreme (no declared range)"
        else:
            where = f"at the {self.range_source} [{self.range_min:g}, {self.range_max:g}]"
        if self.clip.n_runs:
            out.append(("clipping", self.clip.first_start, self.clip.n_samples,
                        f"{self.clip.n_samples} samples in {self.clip.n_runs} flat run(s) {where}, "
                        f"first at sample {self.clip.first_start} (value {self.clip.value:g})"))
        if self.dropout.n_runs:
            d = self.dropout
            what = ("channel is constant" if constant and d.first_len == n
                    else f"{d.n_runs} run(s) of >= {self.n_dropout} identical samples")
            out.append(("dropout", d.first_start, d.n_samples,
                        f"{what}: first at sample {d.first_start}, {d.first_len} samples of "
                        f"value {d.value:g}"))
        return out


class TimestampChecker:
    """Streaming checks of a timestamp dataset: NaN, order, gaps.

    The nominal step is the median step of the first chunk.
    """

    def __init__(self, limits: QualityLimits = QualityLimits()) -> None:
        self.gap_factor = limits.gap_factor
        self.pos = 0
        self._prev: float | None = None
        self.step_s: float | None = None
        self.first_t: float | None = None
        self.last_t: float | None = None
        self.n_nan = 0
        self.first_nan: int | None = None
        self.n_back = 0
        self.first_back: tuple[int, float, float] | None = None
        self.n_gaps = 0
        self.n_missing = 0
        self.first_gap: tuple[int, float] | None = None

    def update(self, t: np.ndarray) -> None:
        """Check the next chunk of timestamps (s)."""
        n = int(t.shape[0])
        if n == 0:
            return
        start = self.pos
        self.pos += n
        bad = ~np.isfinite(t)
        if bad.any():
            self.n_nan += int(bad.sum())
            if self.first_nan is None:
                self.first_nan = start + int(np.argmax(bad))
            return  # order and gaps are meaningless around non-finite times
        if self.first_t is None:
            self.first_t = float(t[0])
        self.last_t = float(t[-1])
        full = t if self._prev is None else np.concatenate(([self._prev], t))
        offset = start if self._prev is None else start - 1
        self._prev = float(t[-1])
        d = np.diff(full)
        if d.size == 0:
            return
        if self.step_s is None:
            positive = d[d > 0]
            self.step_s = float(np.median(positive)) if positive.size else math.nan
        back = d <= 0
        if back.any():
            i = int(np.argmax(back))
            self.n_back += int(back.sum())
            if self.first_back is None:
                self.first_back = (offset + i + 1, float(full[i]), float(full[i + 1]))
        if self.step_s and math.isfinite(self.step_s):
            gap = d > self.gap_factor * self.step_s
            if gap.any():
                self.n_gaps += int(gap.sum())
                self.n_missing += int(np.sum(np.round(d[gap] / self.step_s) - 1))
                if self.first_gap is None:
                    i = int(np.argmax(gap))
                    self.first_gap = (offset + i + 1, float(d[i]))

    @property
    def mean_rate_hz(self) -> float:
        """``(n - 1) / (t_last - t_first)``, Hz (NaN when undefined)."""
        if self.first_t is None or self.last_t is None or self.pos < 2 or self.last_t <= self.first_t:
            return math.nan
        return (self.pos - 1) / (self.last_t - self.first_t)

    def finish(self) -> list[tuple[str, int | None, int, str]]:
        """Findings as ``(flag, sample_index, n_samples, detail)``."""
        out: list[tuple[str, int | None, int, str]] = []
        if self.n_nan:
            out.append(("nan", self.first_nan, self.n_nan,
                        f"{self.n_nan} non-finite timestamp(s), first at sample {self.first_nan}"))
        if self.first_back is not None:
            i, t0, t1 = self.first_back
            out.append(("nonmonotonic_timestamps", i, self.n_back,
                        f"{self.n_back} step(s) not strictly increasing, first at sample {i} "
                        f"({t0!r} s -> {t1!r} s)"))
        if self.first_gap is not None:
            i, d = self.first_gap
            out.append(("dropout", i, self.n_missing,
                        f"{self.n_gaps} gap(s) in the timestamps, {self.n_missing} missing "
                        f"sample(s); first at sample {i}: step {d:g} s, nominal {self.step_s:g} s"))
        return out
