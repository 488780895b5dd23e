"""Hand-built synthetic shaker-lab signals with exact answers (for tests and the benchmark).

Not a physical simulator (that is :mod:`rattle_lab.rig`): impacts are placed at
chosen times with chosen incoming velocities and restitution, and every channel
is built around them analytically, so the detectors have exact truths.

Velocity: between impacts ``k`` and ``k+1`` (gap ``T``),
``v(s) = a + b cos(pi s / T)``, ``a = (v_out_k + v_in_{k+1})/2``,
``b = (v_out_k - v_in_{k+1})/2``; before the first impact
``v_in_1 cos(2 pi f (t - t_1))``, after the last ``v_out_K cos(2 pi f (t - t_K))``;
``v_out = -e v_in``.  Plate acceleration: the derivative of that plus a
half-sine contact pulse of ``pulse_s`` centred at each impact, of area
``v_out - v_in``.  Sound: ``gain * |v_in| g(t - t_k - delay)`` with
``g(u) = sin(2 pi f_a u) exp(-u / decay)`` for ``u >= 0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Acoustics:
    """Sound model: ``p = gain_pa_per_m_s |v_in| g(t - t_k - delay_s)``."""

    gain_pa_per_m_s: float = 0.5
    delay_s: float = 0.3 / 343.0
    ring_hz: float = 1500.0
    decay_s: float = 1.5e-3

    def g(self, u: np.ndarray) -> np.ndarray:
        """The unit sound response (0 before arrival)."""
        u = np.asarray(u, dtype=float)
        out = np.sin(2 * np.pi * self.ring_hz * u) * np.exp(-np.clip(u, 0, None) / self.decay_s)
        return np.where(u >= 0, out, 0.0)

    def peaks(self) -> tuple[float, float, float, float]:
        """``(u_first, g_first, u_max, g_max)`` of ``|g|`` (fine grid): first = max here."""
        u = np.linspace(0, 5 * self.decay_s, 200001)
        g = np.abs(self.g(u))
        k = int(np.argmax(g))
        return float(u[k]), float(g[k]), float(u[k]), float(g[k])


def synthetic_signals(fs_hz: float, n_samples: int, freq_hz: float, impact_t_s: np.ndarray,
                      v_in_m_s: np.ndarray, e: float, *, base_amp_ms2: np.ndarray | float = 1.0,
                      acoustics: Acoustics | None = None, pulse_s: float = 1e-4,
                      noise_v_m_s: float = 0.0, noise_a_ms2: float = 0.0, noise_p_pa: float = 0.0,
                      noise_base_ms2: float = 0.0, rng: np.random.Generator | None = None,
                      free_v_m_s: float = 0.05) -> dict[str, np.ndarray]:
    """Channels ``velocity, plate_acc, base_acc, pressure`` (and ``t``) around given impacts."""
    acoustics = acoustics or Acoustics()
    t = np.arange(n_samples) / fs_hz
    ti = np.asarray(impact_t_s, dtype=float)
    vin = np.asarray(v_in_m_s, dtype=float)
    vout = -e * vin
    w = 2 * np.pi * freq_hz
    v = np.empty(n_samples)
    dv = np.empty(n_samples)
    if ti.size == 0:
        v[:] = free_v_m_s * np.cos(w * t)
        dv[:] = -free_v_m_s * w * np.sin(w * t)
    else:
        seg = np.searchsorted(ti, t, side="right")  # 0: before the first impact
        m = seg == 0
        v[m] = vin[0] * np.cos(w * (t[m] - ti[0]))
        dv[m] = -vin[0] * w * np.sin(w * (t[m] - ti[0]))
        m = seg == ti.size
        v[m] = vout[-1] * np.cos(w * (t[m] - ti[-1]))
        dv[m] = -vout[-1] * w * np.sin(w * (t[m] - ti[-1]))
        for k in range(ti.size - 1):
            m = seg == k + 1
            T = ti[k + 1] - ti[k]
            a, b = 0.5 * (vout[k] + vin[k + 1]), 0.5 * (vout[k] - vin[k + 1])
            s = t[m] - ti[k]
            v[m] = a + b * np.cos(np.pi * s / T)
            dv[m] = -b * np.pi / T * np.sin(np.pi * s / T)
    acc = dv.copy()
    p = np.zeros(n_samples)
    for k in range(ti.size):
        u = t - ti[k]
        inside = np.abs(u) < pulse_s / 2
        # half-sine of area (vout - vin) over pulse_s: peak = area * pi / (2 pulse_s)
        acc[inside] += (vout[k] - vin[k]) * np.pi / (2 * pulse_s) * np.cos(np.pi * u[inside] / pulse_s)
        lo = int(np.searchsorted(t, ti[k] + acoustics.delay_s))
        hi = min(n_samples, lo + int(round(10 * acoustics.decay_s * fs_hz)))
        p[lo:hi] += acoustics.gain_pa_per_m_s * abs(vin[k]) * acoustics.g(
            t[lo:hi] - ti[k] - acoustics.delay_s)
    base = np.asarray(base_amp_ms2, dtype=float) * np.sin(w * t)
    rng = rng if rng is not None else np.random.default_rng(0)
    out = {"t": t, "velocity": v, "plate_acc": acc, "base_acc": base, "pressure": p}
    for key, sigma in (("velocity", noise_v_m_s), ("plate_acc", noise_a_ms2),
                       ("pressure", noise_p_pa), ("base_acc", noise_base_ms2)):
        if sigma > 0:
            out[key] = out[key] + sigma * rng.standard_normal(n_samples)
    return out


def ramp_impacts(freq_hz: float, amp_of_t: np.ndarray, fs_hz: float, threshold_ms2: float,
                 direction: str, *, phase: float = 0.3, v_per_ms2: float = 0.05,
                 v_min_m_s: float = 0.02) -> tuple[np.ndarray, np.ndarray]:
    """Impacts once per cycle where the ramp amplitude is above (``up``) / while above (``down``)
    ``threshold_ms2``; incoming velocity ``-(v_min + v_per_ms2 * (A - A_thr))``, m/s."""
    n = amp_of_t.size
    t_cycles = (np.arange(int(n / fs_hz * freq_hz) + 1) + phase) / freq_hz
    t_cycles = t_cycles[t_cycles < (n - 1) / fs_hz]
    amp = np.interp(t_cycles * fs_hz, np.arange(n), amp_of_t)
    keep = amp >= threshold_ms2
    del direction  # the same rule for both directions: impact while A >= threshold
    ti = t_cycles[keep]
    return ti, -(v_min_m_s + v_per_ms2 * np.abs(amp[keep] - threshold_ms2))
