"""ISO 532-1:2017 method 1 (Zwicker, time-varying sounds), compiled end to end in one pass.

One numba loop over the 48 kHz pressure samples does every step of the standard's
section 6 for all 28 third-octave bands at once, with nothing stored at the sample rate:

1. the 28 third-octave filters (three second-order sections each, the coefficients of
   ISO 532-1 table A.1), squaring, and the three first-order smoothing low-passes
   (time constant ``2 / (3 fc)``, at most ``2 / 3000`` s);
2. every 24th sample (2 kHz, 0.5 ms) the band levels, the core loudness of the 20
   critical bands (tables A.3-A.7: ``DLL``/``RAP`` low-frequency weighting, ``A0``
   transmission, ``DDF`` diffuse field, ``LTQ`` threshold in quiet, ``DCB``);
3. the nonlinear temporal decay (the two-capacitor network, 24 virtual sub-steps per
   frame; one frame of look-ahead for its linear interpolation);
4. the slopes of the specific loudness (table A.8 ``USL``, ``RNS``, ``ZUP``) and the
   total loudness, rounded as the standard prints it;
5. the temporal weighting of the total loudness (0.47 of a 3.5 ms and 0.53 of a 70 ms
   low-pass, again on 24 interpolated sub-steps; one more frame of look-ahead);
6. every 4th frame (2 ms) the output ``N(t)`` and a running sum of ``N'(z)`` (for the
   time-averaged specific loudness that DIN 45692 sharpness needs).

Memory is the 500 Hz loudness curve and a few hundred state numbers, whatever the
length of the record.  The order of operations follows MoSQITo (the reference of the
tests, ``tests/acoustics/test_acoustics.py``) where the standard leaves it open: the level is
taken at samples 0, 24, 48, ...; the interpolation of the last frame runs towards zero.
Two places follow the standard instead of MoSQITo: the decay network starts from rest
(MoSQITo's first step reads the record's last frame, a wrap-around of a NumPy index) and
the low-frequency weighting uses the ``RAP = 120 dB`` row of ``DLL`` above 100 dB
(MoSQITo uses no weighting there).  The first affects the first few milliseconds of a
record (within the tolerances the tests check from the first sample), the second only
third-octave levels above 100 dB below 300 Hz (where MoSQITo refuses levels above 120 dB).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from rattle_lab.exceptions import ParameterError

from ._nl_decay import NL_ITER, _coefficients

#: ISO 532-1 table A.1: the denominators' deviations (a1, a2) from (-2, 1) of the three
#: second-order sections of each third-octave filter (25 Hz ... 12.5 kHz) at 48 kHz.
_THIRD_OCTAVE_DA = np.array([
    [[-6.70260e-4, 6.59453e-4], [-3.75071e-4, 3.61926e-4], [-3.06523e-4, 2.97634e-4]],
    [[-8.47258e-4, 8.30131e-4], [-4.76448e-4, 4.55616e-4], [-3.88773e-4, 3.74685e-4]],
    [[-1.07210e-3, 1.04496e-3], [-6.06567e-4, 5.73553e-4], [-4.94004e-4, 4.71677e-4]],
    [[-1.35836e-3, 1.31535e-3], [-7.74327e-4, 7.22007e-4], [-6.29154e-4, 5.93771e-4]],
    [[-1.72380e-3, 1.65564e-3], [-9.91780e-4, 9.08866e-4], [-8.03529e-4, 7.47455e-4]],
    [[-2.19188e-3, 2.08388e-3], [-1.27545e-3, 1.14406e-3], [-1.02976e-3, 9.40900e-4]],
    [[-2.79386e-3, 2.62274e-3], [-1.64828e-3, 1.44006e-3], [-1.32520e-3, 1.18438e-3]],
    [[-3.57182e-3, 3.30071e-3], [-2.14252e-3, 1.81258e-3], [-1.71397e-3, 1.49082e-3]],
    [[-4.58305e-3, 4.15355e-3], [-2.80413e-3, 2.28135e-3], [-2.23006e-3, 1.87646e-3]],
    [[-5.90655e-3, 5.22622e-3], [-3.69947e-3, 2.87118e-3], [-2.92205e-3, 2.36178e-3]],
    [[-7.65243e-3, 6.57493e-3], [-4.92540e-3, 3.61318e-3], [-3.86007e-3, 2.97240e-3]],
    [[-1.00023e-2, 8.29610e-3], [-6.63788e-3, 4.55999e-3], [-5.15982e-3, 3.75306e-3]],
    [[-1.31230e-2, 1.04220e-2], [-9.02274e-3, 5.73132e-3], [-6.94543e-3, 4.71734e-3]],
    [[-1.73693e-2, 1.30947e-2], [-1.24176e-2, 7.20526e-3], [-9.46002e-3, 5.93145e-3]],
    [[-2.31934e-2, 1.64308e-2], [-1.73009e-2, 9.04761e-3], [-1.30358e-2, 7.44926e-3]],
    [[-3.13292e-2, 2.06370e-2], [-2.44342e-2, 1.13731e-2], [-1.82108e-2, 9.36778e-3]],
    [[-4.28261e-2, 2.59325e-2], [-3.49619e-2, 1.43046e-2], [-2.57855e-2, 1.17912e-2]],
    [[-5.91733e-2, 3.25054e-2], [-5.06072e-2, 1.79513e-2], [-3.69401e-2, 1.48094e-2]],
    [[-8.26348e-2, 4.05894e-2], [-7.40348e-2, 2.24476e-2], [-5.34977e-2, 1.85371e-2]],
    [[-1.17018e-1, 5.08116e-2], [-1.09516e-1, 2.81387e-2], [-7.85097e-2, 2.32872e-2]],
    [[-1.67714e-1, 6.37872e-2], [-1.63378e-1, 3.53729e-2], [-1.16419e-1, 2.93723e-2]],
    [[-2.42528e-1, 7.98576e-2], [-2.45161e-1, 4.43370e-2], [-1.73972e-1, 3.70015e-2]],
    [[-3.53142e-1, 9.96330e-2], [-3.69163e-1, 5.53535e-2], [-2.61399e-1, 4.65428e-2]],
    [[-5.16316e-1, 1.24177e-1], [-5.55473e-1, 6.89403e-2], [-3.93998e-1, 5.86715e-2]],
    [[-7.56635e-1, 1.55023e-1], [-8.34281e-1, 8.58123e-2], [-5.94547e-1, 7.43960e-2]],
    [[-1.10165e0, 1.91713e-1], [-1.23939e0, 1.05243e-1], [-8.91666e-1, 9.40354e-2]],
    [[-1.58477e0, 2.39049e-1], [-1.80505e0, 1.28794e-1], [-1.32500e0, 1.21333e-1]],
    [[-2.50630e0, 1.42308e-1], [-2.19464e0, 2.76470e-1], [-1.90231e0, 1.47304e-1]],
])
#: The sections' numerators (the same for every band): b = (1, 2, 1), (1, 0, -1), (1, -2, 1).
_SECTION_B1 = np.array([2.0, 0.0, -2.0])
_SECTION_B2 = np.array([1.0, -1.0, 1.0])
#: ISO 532-1 table A.1: the gain of each band's filter.
_THIRD_OCTAVE_GAIN = np.array([
    4.30764e-11, 8.59340e-11, 1.71424e-10, 3.41944e-10, 6.82035e-10, 1.36026e-9, 2.71261e-9,
    5.40870e-9, 1.07826e-8, 2.14910e-8, 4.28228e-8, 8.54316e-8, 1.70009e-7, 3.38215e-7,
    6.71990e-7, 1.33531e-6, 2.65172e-6, 5.25477e-6, 1.03780e-5, 2.04870e-5, 4.05198e-5,
    7.97914e-5, 1.56511e-4, 3.04954e-4, 5.99157e-4, 1.16544e-3, 2.27488e-3, 3.91006e-3,
])
#: Table A.3: upper levels of the ranges of the low-frequency weighting, dB.
_RAP = np.array([45.0, 55.0, 65.0, 71.0, 80.0, 90.0, 100.0, 120.0])
#: Table A.3: level corrections of the 11 third-octave bands 25-250 Hz per range, dB.
_DLL = np.array([
    [-32, -24, -16, -10, -5, 0, -7, -3, 0, -2, 0],
    [-29, -22, -15, -10, -4, 0, -7, -2, 0, -2, 0],
    [-27, -19, -14, -9, -4, 0, -6, -2, 0, -2, 0],
    [-25, -17, -12, -9, -3, 0, -5, -2, 0, -2, 0],
    [-23, -16, -11, -7, -3, 0, -4, -1, 0, -1, 0],
    [-20, -14, -10, -6, -3, 0, -4, -1, 0, -1, 0],
    [-18, -12, -9, -6, -2, 0, -3, -1, 0, -1, 0],
    [-15, -10, -8, -4, -2, 0, -3, -1, 0, -1, 0],
], dtype=float)
#: Table A.4: threshold in quiet of the 20 critical bands, dB.
_LTQ = np.array([30, 18, 12, 8, 7, 6, 5, 4, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3, 3], dtype=float)
#: Table A.5: transmission through the outer ear, dB.
_A0 = np.array([0, 0, 0, 0, 0, 0, 0, 0, 0, 0, -0.5, -1.6, -3.2, -5.4, -5.6, -4, -1.5, 2, 5, 12])
#: Table A.6: level difference between diffuse and free field, dB.
_DDF = np.array([0, 0, 0.5, 0.9, 1.2, 1.6, 2.3, 2.8, 3, 2, 0, -1.4, -2, -1.9, -1, 0.5, 3, 4,
                 4.3, 4])
#: Table A.7: correction for the critical bands' widths below 500 Hz, dB.
_DCB = np.array([-0.25, -0.6, -0.8, -0.8, -0.5, 0, 0.5, 1.1, 1.5, 1.7, 1.8, 1.8, 1.7, 1.6, 1.4,
                 1.2, 0.8, 0.5, 0, -0.5])
#: Table A.8: upper limits of the approximated critical bands, Bark.
_ZUP = np.array([0.9, 1.8, 2.8, 3.5, 4.4, 5.4, 6.6, 7.9, 9.2, 10.6, 12.3, 13.8, 15.2, 16.7,
                 18.1, 19.3, 20.6, 21.8, 22.7, 23.6, 24.0])
#: Table A.8: ranges of specific loudness for the upper slopes, sone/Bark.
_RNS = np.array([21.5, 18, 15.1, 11.5, 9, 6.1, 4.4, 3.1, 2.13, 1.36, 0.82, 0.42, 0.30, 0.22,
                 0.15, 0.10, 0.035, 0.0])
#: Table A.8: steepness of the upper slopes, sone/Bark per Bark (rows: RNS ranges,
#: columns: the critical band the slope starts in, the last for bands 8 and above).
_USL = np.array([
    [13, 8.2, 6.3, 5.5, 5.5, 5.5, 5.5, 5.5], [9, 7.5, 6, 5.1, 4.5, 4.5, 4.5, 4.5],
    [7.8, 6.7, 5.6, 4.9, 4.4, 3.9, 3.9, 3.9], [6.2, 5.4, 4.6, 4.0, 3.5, 3.2, 3.2, 3.2],
    [4.5, 3.8, 3.6, 3.2, 2.9, 2.7, 2.7, 2.7], [3.7, 3.0, 2.8, 2.35, 2.2, 2.2, 2.2, 2.2],
    [2.9, 2.3, 2.1, 1.9, 1.8, 1.7, 1.7, 1.7], [2.4, 1.7, 1.5, 1.35, 1.3, 1.3, 1.3, 1.3],
    [1.95, 1.45, 1.3, 1.15, 1.1, 1.1, 1.1, 1.1], [1.5, 1.2, 0.94, 0.86, 0.82, 0.82, 0.82, 0.82],
    [0.72, 0.67, 0.64, 0.63, 0.62, 0.62, 0.62, 0.62], [0.59, 0.53, 0.51, 0.50, 0.42, 0.42, 0.42, 0.42],
    [0.40, 0.33, 0.26, 0.24, 0.24, 0.22, 0.22, 0.22], [0.27, 0.21, 0.20, 0.18, 0.17, 0.17, 0.17, 0.17],
    [0.16, 0.15, 0.14, 0.12, 0.11, 0.11, 0.11, 0.11], [0.12, 0.11, 0.10, 0.08, 0.08, 0.08, 0.08, 0.08],
    [0.09, 0.08, 0.07, 0.06, 0.06, 0.06, 0.06, 0.05], [0.06, 0.05, 0.03, 0.02, 0.02, 0.02, 0.02, 0.02],
])

FS_HZ = 48000
N_BANDS = 28
N_CORE = 21
N_BARK = 240
_DEC_LEVEL = 24     # 48 kHz -> 2 kHz
_DEC_OUT = 4        # 2 kHz -> 500 Hz
_I_REF = 4e-10      # (2e-5 Pa)^2 in the standard's units of the filtered square
_TINY = 1e-12


def _smoothing() -> np.ndarray:
    """Coefficient ``a`` of each band's first-order smoothing low-pass, y = (1-a) x + a y."""
    fc = 1000.0 * 10.0 ** ((np.arange(N_BANDS) - 16) / 10.0)
    tau = np.where(fc <= 1000.0, 2.0 / (3.0 * fc), 2.0 / 3000.0)
    return np.exp(-1.0 / (FS_HZ * tau))


def _core_tables(diffuse: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The level tables of section 6.3.2 folded into factors on the band energies.

    With ``e = 10^(L/10)`` a band's energy relative to 20 uPa, the standard's tests and
    corrections on levels become products and comparisons on energies (no logarithm per
    frame): ``L > RAP - DLL`` is ``e > 10^((RAP - DLL)/10)``; ``10^((L + DLL)/10)`` is
    ``e 10^(DLL/10)``; for the critical bands ``L_E = L - A0 (+ DDF)`` exceeds ``LTQ`` when
    ``e > 10^((LTQ + A0 - DDF)/10)`` and then ``10^((L_E - DCB - LTQ)/10)`` is
    ``e 10^((-A0 + DDF - DCB - LTQ)/10)``.
    """
    ddf = _DDF if diffuse else np.zeros(20)
    rap_e = 10.0 ** ((_RAP[:, None] - _DLL) / 10.0)          # (8, 11)
    dll_f = 10.0 ** (_DLL / 10.0)                            # (8, 11)
    thr_e = 10.0 ** ((_LTQ + _A0 - ddf) / 10.0)              # (20,)
    rel_f = 10.0 ** ((-_A0 + ddf - _DCB - _LTQ) / 10.0)      # (20,)
    return rap_e, dll_f, thr_e, rel_f


#: ``0.0635 10^(0.025 LTQ)``, the factor of the core loudness of each critical band.
_CORE_F = 0.0635 * 10.0 ** (0.025 * _LTQ)


@numba.njit(cache=True, fastmath={"contract"})
def _core_loudness(energy: np.ndarray, rap_e: np.ndarray, dll_f: np.ndarray,
                   thr_e: np.ndarray, rel_f: np.ndarray, core: np.ndarray) -> None:
    """Core loudness of the 20 critical bands (and a 21st, zero) from the 28 band
    energies ``e = 10^(L/10)`` (section 6.3.2; the tables as :func:`_core_tables` folds them)."""
    g0 = 0.0
    g1 = 0.0
    g2 = 0.0
    for i in range(11):      # low-frequency weighting; the three lowest critical bands
        j = 0
        while energy[i] > rap_e[j, i] and j < 7:
            j += 1
        ti = energy[i] * dll_f[j, i]
        if i < 6:
            g0 += ti
        elif i < 9:
            g1 += ti
        else:
            g2 += ti
    for k in range(20):
        if k == 0:
            e = g0
        elif k == 1:
            e = g1
        elif k == 2:
            e = g2
        else:
            e = energy[k + 8]
        n = 0.0
        if e > thr_e[k]:
            n = _CORE_F[k] * (math.sqrt(math.sqrt(0.75 + 0.25 * e * rel_f[k])) - 1.0)
            if n < 0.0:
                n = 0.0
        core[k] = n
    core[20] = 0.0
    if core[0] > 0.0:
        korry = 0.4 + 0.32 * core[0] ** 0.2
        if korry <= 1.0:
            core[0] *= korry


@numba.njit(cache=True)
def _slopes(core: np.ndarray, spec: np.ndarray, fill: bool) -> float:
    """Total loudness, sone, and the specific loudness on a 0.1 Bark grid (``spec``, 240
    values at z = 0.1 ... 24 Bark) of one frame of (decayed) core loudness: the upper
    slopes of table A.8, section 6.4 of the standard."""
    total = 0.0
    z1 = 0.0
    n1 = 0.0
    n2 = 0.0
    z2 = 0.0
    iz = 0
    j = 0
    for i in range(N_CORE):
        zup = _ZUP[i] + 0.0001
        ig = i - 1
        if ig > 7:
            ig = 7
        if ig < 0:
            ig = 0
        first = True
        while z1 < zup or first:
            first = False
            if n1 > core[i]:           # a falling slope
                n2 = _RNS[j]
                if n2 < core[i]:
                    n2 = core[i]
                usl = _USL[j, ig]
                dz = (n1 - n2) / usl
                z2 = z1 + dz
                if z2 > zup:
                    z2 = zup
                    dz = z2 - z1
                    n2 = n1 - dz * usl
                total += dz * (n1 + n2) / 2.0
                while fill and iz < N_BARK and (iz + 1) * 0.1 <= z2 + 1e-9:
                    spec[iz] = n1 - ((iz + 1) * 0.1 - z1) * usl
                    iz += 1
                while n2 <= _RNS[j] and j < 17:
                    j += 1
            else:                      # a plateau at the band's core loudness
                if n1 < core[i]:
                    j = 0
                    while _RNS[j] >= core[i] and j < 17:
                        j += 1
                z2 = zup
                n2 = core[i]
                total += n2 * (z2 - z1)
                while fill and iz < N_BARK and (iz + 1) * 0.1 <= z2 + 1e-9:
                    spec[iz] = n2
                    iz += 1
            z1 = z2
            n1 = n2
    while fill and iz < N_BARK:
        spec[iz] = 0.0
        iz += 1
    if total < 0.0:
        total = 0.0
    if total <= 16.0:
        return math.floor(total * 1000.0 + 0.5) / 1000.0
    return math.floor(total * 100.0 + 0.5) / 100.0


@numba.njit(cache=True, fastmath={"contract"})
def _decay_frame(cur: np.ndarray, nxt: np.ndarray, uo: np.ndarray, u2: np.ndarray,
                 b: np.ndarray, x: np.ndarray, step: np.ndarray, out: np.ndarray) -> None:
    """The nonlinear decay network over the 24 sub-steps of one frame (section 6.3.3):
    ``cur`` the frame's core loudness, ``nxt`` the next frame's (for the interpolation);
    ``uo``, ``u2`` the capacitors' state, carried; ``out`` the value at the first sub-step.
    ``x``, ``step``: work arrays.  Bands are the inner loop, branches are selects."""
    b0, b1, b2, b3, b4, b5 = b[0], b[1], b[2], b[3], b[4], b[5]
    for r in range(N_CORE):
        step[r] = (nxt[r] - cur[r]) / NL_ITER
        x[r] = cur[r]
    for m in range(NL_ITER):
        if m > 0:
            for r in range(N_CORE):
                x[r] = x[r] + step[r]
        for r in range(N_CORE):
            xr = x[r]
            uo_p = uo[r]
            u2_p = u2[r]
            higher = uo_p > u2_p
            cand = uo_p * b2 - u2_p * b3          # both capacitors discharge
            new = cand if (higher and cand >= xr) else xr
            cand = uo_p * b4                      # the long branch alone
            new = cand if ((not higher) and cand >= xr) else new
            cand = uo_p * b0 - u2_p * b1
            u2n = cand if (xr < uo_p and higher and cand <= new) else new
            cand = (u2_p - xr) * b5 + xr
            u2n = cand if (xr >= uo_p and not (abs(xr - uo_p) < 1e-5 and new <= u2_p)) else u2n
            uo[r] = new
            u2[r] = u2n
        if m == 0:
            for r in range(N_CORE):
                out[r] = uo[r]


@numba.njit(cache=True)
def _weight_frame(cur: float, nxt: float, state: np.ndarray, a: np.ndarray) -> None:
    """Temporal weighting: run both low-passes over sub-steps 1..23 of a frame (after its
    sub-step 0) towards the next frame's loudness, then sub-step 0 of the next frame."""
    step = (nxt - cur) / NL_ITER
    for k in range(2):
        y = state[k]
        x = cur
        for _m in range(1, NL_ITER):
            x = x + step
            y = (1.0 - a[k]) * x + a[k] * y
        state[k] = (1.0 - a[k]) * nxt + a[k] * y


@numba.njit(cache=True, fastmath={"contract"})
def _run(p: np.ndarray, da: np.ndarray, gain: np.ndarray, smooth: np.ndarray,
         rap_e: np.ndarray, dll_f: np.ndarray, thr_e: np.ndarray, rel_f: np.ndarray,
         b_decay: np.ndarray, a_weight: np.ndarray, n_out: np.ndarray,
         spec_sum: np.ndarray) -> int:
    """The whole chain over ``p`` (Pa at 48 kHz); fills ``n_out`` (N(t) at 500 Hz) and
    ``spec_sum`` (the sum of N'(z) over those output frames); returns their count."""
    n = p.size
    n_frames = (n + _DEC_LEVEL - 1) // _DEC_LEVEL
    a1 = np.empty((3, N_BANDS))
    a2 = np.empty((3, N_BANDS))
    for s in range(3):
        for bnd in range(N_BANDS):
            a1[s, bnd] = -2.0 - da[bnd, s, 0]
            a2[s, bnd] = 1.0 - da[bnd, s, 1]
    z1 = np.zeros((3, N_BANDS))
    sb1_0, sb1_1, sb1_2 = _SECTION_B1[0], _SECTION_B1[1], _SECTION_B1[2]
    sb2_0, sb2_1, sb2_2 = _SECTION_B2[0], _SECTION_B2[1], _SECTION_B2[2]
    z2 = np.zeros((3, N_BANDS))
    sm = np.zeros((3, N_BANDS))
    c0 = 1.0 - smooth
    gain2 = gain * gain
    energy = np.empty(N_BANDS)
    core_prev = np.zeros(N_CORE)
    core_cur = np.zeros(N_CORE)
    decayed = np.empty(N_CORE)
    work_x = np.empty(N_CORE)
    work_step = np.empty(N_CORE)
    uo = np.zeros(N_CORE)
    u2 = np.zeros(N_CORE)
    spec = np.zeros(N_BARK)
    wstate = np.zeros(2)
    n_prev = 0.0        # total loudness of the frame before the one being decayed
    n_written = 0
    # frame f's level is taken after sample 24 f; it is decayed once frame f + 1 is known
    # (the interpolation), and weighted once the loudness of frame f + 1 is known
    for frame in range(n_frames + 1):
        if frame < n_frames:
            lo = 0 if frame == 0 else (frame - 1) * _DEC_LEVEL + 1
            for i in range(lo, frame * _DEC_LEVEL + 1):
                x = p[i]
                # each band through its three sections (direct form II transposed, as
                # sosfilt) and its three smoothing low-passes in one pass: the bands are
                # the inner loop, so the compiler runs several side by side in SIMD lanes
                for bnd in range(N_BANDS):
                    y0 = x + z1[0, bnd]
                    z1[0, bnd] = x * sb1_0 - a1[0, bnd] * y0 + z2[0, bnd]
                    z2[0, bnd] = x * sb2_0 - a2[0, bnd] * y0
                    y1 = y0 + z1[1, bnd]
                    z1[1, bnd] = y0 * sb1_1 - a1[1, bnd] * y1 + z2[1, bnd]
                    z2[1, bnd] = y0 * sb2_1 - a2[1, bnd] * y1
                    y2 = y1 + z1[2, bnd]
                    z1[2, bnd] = y1 * sb1_2 - a1[2, bnd] * y2 + z2[2, bnd]
                    z2[2, bnd] = y1 * sb2_2 - a2[2, bnd] * y2
                    w = gain2[bnd] * (y2 * y2)
                    a = smooth[bnd]
                    c = c0[bnd]
                    s0 = c * w + a * sm[0, bnd]
                    s1 = c * s0 + a * sm[1, bnd]
                    s2 = c * s1 + a * sm[2, bnd]
                    sm[0, bnd] = s0
                    sm[1, bnd] = s1
                    sm[2, bnd] = s2
            for bnd in range(N_BANDS):
                energy[bnd] = (sm[2, bnd] + _TINY) / _I_REF
            _core_loudness(energy, rap_e, dll_f, thr_e, rel_f, core_cur)
        else:
            core_cur[:] = 0.0              # the last frame decays towards silence
        if frame >= 1:
            k = frame - 1
            _decay_frame(core_prev, core_cur, uo, u2, b_decay, work_x, work_step, decayed)
            n_tot = _slopes(decayed, spec, k % _DEC_OUT == 0)
            if k == 0:
                wstate[0] = (1.0 - a_weight[0]) * n_tot
                wstate[1] = (1.0 - a_weight[1]) * n_tot
            else:
                _weight_frame(n_prev, n_tot, wstate, a_weight)
            if k % _DEC_OUT == 0:
                n_out[n_written] = 0.47 * wstate[0] + 0.53 * wstate[1]
                for iz in range(N_BARK):
                    spec_sum[iz] += spec[iz]
                n_written += 1
            n_prev = n_tot
        core_prev[:] = core_cur
    return n_written


def time_varying_loudness(p48: np.ndarray, *, diffuse: bool = False
                          ) -> tuple[np.ndarray, np.ndarray]:
    """ISO 532-1 time-varying loudness of a 48 kHz pressure signal, compiled.

    Parameters
    ----------
    p48 : ndarray
        Sound pressure, Pa, sampled at 48 kHz.
    diffuse : bool
        Diffuse field instead of free (frontal) field.

    Returns
    -------
    n_t : ndarray
        Total loudness ``N(t)``, sone, every 2 ms from the first sample.
    spec_mean : ndarray, shape (240,)
        Time-averaged specific loudness ``N'(z)``, sone/Bark, at z = 0.1, 0.2, ... 24 Bark.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(48000) / 48000
    >>> p = 2e-5 * 10 ** (40 / 20) * np.sqrt(2) * np.sin(2 * np.pi * 1000 * t)
    >>> n_t, _ = time_varying_loudness(p)
    >>> round(float(n_t[-100]), 2)   # the standard's anchor: 40 dB at 1 kHz is 1 sone
    1.0
    """
    x = np.ascontiguousarray(p48, dtype=np.float64)
    n_frames = (x.size + _DEC_LEVEL - 1) // _DEC_LEVEL
    n_out = np.empty((n_frames + _DEC_OUT - 1) // _DEC_OUT)
    spec_sum = np.zeros(N_BARK)
    a_weight = np.exp(-1.0 / (2000.0 * NL_ITER * np.array([3.5e-3, 70e-3])))
    count = _run(x, _THIRD_OCTAVE_DA, _THIRD_OCTAVE_GAIN, _smoothing(),
                 *_core_tables(bool(diffuse)), _coefficients(), a_weight, n_out, spec_sum)
    return n_out[:count], spec_sum / max(count, 1)


def stationary_loudness(third_octave_db: object, *, diffuse: bool = False
                        ) -> tuple[float, np.ndarray]:
    """ISO 532-1 loudness of a stationary sound from its third-octave band levels (clause 5).

    The method for stationary sounds with measured band levels as input: the core loudness
    of the 20 critical bands (tables A.3-A.7) and the slopes of table A.8, the same steps as
    each frame of :func:`time_varying_loudness` without the temporal ones.

    Parameters
    ----------
    third_octave_db : array_like, shape (28,)
        Sound pressure levels of the third-octave bands 25 Hz ... 12.5 kHz, dB re 20 uPa.
    diffuse : bool
        Diffuse field instead of free (frontal) field.

    Returns
    -------
    n_sone : float
        Total loudness, sone, rounded as the standard prints it (0.001 sone up to 16 sone,
        0.01 sone above).
    spec : ndarray, shape (240,)
        Specific loudness ``N'(z)``, sone/Bark, at z = 0.1, 0.2, ... 24 Bark.

    Raises
    ------
    ParameterError
        For anything but 28 finite levels.

    Examples
    --------
    >>> import numpy as np
    >>> levels = np.full(28, -60.0)
    >>> levels[16] = 40.0            # 40 dB in the 1 kHz band alone
    >>> stationary_loudness(levels)[0]
    0.927

    (A 1 kHz tone at 40 dB is 1 sone: through the band filters it also leaves levels in the
    neighbouring bands, which this example leaves out.)
    """
    levels = np.asarray(third_octave_db, dtype=float)
    if levels.shape != (N_BANDS,) or not np.all(np.isfinite(levels)):
        raise ParameterError(f"`third_octave_db` must be {N_BANDS} finite third-octave levels "
                             f"(25 Hz ... 12.5 kHz), dB; got shape {levels.shape}")
    core = np.zeros(N_CORE)
    spec = np.zeros(N_BARK)
    _core_loudness(10.0 ** (levels / 10.0), *_core_tables(bool(diffuse)), core)
    return float(_slopes(core, spec, True)), spec


__all__ = ["FS_HZ", "stationary_loudness", "time_varying_loudness"]
