"""Synthesis of the rig's channels from the simulated motion (SI units).

Sign convention: the modal force per unit mass is ``-participation * a_base``, so the
base acceleration of forcing phase ``theta`` is ``a_base = -A cos(theta)`` and the
simulator's ``F cos(theta)`` pushes the plate towards the striker.  The shaker
harmonics and the fan tone are measurement-side artefacts: they are in the recorded
base acceleration but do not force the simulated mode.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from ._motion import RunMotion
from ._scene import AcousticSpec, ArtefactSpec, ModelSpec

TWO_PI = 2.0 * math.pi


def n_samples(seconds: float, sample_rate_hz: float) -> int:
    """Samples in ``seconds`` at ``sample_rate_hz`` (rounded, never truncated)."""
    return int(round(seconds * sample_rate_hz))


def impulse_train(t_s: np.ndarray, weights: np.ndarray, n: int, sample_rate_hz: float) -> np.ndarray:
    """Weights placed at the samples nearest to ``t_s`` (summed where they coincide)."""
    out = np.zeros(n)
    idx = np.rint(np.asarray(t_s) * sample_rate_hz).astype(np.int64)
    keep = (idx >= 0) & (idx < n)
    np.add.at(out, idx[keep], np.asarray(weights)[keep])
    return out


def convolve_causal(train: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """``train`` convolved with ``kernel`` (kernel[0] at the impulse), same length as ``train``."""
    if not np.any(train) or kernel.size == 0:
        return np.zeros_like(train)
    return signal.oaconvolve(train, kernel)[: train.size]


def harmonic_envelope(motion: RunMotion, art: ArtefactSpec, sample_rate_hz: float) -> np.ndarray:
    """Shaker loading by impacts in [0, 1] at the samples: first-order lag (``harmonics_tau_s``)
    of the indicator "the current piece has impacts"."""
    assert motion.theta is not None
    n = motion.theta.size
    drive = np.zeros(n)
    for piece, m in zip(motion.pieces, motion.piece_impacts):
        if m:
            drive[n_samples(piece.t0_s, sample_rate_hz):n_samples(piece.t1_s, sample_rate_hz)] = 1.0
    alpha = 1.0 - math.exp(-1.0 / (art.harmonics_tau_s * sample_rate_hz))
    return signal.lfilter([alpha], [1.0, alpha - 1.0], drive)


def base_acceleration(motion: RunMotion, art: ArtefactSpec, sample_rate_hz: float,
                      fan_phase: float) -> np.ndarray:
    """Base acceleration without sensor noise, m/s^2: ``-A cos(theta)``, harmonics, fan."""
    assert motion.theta is not None and motion.level_m_s2 is not None
    a = -motion.level_m_s2 * np.cos(motion.theta)
    if art.harmonics:
        load = harmonic_envelope(motion, art, sample_rate_hz)
        grow = art.harmonics_impact or art.harmonics
        for k, (h0, h1) in enumerate(zip(art.harmonics, grow), start=2):
            a -= motion.level_m_s2 * (h0 + (h1 - h0) * load) * np.cos(k * motion.theta)
    if art.fan_m_s2:
        t = np.arange(a.size) / sample_rate_hz
        a += art.fan_m_s2 * np.sin(TWO_PI * art.fan_hz * t + fan_phase)
    return a


def contact_kernel(contact_s: float, sample_rate_hz: float) -> np.ndarray:
    """Half-sine of unit area over ``contact_s``, sampled (area normalised to 1 / sample_rate)."""
    n = max(1, n_samples(contact_s, sample_rate_hz))
    k = np.sin(math.pi * (np.arange(n) + 0.5) / n)
    return k / (k.sum() / sample_rate_hz)


def contact_step(t_s: np.ndarray, contact_s: float) -> np.ndarray:
    """Momentum transferred by a contact centred on ``t = 0`` as a fraction of the total.

    The contact force is a half-sine over ``-contact_s/2 <= t <= contact_s/2``; the fraction
    is its running integral ``(1 + sin(pi t / contact_s)) / 2`` (0 before, 1 after).  Centring
    the contact on the simulator's rigid impact keeps both the impulse and its first moment,
    so outside the contact the velocity *and* the displacement are exactly the rigid ones.
    """
    t = np.asarray(t_s, dtype=float)
    if contact_s <= 0.0:
        return (t >= 0.0).astype(float)
    inside = np.clip(t / contact_s, -0.5, 0.5)
    return 0.5 * (1.0 + np.sin(math.pi * inside))


def contact_force(t_s: np.ndarray, contact_s: float) -> np.ndarray:
    """Time derivative of :func:`contact_step` (unit area), 1/s: ``pi/(2 contact_s) cos(pi t/contact_s)``
    inside the contact, 0 outside."""
    t = np.asarray(t_s, dtype=float)
    inside = np.abs(t) <= 0.5 * contact_s
    return np.where(inside, 0.5 * math.pi / contact_s * np.cos(math.pi * t / contact_s), 0.0)


def _impact_windows(motion: RunMotion, half_s: float, n: int, sample_rate_hz: float):
    """Per impact: the sample indices within ``half_s`` of it and their times relative to it."""
    for k, t_i in enumerate(motion.impact_t_s):
        lo = max(0, int(math.floor((t_i - half_s) * sample_rate_hz)))
        hi = min(n, int(math.ceil((t_i + half_s) * sample_rate_hz)) + 1)
        if hi > lo:
            idx = np.arange(lo, hi)
            yield k, idx, idx / sample_rate_hz - t_i


def plate_acceleration(motion: RunMotion, a_base: np.ndarray, model: ModelSpec,
                       ringing_freqs_hz: tuple[float, ...], sample_rate_hz: float) -> np.ndarray:
    """Plate-centre acceleration without sensor noise, m/s^2.

    ``a_base + a_rel`` (modal motion, W = 1 at the centre) plus, per impact, a half-sine
    contact pulse of duration ``contact_s`` *centred on the impact time* (:func:`contact_force`
    averaged over each sampling interval at the exact sub-sample position) and of area ``-(v_in + v_out)`` (the momentum
    change per unit mass, ``(1 + e) v_in``), and decaying ringing
    ``ringing_m_s2_per_m_s v_in exp(-t/ringing_decay_s) sin(2 pi f_j t)`` of the higher modes.
    A contact shorter than a sample is one sample of that area at the nearest sample.
    """
    assert motion.a_rel_m_s2 is not None
    n = a_base.size
    out = a_base + motion.a_rel_m_s2
    if motion.impact_t_s.size:
        dv = -(motion.impact_v_in_m_s + motion.impact_v_out_m_s)
        if model.contact_s * sample_rate_hz < 1.0:
            out += convolve_causal(impulse_train(motion.impact_t_s, dv, n, sample_rate_hz),
                                   contact_kernel(model.contact_s, sample_rate_hz))
        else:
            # each sample is the mean over its sampling interval (an integrating ADC): the
            # samples then sum to the impulse exactly and keep the pulse's centroid
            dt = 1.0 / sample_rate_hz
            half = 0.5 * model.contact_s + dt
            for k, idx, tr in _impact_windows(motion, half, n, sample_rate_hz):
                out[idx] += dv[k] * sample_rate_hz * (contact_step(tr + 0.5 * dt, model.contact_s)
                                                      - contact_step(tr - 0.5 * dt, model.contact_s))
        if ringing_freqs_hz and model.ringing_m_s2_per_m_s:
            t = np.arange(n_samples(6 * model.ringing_decay_s, sample_rate_hz)) / sample_rate_hz
            kern = np.exp(-t / model.ringing_decay_s) * sum(
                np.sin(TWO_PI * f * t) / (j + 1) for j, f in enumerate(ringing_freqs_hz))
            v = impulse_train(motion.impact_t_s, model.ringing_m_s2_per_m_s * motion.impact_v_in_m_s,
                              n, sample_rate_hz)
            out += convolve_causal(v, kern)
    return out


def vibrometer_velocity(motion: RunMotion, band_hz: float | None, sample_rate_hz: float,
                        contact_s: float = 0.0) -> np.ndarray:
    """Plate-centre velocity relative to the base, m/s, low-pass filtered at ``band_hz``.

    The vibrometer is taken as differential (reference beam on the base): it measures
    ``v_rel = v_nd omega_s h``, the modal velocity the simulator computes, with each rigid
    velocity jump spread over the finite contact exactly as the plate accelerometer's contact
    pulse spreads it (:func:`contact_step`, centred on the impact), so that the velocity is
    the integral of the relative acceleration the accelerometers see.  Outside the contacts
    it is the simulated velocity.  The band limit is a zero-phase 4th-order Butterworth.
    """
    assert motion.v_rel_m_s is not None
    v = motion.v_rel_m_s
    if motion.impact_t_s.size and contact_s > 0.0:
        v = v.copy()
        # the simulator's jump is -(v_in + v_out) at t_i; replace H(t - t_i) by contact_step
        jump = -(motion.impact_v_in_m_s + motion.impact_v_out_m_s)
        for k, idx, tr in _impact_windows(motion, 0.5 * contact_s, v.size, sample_rate_hz):
            v[idx] += jump[k] * (contact_step(tr, contact_s) - (tr >= 0.0))
    if band_hz is not None and band_hz < 0.45 * sample_rate_hz and v.size > 30:
        sos = signal.butter(4, band_hz, fs=sample_rate_hz, output="sos")
        v = signal.sosfiltfilt(sos, v)
    return v


def sound_pressure(motion: RunMotion, acoustic: AcousticSpec, art: ArtefactSpec,
                   sample_rate_hz: float, rng: np.random.Generator,
                   fan_phase: float) -> tuple[np.ndarray, np.ndarray]:
    """Sound pressure without background noise, Pa, and which impacts had a second peak.

    Per impact a pulse ``p_peak exp(-t/ring_decay_s) cos(2 pi ring_freq_hz t)`` starting
    ``delay_s`` later with ``p_peak = pa_per_m_s v_in + intercept_pa`` (the thesis's linear
    law); some impacts get a larger second pulse; plus ``mode_pa_per_m_s2`` times the
    modal acceleration delayed by ``distance / c``, and the fan tone.
    """
    assert motion.theta is not None
    n = motion.theta.size
    peaks = acoustic.pa_per_m_s * motion.impact_v_in_m_s + acoustic.intercept_pa
    second = rng.random(peaks.size) < acoustic.second_peak_probability
    t = np.arange(n_samples(8 * acoustic.ring_decay_s, sample_rate_hz)) / sample_rate_hz
    kern = np.exp(-t / acoustic.ring_decay_s) * np.cos(TWO_PI * acoustic.ring_freq_hz * t)
    arrival = motion.impact_t_s + acoustic.delay_s
    train = impulse_train(arrival, peaks, n, sample_rate_hz)
    if np.any(second):
        train += impulse_train(arrival[second] + acoustic.second_peak_delay_s,
                               acoustic.second_peak_ratio * peaks[second], n, sample_rate_hz)
    p = convolve_causal(train, kern)
    if acoustic.mode_pa_per_m_s2 and motion.a_rel_m_s2 is not None:
        shift = n_samples(acoustic.distance_m / acoustic.c_m_s, sample_rate_hz)
        lf = acoustic.mode_pa_per_m_s2 * motion.a_rel_m_s2
        p[shift:] += lf[: n - shift] if shift else lf
    if art.fan_pa:
        p += art.fan_pa * np.sin(TWO_PI * art.fan_hz * np.arange(n) / sample_rate_hz + fan_phase)
    return p, second
