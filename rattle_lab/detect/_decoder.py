"""The vibrometer's decoder identified from the impacts, and equalised (issue 28).

A vibrometer's decoder (or the DAQ's anti-alias filter on its output) is a low-pass whose
step response may overshoot and ring for a millisecond or more: an 8th-order Butterworth at
2-3 kHz rings for 30-80 samples at 25.6-51.2 kHz.  The local velocity fits either side of an
impact then read that ringing, and the step centroid that measures the delay is cut off
inside it (:mod:`rattle_lab.detect._timing`): e was off by 5-60 % on such chains.

Every impact is a velocity step at an instant the plate accelerometer gives (its contact
pulse's centroid).  High-passed (zero phase, :data:`HIGH_PASS_HZ`), the forced motion, the
plate's low modes, the offset and the tails of earlier impacts drop out, and what is left
around each impact is the jump times the high-passed step response of the decoder:
``v_hp[n] = J_i s_hp(n - t_i)``, one unknown per impact, ``J_i``, eliminated in closed form.
:func:`identify_decoder` searches the low-pass families a data sheet names (Butterworth and
Bessel, orders 1-8, digital at the record's rate by the bilinear transform, as
``scipy.signal.butter`` / ``bessel(norm="mag")`` design them) for the cut-off and the extra
fractional delay whose step response leaves the least residual.  It is accepted where it
explains the steps: a residual under :data:`ACCEPT_RESIDUAL` of an ideal step's at the
measured delay (on the independent generator's chains 5e-4 to 0.04 for decoders of those
families, 0.13-0.24 for a linear-phase FIR decoder, which is not one of them and is left
alone).

:func:`equalise` then replaces the identified decoder by a zero-phase Gaussian low-pass with
the decoder's zeros at Nyquist (no overshoot, no delay), ``G = T / H`` bounded so that no
frequency gains more than :data:`MAX_GAIN`; or, with ``shape=False``, only advances the
record by the decoder's delay (what a declared delay does).  Which one the detector uses is
:func:`rattle_lab.detect.detect_impacts`' choice (the equalised record, unless the plate's
higher modes ring in the vibrometer, see ``_for_flights`` in :mod:`rattle_lab.detect._impacts`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

#: Zero-phase high-pass (4th-order Butterworth magnitude, squared) applied before the
#: identification: the forced motion (~100 Hz) and the plate's low modes (hundreds of Hz)
#: out, a decoder's response (kHz) in.
HIGH_PASS_HZ = 1000.0
#: Identification window around each impact, s: before and after the measured delay.
WINDOW_BEFORE_S = 1.5e-3
WINDOW_AFTER_S = 3e-3
#: Accepted where the best family's residual is under this share of the ideal step's.
ACCEPT_RESIDUAL = 0.05
#: Fewest impacts for an identification.
MIN_IMPACTS = 8
#: Most impacts an identification uses (spread over the run).
MAX_IMPACTS = 48
#: The equaliser's Gaussian target: -3 dB at this share of the identified cut-off.
TARGET_SHARE = 0.5
#: The equaliser gains at most this much at any frequency (the noise beyond the cut-off).
MAX_GAIN = 4.0
#: Families searched.
FAMILIES = ("butterworth", "bessel")
MAX_ORDER = 8
#: Least extra delay after the filter, samples: a causal chain delays; half a sample of
#: advance is left for where between two samples a jump is read.
MIN_EXTRA_SAMPLES = -0.5
#: Families refined after the coarse pass.
REFINED = 6
_NT = 1024       # the step tables' length (samples), the step at _C0
_C0 = 256


@dataclass(frozen=True)
class DecoderFit:
    """A vibrometer decoder identified from the impacts.

    Attributes
    ----------
    kind : str
        ``"butterworth"`` or ``"bessel"``.
    order : int
        Filter order.
    cutoff_hz : float
        -3 dB frequency, Hz.
    extra_samples : float
        Pure delay after the filter, samples (fractional).
    delay_samples : float
        Low-frequency group delay of the whole (filter plus extra), samples.
    residual_share : float
        Its residual over an ideal step's (the acceptance test).
    settle_samples : float
        How long its step response takes, after its low-frequency delay, to stay within
        :data:`rattle_lab.detect._timing.SETTLED_WITHIN` of the jump, samples.
    n_impacts : int
        Impacts used.
    """

    kind: str
    order: int
    cutoff_hz: float
    extra_samples: float
    delay_samples: float
    residual_share: float
    n_impacts: int
    settle_samples: float = 0.0

    def describe(self, fs_hz: float) -> str:
        name = "Butterworth" if self.kind == "butterworth" else "Bessel"
        return (f"a {name} low-pass of order {self.order}, -3 dB at "
                f"{self.cutoff_hz / 1e3:.3g} kHz, {self.delay_samples:.2f} samples "
                f"({1e6 * self.delay_samples / fs_hz:.1f} us) at low frequency, from "
                f"{self.n_impacts} impacts (residual {100 * self.residual_share:.2g} % of an "
                "ideal step's)")


@functools.cache
def _prototype(kind: str, order: int) -> np.ndarray:
    """Poles of the analog low-pass prototype, -3 dB at 1 rad/s (Bessel magnitude-normalised)."""
    from scipy.signal import besselap, buttap

    _, p, _ = buttap(order) if kind == "butterworth" else besselap(order, norm="mag")
    return np.asarray(p, dtype=complex)


def _zpk(kind: str, order: int, cutoff_hz: float, fs_hz: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The digital filter by the bilinear transform with the cut-off prewarped (what
    ``scipy.signal.butter(order, cutoff_hz, fs=fs_hz, output="zpk")`` and ``bessel(...,
    norm="mag")`` design): ``order`` zeros at -1, unit gain at DC."""
    wc = 2.0 * fs_hz * math.tan(math.pi * cutoff_hz / fs_hz)
    s = wc * _prototype(kind, order)
    p = (1.0 + s / (2.0 * fs_hz)) / (1.0 - s / (2.0 * fs_hz))
    z = -np.ones(order)
    k = float(np.real(np.prod(1.0 - p))) / 2.0 ** order
    return z, p, k


def response(kind: str, order: int, cutoff_hz: float, fs_hz: float, f_hz: np.ndarray,
             extra_samples: float = 0.0) -> np.ndarray:
    """The digital filter's frequency response at ``f_hz`` (times the extra delay's)."""
    w = 2.0 * np.pi * np.asarray(f_hz, dtype=float) / fs_hz
    return _response_on(np.exp(1j * w), w, kind, order, cutoff_hz, fs_hz, extra_samples)


def _response_on(ejw: np.ndarray, w: np.ndarray, kind: str, order: int, cutoff_hz: float,
                 fs_hz: float, extra_samples: float) -> np.ndarray:
    """:func:`response` on a grid given as ``exp(i w)`` and ``w`` (rad/sample)."""
    _, p, k = _zpk(kind, order, cutoff_hz, fs_hz)
    h = k * (ejw + 1.0) ** order / np.prod(ejw[:, None] - p[None, :], axis=1)
    return h * np.exp(-1j * w * extra_samples)


def dc_delay_samples(kind: str, order: int, cutoff_hz: float, fs_hz: float) -> float:
    """Low-frequency group delay of the digital filter, samples: ``sum Re 1/(1 - p) - sum
    Re 1/(1 - z)`` over poles and zeros (the derivative of the phase at DC)."""
    z, p, _ = _zpk(kind, order, cutoff_hz, fs_hz)
    return float(np.sum(np.real(1.0 / (1.0 - p))) - np.sum(np.real(1.0 / (1.0 - z))))


def _high_pass_gain(f_hz: np.ndarray) -> np.ndarray:
    r = (np.asarray(f_hz, dtype=float) / HIGH_PASS_HZ) ** 8
    return r / (1.0 + r)


def _tukey(n: int) -> np.ndarray:
    """A window flat over its middle half, cosine tapers over the outer quarters."""
    from scipy.signal.windows import tukey

    return np.asarray(tukey(n, 0.5))


def _fir(gain: np.ndarray, n_taps: int) -> np.ndarray:
    """A centred FIR (odd length, tapered) from a response on the rfft grid of 2 n_taps."""
    h = np.fft.irfft(gain, 2 * n_taps)
    half = n_taps // 2
    taps = np.r_[h[-half:], h[:half + 1]]
    return taps * _tukey(taps.size)


def _filtered(v: np.ndarray, taps: np.ndarray) -> np.ndarray:
    """``v`` through a centred FIR, the ends mirrored (the chain ran before the record)."""
    from scipy.signal import oaconvolve

    half = taps.size // 2
    if v.size <= half + 1:
        return v.copy()
    xx = np.pad(v, half, mode="reflect")
    return oaconvolve(xx, taps, mode="valid")


class _Problem:
    """The high-passed velocity around each impact; the residual of a step table."""

    def __init__(self, v_hp: np.ndarray, t_idx: np.ndarray, lo: int, hi: int):
        pos, vals, seg = [], [], []
        t = np.sort(np.asarray(t_idx, dtype=float))
        # at most MAX_IMPACTS, spread over the run (a long run's thousands of impacts add
        # nothing a few dozen do not tell: the decoder is the same at every impact)
        use = np.unique(np.linspace(0, t.size - 1, min(t.size, MAX_IMPACTS)).round().astype(int)) \
            if t.size else np.zeros(0, dtype=int)
        for i in use:
            ti = t[i]
            n = np.arange(int(math.floor(ti)) + lo, int(math.ceil(ti)) + hi + 1)
            if n[0] < 0 or n[-1] >= v_hp.size:
                continue
            if (i > 0 and n[0] < t[i - 1] + hi) or (i + 1 < t.size and n[-1] > t[i + 1] + lo):
                continue   # another impact's step inside the window
            # a digital decoder sees the jump at the first sample after it; the table is
            # read half a sample before (between the two readings a jump can have)
            pos.append(n - ti - 0.5 + _C0)
            vals.append(v_hp[n])
            seg.append(n.size)
        self.n = len(seg)
        if not self.n:
            return
        self.pos = np.concatenate(pos)
        self.vals = np.concatenate(vals)
        self.starts = np.r_[0, np.cumsum(seg)[:-1]]
        self.vv = np.add.reduceat(self.vals ** 2, self.starts)
        self.keep = max(1, int(0.9 * self.n))   # the 10 % worst left out (a trigger
        # that is no impact, an impact whose window a neighbour's contact pulse reaches)

    def residual(self, table: np.ndarray) -> float:
        s = np.interp(self.pos, np.arange(_NT, dtype=float), table)
        sv = np.add.reduceat(s * self.vals, self.starts)
        ss = np.add.reduceat(s * s, self.starts)
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(ss > 0, self.vv - sv * sv / ss, self.vv)
        return float(np.sum(np.sort(r)[:self.keep]))


def _step_table(h_f: np.ndarray) -> np.ndarray:
    """The high-passed step response (``_NT`` samples, the step at ``_C0``) of a filter
    given on the rfft grid of ``2 _NT`` points (as a response to an impulse at ``_C0``)."""
    return np.cumsum(np.fft.irfft(h_f, 2 * _NT))[:_NT]


def identify_decoder(v: np.ndarray, t_idx: np.ndarray, fs_hz: float, delay_samples: float
                     ) -> DecoderFit | None:
    """The decoder of the families searched that best explains the velocity steps.

    ``t_idx``: the impacts' instants (the accelerometer's, samples of ``v``);
    ``delay_samples``: the velocity's measured delay (the search starts there).  None with
    fewer than :data:`MIN_IMPACTS` impacts with room, or where no family explains the
    steps (residual over :data:`ACCEPT_RESIDUAL` of an ideal step's).
    """
    from scipy.optimize import minimize

    if not np.isfinite(delay_samples) or len(t_idx) < MIN_IMPACTS:
        return None
    f_tab = np.fft.rfftfreq(2 * _NT) * fs_hz
    hp_gain = _high_pass_gain(f_tab)
    n_hp = 1 << int(math.ceil(math.log2(8 * fs_hz / HIGH_PASS_HZ)))
    f_hp = np.fft.rfftfreq(2 * n_hp) * fs_hz
    v_hp = _filtered(np.asarray(v, dtype=float), _fir(_high_pass_gain(f_hp), n_hp))
    lo = int(math.floor(delay_samples - WINDOW_BEFORE_S * fs_hz))
    hi = int(math.ceil(delay_samples + WINDOW_AFTER_S * fs_hz))
    if hi + _C0 >= _NT or lo + _C0 < 0:
        return None
    problem = _Problem(v_hp, np.asarray(t_idx, dtype=float), lo, hi)
    if problem.n < MIN_IMPACTS:
        return None
    shift = np.exp(-2j * np.pi * np.fft.rfftfreq(2 * _NT) * _C0)   # the impulse at _C0
    ideal = problem.residual(_step_table(
        shift * np.exp(-2j * np.pi * np.fft.rfftfreq(2 * _NT) * delay_samples) * hp_gain))
    if not ideal > 0:
        return None
    f_lo, f_hi = 0.02 * fs_hz, 0.45 * fs_hz

    def unpack(p: np.ndarray, kind: str, order: int) -> tuple[float, float]:
        fc = f_lo + (f_hi - f_lo) / (1.0 + math.exp(-float(p[0])))
        return fc, delay_samples - dc_delay_samples(kind, order, fc, fs_hz) + float(p[1])

    w_tab = 2.0 * np.pi * f_tab / fs_hz
    e_tab = np.exp(1j * w_tab)
    weight = shift * hp_gain

    def cost(p: np.ndarray, kind: str, order: int) -> float:
        fc, extra = unpack(p, kind, order)
        h = _response_on(e_tab, w_tab, kind, order, fc, fs_hz, extra)
        r = problem.residual(_step_table(h * weight))
        if extra < MIN_EXTRA_SAMPLES:
            # a decoder is causal: what only an advance would explain (a zero-phase filter,
            # run forwards and backwards in post-processing) is no decoder of these
            # families.  (A penalty growing with the advance, so that the search finds its
            # way back.)
            r += ideal * (1.0 + (MIN_EXTRA_SAMPLES - extra) ** 2)
        return r

    # every family at a few cut-offs (the extra delay from the measured one), then the
    # closest few refined in cut-off and extra delay together
    # (the measured delay is itself off by up to a few samples where the decoder rings: the
    # centroid is cut off inside the ringing)
    starts = [math.log((f - f_lo) / (f_hi - f)) for f in np.geomspace(0.03 * fs_hz, 0.4 * fs_hz, 11)]
    offsets = tuple(float(o) for o in range(-4, 5))
    coarse = []
    for kind in FAMILIES:
        for order in range(1, MAX_ORDER + 1):
            coarse.append(min((cost(np.array([s, o]), kind, order), kind, order, s, o)
                              for s in starts for o in offsets))
    best: tuple[float, str, int, float, float] | None = None
    for _, kind, order, s0, o0 in sorted(coarse)[:REFINED]:
        res = minimize(cost, np.array([s0, o0]), args=(kind, order), method="Nelder-Mead",
                       options=dict(xatol=1e-3, fatol=1e-15, maxfev=100,
                                    initial_simplex=[[s0, o0], [s0 + 0.3, o0], [s0, o0 + 1.0]]))
        if best is None or res.fun < best[0]:
            fc, extra = unpack(res.x, kind, order)
            best = (float(res.fun), kind, order, fc, extra)
    assert best is not None
    share = best[0] / ideal
    if share > ACCEPT_RESIDUAL:
        return None
    _, kind, order, fc, extra = best
    delay = dc_delay_samples(kind, order, fc, fs_hz) + extra
    return DecoderFit(kind=kind, order=order, cutoff_hz=fc, extra_samples=extra,
                      delay_samples=delay, residual_share=share, n_impacts=problem.n,
                      settle_samples=settle_samples(kind, order, fc, fs_hz, extra, delay))


def settle_samples(kind: str, order: int, cutoff_hz: float, fs_hz: float, extra: float,
                   delay: float) -> float:
    """Samples after ``delay`` until the filter's step response stays within
    :data:`~rattle_lab.detect._timing.SETTLED_WITHIN` of 1 (smoothed over three samples,
    ``[1, 2, 1] / 4``: an oscillation at Nyquist, which a filter with its cut-off near it
    keeps up for long at a small amplitude, is not the ringing the fits read)."""
    from ._timing import SETTLED_WITHIN

    n = 1 << int(math.ceil(math.log2(max(1024.0, 64 * fs_hz / cutoff_hz + 4 * abs(delay)))))
    f = np.fft.rfftfreq(2 * n) * fs_hz
    # (1 + z^-1)^2 / 4: the smoothing made causal, one sample of delay more
    h = response(kind, order, cutoff_hz, fs_hz, f, extra + 1.0) * np.cos(np.pi * f / fs_hz) ** 2
    step = np.cumsum(np.fft.irfft(h, 2 * n))[:n]
    off = np.flatnonzero(np.abs(step - 1.0) > SETTLED_WITHIN)
    return float(max(0.0, (off[-1] + 1 if off.size else 0) - 1.0 - delay))


def equalise(v: np.ndarray, fs_hz: float, fit: DecoderFit, shape: bool = True) -> np.ndarray:
    """``v`` with the identified decoder replaced by a zero-phase Gaussian low-pass at
    :data:`TARGET_SHARE` of its cut-off (gain bounded by :data:`MAX_GAIN`); with ``shape``
    false, only advanced by its low-frequency delay (an all-pass: what a declared
    ``group_delay_s`` does)."""
    # the equaliser's response is about as long as the decoder's (its phase undone) plus
    # the delay it takes off: 64 periods of the cut-off hold it to 1e-4
    n_taps = 1 << int(math.ceil(math.log2(max(256.0, 64 * fs_hz / fit.cutoff_hz
                                                  + 4 * abs(fit.delay_samples)))))
    f = np.fft.rfftfreq(2 * n_taps) * fs_hz
    if not shape:
        # a pure advance, band-limited: the decoder's output holds nothing near Nyquist
        g = np.exp(2j * np.pi * f / fs_hz * fit.delay_samples)
        g[-1] = g[-1].real
        taps = _fir(g, n_taps)
        return _filtered(np.asarray(v, dtype=float), taps / taps.sum())
    h = response(fit.kind, fit.order, fit.cutoff_hz, fs_hz, f, fit.extra_samples)
    # a Gaussian (no overshoot) times the decoder's own zeros at Nyquist (the bilinear
    # transform puts ``order`` of them there), so that the ratio stays bounded up there
    target = np.exp(-math.log(math.sqrt(2.0)) * (f / (TARGET_SHARE * fit.cutoff_hz)) ** 2) \
        * np.cos(np.pi * f / fs_hz) ** fit.order
    mag = np.abs(h)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(target > MAX_GAIN * mag, MAX_GAIN * mag / target, 1.0)
        g = np.where(mag > 0, target * scale / h, 0.0)
    taps = _fir(g, n_taps)
    return _filtered(np.asarray(v, dtype=float), taps / taps.sum())   # unit gain at DC
