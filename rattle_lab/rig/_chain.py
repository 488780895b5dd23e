"""A realistic measurement chain for the synthetic rig (scene table ``[chain]``, opt-in):
applied to the channels here; what each effect is and its parser are in
:mod:`rattle_lab.rig._chain_spec`.  Each effect is off by default.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ._chain_spec import ChainSpec
from ._channels import convolve_causal, impulse_train, n_samples

if TYPE_CHECKING:
    from ._motion import RunMotion
    from ._scene import ModelSpec

TWO_PI = 2.0 * math.pi
def fractional_delay(x: np.ndarray, sample_rate_hz: float, delay_s: float) -> np.ndarray:
    """``x`` delayed by ``delay_s`` (linear phase, band-limited; mirrored, so no wrap step)."""
    if delay_s == 0.0:
        return x
    n = x.size
    ext = np.concatenate([x, x[::-1]])
    f = np.fft.rfftfreq(ext.size, 1.0 / sample_rate_hz)
    return np.fft.irfft(np.fft.rfft(ext) * np.exp(-2j * np.pi * f * delay_s), ext.size)[:n]


def base_velocity(motion: RunMotion, sample_rate_hz: float) -> np.ndarray:
    """The shaker base's velocity, m/s: the integral of its ``-A cos(theta)`` acceleration.

    ``omega = 2 pi f`` of each sample's piece (not the slope of ``theta``: the simulator wraps
    ``theta`` by 2 pi at piece boundaries, where a numerical slope made a spike of ~A/omega
    in the velocity once per piece).
    """
    assert motion.theta is not None and motion.level_m_s2 is not None
    assert motion.freq_hz is not None
    omega = TWO_PI * motion.freq_hz
    return -motion.level_m_s2 / omega * np.sin(motion.theta)


def velocity_ringing(motion: RunMotion, model: ModelSpec, ring_hz: tuple[float, ...],
                     per_m_s: float, n: int, sample_rate_hz: float) -> np.ndarray:
    """The next modes in the vibrometer: ``per_m_s dv sum_j w_j exp(-t/decay) cos(2 pi f_j t)``.

    ``w_j = (1/(j+1)) / sum_k 1/(k+1)`` (as the accelerometer's ringing weights its
    modes), ``dv`` each impact's velocity change.
    """
    if not ring_hz or per_m_s == 0.0 or motion.impact_t_s.size == 0:
        return np.zeros(n)
    t = np.arange(n_samples(6 * model.ringing_decay_s, sample_rate_hz)) / sample_rate_hz
    weights = np.array([1.0 / (j + 1) for j in range(len(ring_hz))])
    weights /= weights.sum()
    kern = np.exp(-t / model.ringing_decay_s) * sum(
        w * np.cos(TWO_PI * f * t) for w, f in zip(weights, ring_hz))
    dv = -(motion.impact_v_in_m_s + motion.impact_v_out_m_s)
    return convolve_causal(impulse_train(motion.impact_t_s, per_m_s * dv, n, sample_rate_hz), kern)


def hum_and_offset(si: np.ndarray, name: str, chain: ChainSpec, sample_rate_hz: float) -> np.ndarray:
    """``si`` plus the sensor's mains hum and DC offset."""
    hum = {"velocity": chain.hum_m_s, "plate": chain.hum_m_s2, "base": chain.hum_m_s2,
           "mic": chain.hum_pa}.get(name, 0.0)
    offset = {"velocity": chain.offset_velocity_m_s, "plate": chain.offset_plate_m_s2,
              "base": chain.offset_base_m_s2, "mic": chain.offset_mic_pa}.get(name, 0.0)
    if hum == 0.0 and offset == 0.0:
        return si
    t = np.arange(si.size) / sample_rate_hz
    return si + hum * np.sin(TWO_PI * chain.hum_hz * t + 0.4) + offset


def floor_reflection(p: np.ndarray, chain: ChainSpec, c_m_s: float,
                     sample_rate_hz: float) -> np.ndarray:
    """``p`` plus one floor reflection: ``floor_gain`` times ``p``, ``floor_extra_path_m / c`` later."""
    if chain.floor_gain == 0.0 or chain.floor_extra_path_m == 0.0:
        return p
    return p + chain.floor_gain * fractional_delay(p, sample_rate_hz,
                                                   chain.floor_extra_path_m / c_m_s)


def quantise(stored: np.ndarray, range_: float | None, bits: int) -> np.ndarray:
    """``stored`` rounded to the ADC's step ``2 range / 2**bits`` (unchanged for ``bits == 0``)."""
    if bits == 0:
        return stored
    full = range_ if range_ is not None else 1.25 * float(np.max(np.abs(stored), initial=0.0))
    if full == 0.0:
        return stored
    lsb = 2.0 * full / 2.0 ** bits
    return np.round(stored / lsb) * lsb


__all__ = ["ChainSpec", "base_velocity", "floor_reflection", "fractional_delay", "hum_and_offset",
           "quantise", "velocity_ringing"]
