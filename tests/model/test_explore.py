"""The explorer (``rattle-lab explore``), driven headless through its widgets (Agg).

The plotted data are checked against :func:`rattle_lab.model.sdf.simulate` and
:func:`rattle_lab.model.analysis.sweep` called directly, and the forced parts against
the closed-form particular solution.  The CLI is run through the installed
entry point without a display.
"""

from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

import h5py
import matplotlib
import numpy as np
import pandas as pd
import pytest

matplotlib.use("Agg")

from rattle_lab.model.analysis import sweep  # noqa: E402
from rattle_lab.exceptions import OutputError, ParameterError  # noqa: E402
from rattle_lab.explorer import (  # noqa: E402
    HISTORY_COLUMNS,
    IMPACT_COLUMNS,
    Explorer,
    compute_histories,
    impacts_path,
    save_histories,
)
from rattle_lab.model.sdf import SDFParams, SDFState, simulate  # noqa: E402

from conftest import RATTLE_LAB as EXE  # noqa: E402

BASE = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6)
CYCLES = 6.0
N_PER_CYCLE = 50
FIELDS = ("x", "v", "a", "forced", "transient", "excitation")
TWO_PI = 2.0 * math.pi


def _expected(params: SDFParams, state: SDFState) -> tuple[np.ndarray, object]:
    """What the explorer should show: the simulator called directly."""
    duration = CYCLES * params.period
    t = state.t + np.linspace(0.0, duration, round(CYCLES * N_PER_CYCLE) + 1)
    res = simulate(params, duration=duration, state=state, dense_t=t, dense_fields=FIELDS)
    return t, res


def _explorer(**kw: object) -> Explorer:
    options: dict[str, object] = dict(params=BASE, cycles=CYCLES, n_per_cycle=N_PER_CYCLE,
                                      sweep_points=9, sweep_cycles=30, sweep_discard=20)
    options.update(kw)
    return Explorer(**options)  # type: ignore[arg-type]


def _click(ex: Explorer, name: str) -> None:
    ex.buttons[name]._observers.process("clicked", None)


def _assert_shows(ex: Explorer, params: SDFParams, state: SDFState) -> None:
    t, res = _expected(params, state)
    d = res.dense  # type: ignore[attr-defined]
    for (q, part), field in {("x", "total"): "x", ("v", "total"): "v", ("a", "total"): "a",
                             ("x", "forced"): "forced", ("x", "transient"): "transient",
                             ("a", "excitation"): "excitation"}.items():
        line = ex.lines[(q, part)]
        np.testing.assert_array_equal(line.get_xdata(), t)
        np.testing.assert_array_equal(line.get_ydata(), getattr(d, field))
    imp = res.impacts  # type: ignore[attr-defined]
    np.testing.assert_array_equal(ex.histories.impacts.t, imp.t)
    np.testing.assert_array_equal(ex.histories.impacts.v_in, imp.v_in)
    phase_line = ex.axes["phase"].get_lines()[0]
    np.testing.assert_array_equal(phase_line.get_xdata(), d.x)
    np.testing.assert_array_equal(phase_line.get_ydata(), d.v)


# --------------------------------------------------------------------------- time histories
def test_initial_plot_is_the_simulation_from_rest() -> None:
    ex = _explorer()
    assert ex.params == BASE
    _assert_shows(ex, BASE, SDFState())
    assert len(ex.histories.impacts) > 0  # F = 0.2 at omega = 1 impacts (1/1 orbit)


@pytest.mark.parametrize(("key", "value", "param"), [
    ("omega", 1.25, "omega"), ("F", 0.35, "F"), ("zeta", 0.1, "zeta"), ("e", 0.8, "e")])
def test_slider_runs_again_from_the_last_state(key: str, value: float, param: str) -> None:
    ex = _explorer()
    before = ex.histories.result.state
    ex.sliders[key].set_val(value)
    assert getattr(ex.params, param) == value
    _assert_shows(ex, BASE.replace(**{param: value}), before)


def test_restart_and_advance() -> None:
    ex = _explorer()
    ex.sliders["omega"].set_val(1.1)
    _click(ex, "restart")
    _assert_shows(ex, BASE.replace(omega=1.1), SDFState())
    end = ex.histories.result.state
    _click(ex, "advance")
    _assert_shows(ex, BASE.replace(omega=1.1), end)
    assert ex.histories.t[0] == end.t


def test_parts_match_the_closed_form_linear_response() -> None:
    p = SDFParams(F=0.05, omega=0.7, zeta=0.05, e=0.6)  # no impact: the linear response
    h = compute_histories(p, cycles=CYCLES, n_per_cycle=N_PER_CYCLE)
    assert len(h.impacts) == 0
    # Independent reference, written here from x'' + 2 zeta x' + x = F cos(w t) started at
    # rest: x_p = A cos(w t - delta), tan delta = 2 zeta w / (1 - w^2); the transient is the
    # damped homogeneous solution that cancels x_p(0), v_p(0).  Each part and the total are
    # checked against it (tolerance: rounding of a closed form, 1e-12 of the amplitude).
    w, z, t = p.omega, p.zeta, h.t
    amp = p.F / math.hypot(1 - w * w, 2 * z * w)
    delta = math.atan2(2 * z * w, 1 - w * w)
    xp, vp = amp * np.cos(w * t - delta), -amp * w * np.sin(w * t - delta)
    wd = math.sqrt(1 - z * z)
    c1 = -amp * math.cos(-delta)
    c2 = (amp * w * math.sin(-delta) + z * c1) / wd
    decay, cos_d, sin_d = np.exp(-z * t), np.cos(wd * t), np.sin(wd * t)
    xt = decay * (c1 * cos_d + c2 * sin_d)
    vt = decay * ((wd * c2 - z * c1) * cos_d - (wd * c1 + z * c2) * sin_d)
    at = -2 * z * vt - xt
    atol = 1e-12 * amp
    for got, want in ((h.x_transient, xt), (h.v_transient, vt), (h.a_transient, at),
                      (h.x, xp + xt), (h.v, vp + vt), (h.a, -w * w * xp + at)):
        np.testing.assert_allclose(got, want, rtol=0, atol=atol)
    # x_p = A cos(theta - delta) with A = F / sqrt((1 - w^2)^2 + (2 zeta w)^2), so
    # x_p^2 + (v_p / w)^2 = A^2 and a_p = -w^2 x_p (rounding only: 4 sqrt(eps)).
    w, z = p.omega, p.zeta
    amp2 = p.F**2 / ((1 - w * w) ** 2 + (2 * z * w) ** 2)
    np.testing.assert_allclose(h.x_forced**2 + (h.v_forced / w) ** 2, amp2,
                               rtol=4 * math.sqrt(np.finfo(float).eps))
    np.testing.assert_allclose(h.a_forced, -w * w * h.x_forced, rtol=0,
                               atol=4 * math.sqrt(np.finfo(float).eps) * math.sqrt(amp2))
    np.testing.assert_allclose(h.excitation, p.F * np.cos(w * h.t), rtol=0, atol=1e-12)


def test_forced_velocity_is_nan_at_the_undamped_resonance() -> None:
    h = compute_histories(SDFParams(F=0.05, omega=1.0, zeta=0.0, e=0.6), cycles=2)
    assert np.all(np.isnan(h.v_forced)) and np.all(np.isnan(h.a_forced))
    assert np.all(np.isfinite(h.x_forced))


def test_check_buttons_toggle_the_parts() -> None:
    ex = _explorer()
    assert ex.visible_parts == {"total": True, "forced": False, "transient": False,
                                "excitation": False}
    assert not ex.lines[("x", "forced")].get_visible()
    ex.checks.set_active(1)  # forced part
    assert ex.visible_parts["forced"]
    assert all(ex.lines[(q, "forced")].get_visible() for q in ("x", "v", "a"))
    ex.checks.set_active(0)  # total off
    assert not any(ex.lines[(q, "total")].get_visible() for q in ("x", "v", "a"))
    ex.checks.set_active(3)
    assert ex.lines[("a", "excitation")].get_visible()
    # the method keeps the check boxes in step
    ex.toggle("transient")
    assert ex.checks.get_status() == [False, True, True, True]
    assert all(ex.lines[(q, "transient")].get_visible() for q in ("x", "v", "a"))
    ex.toggle("transient", False)
    assert ex.checks.get_status()[2] is False
    # every part line shows the histories' arrays (x parts are checked against the simulator
    # in _assert_shows; the parts add up to the total in the closed-form test below)
    h = ex.histories
    for q in ("x", "v", "a"):
        for part in ("forced", "transient"):
            line = ex.lines[(q, part)]
            np.testing.assert_array_equal(line.get_xdata(), h.t)
            np.testing.assert_array_equal(line.get_ydata(), getattr(h, f"{q}_{part}"))
    np.testing.assert_array_equal(ex.lines[("a", "excitation")].get_ydata(), h.excitation)
    with pytest.raises(ParameterError, match="`part` must be one of"):
        ex.toggle("velocity")  # type: ignore[arg-type]


def test_impact_view_radio() -> None:
    ex = _explorer()
    imp = ex.histories.impacts
    line = ex.axes["impacts"].get_lines()[0]
    np.testing.assert_array_equal(line.get_xdata(), imp.t)
    np.testing.assert_array_equal(line.get_ydata(), imp.v_in)
    ex.radios["impact_view"].set_active(1)
    np.testing.assert_array_equal(line.get_xdata(), imp.phase)
    np.testing.assert_array_equal(line.get_ydata(), imp.v_in)
    assert ex.axes["impacts"].get_xlim() == (0.0, TWO_PI)
    assert "phase" in ex.axes["impacts"].get_xlabel()


# --------------------------------------------------------------------------- physical amplitude
def test_acceleration_mode_and_gap() -> None:
    ex = _explorer()
    f_s, gap = 100.0, 1e-3
    ex.radios["amplitude"].set_active(1)
    assert ex.amplitude_mode == "accel"
    assert ex.sliders["accel_ms2"].ax.get_visible() and not ex.sliders["F"].ax.get_visible()
    # eq. (2.31) with F_es = A_e: F = A_e / ((2 pi f_s)^2 h)
    ex.sliders["accel_ms2"].set_val(50.0)
    F_expected = 50.0 / ((TWO_PI * f_s) ** 2 * gap)
    assert ex.params.F == pytest.approx(F_expected, rel=1e-14)
    assert ex.sliders["F"].val == ex.params.F
    # a wider gap at the same acceleration: smaller F
    ex.sliders["gap_mm"].set_val(2.0)
    assert ex.gap_m == pytest.approx(2e-3, rel=1e-15)
    assert ex.params.F == pytest.approx(F_expected / 2, rel=1e-12)
    assert ex.accel_ms2 == pytest.approx(50.0, rel=1e-12)
    # in F mode the gap changes only the physical scale
    ex.set_amplitude_mode("F")
    assert ex.radios["amplitude"].index_selected == 0
    F_before = ex.params.F
    ex.sliders["gap_mm"].set_val(0.5)
    assert ex.params.F == F_before
    assert ex.accel_ms2 == pytest.approx(F_before * (TWO_PI * f_s) ** 2 * 0.5e-3, rel=1e-12)


def test_invalid_values_change_nothing() -> None:
    ex = _explorer()
    before = ex.histories
    with pytest.raises(ParameterError, match=r"`e` must be in \[0, 1\], was 1.5"):
        ex.set_param("e", 1.5)
    with pytest.raises(ParameterError, match="`gap_m` must be finite and > 0, was 0.0"):
        ex.set_param("gap_m", 0.0)
    with pytest.raises(ParameterError, match="`accel_ms2` must be finite and >= 0, was -1.0"):
        ex.set_param("accel_ms2", -1.0)
    with pytest.raises(ParameterError, match="`name` must be one of"):
        ex.set_param("mass", 1.0)  # type: ignore[arg-type]
    assert ex.params == BASE and ex.histories is before
    # a slider cannot reach an invalid value; the callback guard turns errors into the status
    ex.sliders["omega"].set_val(0.0)
    assert ex.status == "error: `omega` must be > 0, was 0.0"
    assert ex.params == BASE


@pytest.mark.parametrize(("kw", "match"), [
    ({"gap_m": -1.0}, "`gap_m` must be finite and > 0, was -1.0"),
    ({"f_s_hz": 0.0}, "`f_s_hz` must be finite and > 0, was 0.0"),
    ({"participation": 0.0}, "`participation` must be finite and != 0, was 0.0"),
    ({"cycles": float("nan")}, "`cycles` must be finite and > 0, was nan"),
    ({"amplitude_mode": "g"}, "`amplitude_mode` must be one of"),
    ({"sweep_points": 1}, "`sweep_points` must be an integer >= 2, was 1"),
])
def test_constructor_validates(kw: dict[str, object], match: str) -> None:
    with pytest.raises(ParameterError, match=match):
        _explorer(**kw)


# --------------------------------------------------------------------------- sweeps
@pytest.mark.parametrize(("index", "param", "lo", "hi", "n"), [
    (0, "omega", 0.2, 3.0, 17), (1, "F", 0.0, 1.0, 9), (2, "e", 0.0, 1.0, 9)])
def test_sweep_button(index: int, param: str, lo: float, hi: float, n: int) -> None:
    ex = _explorer(sweep_points=n)
    start = ex.histories.result.state
    ex.radios["sweep"].set_active(index)
    _click(ex, "sweep")
    sw = ex.last_sweep
    assert sw is not None and sw.param == param and ex.status.startswith("swept")
    np.testing.assert_allclose(sw.values, np.linspace(lo, hi, n), rtol=0, atol=1e-15)
    ref = sweep(param, np.linspace(lo, hi, n), base=BASE, cycles=30, discard=20, state=start,
                n_max=5, lyapunov="none")
    np.testing.assert_array_equal(sw.mean_impact_velocity, ref.mean_impact_velocity)
    assert sw.labels == ref.labels and "1/1" in sw.labels
    ax = ex.axes["sweep"]
    dots, mean = ax.get_lines()[0], ax.get_lines()[1]
    expected = [(x, v) for x, pt in zip(ref.values, ref.points) for v in pt.impact_velocities]
    assert expected
    np.testing.assert_array_equal(np.column_stack([dots.get_xdata(), dots.get_ydata()]),
                                  np.array(expected))
    np.testing.assert_array_equal(mean.get_ydata(), ref.mean_impact_velocity)
    assert param in ax.get_xlabel() and "nondimensional" in ax.get_ylabel()


def test_amplitude_sweep_in_acceleration_units() -> None:
    ex = _explorer(amplitude_mode="accel")
    sw = ex.run_sweep("A")
    assert sw.param == "F"
    assert ex.radios["sweep"].index_selected == 1
    accel = sw.values * (TWO_PI * 100.0) ** 2 * 1e-3
    xs = ex.axes["sweep"].get_lines()[1].get_xdata()
    np.testing.assert_allclose(xs, accel, rtol=1e-12)
    np.testing.assert_allclose(accel[[0, -1]], [ex.sliders["accel_ms2"].valmin,
                                                ex.sliders["accel_ms2"].valmax], rtol=1e-12)
    assert "m/s^2" in ex.axes["sweep"].get_xlabel()


# --------------------------------------------------------------------------- saving
def test_save_csv_through_the_text_box(tmp_path: Path) -> None:
    ex = _explorer()
    target = tmp_path / "run.csv"
    ex.textbox.set_val(str(target))
    _click(ex, "save")
    assert ex.status == f"saved {target}, {tmp_path / 'run_impacts.csv'}"
    hist = pd.read_csv(target, comment="#")
    assert list(hist.columns) == [c for c, _, _ in HISTORY_COLUMNS]
    table = ex.histories.history_table()
    for name in hist.columns:
        np.testing.assert_array_equal(hist[name].to_numpy(), table[name])
    imp = pd.read_csv(impacts_path(target), comment="#")
    assert list(imp.columns) == [c for c, _, _ in IMPACT_COLUMNS]
    np.testing.assert_array_equal(imp["v_in"].to_numpy(), ex.histories.impacts.v_in)
    # physical columns: eq. (2.29), (2.30), (4.4) with f_s = 100 Hz, h = 1 mm
    w = TWO_PI * 100.0
    np.testing.assert_allclose(hist["time_s"], hist["t"] / w, rtol=1e-15)
    np.testing.assert_allclose(hist["v_ms"], hist["v"] * w * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(imp["v_in_ms"], imp["v_in"] * w * 1e-3, rtol=1e-15)
    header = target.read_text().splitlines()[:5]
    assert any(line.startswith("# units: t [1], time_s [s]") for line in header)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv", "run_impacts.csv"]


def test_save_hdf5(tmp_path: Path) -> None:
    ex = _explorer()
    (path,) = ex.save(tmp_path / "run.h5")
    with h5py.File(path, "r") as f:
        assert f.attrs["F"] == BASE.F and f.attrs["omega"] == BASE.omega
        assert f.attrs["gap_m"] == 1e-3 and f.attrs["f_s_hz"] == 100.0
        assert "rattle_lab" in f.attrs["provenance"]
        assert list(f["time_history"]) == sorted(c for c, _, _ in HISTORY_COLUMNS)
        for name, unit, _ in HISTORY_COLUMNS:
            assert f["time_history"][name].attrs["units"] == unit
        np.testing.assert_array_equal(f["time_history/x"][()], ex.histories.x)
        np.testing.assert_array_equal(f["impacts/t"][()], ex.histories.impacts.t)
        assert f["impacts/v_in_ms"].attrs["units"] == "m/s"
    assert [p.name for p in tmp_path.iterdir()] == ["run.h5"]


def test_save_default_path_and_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    ex = _explorer()
    assert ex.save() == (Path("rattle_explore.h5"),)
    assert (tmp_path / "rattle_explore.h5").is_file()
    with pytest.raises(ParameterError, match="must end in one of .csv, .h5, .hdf5"):
        ex.save(tmp_path / "run.txt")
    with pytest.raises(OutputError, match="output directory .* does not exist"):
        ex.save(tmp_path / "missing" / "run.h5")
    ex.textbox.set_val(str(tmp_path / "missing" / "run.csv"))
    _click(ex, "save")  # the button reports instead of raising
    assert ex.status.startswith("error: ") and "does not exist" in ex.status
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rattle_explore.h5"]


def test_save_no_impacts_writes_empty_table(tmp_path: Path) -> None:
    h = compute_histories(SDFParams(F=0.05, omega=0.7, zeta=0.05, e=0.6), cycles=2)
    a, b = save_histories(h, tmp_path / "quiet.csv")
    assert len(pd.read_csv(b, comment="#")) == 0
    assert len(pd.read_csv(a, comment="#")) == h.t.size


# --------------------------------------------------------------------------- labels, image
def test_every_axis_is_labelled_with_units(tmp_path: Path) -> None:
    ex = _explorer()
    ex.run_sweep("omega")
    for name, ax in ex.axes.items():
        if name in ("x", "v"):  # share the time axis with "a"
            labels = [ax.get_ylabel()]
        else:
            labels = [ax.get_xlabel(), ax.get_ylabel()]
        for label in labels:
            assert label, name
            assert "nondimensional" in label or "[" in label, (name, label)
    png = ex.save_png(tmp_path / "explorer.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# --------------------------------------------------------------------------- CLI
def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["MPLBACKEND"] = "Agg"
    return subprocess.run([str(EXE), "explore", *args], capture_output=True, text=True,
                          timeout=120, env=env, cwd=cwd)


def test_cli_without_display_exits_2_with_one_line(tmp_path: Path) -> None:
    out = _cli("--F", "0.3", cwd=tmp_path)
    assert out.returncode == 2
    assert out.stdout == ""
    lines = out.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rattle-lab: error: no display")
    assert "--save-png" in lines[0]


def test_cli_save_png(tmp_path: Path) -> None:
    out = _cli("--accel-ms2", "80", "--omega", "1.1", "--zeta", "0.05", "--e", "0.7",
               "--cycles", "5", "--save-png", "explorer.png", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout == ""
    assert (tmp_path / "explorer.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_errors_are_one_line(tmp_path: Path) -> None:
    out = _cli("--e", "1.5", "--save-png", "x.png", cwd=tmp_path)
    assert out.returncode == 2 and out.stdout == ""
    assert out.stderr == "rattle-lab: error: `e` must be in [0, 1], was 1.5\n"
    out = _cli("--save-png", "x.gif", cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.startswith("rattle-lab: error: plot file 'x.gif' must end in")
    assert list(tmp_path.iterdir()) == []


def test_real_mouse_events_reach_the_widgets() -> None:
    """Clicks delivered through the canvas (as a window would) drive the explorer."""
    from matplotlib.backend_bases import MouseEvent
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    ex = _explorer()
    canvas = FigureCanvasAgg(ex.figure)
    canvas.draw()

    def click(ax: object, fx: float, fy: float = 0.5) -> None:
        x, y = ax.transAxes.transform((fx, fy))  # type: ignore[attr-defined]
        for name in ("button_press_event", "button_release_event"):
            MouseEvent(name, canvas, x, y, button=1)._process()

    slider = ex.sliders["omega"]
    click(slider.ax, 0.5)  # the middle of the omega slider
    assert ex.params.omega == pytest.approx(0.5 * (slider.valmin + slider.valmax), rel=0.02)
    end = ex.histories.result.state
    click(ex.buttons["advance"].ax, 0.5)
    assert ex.histories.start_state == end
    click(ex.buttons["restart"].ax, 0.5)
    assert ex.histories.start_state == SDFState()


def _legend_labels(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_legends_list_only_the_curves_shown() -> None:
    # issue 17: the legend listed the hidden parts (forced, transient, excitation)
    ex = _explorer()
    assert _legend_labels(ex.axes["x"]) == [ex.lines[("x", "total")].get_label(), "stop (x = 1)"]
    assert ex.lines[("a", "excitation")].get_label() not in _legend_labels(ex.axes["a"])
    ex.toggle("forced", True)
    ex.toggle("total", False)
    shown_x = _legend_labels(ex.axes["x"])
    assert ex.lines[("x", "forced")].get_label() in shown_x
    assert ex.lines[("x", "total")].get_label() not in shown_x
    ex.toggle("excitation", True)
    assert ex.lines[("a", "excitation")].get_label() in _legend_labels(ex.axes["a"])


def test_the_sweep_panel_opens_with_a_sweep() -> None:
    # issue 27: the panel was an empty placeholder until 'sweep' was pressed; it opens with
    # the sweep of omega from the opening state (the same as sweep() called directly), and
    # its axis says v_in like the rest of the window
    ex = _explorer()
    sw = ex.last_sweep
    assert sw is not None and sw.param == "omega"
    start = _explorer(initial_sweep=False).histories.result.state
    ref = sweep("omega", ex.sweep_values("omega"), base=BASE, cycles=30, discard=20,
                state=start, n_max=5, lyapunov="none")
    np.testing.assert_array_equal(sw.mean_impact_velocity, ref.mean_impact_velocity)
    ax = ex.axes["sweep"]
    assert ax.get_lines() and any(line.get_xdata().size for line in ax.get_lines())
    assert "v_in" in ax.get_ylabel() and "v_im" not in ax.get_ylabel()
    assert not any("no sweep yet" in t.get_text() for t in ax.texts)


def test_sweep_panel_is_never_a_blank_frame() -> None:
    # issue 17: without the opening sweep the panel says how to fill it; a sweep without
    # impacts says so
    ex = _explorer(initial_sweep=False)
    ax = ex.axes["sweep"]
    assert any("no sweep yet" in t.get_text() for t in ax.texts)
    ex.set_param("F", 1e-4)  # far below the grazing amplitude: no impact anywhere
    ex.run_sweep("omega")
    assert ex.last_sweep is not None
    texts = [t.get_text() for t in ax.texts]
    assert not any("no sweep yet" in t for t in texts)
    assert not any(p.impact_velocities.size for p in ex.last_sweep.points)
    assert "no impact at any value of this sweep" in texts
