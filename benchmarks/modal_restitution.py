"""e predicted by the multi-mode model: convergence in N, striker position, contact stiffness,
and the SDF model with that e against the multi-mode model (thesis chapter 5).

Thesis FEM plate (section 5.1): CFCF 0.254 x 0.2286 x 0.001 m aluminium, striker at the
centre, P = 285 Pa (F = 0.3 at h = 1 mm), f = 99.8 Hz (omega = 0.95) and 115.6 Hz
(omega = 1.1), 2 zeta = 0.1 for every mode.  Each run starts at rest, lasts ``CYCLES``
forcing periods, and the statistics use the episodes of the last ``LAST`` periods.

    e_mode1 = -q1'(after) / q1'(before)     (mode 1's modal velocity over the episode)
    e_point = v_out / v_in                  (contact-point velocity, what the thesis read
                                             off its FEM time history: e ~ 0.2)

Run: ``python benchmarks/modal_restitution.py [--quick]``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rattle_lab.model import scaling
from rattle_lab.model.modal import (HertzContact, KelvinVoigtContact, RigidContact, THESIS_PLATE, plate_system,
                              simulate_modal)
from rattle_lab.model.sdf import SDFParams, simulate

CYCLES = 60
LAST = 20


def stats(system, contact):
    res = simulate_modal(system, contact, cycles=CYCLES)
    im = res.impacts
    keep = im.t_s > (CYCLES - LAST) / system.freq_hz
    if not np.any(keep):
        return dict(n=0, v_in=np.nan, v1=np.nan, e1=np.nan, e1_sd=np.nan, ep=np.nan, nc=np.nan)
    w1 = float(system.shape_at_striker[0])
    return dict(n=int(keep.sum()), v_in=float(np.mean(im.v_in_m_s[keep])), v_in_sd=float(np.std(im.v_in_m_s[keep])),
                v1=float(np.mean(im.mode_velocity_in[keep, 0])) * w1,
                e1=float(np.mean(im.e_mode1[keep])), e1_sd=float(np.std(im.e_mode1[keep])),
                ep=float(np.mean(im.v_out_m_s[keep] / im.v_in_m_s[keep])), nc=float(np.mean(im.n_contacts[keep])))


def row(label, s):
    return (f"{label:>22}  {s['n']:>4}  {s['v_in']:8.3f}  {s['v1']:8.3f}  {s['e1']:8.3f}  {s['e1_sd']:7.3f}  "
            f"{s['ep']:8.3f}  {s['nc']:6.1f}")


HEAD = f"{'':>22}  {'imp':>4}  {'v_in m/s':>8}  {'v1_in':>8}  {'e_mode1':>8}  {'sd':>7}  {'e_point':>8}  {'cont.':>6}"


def sdf_v_in(system_n1, gap_m, freq_hz, e):
    """Mean impact velocity [m/s] of the SDF model (mode 1 of the same plate, eq. 2.26-2.33)."""
    b1 = float(system_n1.shape_at_striker[0])
    modes = system_n1.modes.modes
    sc = scaling.SDFScaling.from_modal_data(lam=float(modes.lam[0]), Q1=float(modes.Q1[0]), Q2=float(modes.Q2[0]),
                                            gap_m=gap_m / b1, a_m=THESIS_PLATE.a_m, h_p_m=THESIS_PLATE.h_p_m,
                                            E_pa=THESIS_PLATE.E_pa, nu=THESIS_PLATE.nu,
                                            rho_kg_m3=THESIS_PLATE.rho_kg_m3)
    ex = sc.to_nondimensional(freq_hz=freq_hz, pressure_pa=285.0)
    p = SDFParams(F=float(ex.F), omega=float(ex.omega), zeta=0.05, e=float(np.clip(e, 0.0, 1.0)))
    res = simulate(p, cycles=CYCLES)
    keep = res.impacts.t > (CYCLES - LAST) * p.period
    if not np.any(keep):
        return np.nan, float(ex.F)
    return float(np.mean(sc.velocity_ms(res.impacts.v_in[keep]))) * b1, float(ex.F)


def main() -> None:
    global CYCLES, LAST
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="fewer cases (N up to 16)")
    args = ap.parse_args()
    n_list = (1, 2, 4, 8, 16) if args.quick else (1, 2, 4, 8, 16, 32, 48)
    t0 = time.perf_counter()
    for f in (99.8, 115.6):
        print(f"\n== convergence in N: f = {f} Hz (omega = {f / 105.0:.2f}), h = 1 mm, P = 285 Pa ==")
        print(HEAD)
        for name, contact in (("kelvin-voigt k=4.4e8", KelvinVoigtContact()), ("hertz", HertzContact()),
                              ("rigid e=0.8", RigidContact(0.8))):
            for n in n_list:
                if name == "hertz" and n > 16:
                    continue
                s = stats(plate_system(n_modes=n, freq_hz=f, skip_unexcited=True), contact)
                print(row(f"{name} N={n}", s))
    print("\n== striker position (first 48 plate modes, all symmetries, Kelvin-Voigt, f = 115.6 Hz) ==")
    print(HEAD)
    a, b = THESIS_PLATE.a_m, THESIS_PLATE.b_m
    for xi, eta in ((0.5, 0.5), (0.4, 0.5), (0.5, 0.4), (0.3, 0.5), (0.5, 0.3), (0.35, 0.35)):
        system = plate_system(n_modes=48, freq_hz=115.6, striker_xy_m=(xi * a, eta * b))
        s = stats(system, KelvinVoigtContact())
        print(row(f"x/a={xi} y/b={eta}", s))
    print("   (v1_in: W_1(x_s, y_s) q_1' at first touch, mode 1's share of the contact-point velocity)")
    print("\n== contact stiffness (N = 16, Kelvin-Voigt, f = 115.6 Hz) ==")
    print(HEAD)
    for k in (1e5, 1e6, 1e7, 1e8, 4.4e8, 2e9):
        s = stats(plate_system(n_modes=16, freq_hz=115.6, skip_unexcited=True), KelvinVoigtContact(k))
        print(row(f"k = {k:.1e} N/m", s))
    print("\n== SDF with the predicted e against the multi-mode model (N = 16, Kelvin-Voigt) ==")
    print("   (v1_in = mode 1's velocity at first touch, the SDF model's v_im; e < 0 is clipped to 0 for the SDF)")
    print(f"{'f Hz':>6} {'gap mm':>7} {'F':>6}  {'v1_in modal':>11}  {'e_mode1':>8}  {'e_point':>8}  "
          f"{'v_in SDF(e_mode1)':>17}  {'v_in SDF(e_point)':>17}  {'v_in SDF(0.6)':>13}")
    for f in (99.8, 115.6):
        for gap_mm in (0.3, 0.5, 1.0, 1.5, 2.0, 3.0):
            system = plate_system(n_modes=16, freq_hz=f, gap_m=gap_mm * 1e-3, skip_unexcited=True)
            s = stats(system, KelvinVoigtContact())
            one = plate_system(n_modes=1, freq_hz=f, gap_m=gap_mm * 1e-3)
            v1, F = sdf_v_in(one, gap_mm * 1e-3, f, s["e1"]) if s["n"] else (np.nan, np.nan)
            v2, _ = sdf_v_in(one, gap_mm * 1e-3, f, s["ep"]) if s["n"] else (np.nan, np.nan)
            v3, _ = sdf_v_in(one, gap_mm * 1e-3, f, 0.6)
            print(f"{f:6.1f} {gap_mm:7.1f} {F:6.3f}  {s['v1']:11.3f}  {s['e1']:8.3f}  {s['ep']:8.3f}  "
                  f"{v1:17.3f}  {v2:17.3f}  {v3:13.3f}")
    print("\n== SDF impact velocity against e (mode 1 of the thesis plate, h = 1 mm) ==")
    one = {f: plate_system(n_modes=1, freq_hz=f) for f in (99.8, 115.6)}
    print("     e  " + "  ".join(f"v_im {f} Hz" for f in one))
    for e in (0.0, 0.2, 0.4, 0.6, 0.8, 1.0):
        print(f"{e:6.1f}  " + "  ".join(f"{sdf_v_in(one[f], 1e-3, f, e)[0]:13.3f}" for f in one))
    print(f"\n(total {time.perf_counter() - t0:.0f} s; 2-core machine shared with other jobs)")


if __name__ == "__main__":
    main()
