"""How fast can ECMA-418-2 be on one core?  The cost of two of its steps, compiled or FFT.

Issue 26 asks every psychoacoustic metric to run at >= 50 times real time per core.
ECMA-418-2's tonality (which also gives its loudness) is the slow one: sottek-hearing-model
takes about 6 CPU seconds per second of sound.  This benchmark times two steps that any
implementation of the standard has to do, with the fastest code we have for each, on one
thread, per second of 48 kHz sound.  Their sum is a floor: the whole method (outer and
middle ear filter, rectification, nonlinearity, the ACF's averaging and windowing, noise
reduction, the roughness's envelope spectra) costs more.

1. **The auditory filter bank** (ECMA-418-2:2025 section 5.1.4): 53 bands on the half-Bark
   scale ``z = 0.5 .. 26.5``, centre ``F(z) = (df0 / c) sinh(c z)``, ``df0 = 81.9289 Hz``,
   ``c = 0.1618``, each a complex recursive filter of order 5 at 48 kHz (5 feedback and 5
   feed-forward coefficients).  Here as one numba loop over the samples with the 53 bands
   inside (vectorised by the compiler).
2. **The tonality's autocorrelation** (section 6.2.2, Table 4): each band cut into blocks of
   ``s_b`` = 8192 (3 bands), 4096 (13), 2048 (9), 1024 (28) samples with 75 % overlap
   (hop ``s_b / 4``), and each block's ACF as ``irfft(|rfft(x, 2 s_b)|^2)``.  Here SciPy's
   pocketfft in single precision on all blocks of a band at once (the fastest of NumPy and
   SciPy, double and single, on this machine).

The parameters are those sottek-hearing-model 0.1.14 quotes from ECMA-418-2:2025 (the
standard's text was not available to us); the filter coefficients follow its equations 14
and 15 (poles at ``d e^(i 2 pi F / fs)``, ``d = exp(-1 / (fs tau))``).

Run: ``python benchmarks/ecma418_floor.py [seconds]`` (default 10 s of sound).
"""

from __future__ import annotations

import sys
import time
from math import comb

import numba
import numpy as np
from threadpoolctl import threadpool_limits

FS = 48000.0
N_BANDS = 53
ORDER = 5
#: Block sizes of ECMA-418-2 Table 4, per band (hop: a quarter of the block).
BLOCKS = (8192,) * 3 + (4096,) * 13 + (2048,) * 9 + (1024,) * 28


def coefficients() -> tuple[np.ndarray, np.ndarray]:
    """Feed-forward ``b`` (53 x 5) and feedback ``a`` (53 x 6) of the 53 band filters."""
    df0, c = 81.9289, 0.1618
    z = np.arange(0.5, 27.0, 0.5)
    f_c = df0 / c * np.sinh(c * z)
    bw = np.sqrt(df0**2 + (c * f_c) ** 2)
    tau = comb(2 * ORDER - 2, ORDER - 1) / 2 ** (2 * ORDER - 1) / bw
    d = np.exp(-1.0 / (FS * tau))
    e = np.array([0.0, 1.0, 11.0, 11.0, 1.0])
    a = np.empty((N_BANDS, ORDER + 1), complex)
    b = np.empty((N_BANDS, ORDER), complex)
    for j in range(N_BANDS):
        rot = np.exp(2j * np.pi * f_c[j] * np.arange(ORDER + 1) / FS)
        a[j] = np.array([comb(ORDER, m) * (-d[j]) ** m for m in range(ORDER + 1)]) * rot
        gain = (1 - d[j]) ** ORDER / np.sum(e[1:] * d[j] ** np.arange(1, ORDER))
        b[j] = gain * d[j] ** np.arange(ORDER) * e * rot[:ORDER]
    return b, a


@numba.njit(fastmath=True)
def filter_bank(x: np.ndarray, b: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``2 Re`` of each band's output (samples x bands), direct form, bands innermost."""
    nb = b.shape[0]
    out = np.empty((x.size, nb))
    y = np.zeros((ORDER, nb), dtype=np.complex128)   # y[n-1] .. y[n-5], ring buffer
    xs = np.zeros(ORDER)
    for n in range(x.size):
        for m in range(ORDER - 1, 0, -1):
            xs[m] = xs[m - 1]
        xs[0] = x[n]
        head = n % ORDER
        for j in range(nb):
            acc = 0j
            for m in range(ORDER):
                acc += b[j, m] * xs[m]
            for m in range(1, ORDER + 1):
                acc -= a[j, m] * y[(head - m) % ORDER, j]
            y[head, j] = acc
            out[n, j] = 2.0 * acc.real
        # the slot written now is y[n]; the next sample reads it as y[(n+1) - 1]
    return out


def acf_blocks(bands: np.ndarray) -> float:
    """Every band's blocks' ACFs by FFT, in single precision (SciPy's pocketfft: 2 times
    NumPy's in double, 4 times in single, on this machine); returns a checksum (so
    nothing is optimised away)."""
    from scipy import fft

    total = 0.0
    for j, s_b in enumerate(BLOCKS):
        x = bands[:, j].astype(np.float32)
        hop = s_b // 4
        n_blocks = max(1, (x.size - s_b) // hop + 1)
        idx = np.arange(s_b)[None, :] + hop * np.arange(n_blocks)[:, None]
        spec = fft.rfft(x[idx], n=2 * s_b, axis=1)
        acf = fft.irfft(spec.real**2 + spec.imag**2, n=2 * s_b, axis=1)[:, :s_b]
        total += float(acf[:, 0].sum(dtype=np.float64))
    return total


def floor_rows(seconds: float = 10.0) -> list[tuple[str, float, float]]:
    """(step, seconds of sound, CPU s) of the filter bank and the ACFs, one thread."""
    rng = np.random.default_rng(0)
    x = rng.normal(0.0, 0.02, round(seconds * FS))
    b, a = coefficients()
    filter_bank(x[:1000], b, a)   # compile
    with threadpool_limits(1):
        t0 = time.process_time()
        bands = filter_bank(x, b, a)
        t_bank = time.process_time() - t0
        acf_blocks(bands[: round(FS)])   # warm the FFT plans
        t0 = time.process_time()
        acf_blocks(bands)
        t_acf = time.process_time() - t0
    # the filters are the standard's: unit gain at each band's centre (a check of the above)
    f_c = 81.9289 / 0.1618 * np.sinh(0.1618 * np.arange(0.5, 27.0, 0.5))
    for j in (5, 26, 45):
        w = np.exp(-2j * np.pi * f_c[j] / FS * np.arange(ORDER + 1))
        g = abs(np.dot(b[j], w[:ORDER]) / np.dot(a[j], w))
        assert abs(g - 1.0) < 0.02, (j, g)
    return [("ECMA-418-2 floor: 53-band order-5 filter bank (numba)", seconds, t_bank),
            ("ECMA-418-2 floor: tonality ACFs, Table 4 blocks (float32 FFT)", seconds, t_acf),
            ("ECMA-418-2 floor: the two together", seconds, t_bank + t_acf)]


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
    print(f"{'step (one thread, 48 kHz)':62s} {'sound s':>8s} {'CPU s':>8s} {'x real time':>12s}")
    for name, sound, t in floor_rows(seconds):
        print(f"{name:62s} {sound:8.1f} {t:8.3f} {sound / t:12.1f}")


if __name__ == "__main__":
    main()
