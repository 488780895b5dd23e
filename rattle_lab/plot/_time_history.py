"""The time histories and phase portrait of one simulation."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from rattle_lab.exceptions import ParameterError

from ._figures import save_figure

if TYPE_CHECKING:
    from rattle_lab.model.sdf import SimResult


def plot_time_history(res: SimResult, path: str | Path) -> Path:
    """Time histories (x, v, a with forced/transient parts) and the phase portrait.

    ``res`` must hold dense samples with fields x, v, a, forced and excitation.
    """
    from matplotlib.figure import Figure

    d = res.dense
    if d is None or d.x is None or d.v is None:
        raise ParameterError("plot_time_history needs a result with dense x and v samples")
    fig = Figure(figsize=(10, 7.5), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=(2.2, 1))
    ax_x = fig.add_subplot(gs[0, 0])
    ax_v = fig.add_subplot(gs[1, 0], sharex=ax_x)
    ax_a = fig.add_subplot(gs[2, 0], sharex=ax_x)
    ax_p = fig.add_subplot(gs[:, 1])
    p = res.params
    ax_x.plot(d.t, d.x, lw=1, label="x")
    if d.forced is not None:
        ax_x.plot(d.t, d.forced, lw=0.8, ls="--", label="forced part")
    if d.transient is not None:
        ax_x.plot(d.t, d.transient, lw=0.8, ls=":", label="transient part")
    ax_x.axhline(1.0, color="k", lw=0.8)
    ax_x.set_ylabel("displacement x = x_s / h (nondim.)")
    ax_x.legend(loc="lower left", fontsize=8)
    ax_v.plot(d.t, d.v, lw=1)
    imp = res.impacts
    if len(imp):
        ax_v.plot(imp.t, imp.v_in, "o", ms=3, mfc="none", label="v_in at impact")
        ax_v.legend(loc="lower left", fontsize=8)
    ax_v.set_ylabel("velocity dx/dt (nondim.)")
    if d.a is not None:
        ax_a.plot(d.t, d.a, lw=1, label="acceleration")
    if d.excitation is not None:
        ax_a.plot(d.t, d.excitation, lw=0.8, ls="--", label="excitation F cos(omega t + phi)")
    ax_a.set_ylabel("acceleration (nondim.)")
    ax_a.set_xlabel("time t = omega_s t_phys (nondim.)")
    ax_a.legend(loc="lower left", fontsize=8)
    ax_p.plot(d.x, d.v, lw=0.7)
    ax_p.axvline(1.0, color="k", lw=0.8)
    ax_p.set_xlabel("displacement x (nondim.)")
    ax_p.set_ylabel("velocity dx/dt (nondim.)")
    ax_p.set_title("phase portrait")
    fig.suptitle(f"SDF impact oscillator: F={p.F:g}, omega={p.omega:g}, zeta={p.zeta:g}, e={p.e:g}")
    return save_figure(fig, path)



