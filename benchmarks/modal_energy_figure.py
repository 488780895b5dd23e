"""Draw docs/modal_energy.png: modal energies through one impact (contact episode).

Thesis plate (CFCF 0.254 x 0.2286 x 0.001 m), striker at the centre 1 mm behind it,
285 Pa at 115.6 Hz (F = 0.3, omega = 1.1), N = 16 doubly symmetric modes, Kelvin-Voigt
striker (k = 4.4e8 N/m).  The 30th forcing period's impact is shown: mode 1 hands its
energy to the higher modes during the micro-contacts of the episode.

Run: ``python benchmarks/modal_energy_figure.py [output.png]``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from rattle_lab.model.modal import KelvinVoigtContact, plate_system, simulate_modal  # noqa: E402


def main(out: Path) -> None:
    system = plate_system(n_modes=16, freq_hz=115.6, skip_unexcited=True)
    res = simulate_modal(system, KelvinVoigtContact(), cycles=32, dense=True)
    im = res.impacts
    i = int(np.searchsorted(im.t_s, 29 / system.freq_hz))
    t0, t1 = im.t_s[i], im.t_end_s[i]
    t = np.linspace(t0 - 0.6e-3, t1 + 2.5e-3, 6000)
    E = res.modal_energy_j(t)
    f = system.omega_rad_s / (2 * np.pi)
    fig, ax = plt.subplots(figsize=(7.5, 4.2), dpi=120)
    tm = (t - t0) * 1e3
    for k in range(4):
        ax.plot(tm, E[k] * 1e3, lw=1.4, label=f"model mode {k + 1} ({f[k]:.0f} Hz)")
    ax.plot(tm, E[4:].sum(axis=0) * 1e3, lw=1.2, color="0.4", label=f"modes 5-16 (to {f[-1]:.0f} Hz)")
    ax.plot(tm, E.sum(axis=0) * 1e3, lw=1.0, color="k", ls="--", label="sum of modes")
    for c0, c1 in zip(res.contacts.t_start_s, res.contacts.t_end_s):
        if t[0] <= c0 <= t[-1]:
            ax.axvspan((c0 - t0) * 1e3, (c1 - t0) * 1e3, color="tab:red", alpha=0.25, lw=0)
    ax.set_yscale("log")
    ax.set_ylim(3e-3, 2 * float(E.sum(axis=0).max()) * 1e3)
    ax.set_xlabel("time from first touch [ms]  (red: contact; model modes = the doubly symmetric plate modes)")
    ax.set_ylabel("modal energy [mJ]")
    ax.set_title(f"Modal energies through one impact: thesis plate, N = 16, Kelvin-Voigt striker\n"
                 f"v_in = {im.v_in_m_s[i]:.2f} m/s, {im.n_contacts[i]} contacts, "
                 f"e_mode1 = {im.e_mode1[i]:.2f}, contact-point e = {im.v_out_m_s[i] / im.v_in_m_s[i]:.2f}",
                 fontsize=9)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[1] / "docs" / "modal_energy.png")
