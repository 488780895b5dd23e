"""The report computes nothing (issue 12): content is computed first, pages only draw it.

* The report package imports no computation: an AST check of every module's imports
  against an allow-list (the standard library, numpy and matplotlib, the report's own
  modules, plot's line styles, and the atomic writer and exceptions for the PDF), which
  is shown to fail on a module importing a fit function, the model, scipy or a builder.
* Every page renders from a hand-built content object, with no store on disk.
* The functions the content builders call (in :mod:`rattle_lab.workflow`) are checked
  against independent references.
"""

from __future__ import annotations

import ast
import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from rattle_lab.acoustics import energy_mean_db
from rattle_lab.detect import impacts_per_cycle
from rattle_lab.fit import linear_law_band, negative_hysteresis
from rattle_lab.model.analysis import bifurcation_sets, grazing_forcing, sweep_thresholds
from rattle_lab.plot import db_slope_guide, power_law_guide
from rattle_lab.report import ReportContent, render_pages
from rattle_lab.report._content_types import (AcousticsContent, ChannelInfo, GrazingCurve,
                                              ModelContent, PatternContent, RecordInfo,
                                              RigContent, SplContent, SplCurve,
                                              SweepComparison, ThresholdContent, Trace,
                                              WaveformColumn, WaveformContent)
from rattle_lab.report._pages import (pattern_page, rig_page, spl_page, threshold_page,
                                      waveform_page)
from rattle_lab.report._pages_acoustics import acoustics_page
from rattle_lab.report._pages_model import model_pages
from rattle_lab.workflow import ReportData

REPORT = Path(__file__).resolve().parents[2] / "rattle_lab" / "report"
#: Every module of the report package (drawing, the content types, the PDF writer).
REPORT_MODULES = sorted(p.name for p in REPORT.glob("*.py"))
#: What they may import besides the standard library: (module, names or None for any).
ALLOWED: dict[str, set[str] | None] = {
    "numpy": None, "matplotlib": None, "matplotlib.figure": None, "matplotlib.lines": None,
    "matplotlib.patches": None, "matplotlib.ticker": None,
    "matplotlib.style": None,   # drawing in the default style, whatever the session's rc
    "matplotlib.backends.backend_pdf": {"PdfPages"},
    # the report's own modules: pages, shared drawing helpers, content types, the renderer
    "rattle_lab.report": {"_pages", "_pages_acoustics", "_pages_model", "_pages_shocks"},
    "rattle_lab.report._common": None, "rattle_lab.report._content_types": None,
    "rattle_lab.report._render": None,
    # a style table, shared with `model bifsets` (not smooth_region: that computes)
    "rattle_lab.plot": {"BIFURCATION_LINESTYLES"},
    # writing the PDF: the atomic writer and the error for a bad output name
    "rattle_lab._atomic": {"atomic_path"}, "rattle_lab.exceptions": {"ParameterError"},
}


def _allowed(module: str, name: str | None) -> bool:
    if module.split(".")[0] in sys.stdlib_module_names:
        return True
    if module not in ALLOWED:
        return False
    names = ALLOWED[module]
    return names is None or name is None or name in names


def _disallowed_imports(path: Path) -> list[str]:
    bad = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if not _allowed(alias.name, None) or alias.name.startswith("rattle_lab"):
                    bad.append(f"line {node.lineno}: import {alias.name}")
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:  # relative: inside rattle_lab.report
                module = "rattle_lab.report" + ("." + module if module else "")
            for alias in node.names:
                if not _allowed(module, alias.name):
                    bad.append(f"line {node.lineno}: from {module} import {alias.name}")
    return bad


def test_every_report_module_is_checked() -> None:
    # the check below runs on every module of the package, the pages and the writer among them
    assert {"__init__.py", "_common.py", "_content_types.py", "_pages.py",
            "_pages_acoustics.py", "_pages_model.py", "_render.py"} <= set(REPORT_MODULES)


@pytest.mark.parametrize("name", REPORT_MODULES)
def test_report_modules_import_no_computation(name: str) -> None:
    bad = _disallowed_imports(REPORT / name)
    assert not bad, f"{name} imports beyond drawing: " + "; ".join(bad)


def test_the_import_check_catches_a_computing_module(tmp_path: Path) -> None:
    # a module that computes the grazing band itself, simulates, uses scipy, smooths a
    # region, reads the store and calls a builder: each import is flagged
    probe = tmp_path / "_pages_probe.py"
    probe.write_text("from rattle_lab.fit import grazing_band_ms2\n"
                     "import scipy\n"
                     "from rattle_lab.workflow._report._content import threshold_content\n"
                     "from rattle_lab.plot._bifsets import smooth_region\n"
                     "from ..model import analysis\n"
                     "import rattle_lab.store\n"
                     "import pandas\n"
                     "from ._content_types import ThresholdContent\n"
                     "import math\n"
                     "from matplotlib.figure import Figure\n")
    bad = _disallowed_imports(probe)
    assert [b.split(":")[0] for b in bad] == [f"line {k}" for k in range(1, 8)]
    assert "threshold_content" in bad[2] and "smooth_region" in bad[3]
    assert "rattle_lab.report.model" in bad[4]  # a relative import climbing out of report


def test_no_report_module_is_over_600_lines() -> None:
    for path in REPORT.glob("*.py"):
        assert len(path.read_text().splitlines()) <= 600, path.name


# --- pages from hand-built content, no store ---------------------------------------------

def _texts(fig: Figure) -> str:
    out = [t.get_text() for t in fig.texts]
    for ax in fig.axes:
        out += [ax.get_xlabel(), ax.get_ylabel(), ax.get_title()]
        legend = ax.get_legend()
        if legend is not None:
            out += [t.get_text() for t in legend.get_texts()]
        out += [t.get_text() for t in ax.texts]
        out += [cell.get_text().get_text() for tab in ax.tables
                for cell in tab.get_celld().values()]
    return "\n".join(out)


def _threshold_content() -> ThresholdContent:
    f = np.array([90.0, 95.0, 100.0])
    up, down = np.array([10.0, 8.0, 12.0]), np.array([7.0, 9.0, np.nan])
    grid = np.linspace(88.0, 102.0, 50)
    y = 5.0 + 0.01 * (grid - 95.0) ** 2
    curve = GrazingCurve(grid, y, (y - 0.5, y + 0.5), 4,
                         1.2e-3, 96.0, 0.02, np.array([100.0]), np.array([12.0]))
    hyst = up - down
    return ThresholdContent(f, up, down, hyst, np.isfinite(hyst) & (hyst < 0),
                            np.isfinite(up) & np.isfinite(down), 3.0, curve)


def test_threshold_page_draws_its_content() -> None:
    (fig,) = threshold_page(_threshold_content())
    ax, ax_r, ax_h = fig.axes  # thresholds, the residuals below them, the hysteresis
    text = _texts(fig)
    for key in ("eq. (3.4) fit: gap 1.2 mm, f_s 96 Hz, zeta 0.02", "Student t, 4 dof",
                "left out of the fit (outlier)", "NEGATIVE: disappearance above onset",
                "negative\n-1 m/s^2"):
        assert key in text, key
    # the fit curve is drawn at the content's values, not recomputed
    curve = _threshold_content().curve
    assert curve is not None
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), curve.accel_ms2)
    # the hysteresis bars are the content's: two expected (one NaN), one negative
    heights = sorted(h for h in (p.get_height() for p in ax_h.patches) if np.isfinite(h))
    np.testing.assert_allclose(heights, [-1.0, 3.0])


def test_every_page_renders_from_content_without_a_store(tmp_path: Path) -> None:
    channel = ChannelInfo("in1", "acc", "plate_acceleration", "m/s^2", "mV", 0.1, "10 mV/g",
                          51200.0, "PCB 352C33", "123", "2024-01-01", "-50 .. 50", "(0, 0, 0)")
    record = RecordInfo("in1", "camp", "generated", {"apparatus": "plate", "gap_m": 1e-3},
                        (channel,), {})
    pattern = PatternContent(np.array([[94.88, 1.0, 0, 0.0], [94.88, 2.0, 1, 0.0],
                                       [100.0, 3.0, 2, 1.0], [100.0, 3.0, 1, 1.0]]),
                             ("m/s^2",), ((1, 100.0, 3.0, 0.5), (2, 100.0, 3.0, 0.5)))
    t = np.linspace(0.0, 0.05, 500)
    trace = Trace(t, np.sin(200 * t), np.array([0.01, 0.03]), np.array([0.1, 0.2]))
    sound = Trace(t, np.cos(200 * t), np.zeros(0), np.zeros(0),
                  (("first", np.array([0.011]), np.array([0.3])),
                   ("max", np.array([0.012]), np.array([0.5]))))
    waves = WaveformContent((WaveformColumn("r1", "sine_dwell", 100.0, "1/1",
                                            (trace, trace, sound)),))
    v = np.linspace(0.1, 0.5, 20)
    spl = SplContent((SplCurve("first", v, 2.0 * v + 0.1, 2.0, 0.1, 0.99, v, 2.0 * v + 0.1,
                               (1.9 * v + 0.1, 2.1 * v + 0.1)),))
    f_b = np.array([100.0, 125.0, 160.0])
    rows = tuple({"run_id": f"r{k}", "v_rms_m_s": 0.1 * (k + 1),
                  "acoustics": {"laeq_db": 60.0 + k, "lafmax_db": 65.0 + k,
                                "loudness_n5_sone": 2.0 + k, "loudness_max_sone": 3.0 + k}}
                 for k in range(3))
    acoustics = AcousticsContent(rows, (("rattle", f_b, np.array([50.0, 55.0, 52.0])),),
                                 {"rattle": (f_b, np.array([50.0, 55.0, 52.0])),
                                  "background": None},
                                 np.array([0.1, 0.2, 0.3]), np.array([60.0, 61.0, 62.0]),
                                 np.array([65.0, 66.0, 67.0]), np.array([2.0, 3.0, 4.0]),
                                 np.array([3.0, 4.0, 5.0]), None, None,
                                 "a hand-built calibration note", ("diffuse",))
    sets = bifurcation_sets((1, 2), omega_range=(0.8, 1.2), F_range=(0.0, 0.2), zeta=0.02,
                            e=0.8, n_omega=9, n_F=8, n_v=11)
    none = tuple(None for _ in sets.ns)
    sweeps = SweepComparison(np.array([95.0]), np.array([9.0]), np.array([np.nan]), 0.2, 20.0,
                             40, np.array([95.0]), np.array([8.0]), np.array([7.0]))
    model = ModelContent(sets, none, none, None, np.array([0.99]), np.array([0.05]),
                         np.array([0.99]), np.array([0.04]), 0.02, "ramp model", 0.8, sweeps)
    absent = tmp_path / "no_such_store.h5"  # nothing may be read: it does not exist
    sections = (("rig and calibration", RigContent((record,))),
                ("thresholds", _threshold_content()), ("impact patterns", pattern),
                ("waveforms", waves), ("SPL law", spl), ("acoustics", acoustics),
                ("model predictions", model))
    content = ReportContent(absent.name, ("store: no_such_store.h5", "  a summary line"),
                            sections, {"eq. 3.4 fit curve": "a hand-built reason"})
    pages, names = render_pages(content)
    assert not absent.exists()
    assert names == ("summary", *(n for n, _ in sections))
    assert len(pages) == 9  # summary, one page per section, two model pages
    texts = [_texts(fig) for _, fig in pages]
    assert "a summary line" in texts[0]
    assert "missing: eq. 3.4 fit curve: a hand-built reason" in texts[0]
    for i, (_, fig) in enumerate(pages, start=1):
        assert f"Page {i} of 9" in texts[i - 1]
        fig.canvas.draw()  # Agg: the page really renders
    expected = {1: "PCB 352C33", 2: "hysteresis", 3: "sine dwell (size: share of its cycles)",
                4: "r1 (sine_dwell, 100 Hz, pattern 1/1)", 5: "p = 2 Pa/(m/s) |v_in| + 0.1 Pa",
                6: "rattle: energy mean of 3 runs", 7: "ramp model",
                8: "up to 20 m/s^2"}
    for page, key in expected.items():
        assert key in texts[page], (page, key)
    # the acoustics page prints the content's calibration note and sound field as given
    assert "a hand-built calibration note" in texts[6]
    assert "(diffuse field)" in texts[6]
    # the single pages draw exactly the content they were given
    (wave,) = waveform_page(waves)
    np.testing.assert_array_equal(wave.axes[1].lines[1].get_ydata(), [0.1, 0.2])
    (spl_fig,) = spl_page(spl)
    np.testing.assert_array_equal(spl_fig.axes[0].lines[1].get_ydata(), 2.0 * v + 0.1)
    assert len(rig_page(RigContent((record,)))) == 1
    assert len(pattern_page(pattern)) == 1 and len(acoustics_page(acoustics)) == 1
    assert len(model_pages(dataclasses.replace(model, sweeps=None))) == 1


def test_content_is_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        _threshold_content().curve = None  # type: ignore[misc]


# --- the computations the report now calls ------------------------------------------------

def test_impacts_per_cycle_against_a_loop() -> None:
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(-0.05, 1.05, 300))
    f, t0, dur = 37.0, 0.01, 0.97
    n = int(np.floor(dur * f))
    expected = [sum(1 for x in t if t0 + k / f <= x < t0 + (k + 1) / f) for k in range(n)]
    # exact: cycle edges t0 + k / f and floor((t - t0) f) agree away from rounding at an edge
    assert impacts_per_cycle(t, f, t0, dur).tolist() == expected


def test_energy_mean_db_closed_form() -> None:
    # two levels 10 dB apart: 10 log10((10 + 1) / 2) dB above the lower one (exact to 1e-12)
    assert energy_mean_db([50.0, 60.0]) == pytest.approx(50.0 + 10 * np.log10(5.5), abs=1e-12)
    assert energy_mean_db([42.0]) == pytest.approx(42.0, abs=1e-12)


def test_linear_law_band_against_the_ols_covariance() -> None:
    # independent reference: the band of the mean is t * sqrt(x0' C x0), with C the OLS
    # coefficient covariance from numpy's polyfit (matrix form); agreement to 1e-9 relative
    from scipy import stats

    rng = np.random.default_rng(7)
    v = rng.uniform(0.1, 1.0, 40)
    p = 3.0 * v + 0.2 + rng.normal(0, 0.1, v.size)
    (slope, icpt), cov = np.polyfit(v, p, 1, cov=True)
    grid = np.linspace(0.0, 1.1, 12)
    x0 = np.vstack([grid, np.ones_like(grid)])
    ref = stats.t.ppf(0.975, v.size - 2) * np.sqrt(np.einsum("ik,ij,jk->k", x0, cov, x0))
    band = linear_law_band(v, p, slope, icpt, grid)
    assert band is not None
    np.testing.assert_allclose(band, ref, rtol=1e-9)
    assert linear_law_band(v[:2], p[:2], slope, icpt, grid) is None
    assert linear_law_band(np.ones(5), p[:5], slope, icpt, grid) is None


def test_negative_hysteresis_lists_only_significantly_negative_values() -> None:
    f, up, down = [90.0, 95.0, 96.0, 100.0], [5.0, 4.0, 4.0, np.nan], [4.0, 4.5, 4.1, 3.0]
    se = [0.1, 0.1, 0.1, 0.1]
    # -0.5 is 3.5 standard uncertainties (hypot(0.1, 0.1)) below zero; -0.1 is 0.7: not flagged
    assert negative_hysteresis(f, up, down, se, se) == [(95.0, -0.5)]
    # a larger uncertainty (an irregular regime's cycle-to-cycle level change) clears it
    assert negative_hysteresis(f, up, down, [0.2] * 4, [0.2] * 4) == []
    # the sign alone decides nothing: unknown uncertainties flag nothing
    assert negative_hysteresis(f, up, down) == []
    assert negative_hysteresis(f, up, down, [np.nan] * 4, se) == []


def test_guides_have_the_law_slopes() -> None:
    v = np.array([0.1, 0.2, 0.4])
    x, level = db_slope_guide(v, [50.0, 56.0, np.nan], 20.0)
    # 20 dB per decade exactly; through (geometric median of v, median of the levels)
    assert np.allclose(np.diff(level) / np.diff(np.log10(x)), 20.0)
    assert np.interp(np.log10(0.2), np.log10(x), level) == pytest.approx(53.0)
    x, n = power_law_guide(v, [1.0, 2.0, 4.0], 0.602)
    assert np.allclose(np.diff(np.log(n)) / np.diff(np.log(x)), 0.602)
    assert x[0] == pytest.approx(0.1 / 1.2) and x[-1] == pytest.approx(0.4 * 1.2)


def test_sweep_thresholds_find_the_grazing_onset() -> None:
    # below resonance the impact-free response loses to impacts where it grazes the stop:
    # eq. (3.4) F = sqrt((1 - w^2)^2 + (2 zeta w)^2).  The sweep resolves it to half a
    # step (the threshold is reported mid-step); the return down never stops above it.
    omega, zeta = 0.8, 0.05
    F_g = float(grazing_forcing(omega, zeta))
    grid = np.linspace(0.5 * F_g, 1.5 * F_g, 21)
    res = sweep_thresholds(omega, grid, zeta=zeta, e=0.8)
    assert res.step_F == pytest.approx(grid[1] - grid[0])
    assert abs(res.onset_F - F_g) <= res.step_F / 2 + 1e-12
    assert res.disappearance_F <= res.onset_F + 1e-12


def _fitted_data(tmp_path: Path, *, e: float, f_s_hz: float = 96.0) -> ReportData:
    from types import SimpleNamespace

    from rattle_lab.fit import (FitSummary, Fits, GrazingParameter, GrazingSummary,
                                RatioRestitution)

    g = GrazingSummary(gap_m=GrazingParameter(1e-3, 1e-4, "m"),
                       f_s_hz=GrazingParameter(f_s_hz, 0.1, "Hz"),
                       zeta=GrazingParameter(0.02, 0.001, "1"),
                       participation=GrazingParameter(1.0, None, "1", vary=False))
    summary = FitSummary(n_runs=1, n_ok=1, fits=Fits(
        grazing=g, restitution_ratio=RatioRestitution(e, 0.01, "1", n=10)))
    results = SimpleNamespace(thresholds={"freq_hz": [90.0, 95.0], "up_ms2": [20.0, 10.0],
                                          "down_ms2": [18.0, 9.0]}, runs={})
    return ReportData(tmp_path / "absent.h5", None, (), [], results, {}, summary)


def test_model_content_leaves_out_what_the_model_cannot_use(tmp_path: Path) -> None:
    from rattle_lab.workflow._report import Missing
    from rattle_lab.workflow._report._content_model import model_content

    # e = 0: the bifurcation sets need e > 0 (once a ParameterError that ended the report)
    with pytest.raises(Missing, match=r"fitted e = 0 is outside \(0, 1\]"):
        model_content(_fitted_data(tmp_path, e=0.0))
    with pytest.raises(Missing, match="unusable for the model"):
        model_content(_fitted_data(tmp_path, e=0.8, f_s_hz=-5.0), max_freqs=0)


def test_model_content_converts_the_thresholds_by_the_scaling(tmp_path: Path) -> None:
    # eq. (2.28), (2.31) written out here: omega = f / f_s, F = Q A / ((2 pi f_s)^2 h)
    from rattle_lab.workflow._report._content_model import model_content

    c = model_content(_fitted_data(tmp_path, e=0.8), max_freqs=0)
    np.testing.assert_allclose(c.omega_up, np.array([90.0, 95.0]) / 96.0, rtol=1e-15)
    np.testing.assert_allclose(c.F_down, np.array([18.0, 9.0]) / ((2 * np.pi * 96.0) ** 2
                                                                  * 1e-3), rtol=1e-14)
    assert c.sweeps is None and c.zeta == 0.02 and c.zeta_source == "eq. (3.4) fit"
    assert len(c.exists_fields) == len(c.sets.ns) == 2


def test_shock_page_renders_from_content_without_a_store() -> None:
    from rattle_lab.report._content_types import ShockContent, ShockRun, ShockTrace
    from rattle_lab.report._pages_shocks import shock_pages

    t = np.linspace(-10.0, 30.0, 200)
    traces = (ShockTrace("force", "excitation_force", "N", "cause", "A", 10000.0, True, t,
                         np.exp(-((t - 2.0) / 1.0) ** 2), 2.0),
              ShockTrace("plate", "plate_acceleration", "m/s^2", "response", "A", 10000.0,
                         False, t, np.zeros_like(t), None))
    run = ShockRun("in_1", "hit_1", ("cause    force (excitation_force, clock A): onset ...",
                                     "clock A: 10000 Hz, shared by every channel"), traces)
    (fig,) = shock_pages(ShockContent((run,)))
    text = "\n".join([_texts(fig)] + [t.get_text() for sub in fig.subfigs for t in sub.texts]
                     + [ax.get_title(loc="left") for ax in fig.axes])
    assert "Shock of transient run in_1/hit_1" in text and "clock A: 10000 Hz" in text
    assert "plate (plate_acceleration, response, clock A, 10000 Hz), no shock" in text
    axes = [ax for ax in fig.axes if ax.get_lines()]
    assert len(axes) == 2
    np.testing.assert_array_equal(axes[0].get_lines()[0].get_ydata(), traces[0].y)


@pytest.mark.parametrize("flags, ecma, says", [
    (["ecma418_unavailable"], None, "sottek-hearing-model is not installed"),
    (["uncalibrated_no_loudness"], None, "microphone uncalibrated"),
    ([], None, "ecma418_s = 0"),
    ([], 3.5, ""),
])
def test_the_listener_page_says_why_ecma_418_is_absent(flags, ecma, says) -> None:
    from rattle_lab.workflow._report._content_runs import listener_metrics

    rows = [{"acoustics": {"psychoacoustic_flags": flags, "loudness_ecma_sone": ecma,
                           "impulse_penalty_db": 4.5, "impacts_per_s": None}}]
    m = listener_metrics(rows)
    assert (says in m.ecma_note) if says else m.ecma_note == ""
    assert m.flags == tuple(flags) and m.impulse_penalty_db[0] == 4.5
    assert np.isnan(m.impacts_per_s[0])
    assert (np.isnan(m.loudness_ecma_sone[0]) if ecma is None
            else m.loudness_ecma_sone[0] == ecma)


def test_the_listener_page_draws_a_note_where_no_run_has_a_value() -> None:
    # a campaign without background stretches has no loudness above the background and no
    # impulsiveness: the page says so instead of a log axis without data (which cannot draw)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from rattle_lab.report._pages_acoustics import listener_page
    from rattle_lab.workflow._report._content_runs import listener_metrics

    rows = [{"acoustics": {"psychoacoustic_flags": ["no_background"], "impacts_per_s": 95.0 + k,
                           "impulse_penalty_db": None}} for k in range(3)]
    fig = listener_page(np.array([0.04, 0.05, np.nan]), listener_metrics(rows))
    FigureCanvasAgg(fig).draw()
    texts = _texts(fig)
    assert texts.count("no run has both an impact velocity and this value") == 2
    assert "flags: no_background" in texts
    rate = next(ax for ax in fig.axes if ax.get_title().startswith("Impact rate"))
    assert rate.get_xscale() == "log" and len(rate.lines[0].get_xdata()) == 2


def test_the_acoustics_page_draws_a_note_where_no_run_has_an_impact_velocity() -> None:
    # a campaign below the rattle onset (no impact detected in any run) still has levels and
    # loudness, but no impact velocity: the two velocity panels say so instead of log axes
    # without data (matplotlib refuses to draw those: "Data cannot be log-scaled")
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    f_b = np.array([100.0, 125.0, 160.0])
    rows = tuple({"run_id": f"r{k}", "v_rms_m_s": None,
                  "acoustics": {"laeq_db": 40.0 + k, "lafmax_db": 45.0 + k,
                                "loudness_n5_sone": 1.0, "loudness_max_sone": 1.5}}
                 for k in range(2))
    nan = np.full(2, np.nan)
    content = AcousticsContent(rows, (("background", f_b, np.array([30.0, 31.0, 29.0])),),
                               {"rattle": None, "background": (f_b, np.array([30.0, 31.0, 29.0]))},
                               nan, np.array([40.0, 41.0]), np.array([45.0, 46.0]),
                               np.array([1.0, 1.0]), np.array([1.5, 1.5]), None, None,
                               "a hand-built calibration note", ("free",))
    (fig,) = acoustics_page(content)
    FigureCanvasAgg(fig).draw()   # raised ValueError before the note
    texts = _texts(fig)
    assert texts.count("no run has an impact velocity and this value") == 2
    velocity_axes = [ax for ax in fig.axes if ax.get_xlabel().startswith("RMS impact velocity")]
    assert len(velocity_axes) == 2 and all(ax.get_xscale() == "linear" for ax in velocity_axes)
    # with one run that has a velocity the panels are drawn on log axes as before
    one = dataclasses.replace(content, v_rms_m_s=np.array([0.2, np.nan]))
    (fig,) = acoustics_page(one)
    FigureCanvasAgg(fig).draw()
    assert "no run has an impact velocity" not in _texts(fig)
    assert all(ax.get_xscale() == "log" for ax in fig.axes
               if ax.get_xlabel().startswith("RMS impact velocity"))
