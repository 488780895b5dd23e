"""A-weighting and third-octave filters: exact analog responses on FFT bins (rattle_lab) against
the digital IIR filters a user would otherwise pick (bilinear transform, scipy.signal.butter with
``fs``), and the cost of ISO 532-1 loudness (MoSQITo).

Error: the largest deviation from the IEC 61672-1 A-weighting design goal over 20 Hz-20 kHz
(measured with a steady tone at each exact third-octave frequency), and the number of the 31
third-octave bands 20 Hz-20 kHz (those below Nyquist) that leave the IEC 61260 class-1
attenuation mask.  Time: 10 s of noise at 48 kHz (wall clock on a shared 2-core machine, under
load: compare within a row only).

Run: ``python benchmarks/bench_acoustic_filters.py``
"""

from __future__ import annotations

import time

import numpy as np
from scipy import signal

from rattle_lab.acoustics import apply_weighting, band_edges_hz, band_mean_squares, loudness
from rattle_lab.acoustics._filters import weighting_response

FS = 48000.0
G = 10 ** 0.3


def _digital_a_sos(fs: float) -> np.ndarray:
    # the usual digital A-weighting: the analog zpk through the bilinear transform
    f1, f2, f3, f4 = 20.598997, 107.65265, 737.86223, 12194.217
    z = [0.0] * 4
    p = [-2 * np.pi * f for f in (f1, f1, f2, f3, f4, f4)]
    zd, pd, kd = signal.bilinear_zpk(z, p, 1.0, fs)
    sos = signal.zpk2sos(zd, pd, kd)
    _, h = signal.sosfreqz(sos, worN=[1000.0], fs=fs)
    sos[0, :3] /= abs(h[0])
    return sos


def _a_error_db(weight) -> float:
    worst = 0.0
    for k in range(-17, 14):
        f = 1000.0 * 10 ** (k / 10)
        if f >= FS / 2:
            continue
        t = np.arange(int(2 * FS)) / FS
        x = np.sin(2 * np.pi * f * t)
        y = weight(x)[int(FS):]  # the second second: steady state
        got = 10 * np.log10(np.mean(y**2) / 0.5)
        goal = 20 * np.log10(abs(weighting_response("A", f)))
        worst = max(worst, abs(got - goal))
    return worst


def _mask_failures(gain_db) -> int:
    xs = np.array([0, 1 / 8, 1 / 4, 3 / 8, 1 / 2, 1, 2, 3, 4])
    lo = np.array([-0.3, -0.4, -0.6, -1.3, -5.0, -np.inf, -np.inf, -np.inf, -np.inf])
    hi = np.array([0.3, 0.3, 0.3, 0.3, -2.0, -17.5, -42.0, -61.0, -70.0])
    om = 1 + (G ** (1 / 6) - 1) / (G**0.5 - 1) * (G**xs - 1)
    bad = 0
    for x_band in range(-17, 14):
        lo_e, fm, hi_e = band_edges_hz(x_band)
        if hi_e >= FS / 2:
            continue
        f = np.concatenate([fm / om[::-1], fm * om[1:]])
        lim_lo, lim_hi = np.concatenate([lo[::-1], lo[1:]]), np.concatenate([hi[::-1], hi[1:]])
        keep = f < FS / 2
        g = gain_db(x_band, f[keep])
        bad += int(np.any((g < lim_lo[keep] - 1e-9) | (g > lim_hi[keep] + 1e-9)))
    return bad


def main() -> None:
    rng = np.random.default_rng(0)
    noise = rng.standard_normal(int(10 * FS))
    sos_a = _digital_a_sos(FS)
    rows = []
    t0 = time.perf_counter()
    apply_weighting(noise, FS, "A")
    t_fft = time.perf_counter() - t0
    t0 = time.perf_counter()
    signal.sosfilt(sos_a, noise)
    t_iir = time.perf_counter() - t0
    rows.append(("A-weighting, exact analog on FFT bins (rattle_lab)", t_fft,
                 f"{_a_error_db(lambda x: apply_weighting(x, FS, 'A')):.3f} dB"))
    rows.append(("A-weighting, bilinear IIR (scipy.signal.bilinear_zpk)", t_iir,
                 f"{_a_error_db(lambda x: signal.sosfilt(sos_a, x)):.3f} dB"))
    from rattle_lab.acoustics import band_gain

    t0 = time.perf_counter()
    band_mean_squares(noise, FS)
    t_bands = time.perf_counter() - t0
    rows.append(("1/3-octave, analog Butterworth-3 on FFT (rattle_lab)", t_bands,
                 f"{_mask_failures(lambda b, f: 20 * np.log10(band_gain(b, f))):d} bands fail"))

    def digital_gain(b: int, f: np.ndarray) -> np.ndarray:
        lo, _, hi = band_edges_hz(b)
        sos = signal.butter(3, [lo, hi], "bandpass", fs=FS, output="sos")
        return 20 * np.log10(np.abs(signal.sosfreqz(sos, worN=f, fs=FS)[1]))

    t0 = time.perf_counter()
    for b in range(-17, 14):
        lo, _, hi = band_edges_hz(b)
        if hi < FS / 2:
            signal.sosfilt(signal.butter(3, [lo, hi], "bandpass", fs=FS, output="sos"), noise)
    t_dig = time.perf_counter() - t0
    rows.append(("1/3-octave, digital Butterworth-3 (scipy.signal.butter fs=)", t_dig,
                 f"{_mask_failures(digital_gain):d} bands fail"))
    t0 = time.perf_counter()
    res = loudness(np.sqrt(2) * 20e-6 * 10 ** 3 * np.sin(2 * np.pi * 1000 * np.arange(int(FS))
                                                          / FS), FS)
    t_loud = time.perf_counter() - t0
    rows.append(("ISO 532-1 loudness, 1 s of 1 kHz at 60 dB (MoSQITo)", t_loud,
                 f"{res.n5_sone:.3f} sone (4.0)"))
    print(f"{'method':<62} {'time (s)':>9}  error")
    print("-" * 62 + " " + "-" * 9 + "  " + "-" * 24)
    for name, t, err in rows:
        print(f"{name:<62} {t:>9.3f}  {err}")


if __name__ == "__main__":
    main()
