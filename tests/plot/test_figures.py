"""Figure guards outside the report (issue 17): the Fig. 4-3 sweep plot and the sweep header.

Read back from the written PDF (pypdf text) and from the figure's own axes.
"""

from __future__ import annotations

import numpy as np
import pypdf
from record_factory import run_cli

from rattle_lab.model.analysis import sweep_up_down
from rattle_lab.model.analysis._sweep import sweep_values
from rattle_lab.model.sdf import SDFParams
from rattle_lab.plot import plot_sweeps


def _sweeps():
    base = SDFParams(F=0.1, omega=0.9, zeta=0.05, e=0.8)
    return sweep_up_down("omega", sweep_values(0.9, 1.1, 0.05), base=base, cycles=40,
                         discard=20, n_max=6, lyapunov="none")


def test_sweep_plot_has_rendered_mathtext_and_data_driven_axis(tmp_path, monkeypatch):
    up, down = _sweeps()
    captured = {}
    from matplotlib.figure import Figure

    real_savefig = Figure.savefig

    def spy(self, *args, **kwargs):  # keep the figure to look at its axes
        captured["fig"] = self
        return real_savefig(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", spy)
    out = plot_sweeps([up, down], tmp_path / "sweep.pdf")
    text = "".join(p.extract_text() for p in pypdf.PdfReader(out).pages)
    assert "{x=0}" not in text and "^+" not in text and "v_im" not in text  # no raw TeX
    assert "crossing velocity" in text and "impact velocity" in text
    fig = captured["fig"]
    axes = np.array(fig.axes).reshape(3, 2)
    for col, sw in enumerate((up, down)):
        v = np.concatenate([p.impact_velocities for p in sw.points] or [np.zeros(0)])
        if v.size:  # the data fill the axis: the linear estimate does not stretch it
            lo, hi = axes[0, col].get_ylim()
            span = float(v.max() - v.min()) or 1.0
            assert hi - lo <= 1.2 * span + 1e-12


def test_sweep_header_lists_only_fixed_parameters():
    proc = run_cli("model", "sweep", "--param", "omega", "--start", "0.9", "--stop", "1.0",
                   "--step", "0.05", "--F", "0.1", "--zeta", "0.05", "--e", "0.8",
                   "--cycles", "40", "--discard", "20", "--n-max", "6", "--lyapunov", "none",
                   "--quiet")
    assert proc.returncode == 0, proc.stderr
    header = proc.stdout.splitlines()[0]
    assert "fixed: F=0.1 zeta=0.05 e=0.8;" in header
    assert "omega=" not in header and "where fixed" not in header
