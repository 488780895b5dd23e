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
from typing import Any

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


@dataclass(frozen=True)
class CampaignTruth:
    """Truth of :func:`synthetic_campaign`.

    Attributes
    ----------
    gap_m, f_s_hz, zeta, e, participation : float
        Model parameters of the thresholds (eq. 3.4 and the 1/1 saddle-node).
    up_freq_hz, up_ms2, down_freq_hz, down_ms2 : ndarray
        True appearance / disappearance thresholds, m/s^2.
    impacts : dict of run_id to (t_s, v_in_m_s)
        True impacts of every run.
    acoustics : Acoustics
        Sound model (SPL-law slope of the maximum peak: ``gain * max|g|``).
    """

    gap_m: float
    f_s_hz: float
    zeta: float
    e: float
    participation: float
    up_freq_hz: np.ndarray
    up_ms2: np.ndarray
    down_freq_hz: np.ndarray
    down_ms2: np.ndarray
    impacts: dict[str, tuple[np.ndarray, np.ndarray]]
    acoustics: Acoustics


def synthetic_campaign(*, fs_hz: float = 12800.0, duration_s: float = 1.0,
                       up_freq_hz: tuple[float, ...] = (80.0, 88.0, 93.0, 94.5, 95.5, 96.0, 96.5,
                                                        97.5, 99.0, 104.0, 112.0),
                       down_freq_hz: tuple[float, ...] = (104.0, 108.0, 112.0, 116.0),
                       gap_m: float = 0.35e-3, f_s_hz: float = 96.0, zeta: float = 0.0085,
                       e: float = 0.8, participation: float = 1.2, noise_rel: float = 0.01,
                       seed: int = 0, extra_runs: bool = True) -> tuple[Any, CampaignTruth]:
    """A rattle record of ramp runs whose thresholds follow eq. (3.4) and the saddle-node.

    Each ramp spans 0.6 to 1.4 times its threshold over ``duration_s``; impacts
    happen once per cycle while the ramp is above the threshold.  The thresholds are the
    *quasi-static* ones, with no ramp lag (not what a plate does on a ramp this fast: use
    :mod:`rattle_lab.rig` for that), so fit them with ``method="quasi-static"``.  Noise: Gaussian,
    ``noise_rel`` times 0.02 m/s on the velocity, 10 m/s^2 on the plate
    acceleration, 0.005 Pa on the pressure, ``noise_rel`` of the threshold on the base.
    With ``extra_runs``: a dwell without impacts (``dwell_quiet``) and a run with no
    plate channel (``base_only``, to be skipped).
    """
    from rattle_lab.model.analysis import saddle_node_forcing
    from rattle_lab.model.linear import threshold_accel_ms2
    from rattle_lab.records import Channel, Record, Rig, Run
    from rattle_lab.records import as_source

    rng = np.random.default_rng(seed)
    n = int(round(duration_s * fs_hz))
    t = np.arange(n) / fs_hz
    ac = Acoustics()
    up_f = np.asarray(up_freq_hz, dtype=float)
    down_f = np.asarray(down_freq_hz, dtype=float)
    up_a = np.asarray(threshold_accel_ms2(up_f, gap_m, f_s_hz, zeta, participation), dtype=float)
    F_sn, _ = saddle_node_forcing(1, down_f / f_s_hz, zeta, e)
    down_a = gap_m * (2 * np.pi * f_s_hz) ** 2 * np.asarray(F_sn) / participation
    runs: list[Run] = []
    impacts: dict[str, tuple[np.ndarray, np.ndarray]] = {}

    def chans(sig: dict[str, np.ndarray], skip_plate: bool = False) -> Any:
        common: dict[str, Any] = {"sample_rate_hz": fs_hz, "start_time_s": 0.0}
        out = [Channel("base", "base_acceleration", "m/s^2", as_source(sig["base_acc"]), **common),
               Channel("mic", "sound_pressure", "Pa", as_source(sig["pressure"]), **common)]
        if not skip_plate:
            out += [Channel("velocity", "plate_velocity", "m/s", as_source(sig["velocity"]), **common),
                    Channel("plate", "plate_acceleration", "m/s^2", as_source(sig["plate_acc"]), **common)]
        return out

    for direction, freqs, thrs in (("up", up_f, up_a), ("down", down_f, down_a)):
        for f, thr in zip(freqs, thrs):
            lo, hi = 0.6 * thr, 1.4 * thr
            amp = lo + (hi - lo) * t / duration_s if direction == "up" else hi - (hi - lo) * t / duration_s
            ti, vin = ramp_impacts(f, amp, fs_hz, thr, direction, phase=float(rng.uniform(0.1, 0.9)),
                                   v_per_ms2=0.1 / thr)
            sig = synthetic_signals(fs_hz, n, f, ti, vin, e, base_amp_ms2=amp, acoustics=ac,
                                    noise_v_m_s=0.02 * noise_rel, noise_a_ms2=10.0 * noise_rel,
                                    noise_p_pa=0.005 * noise_rel, noise_base_ms2=noise_rel * thr,
                                    rng=rng)
            run_id = f"ramp_{direction}_{f:.1f}".replace(".", "p")
            impacts[run_id] = (ti, vin)
            runs.append(Run(run_id, "amplitude_ramp_up" if direction == "up" else "amplitude_ramp_down",
                            chans(sig),
                            excitation_freq_hz=float(f),
                            nominal_level=float(amp[0]), level_end=float(amp[-1]),
                            nominal_level_units="m/s^2", start_time_iso="2026-01-01T00:00:00Z"))
    if extra_runs:
        sig = synthetic_signals(fs_hz, n, 90.0, np.zeros(0), np.zeros(0), e, base_amp_ms2=0.5,
                                noise_v_m_s=0.02 * noise_rel, noise_a_ms2=10.0 * noise_rel,
                                noise_p_pa=0.005 * noise_rel, rng=rng)
        impacts["dwell_quiet"] = (np.zeros(0), np.zeros(0))
        runs.append(Run("dwell_quiet", "sine_dwell", chans(sig), excitation_freq_hz=90.0,
                        nominal_level=0.5, nominal_level_units="m/s^2", start_time_iso="2026-01-01T00:00:00Z"))
        runs.append(Run("base_only", "sine_dwell", chans(sig, skip_plate=True),
                        excitation_freq_hz=90.0, nominal_level=0.5, nominal_level_units="m/s^2",
                        start_time_iso="2026-01-01T00:00:00Z"))
    # the plate described has its first mode at f_s_hz (the plate model: 0.915 mm of this
    # CFCF aluminium plate is 96.05 Hz; f1 goes as the thickness), so that fit's check of the
    # plate model against the fitted f_s (issue 28) finds them consistent
    rig = Rig(apparatus="plate_striker", plate_length_m=0.254, plate_width_m=0.2286,
              plate_thickness_m=0.000915 * f_s_hz / 96.0, plate_material="aluminium",
              edge_conditions="CFCF",
              striker_x_m=0.127, striker_y_m=0.1143, gap_m=gap_m,
              mic_distance_m=ac.delay_s * 343.0)
    record = Record("synthetic_ramps", "measured", rig, tuple(runs),
                    description="hand-built ramp campaign (rattle_lab.rig._handbuilt)")
    truth = CampaignTruth(gap_m, f_s_hz, zeta, e, participation, up_f, up_a, down_f, down_a,
                          impacts, ac)
    return record, truth
