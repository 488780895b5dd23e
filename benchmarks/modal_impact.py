"""Speed of the modal impact model: cost per contact episode against DOP853, and growth with N.

The same modal equations (thesis plate, N excited modes with the omitted modes' element
at the contact point, ``k_r r + Z r' = f_c``, as the CLI's defaults; Kelvin-Voigt striker
k = 4.4e8 N/m, P = 285 Pa at 115.6 Hz, 2 zeta = 0.1, one Ritz basis of 32 terms) are
solved by

* ``exact``: :func:`rattle_lab.model.modal.simulate_modal` (closed-form flows, event location
  to rounding);
* ``DOP853``: scipy's ``solve_ivp`` with terminal events (contact start ``delta = 0`` up,
  contact end ``f_c = 0`` down), restarted at each event with the other right-hand side,
  at two rtol (atol = rtol times the state's scale).  During contact the striker against
  the element's dashpot is stiff (eigenvalue ``-(k + k_r) / Z ~ -1.3e7 /s``), which an
  explicit method pays for in steps.

Error: the largest relative difference of the contact-start velocities from the exact
run, over the contacts both runs have.  Every episode is one contact with the element.
Timings are wall-clock on a shared 2-core machine (other jobs were running): read
ratios, not absolutes.

Run: ``python benchmarks/modal_impact.py``.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp

from rattle_lab.model.modal import KelvinVoigtContact, plate_system, simulate_modal

CYCLES = 10
FREQ_HZ = 115.6
N_TERMS = 48


def direct(system, k: float, rtol: float):
    n = system.n_modes
    beta, phi, gap = system.beta, system.phi, system.gap_m
    w, z, Om = system.omega_rad_s, system.zeta, system.Omega_rad_s
    Zl, Gr = system.local_impedance_n_s_m, system.residual_compliance_m_n
    scale_p = gap / math.sqrt(beta @ beta)
    atol = rtol * np.concatenate([np.full(n, scale_p), np.full(n, scale_p * w.max()), [gap]])

    def modes(t, y, f):
        return np.concatenate([y[n:2 * n], phi * np.cos(Om * t) - 2 * z * w * y[n:2 * n] - w**2 * y[:n] - beta * f])

    def free(t, y):
        return np.concatenate([modes(t, y, 0.0), [-y[2 * n] / (Gr * Zl)]])

    def contact(t, y):
        f = k * (beta @ y[:n] - y[2 * n] - gap)
        return np.concatenate([modes(t, y, f), [(f - y[2 * n] / Gr) / Zl]])

    def touch(t, y):
        return beta @ y[:n] - y[2 * n] - gap
    touch.terminal, touch.direction = True, 1

    def release(t, y):
        return k * (beta @ y[:n] - y[2 * n] - gap)
    release.terminal, release.direction = True, -1
    t, y = 0.0, np.zeros(2 * n + 1)
    t_end = CYCLES / system.freq_hz
    u_in = []
    in_contact = False
    while t < t_end:
        sol = solve_ivp(contact if in_contact else free, (t, t_end), y, method="DOP853", rtol=rtol, atol=atol,
                        events=release if in_contact else touch)
        if sol.status == 1:
            t, y = float(sol.t_events[0][0]), sol.y_events[0][0]
            if not in_contact:
                u_in.append(float(beta @ y[n:2 * n]) + y[2 * n] / (Gr * Zl))
            in_contact = not in_contact
            t = np.nextafter(t, np.inf)
        else:
            break
    return np.array(u_in)


def main() -> None:
    k = 4.4e8
    print(f"thesis plate with the omitted modes' element, Kelvin-Voigt k = {k:.1e} N/m, {FREQ_HZ} Hz, "
          f"{CYCLES} forcing periods; times per contact episode, exact: best of 3 (shared 2-core machine)")
    print(f"{'N':>3}  {'method':>16}  {'contacts':>8}  {'max rel err v_in':>16}  {'ms/contact':>10}  {'total s':>8}")
    for n in (1, 2, 4, 8, 16, 32, 64):
        system = plate_system(n_modes=n, freq_hz=FREQ_HZ, skip_unexcited=True, omitted_modes=True, n_terms=N_TERMS)
        simulate_modal(system, KelvinVoigtContact(k), cycles=1)  # compile / warm up
        dt = float("inf")
        for _ in range(3):  # best of 3: the machine is shared
            t0 = time.perf_counter()
            res = simulate_modal(system, KelvinVoigtContact(k), cycles=CYCLES)
            dt = min(dt, time.perf_counter() - t0)
        ref = res.contacts.u_in_m_s
        m = len(ref)
        print(f"{n:>3}  {'exact':>16}  {m:>8}  {'(rounding)':>16}  {1e3 * dt / max(m, 1):10.3f}  {dt:8.2f}")
        if n not in (1, 4, 16):
            continue
        for rtol in (1e-6, 1e-9):
            t0 = time.perf_counter()
            u = direct(system, k, rtol)
            dt = time.perf_counter() - t0
            c = min(len(u), m)
            err = float(np.max(np.abs(u[:c] - ref[:c]) / np.abs(ref[:c]))) if c else float("nan")
            flag = "" if len(u) == m else f" ({len(u)} found)"
            print(f"{n:>3}  {f'DOP853 rtol={rtol:g}':>16}  {m:>8}  {err:16.2e}  {1e3 * dt / max(len(u), 1):10.3f}  "
                  f"{dt:8.2f}{flag}")


if __name__ == "__main__":
    main()
