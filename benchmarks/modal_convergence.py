"""Convergence in N of the modal impact model with the omitted modes' element (issue 24).

Thesis plate (CFCF 0.254 x 0.2286 x 0.001 m aluminium), striker at the centre 1 mm behind
it, P = 285 Pa, 2 zeta = 0.1, Kelvin-Voigt striker k = 4.4e8 N/m, 30 forcing periods from
rest, microphone 0.3 m in front of the centre at 50 kHz; N excited modes with
``omitted_modes=True`` (the CLI's defaults).  For N = 8, 16, 32, 64 it prints the first
three contact episodes (t, v_in, e_mode1, contacts, peak pressure through the stated
microphone) and the run's means (e_mode1 and the peak-pressure slope in Pa/(m/s), with
their standard deviations over the run's impacts), then the relative changes from N to
2N.

Run: ``python benchmarks/modal_convergence.py [freq_hz ...] [--modes 8,16,32,64] [--plain]``
(``--plain``: without the element, for comparison).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from rattle_lab.model.modal import KelvinVoigtContact, microphone, modal_channels, plate_system
from rattle_lab.model.modal._sound import C_AIR_M_S, peak_per_impact

FS_HZ = 50000.0
CYCLES = 30


#: One Ritz basis for every N (the largest the solver handles), so that only N changes.
N_TERMS = 48


def run(freq_hz: float, n: int, corrected: bool) -> dict:
    t0 = time.perf_counter()
    system = plate_system(n_modes=n, pressure_pa=285.0, freq_hz=freq_hz, zeta=0.05, skip_unexcited=True,
                          omitted_modes=corrected, n_terms=N_TERMS)
    t = np.arange(int(round(CYCLES / freq_hz * FS_HZ))) / FS_HZ
    ch = modal_channels(system, KelvinVoigtContact(), t)
    plate = system.plate
    delay = math.hypot(0.3, 0.0) / C_AIR_M_S
    assert plate is not None
    heard = peak_per_impact(microphone(ch.mic_pa, FS_HZ), t, ch.impacts.t_s, delay)
    im = ch.impacts
    # A line through the origin, p = S v_in (least squares): one number per run for N to 2N
    v = im.v_in_m_s
    S = float(np.sum(heard * v) / np.sum(v * v))
    S_se = float(np.sqrt(np.sum((heard - S * v) ** 2) / max(len(v) - 1, 1) / np.sum(v * v)))
    # and the law the pipeline fits (`spl_law_first`, linear): p = S v_in + c, 95 % intervals
    from rattle_lab.fit import fit_linear_law

    law = fit_linear_law(v, heard)
    e = im.e_mode1[np.isfinite(im.e_mode1)]
    return {"n": n, "s": time.perf_counter() - t0, "impacts": im, "heard": heard,
            "e_mean": float(np.mean(e)), "e_std": float(np.std(e, ddof=1)), "e_se": float(np.std(e, ddof=1)
                                                                                         / math.sqrt(e.size)),
            "S_mean": S, "S_std": S_se, "count": len(im), "contacts": len(ch.result.contacts),
            "q1_in": im.mode_velocity_in[:, 0], "law": law}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("freqs", nargs="*", type=float, default=[99.8, 115.6])
    ap.add_argument("--modes", default="8,16,32,64")
    ap.add_argument("--plain", action="store_true")
    a = ap.parse_args()
    ns = [int(x) for x in a.modes.split(",")]
    for f in a.freqs:
        rows = [run(f, n, not a.plain) for n in ns]
        print(f"\n## {f} Hz ({'plain truncated sum' if a.plain else 'with the omitted modes element'})")
        print("| N | impact | t [ms] | v_in [m/s] | q1'(before) [m/s] | e_mode1 | contacts | peak (mic) [Pa] |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            im = r["impacts"]
            for i in range(min(3, len(im))):
                print(f"| {r['n']} | {i + 1} | {im.t_s[i] * 1e3:.4f} | {im.v_in_m_s[i]:.4f} | {r['q1_in'][i]:.4f} | "
                      f"{im.e_mode1[i]:.4f} | "
                      f"{im.n_contacts[i]} | {r['heard'][i]:.3f} |")
        print("\n| N | run [s] | impacts | contacts | mean e_mode1 (std; s.e.) "
              "| S = fitted peak/v_in [Pa/(m/s)] (s.e.) |")
        print("|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['n']} | {r['s']:.0f} | {r['count']} | {r['contacts']} | {r['e_mean']:.4f} ({r['e_std']:.3f}; "
                  f"{r['e_se']:.3f}) | "
                  f"{r['S_mean']:.3f} ({r['S_std']:.3f}) |")
        print("\nThe pipeline's linear SPL law (fit_linear_law: p = S v_in + c, 95 % intervals):")
        for r in rows:
            law = r["law"]
            print(f"  N = {r['n']}: S = {law.slope:.3f} ({law.slope_ci_low:.3f} to {law.slope_ci_high:.3f}) "
                  f"Pa/(m/s), c = {law.intercept:.3f} ({law.intercept_ci_low:.3f} to "
                  f"{law.intercept_ci_high:.3f}) Pa, r2 {law.r2:.3f}, {law.n} impacts, v_in "
                  f"{np.min(r['impacts'].v_in_m_s):.3f}-{np.max(r['impacts'].v_in_m_s):.3f} m/s")
        print("\nN -> 2N, relative change (first three impacts: t, v_in, e_mode1, peak; run means: e_mode1, slope)")
        for lo, hi in zip(rows, rows[1:]):
            if hi["n"] != 2 * lo["n"]:
                continue
            a_, b_ = lo["impacts"], hi["impacts"]
            parts = []
            for i in range(min(3, len(a_), len(b_))):
                rel = [abs(b_.t_s[i] / a_.t_s[i] - 1), abs(b_.v_in_m_s[i] / a_.v_in_m_s[i] - 1),
                       abs(b_.e_mode1[i] / a_.e_mode1[i] - 1), abs(hi["heard"][i] / lo["heard"][i] - 1)]
                parts.append("/".join(f"{100 * x:.2g}%" for x in rel))
            de = hi["e_mean"] - lo["e_mean"]
            print(f"{lo['n']} -> {hi['n']}: " + "; ".join(parts)
                  + f"; mean e_mode1 {de:+.4f} (s.e. of the difference {math.hypot(lo['e_se'], hi['e_se']):.4f})"
                  + f", S {100 * abs(hi['S_mean'] / lo['S_mean'] - 1):.2g}%")


if __name__ == "__main__":
    main()
