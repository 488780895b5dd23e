"""An independent campaign generator: plain numpy, its own SDF physics and measurement chain.

Shares no code with rattle_lab (only NumPy and h5py): the records it writes are records we
did not make, the check that the pipeline holds on them (issue 15).

Physics: the relative plate displacement ``y`` (m; the striker at ``y = +gap_m``)
obeys ``y'' + 2 zeta w y' + w^2 y = -q a_b(t)`` with the base acceleration
``a_b = A_k sin(W t)``, ``A_k`` constant over each forcing period (a ramp steps once a
period).  Between impacts the solution is in closed form (particular + damped free
response); an impact is the first root of ``y = gap`` with ``y' > 0`` (grid of 1/256
of the shorter period, then 60 bisections), where ``y' -> -e y'``.

Measurement chain: a vibrometer (panel relative to the striker, or absolute: plus the base
velocity) whose decoder delays it by ``decoder_delay_s`` (a linear-phase FIR, applied as a
fractional delay in the frequency domain after an 8 kHz low-pass) or, with ``decoder`` set to
``"butterworth"`` or ``"bessel"``, filters it with a causal digital low-pass of that family
(``decoder_order``, -3 dB at ``decoder_cutoff_hz``; analog prototype, bilinear transform
prewarped at the cut-off, applied through the FFT with zero padding) followed by a pure
fractional delay of ``decoder_delay_s`` (then the extra delay of the chain), or with
``"none"`` passes the velocity as it is (an ideal vibrometer), a plate accelerometer,
a base accelerometer; higher modes ringing after each impact (each excited by the impact's
impulse: a velocity step ``r_j dv`` decaying with ``zeta_j``); DC offsets; white noise;
mains hum; ADC quantisation; a microphone at ``mic_m`` with propagation delay and one floor
reflection.  Written straight into the ``data_schema`` layout with h5py: schema version 2 with
the chain declared as chosen (``declare_delay``: the total low-frequency group delay of the
vibrometer, ``declare_measurand``), or schema version 1 (``schema_version=1``: nothing of the
chain declared, as a lab without rattle_lab writes it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np


@dataclass(frozen=True)
class Plant:
    f_s_hz: float = 96.0
    zeta: float = 0.01
    q: float = 1.2442
    gap_m: float = 0.0013
    e: float = 0.55


@dataclass(frozen=True)
class Chain:
    fs_hz: float = 25600.0
    decoder_delay_s: float = 18e-6
    measurand: str = "panel_relative_to_striker"
    ring_hz: tuple[float, ...] = (171.0, 293.0, 390.0)
    ring_ratio: tuple[float, ...] = (0.15, 0.08, 0.05)     # velocity step per m/s of dv
    ring_zeta: tuple[float, ...] = (0.02, 0.02, 0.02)
    ring_in_velocity: bool = True    # False: a vibrometer at a nodal line of those modes
    noise_v_m_s: float = 2e-4
    noise_a_ms2: float = 0.5
    noise_b_ms2: float = 0.02
    offset_v_m_s: float = 3e-3
    offset_a_ms2: float = 0.7
    hum_hz: float = 50.0
    hum_v_m_s: float = 5e-4
    adc_bits: int = 16
    mic_m: float = 0.3
    mic_floor_m: float = 0.9        # extra path of the floor reflection
    pa_per_m_s: float = 4.0
    declare_delay: bool = True
    declare_filter: bool = False    # the decoder's family, order, cut-off and rate (schema v2)
    declare_measurand: bool = True
    decoder: str = "fir"            # "fir" | "butterworth" | "bessel" | "none"
    decoder_order: int = 4
    decoder_cutoff_hz: float = 10000.0
    schema_version: int = 2
    participation_declared: bool = True

    @property
    def velocity_delay_s(self) -> float:
        """The vibrometer's total delay at low frequency (its filter's DC group delay + the pure delay)."""
        if self.decoder in ("fir", "none"):
            return self.decoder_delay_s
        return iir_dc_delay_s(self.decoder, self.decoder_order, self.decoder_cutoff_hz,
                              self.fs_hz) + self.decoder_delay_s


@dataclass
class Truth:
    impacts: dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]] = field(default_factory=dict)
    thresholds: dict[str, float] = field(default_factory=dict)


def _free(y0: float, v0: float, w: float, z: float, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    wd = w * math.sqrt(1 - z * z)
    a = z * w
    c = np.cos(wd * tau)
    s = np.sin(wd * tau)
    ex = np.exp(-a * tau)
    B = (v0 + a * y0) / wd
    y = ex * (y0 * c + B * s)
    v = ex * ((-a * y0 + wd * B) * c + (-a * B - wd * y0) * s)
    return y, v


def _particular(A: float, W: float, w: float, z: float, q: float):
    # y_p = P cos(W t) + Q sin(W t) for y'' + 2 z w y' + w^2 y = -q A sin(W t)
    k = w * w - W * W
    c = 2 * z * w * W
    den = k * k + c * c
    Q = -q * A * k / den
    P = q * A * c / den

    def yp(t):
        return P * np.cos(W * t) + Q * np.sin(W * t)

    def vp(t):
        return W * (-P * np.sin(W * t) + Q * np.cos(W * t))
    return yp, vp


def simulate(plant: Plant, W: float, levels: np.ndarray, fs_hz: float, y0=0.0, v0=0.0):
    """Exact motion sampled at fs_hz over len(levels) forcing periods; impacts (t, v_in, v_out)."""
    w, z, q, h, e = 2 * math.pi * plant.f_s_hz, plant.zeta, plant.q, plant.gap_m, plant.e
    T = 2 * math.pi / W
    n = int(round(len(levels) * T * fs_hz))
    ts = np.arange(n) / fs_hz
    y = np.empty(n)
    v = np.empty(n)
    imp_t, imp_in, imp_out = [], [], []
    grid = min(T, 2 * math.pi / w) / 256
    t0, ys, vs = 0.0, y0, v0
    for k, A in enumerate(levels):
        t_end = (k + 1) * T
        yp, vp = _particular(float(A), W, w, z, q)
        while True:
            # state relative to the particular solution at t0
            hy, hv = ys - yp(t0), vs - vp(t0)
            tau = np.arange(grid * 1e-3, t_end - t0 + grid, grid)
            tau = tau[tau <= t_end - t0]
            yy = _free(hy, hv, w, z, tau)[0] + yp(t0 + tau)
            hit = np.flatnonzero(yy >= h)
            if hit.size == 0:
                t_next = t_end
                impact = False
            else:
                j = int(hit[0])
                lo = tau[j - 1] if j > 0 else 0.0
                hi = tau[j]
                for _ in range(60):
                    mid = 0.5 * (lo + hi)
                    if _free(hy, hv, w, z, np.array([mid]))[0][0] + yp(t0 + mid) >= h:
                        hi = mid
                    else:
                        lo = mid
                t_next = t0 + lo
                impact = True
            # the samples with t0 <= t < end (ts is sorted: an index range, not a mask over
            # the whole record per flight)
            sel = slice(int(np.searchsorted(ts, t0)), int(np.searchsorted(
                ts, t_next if impact or k + 1 < len(levels) else np.inf)))
            yf, vf = _free(hy, hv, w, z, ts[sel] - t0)
            y[sel] = yf + yp(ts[sel])
            v[sel] = vf + vp(ts[sel])
            yf1, vf1 = _free(hy, hv, w, z, np.array([t_next - t0]))
            ys, vs = float(yf1[0] + yp(t_next)), float(vf1[0] + vp(t_next))
            t0 = t_next
            if not impact:
                break
            vin = vs
            vs = -e * vin
            ys = min(ys, h)
            imp_t.append(t0)
            imp_in.append(vin)
            imp_out.append(vs)
            if abs(vin) < 1e-6:
                # the end of a chatter sequence: the plate rests on the striker until the
                # forcing pulls it away (net acceleration at y = gap, v = 0 below zero)
                tt = t0 + np.arange(1, 4096) * grid / 4
                tt = tt[tt < t_end]
                pull = -w * w * h - q * float(A) * np.sin(W * tt)
                away = np.flatnonzero(pull < 0)
                t_go = float(tt[away[0]]) if away.size else t_end
                sel = slice(int(np.searchsorted(ts, t0)), int(np.searchsorted(ts, t_go)))
                y[sel] = h
                v[sel] = 0.0
                t0, ys, vs = t_go, h * (1 - 1e-12), 0.0
                if t_go >= t_end:
                    break
    return ts, y, v, np.array(imp_t), np.array(imp_in), np.array(imp_out)


def _delay(x: np.ndarray, fs_hz: float, delay_s: float, cutoff_hz: float) -> np.ndarray:
    """Low-pass (raised-cosine edge) and delay by ``delay_s`` (linear phase), in the frequency domain."""
    n = x.size
    m = 2 * n                       # mirrored: no step where the circular shift wraps
    X = np.fft.rfft(np.r_[x, x[::-1]])
    f = np.fft.rfftfreq(m, 1 / fs_hz)
    gain = np.clip((cutoff_hz * 1.25 - f) / (0.25 * cutoff_hz), 0, 1)
    gain = 0.5 - 0.5 * np.cos(np.pi * gain)
    return np.fft.irfft(X * gain * np.exp(-2j * np.pi * f * delay_s), m)[:n]


def _analog_poles(kind: str, order: int) -> np.ndarray:
    """Poles of the analog low-pass prototype, -3 dB at 1 rad/s."""
    if kind == "butterworth":
        k = np.arange(1, order + 1)
        return np.exp(1j * np.pi * (2 * k + order - 1) / (2 * order))
    if kind != "bessel":
        raise ValueError(f"unknown decoder {kind!r}")
    # reverse Bessel polynomial theta_n(s) = sum a_k s^k, a_k = (2n-k)! / (2^(n-k) k! (n-k)!)
    a = [math.factorial(2 * order - k) / (2 ** (order - k) * math.factorial(k)
                                          * math.factorial(order - k)) for k in range(order + 1)]
    poles = np.roots(a[::-1])

    def mag(w: float) -> float:
        return abs(np.prod(-poles) / np.prod(1j * w - poles))
    lo, hi = 1e-3, 1e3                      # -3 dB frequency of the delay-normalised filter
    for _ in range(200):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if mag(mid) > 2 ** -0.5 else (lo, mid)
    return poles / math.sqrt(lo * hi)


def _digital_poles(kind: str, order: int, cutoff_hz: float, fs_hz: float) -> np.ndarray:
    wa = 2 * fs_hz * math.tan(math.pi * cutoff_hz / fs_hz)     # prewarped cut-off
    s = wa * _analog_poles(kind, order)
    return (1 + s / (2 * fs_hz)) / (1 - s / (2 * fs_hz))


def iir_response(kind: str, order: int, cutoff_hz: float, fs_hz: float, f_hz: np.ndarray) -> np.ndarray:
    """Frequency response of the digital decoder: zeros at z = -1, unit gain at DC."""
    z = _digital_poles(kind, order, cutoff_hz, fs_hz)
    ejw = np.exp(2j * np.pi * np.asarray(f_hz) / fs_hz)
    h = np.ones(ejw.shape, dtype=complex)
    for zk in z:
        h *= (ejw + 1) / (ejw - zk) * (1 - zk) / 2
    return h


def iir_dc_delay_s(kind: str, order: int, cutoff_hz: float, fs_hz: float) -> float:
    """Group delay at DC of the digital decoder: sum Re 1/(1 - z_k) - n/2 samples."""
    z = _digital_poles(kind, order, cutoff_hz, fs_hz)
    return float(np.sum(np.real(1 / (1 - z))) - order / 2) / fs_hz


def _iir(x: np.ndarray, chain: Chain) -> np.ndarray:
    """The causal decoder and the extra pure delay, through the FFT (zero padded, lead-in mirrored)."""
    fs = chain.fs_hz
    lead = min(x.size, 4096)
    xx = np.r_[x[lead:0:-1], x]                 # the decoder was running before the record
    m = 1 << int(math.ceil(math.log2(xx.size + 8192)))
    f = np.fft.rfftfreq(m, 1 / fs)
    h = iir_response(chain.decoder, chain.decoder_order, chain.decoder_cutoff_hz, fs, f)
    y = np.fft.irfft(np.fft.rfft(xx, m) * h * np.exp(-2j * np.pi * f * chain.decoder_delay_s), m)
    return y[lead:lead + x.size]


def _quantise(x: np.ndarray, full_scale: float, bits: int) -> tuple[np.ndarray, float]:
    lsb = 2 * full_scale / 2 ** bits
    counts = np.clip(np.round(x / lsb), -2 ** (bits - 1), 2 ** (bits - 1) - 1)
    return counts * lsb, lsb


def measure(plant: Plant, chain: Chain, W: float, levels: np.ndarray, rng: np.random.Generator):
    """Channels (SI) and the true impacts of one run."""
    fs = chain.fs_hz
    ts, y, v, ti, vin, vout = simulate(plant, W, levels, fs)
    T = 2 * math.pi / W
    k = np.minimum((ts / T).astype(int), len(levels) - 1)
    a_b = levels[k] * np.sin(W * ts)
    v_b = -levels[k] / W * np.cos(W * ts)
    # relative acceleration from the equation of motion, plus the contact pulses
    w, z = 2 * math.pi * plant.f_s_hz, plant.zeta
    acc = -2 * z * w * v - w * w * y - plant.q * a_b
    ring_v = np.zeros_like(ts)
    ring_a = np.zeros_like(ts)
    for t_i, dv in zip(ti, vout - vin):
        i0 = int(math.ceil(t_i * fs))
        tau = ts[i0:i0 + int(0.25 * fs)] - t_i
        for f, r, zz in zip(chain.ring_hz, chain.ring_ratio, chain.ring_zeta):
            wj = 2 * math.pi * f
            env = np.exp(-zz * wj * tau)
            ring_v[i0:i0 + tau.size] += r * dv * env * np.cos(wj * tau)
            ring_a[i0:i0 + tau.size] += -r * dv * wj * env * np.sin(wj * tau)
        # the velocity step spread over one sample: a contact pulse of area dv in the accelerometer
        # (linear interpolation of a delta at t_i: the centroid of the two samples is t_i)
        frac = i0 - t_i * fs
        if i0 - 1 >= 0:
            acc[i0 - 1] += dv * fs * frac
        if i0 < acc.size:
            acc[i0] += dv * fs * (1 - frac)
    vel = v + (ring_v if chain.ring_in_velocity else 0.0) + (v_b if chain.measurand == "panel_absolute" else 0.0)
    hum = chain.hum_v_m_s * np.sin(2 * math.pi * chain.hum_hz * ts + 0.3)
    vel = vel + hum + chain.offset_v_m_s + chain.noise_v_m_s * rng.standard_normal(ts.size)
    if chain.decoder == "none":     # the velocity as it is (a pure delay, if any)
        vel = _delay(vel, fs, chain.decoder_delay_s, fs) if chain.decoder_delay_s else vel
    else:
        vel = _delay(vel, fs, chain.decoder_delay_s, 8000.0) if chain.decoder == "fir" else \
            _iir(vel, chain)
    vel, _ = _quantise(vel, 2.0, chain.adc_bits)
    plate = acc + ring_a + a_b + chain.offset_a_ms2 + chain.noise_a_ms2 * rng.standard_normal(ts.size)
    plate, _ = _quantise(plate, 2000.0, chain.adc_bits)
    base = a_b + chain.noise_b_ms2 * rng.standard_normal(ts.size)
    base, _ = _quantise(base, 50.0, chain.adc_bits)
    # microphone: a pulse per impact, direct path and one floor reflection
    p = 2e-3 * rng.standard_normal(ts.size)
    for t_i, v_i in zip(ti, vin):
        for dist, gain in ((chain.mic_m, 1.0), (chain.mic_m + chain.mic_floor_m,
                                                  0.6 * chain.mic_m / (chain.mic_m + chain.mic_floor_m))):
            t_a = t_i + dist / 343.0
            i0 = int(math.ceil(t_a * fs))
            tau = ts[i0:i0 + int(0.01 * fs)] - t_a
            p[i0:i0 + tau.size] += gain * chain.pa_per_m_s * abs(v_i) * np.exp(-tau / 1.5e-3) * \
                np.cos(2 * math.pi * 1300.0 * tau)
    p, _ = _quantise(p, 20.0, chain.adc_bits)
    return {"velocity": vel, "plate": plate, "base": base, "mic": p}, (ti, vin, vout)


def write_campaign(path: Path, plant: Plant, chain: Chain, runs: list[dict], seed: int) -> Truth:
    """Write a data_schema HDF5 campaign; runs: dicts with run_id, protocol, freq_hz, levels."""
    rng = np.random.default_rng(seed)
    truth = Truth()
    with h5py.File(path, "w") as fh:
        v2 = chain.schema_version >= 2
        fh.attrs.update({"schema": "rattle_record", "schema_version": chain.schema_version,
                         "campaign_id": f"independent-{seed}", "source": "measured",
                         "writer": "tests/independent_campaign.py"})
        rig = fh.create_group("rig")
        # a plate whose first mode is the plant's f_s: the CFCF plate bends like a clamped-
        # clamped strip of span b, f1 = 4.7300^2 / (2 pi b^2) sqrt(D / (rho h)), D = E h^3 /
        # (12 (1 - nu^2)), so h = f_s / that frequency per metre (aluminium 70 GPa, 2700
        # kg/m^3, nu 0.33); a plate model's f1 disagreeing with f_s is flagged (issue 28)
        strip = 4.7300 ** 2 / (2 * math.pi * 0.2286 ** 2) * math.sqrt(
            7.0e10 / (12 * (1 - 0.33 ** 2) * 2700.0))
        rig.attrs.update({"apparatus": "plate_striker", "plate_length_m": 0.254,
                          "plate_width_m": 0.2286, "plate_thickness_m": plant.f_s_hz / strip,
                          "plate_material": "aluminium", "edge_conditions": "CFCF",
                          "striker_x_m": 0.127, "striker_y_m": 0.1143,
                          "mic_distance_m": chain.mic_m})
        if v2 and chain.participation_declared:
            rig.attrs["modal_participation"] = plant.q
        runs_g = fh.create_group("runs")
        for spec in runs:
            W = 2 * math.pi * spec["freq_hz"]
            levels = np.asarray(spec["levels"], dtype=float)
            chans, imp = measure(plant, chain, W, levels, rng)
            truth.impacts[spec["run_id"]] = imp
            g = runs_g.create_group(spec["run_id"])
            g.attrs.update({"protocol": spec["protocol"], "excitation_freq_hz": spec["freq_hz"],
                            "nominal_level": float(levels[0]), "nominal_level_units": "m/s^2",
                            "start_time_iso": "2026-05-01T10:00:00"})
            if spec["protocol"].startswith("amplitude_ramp"):
                g.attrs["level_end"] = float(levels[-1])
            ch = g.create_group("channels")
            common = {"sample_rate_hz": chain.fs_hz, "start_time_s": 0.0}
            d = ch.create_dataset("velocity", data=chans["velocity"].astype(np.float32))
            d.attrs.update({"quantity": "plate_velocity", "units": "m/s", **common})
            if v2 and chain.declare_measurand:
                d.attrs["measurand"] = chain.measurand
            if v2 and chain.declare_delay:
                d.attrs["group_delay_s"] = chain.velocity_delay_s
            if v2 and chain.declare_filter:   # a digital decoder at the record's rate
                d.attrs.update({"filter_type": chain.decoder, "filter_order": chain.decoder_order,
                                "filter_cutoff_hz": chain.decoder_cutoff_hz,
                                "filter_sample_rate_hz": chain.fs_hz})
            for name, qty, units in (("plate", "plate_acceleration", "m/s^2"),
                                     ("base", "base_acceleration", "m/s^2"),
                                     ("mic", "sound_pressure", "Pa")):
                d = ch.create_dataset(name, data=chans[name].astype(np.float32))
                d.attrs.update({"quantity": qty, "units": units, **common})
    return truth
