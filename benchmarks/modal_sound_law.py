"""Why a campaign's first-peak SPL law differs from one impact's (issue 24, ask 3).

The multi-mode model (thesis plate, the omitted modes' element, Kelvin-Voigt striker, one
48-term Ritz basis) is run for 30 forcing periods as ``benchmarks/modal_convergence.py``
runs it (285 Pa, 2 zeta = 0.1, omega = 1.1 by default), microphone 0.3 m on axis at 50 kHz
through the microphone model.  Each impact's *own* sound is found by superposition, the
model being linear outside the contact: the run is continued from 2 ms before the impact
once with the striker and once without it (gap 1 m), and the difference of the two
microphone signals is the sound of that impact's contact force alone.  The same is done for
one impact from rest (mode 1 at the gap moving at 0.5, 1, 2 and 4 m/s, no forcing: what
``benchmarks/modal_first_peak.py`` sweeps).

Printed, each as a straight line ``p = S v_in + c`` fitted with the pipeline's
``fit_linear_law``:

* one impact from rest: its own sound (largest ``|p|`` within 300 us of the direct sound's
  arrival), and the pipeline's first-peak rule (:func:`rattle_lab.detect.sound_peaks`) on the
  whole record, which also holds the plate's elastic deceleration at the gap;
* the campaign: each impact's own sound alike; the first-peak rule on the own sound alone;
  the first-peak rule on the record as the pipeline reads it (the forced-mode sinusoid fitted
  over 3 ms before the arrival and subtracted); and what that reading holds besides the own
  sound: the record less the fitted sinusoid less the own sound, at the reading's time,
  signed (positive where it adds to the own sound's ``|p|``; ``fit_linear_law`` fits
  magnitudes, so this line is ``numpy.polyfit``'s).

Run: ``python benchmarks/modal_sound_law.py [--modes 64] [--omega 1.1]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import modal_convergence as mc  # noqa: E402

from rattle_lab.detect import sound_peaks  # noqa: E402
from rattle_lab.fit import fit_linear_law  # noqa: E402
from rattle_lab.model.modal import (KelvinVoigtContact, ModalState, microphone,  # noqa: E402
                                    modal_channels, plate_system, simulate_modal)
from rattle_lab.model.modal._sound import (C_AIR_M_S, plate_surface,  # noqa: E402
                                           rayleigh_pressure, residual_pressure)

R_MIC_M = 0.3
EARLY_S = 300e-6      # the own sound's peak is read within this of the arrival
LEAD_S = 2e-3         # the superposition's runs start this long before an impact
SPAN_S = 8e-3       # beyond the 5 ms sound window after the arrival


def heard(system: object, res: object, t_s: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """The microphone signal of ``res`` over ``t_s`` (velocities held outside
    ``[t0, t1]``: the differences taken here cancel there)."""
    plate = system.plate  # type: ignore[attr-defined]
    mic = (0.5 * plate.a_m, 0.5 * plate.b_m, R_MIC_M)

    def clip(x: np.ndarray) -> np.ndarray:
        return np.clip(x, t0, t1)

    p = rayleigh_pressure(plate_surface(system, 30), lambda x: res.modal_velocity_m_s(clip(x)),
                          t_s, mic)
    p = p + residual_pressure(system, lambda x: res.residual_deflection_m(clip(x)), t_s, mic)
    return microphone(p, mc.FS_HZ)


def own_sound(system: object, state: object, t0: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Time grid, the sound with the striker less that without, and the first contact's
    ``v_in``, for a run from ``state`` at ``t0``."""
    t = np.arange(t0, t0 + SPAN_S, 1.0 / mc.FS_HZ)
    out, v_in = [], float("nan")
    for sys_ in (system, system.replace(gap_m=1.0)):  # type: ignore[attr-defined]
        res = simulate_modal(sys_, KelvinVoigtContact(), duration_s=SPAN_S, state=state,
                             dense=True, episode_gap_s=SPAN_S)
        if sys_ is system:
            v_in = float(res.contacts.u_in_m_s[0])
        out.append(heard(sys_, res, t, t0, t0 + SPAN_S))
    return t, out[0] - out[1], v_in


def early_peak(t: np.ndarray, p: np.ndarray, t_arrival: float) -> float:
    sel = (t >= t_arrival - 0.5 / mc.FS_HZ) & (t <= t_arrival + EARLY_S)
    return float(np.abs(p[sel]).max())


def line(v: list[float] | np.ndarray, p: list[float] | np.ndarray) -> str:
    law = fit_linear_law(np.asarray(v, float), np.asarray(p, float))
    return f"{law.slope:6.2f} v_in {law.intercept:+6.2f} Pa (r2 {law.r2:.3f}, {law.n} impacts)"


def laws(n_modes: int = 64, omega: float = 1.1, max_impacts: int | None = None
         ) -> dict[str, object]:
    """Every line the benchmark prints, and the per-impact values behind them."""
    freq = {0.95: 99.8, 1.1: 115.6}.get(omega, 105.1 * omega)
    system = plate_system(n_modes=n_modes, pressure_pa=285.0, freq_hz=freq, zeta=0.05,
                          skip_unexcited=True, omitted_modes=True, n_terms=mc.N_TERMS)
    delay = R_MIC_M / C_AIR_M_S

    # one impact from rest, on the same plate without forcing
    rest = system.replace(pressure_pa=0.0)
    b1 = float(rest.beta[0])
    v1, own1, rule1 = [], [], []
    for speed in (0.5, 1.0, 2.0, 4.0):
        p0, q0 = np.zeros(n_modes), np.zeros(n_modes)
        p0[0] = rest.gap_m * (1 - 1e-9) / b1
        q0[0] = speed / b1
        t, d, v_in = own_sound(rest, ModalState(-LEAD_S, p0, q0), -LEAD_S)
        # (the run with the striker alone, from rest: what the pipeline would read)
        res = simulate_modal(rest, KelvinVoigtContact(), duration_s=SPAN_S,
                             state=ModalState(-LEAD_S, p0, q0), dense=True,
                             episode_gap_s=SPAN_S)
        whole = heard(rest, res, t, -LEAD_S, -LEAD_S + SPAN_S)
        t_hit = float(res.contacts.t_start_s[0])
        v1.append(v_in)
        own1.append(early_peak(t, d, t_hit + delay))
        rule1.append(float(sound_peaks(whole, mc.FS_HZ, [t_hit], delay_s=delay,
                                       start_time_s=float(t[0])).p_first_pa[0]))

    # the campaign
    t = np.arange(int(round(mc.CYCLES / freq * mc.FS_HZ))) / mc.FS_HZ
    ch = modal_channels(system, KelvinVoigtContact(), t)
    rec = microphone(ch.mic_pa, mc.FS_HZ)
    im = ch.impacts
    pk = sound_peaks(rec, mc.FS_HZ, im.t_s, delay_s=delay, excitation_freq_hz=freq)
    w = 2.0 * np.pi * freq
    n_base = int(round(3e-3 * mc.FS_HZ))
    v, own, own_rule, rest_left = [], [], [], []
    for i, t_i in enumerate(im.t_s[:max_impacts]):
        t0 = float(t_i) - LEAD_S
        p0, q0 = ch.result.modal_state(t0)
        r0 = float(ch.result.residual_deflection_m(t0)[0])
        tt, d, _ = own_sound(system, ModalState(t0, p0[:, 0].copy(), q0[:, 0].copy(), r0), t0)
        v.append(float(im.v_in_m_s[i]))
        own.append(early_peak(tt, d, t_i + delay))
        own_rule.append(float(sound_peaks(d, mc.FS_HZ, [t_i], delay_s=delay,
                                          start_time_s=t0).p_first_pa[0]))
        # the record less the forced sinusoid sound_peaks fits, at its first peak
        k_a = int(round((t_i + delay) * mc.FS_HZ))
        kb = np.arange(max(0, k_a - n_base), k_a)
        cols = np.c_[np.ones(kb.size), np.cos(w * t[kb]), np.sin(w * t[kb])]
        coef = np.linalg.lstsq(cols, rec[kb], rcond=None)[0]
        k_f = int(round(pk.t_first_s[i] * mc.FS_HZ))
        sub = rec[k_f] - np.array([1.0, np.cos(w * t[k_f]), np.sin(w * t[k_f])]) @ coef
        k_d = int(round((pk.t_first_s[i] - t0) * mc.FS_HZ))
        # the rest, counted positive where it adds to the impact's own |p|
        rest_left.append(float((sub - d[k_d]) * np.sign(d[k_d])))
    n = len(v)
    return {"freq_hz": freq, "single_v": np.array(v1), "single_own": np.array(own1),
            "single_rule": np.array(rule1), "v": np.array(v), "own": np.array(own),
            "own_rule": np.array(own_rule), "record_rule": np.asarray(pk.p_first_pa[:n]),
            "left": np.array(rest_left),
            "read_after_s": np.asarray(pk.t_first_s[:n] - im.t_s[:n] - delay)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, default=64)
    ap.add_argument("--omega", type=float, default=1.1,
                    help="forcing over the thesis' omega scale (0.95 or 1.1)")
    args = ap.parse_args()
    t_start = time.perf_counter()
    r = laws(args.modes, args.omega)
    print(f"# N = {args.modes}, forcing {r['freq_hz']} Hz, microphone {R_MIC_M} m on axis, "
          f"{mc.FS_HZ / 1e3:g} kHz")
    print(f"one impact from rest, own sound (with - without striker): "
          f"{line(r['single_v'], r['single_own'])}")
    print(f"one impact from rest, first-peak rule on the record:      "
          f"{line(r['single_v'], r['single_rule'])}")
    v, left = r["v"], r["left"]
    print(f"campaign ({v.size} impacts, v_in {v.min():.2f}-{v.max():.2f} m/s):")
    print(f"  own sound (with - without striker):                      {line(v, r['own'])}")
    print(f"  first-peak rule on the own sound alone:                  "
          f"{line(v, r['own_rule'])}")
    print(f"  first-peak rule on the record (forced sinusoid removed): "
          f"{line(v, r['record_rule'])}")
    slope, icpt = np.polyfit(v, left, 1)
    print(f"  the record less the sinusoid less the own sound there, signed (+ where it adds "
          f"to the own |p|): {slope:+.2f} v_in {icpt:+.2f} Pa; mean {left.mean():+.2f} Pa, "
          f"sd {left.std(ddof=1):.2f} Pa, against the own sound at {np.sum(left < 0)} of "
          f"{left.size} impacts; read {1e6 * np.median(r['read_after_s']):.0f} us after the "
          f"arrival (median)")
    print(f"# {time.perf_counter() - t_start:.0f} s")


if __name__ == "__main__":
    main()
