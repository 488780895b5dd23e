"""The explorer window: the thesis's Java applet (Appendix A, section 4.1.3) in matplotlib.

:class:`Explorer` owns a :class:`matplotlib.figure.Figure` and its widgets.
Every widget callback is a thin call into one public method
(:meth:`Explorer.set_param`, :meth:`Explorer.toggle`,
:meth:`Explorer.run_sweep`, :meth:`Explorer.save`, ...), so the explorer
works without a display: tests and scripts drive it with the Agg backend.

Like the applet (``Impact_sys.setF_related``), a parameter change continues
the motion from where the last run ended, with the forcing phase continuous;
"restart" goes back to rest.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rattle_lab.model.analysis import Sweep, sweep
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.scaling import F_from_accel, accel_ms2_from_F
from rattle_lab.model.sdf import SDFParams, SDFState
from ._choices import (_PART_LABELS, _PART_STYLE,
                       _SWEEP_X_LABELS, _Y_LABELS, AMPLITUDE_MODES,
                       DEFAULT_SAVE_PATH, IMPACT_VIEWS, PARAM_NAMES, PARTS, QUANTITIES,
                       SWEEP_CHOICES, AmplitudeMode, ImpactView, ParamName, Part, Quantity,
                       SweepChoice)
from ._histories import TWO_PI, Histories, compute_histories, save_histories
from ._widgets import Widgets

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

def display_available() -> bool:
    """Whether the explorer can open a window: an interactive backend and a display.

    False when matplotlib resolved (or ``MPLBACKEND`` names) a file-only
    backend such as Agg, and on Linux when neither ``DISPLAY`` nor
    ``WAYLAND_DISPLAY`` is set (pyplot would fall back to Agg silently).
    """
    import matplotlib
    from matplotlib.backends.registry import BackendFilter, backend_registry

    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        return False
    backend = matplotlib.get_backend().lower()
    interactive = {b.lower() for b in backend_registry.list_builtin(  # type: ignore[no-untyped-call]
        BackendFilter.INTERACTIVE)}
    return backend in interactive


def _check_choice(name: str, value: object, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise ParameterError(f"`{name}` must be one of {choices}, was {value!r}")


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ParameterError(f"`{name}` must be finite and > 0, was {value}")
    return value


class Explorer:
    """Interactive explorer of the SDF impact oscillator (the thesis's applet, Appendix A).

    The window shows the time histories of displacement, velocity and
    acceleration with their forced, transient and excitation parts
    (check boxes), the phase portrait, the impacts (incoming velocity against
    time or forcing phase), and a slow sweep of the impact velocity against
    ``omega``, the amplitude or ``e`` (:func:`rattle_lab.model.analysis.sweep`).
    Sliders set ``F`` (or the base acceleration ``A_e`` in m/s^2, through the
    gap and ``f_s``), ``omega``, ``zeta``, ``e`` and the gap.

    Parameters
    ----------
    params : SDFParams, optional
        Start parameters (nondimensional; default F=0.2, omega=1, zeta=0.05, e=0.6).
    gap_m : float
        Gap ``h`` [m] (> 0).
    f_s_hz : float
        Modal frequency ``f_s`` [Hz] (> 0).
    participation : float
        ``Q1 / Q2`` of the mode (eq. 2.27): ``F = participation A_e / ((2 pi f_s)^2 h)``;
        1 for a single-degree-of-freedom oscillator on a shaken base.
    cycles : float
        Forcing periods simulated and shown per run (> 0).
    n_per_cycle : int
        Samples per forcing period.
    amplitude_mode : {"F", "accel"}
        Whether the amplitude slider sets ``F`` or ``A_e`` [m/s^2].
    sweep_points : int
        Values per sweep (>= 2), spread over the slider's range.
    sweep_cycles, sweep_discard : int
        Forcing periods simulated and discarded at each sweep value.
    figure : Figure, optional
        The figure to draw into (e.g. ``plt.figure()`` for a window); a new
        :class:`~matplotlib.figure.Figure` (no pyplot, no display) by default.
    initial_sweep : bool
        Open with a sweep of ``omega`` over its slider's range in the sweep panel (the
        panel is never an empty frame); False leaves it to the 'sweep' button.

    Attributes
    ----------
    figure : Figure
        The window's figure.
    histories : Histories
        The run on display.
    last_sweep : Sweep or None
        The last sweep run.
    sliders, checks, radios, buttons, textbox
        The widgets (``sliders`` keyed by ``"F"``, ``"accel_ms2"``,
        ``"omega"``, ``"zeta"``, ``"e"``, ``"gap_mm"``; ``radios`` by
        ``"amplitude"``, ``"impact_view"``, ``"sweep"``; ``buttons`` by
        ``"sweep"``, ``"advance"``, ``"restart"``, ``"save"``).
    status : str
        The last status line (errors from callbacks land here).

    Examples
    --------
    >>> import numpy as np
    >>> ex = Explorer(cycles=5)
    >>> ex.set_param("omega", 1.2)
    >>> bool(np.isclose(ex.params.omega, 1.2))
    True
    """

    def __init__(self, params: SDFParams | None = None, *, gap_m: float = 1e-3,
                 f_s_hz: float = 100.0, participation: float = 1.0, cycles: float = 20.0,
                 n_per_cycle: int = 100, amplitude_mode: AmplitudeMode = "F",
                 sweep_points: int = 41, sweep_cycles: int = 40, sweep_discard: int = 20,
                 figure: Figure | None = None, initial_sweep: bool = True) -> None:
        self._params = SDFParams(F=0.2, omega=1.0, zeta=0.05, e=0.6) if params is None else params
        if not isinstance(self._params, SDFParams):
            raise ParameterError(f"`params` must be an SDFParams, was {type(params).__name__}")
        self._gap_m = _positive("gap_m", gap_m)
        self._f_s_hz = _positive("f_s_hz", f_s_hz)
        self._participation = float(participation)
        if not math.isfinite(self._participation) or self._participation == 0.0:
            raise ParameterError(f"`participation` must be finite and != 0, was {participation}")
        self._cycles = _positive("cycles", cycles)
        self._n_per_cycle = n_per_cycle
        _check_choice("amplitude_mode", amplitude_mode, AMPLITUDE_MODES)
        if isinstance(sweep_points, bool) or not isinstance(sweep_points, int) or sweep_points < 2:
            raise ParameterError(f"`sweep_points` must be an integer >= 2, was {sweep_points!r}")
        self._sweep_points = sweep_points
        self._sweep_cycles = sweep_cycles
        self._sweep_discard = sweep_discard
        self._mode: AmplitudeMode = amplitude_mode
        self._visible: dict[Part, bool] = {"total": True, "forced": False, "transient": False,
                                           "excitation": False}
        self._impact_view: ImpactView = "time"
        self._sweep_choice: SweepChoice = "omega"
        self.last_sweep: Sweep | None = None
        self.status = ""
        self.histories: Histories = compute_histories(
            self._params, cycles=self._cycles, n_per_cycle=n_per_cycle, gap_m=self._gap_m,
            f_s_hz=self._f_s_hz, participation=self._participation)
        if figure is None:
            from matplotlib.figure import Figure as _Figure

            figure = _Figure(figsize=(16, 10))
        self.figure = figure
        self._build_axes()
        self._widgets = Widgets(self)
        self._redraw()
        if initial_sweep:  # the sweep panel opens with a sweep of omega, not an empty frame
            self.run_sweep()

    # ------------------------------------------------------------------ properties
    @property
    def params(self) -> SDFParams:
        """The current nondimensional parameters."""
        return self._params

    @property
    def gap_m(self) -> float:
        """The gap ``h`` [m]."""
        return self._gap_m

    @property
    def f_s_hz(self) -> float:
        """The modal frequency ``f_s`` [Hz]."""
        return self._f_s_hz

    @property
    def omega_s_rad_s(self) -> float:
        """``2 pi f_s`` [rad/s]."""
        return TWO_PI * self._f_s_hz

    @property
    def accel_ms2(self) -> float:
        """Base-acceleration amplitude ``A_e`` [m/s^2] equivalent to the current ``F``."""
        return float(accel_ms2_from_F(self._params.F, self._participation, self.omega_s_rad_s,
                                      self._gap_m))

    @property
    def amplitude_mode(self) -> AmplitudeMode:
        """``"F"`` or ``"accel"``: what the amplitude slider sets."""
        return self._mode

    @property
    def visible_parts(self) -> dict[Part, bool]:
        """Which parts of the time histories are shown."""
        return dict(self._visible)

    @property
    def lines(self) -> Mapping[tuple[Quantity, Part], Line2D]:
        """The time-history lines, keyed by ``(quantity, part)`` (no excitation on x, v)."""
        return dict(self._lines)

    @property
    def axes(self) -> Mapping[str, Axes]:
        """The plot axes: ``"x"``, ``"v"``, ``"a"``, ``"phase"``, ``"impacts"``, ``"sweep"``."""
        return dict(self._axes)

    # ------------------------------------------------------------------ public actions
    def set_param(self, name: ParamName, value: float) -> None:
        """Set one parameter and run again from the current state.

        Parameters
        ----------
        name : {"F", "accel_ms2", "omega", "zeta", "e", "gap_m"}
            ``"accel_ms2"`` is the base-acceleration amplitude [m/s^2] (sets ``F``
            through the gap and ``f_s``, eq. 2.27, 2.31); ``"gap_m"`` is in metres
            and, in ``"accel"`` amplitude mode, keeps ``A_e`` and changes ``F``.
        value : float
            The new value.

        Raises
        ------
        ParameterError
            If ``name`` is unknown or ``value`` invalid (nothing changes then).
        """
        _check_choice("name", name, PARAM_NAMES)
        value = float(value)
        params, gap_m = self._params, self._gap_m
        if name == "gap_m":
            gap_m = _positive("gap_m", value)
            if self._mode == "accel":
                params = params.replace(F=float(F_from_accel(
                    self.accel_ms2, self._participation, self.omega_s_rad_s, gap_m)))
        elif name == "accel_ms2":
            if not (math.isfinite(value) and value >= 0):
                raise ParameterError(f"`accel_ms2` must be finite and >= 0, was {value}")
            params = params.replace(F=float(F_from_accel(
                value, self._participation, self.omega_s_rad_s, gap_m)))
        else:
            params = params.replace(**{name: value})
        self._params, self._gap_m = params, gap_m
        self._widgets.sync_sliders()
        self._run(self.histories.result.state)

    def set_amplitude_mode(self, mode: AmplitudeMode) -> None:
        """Show the ``F`` slider (``"F"``) or the base-acceleration slider (``"accel"``)."""
        _check_choice("mode", mode, AMPLITUDE_MODES)
        self._mode = mode
        self._widgets.sliders["F"].ax.set_visible(mode == "F")
        self._widgets.sliders["accel_ms2"].ax.set_visible(mode == "accel")
        self._widgets.sync_radio("amplitude", AMPLITUDE_MODES.index(mode))
        self._redraw()

    def toggle(self, part: Part, visible: bool | None = None) -> None:
        """Show or hide one part of the time histories (flip it when ``visible`` is None)."""
        _check_choice("part", part, PARTS)
        self._visible[part] = (not self._visible[part]) if visible is None else bool(visible)
        index = PARTS.index(part)
        checks = self._widgets.checks
        if checks.get_status()[index] != self._visible[part]:
            checks.eventson = False
            try:
                checks.set_active(index)
            finally:
                checks.eventson = True
        self._redraw()

    def set_impact_view(self, view: ImpactView) -> None:
        """Plot the impact velocities against time (``"time"``) or forcing phase (``"phase"``)."""
        _check_choice("view", view, IMPACT_VIEWS)
        self._impact_view = view
        self._widgets.sync_radio("impact_view", IMPACT_VIEWS.index(view))
        self._redraw()

    def advance(self) -> None:
        """Simulate the next ``cycles`` periods with the same parameters."""
        self._run(self.histories.result.state)

    def restart(self) -> None:
        """Start again from rest (x = 0, v = 0, phase 0, t = 0)."""
        self._run(SDFState())

    def sweep_values(self, param: SweepChoice) -> np.ndarray:
        """The ``sweep_points`` values a sweep of ``param`` visits (nondimensional).

        The range is the slider's; for ``"A"`` the values are of ``F`` (in
        ``"accel"`` mode the accel slider's range converted to ``F``).
        """
        _check_choice("param", param, SWEEP_CHOICES)
        if param == "A":
            key = "F" if self._mode == "F" else "accel_ms2"
        else:
            key = param
        s = self._widgets.sliders[key]
        lo, hi = float(s.valmin), float(s.valmax)
        values = np.linspace(lo, hi, self._sweep_points)
        if key == "accel_ms2":
            values = np.asarray(F_from_accel(values, self._participation, self.omega_s_rad_s,
                                             self._gap_m), dtype=float)
        if param == "omega":
            values = values[values > 0]
        return values

    def run_sweep(self, param: SweepChoice | None = None) -> Sweep:
        """Sweep ``param`` up over its slider's range and plot ``v_in`` against it.

        A slow up-sweep (:func:`rattle_lab.model.analysis.sweep`) from the current
        state, the other parameters held at their current values, with
        ``sweep_cycles`` periods per value of which ``sweep_discard`` are
        discarded; no Lyapunov exponents (for speed).

        Parameters
        ----------
        param : {"omega", "A", "e"}, optional
            The parameter (``"A"``: the amplitude, ``F`` or ``A_e`` by the
            amplitude mode); default the one chosen with the radio buttons.

        Returns
        -------
        Sweep
        """
        choice = self._sweep_choice if param is None else param
        _check_choice("param", choice, SWEEP_CHOICES)
        self._sweep_choice = choice
        self._widgets.sync_radio("sweep", SWEEP_CHOICES.index(choice))
        kept = self._sweep_cycles - self._sweep_discard
        result = sweep("F" if choice == "A" else choice, self.sweep_values(choice),
                       base=self._params, direction="up", cycles=self._sweep_cycles,
                       discard=self._sweep_discard, state=self.histories.result.state,
                       n_max=max(1, min(12, kept // 2)), lyapunov="none", quiet=True)
        self.last_sweep = result
        self._draw_sweep()
        self.status = f"swept {choice} over {len(result.points)} values"
        self._redraw()
        return result

    def save(self, path: str | Path | None = None) -> tuple[Path, ...]:
        """Write the current time histories and impacts (CSV or HDF5 by suffix), atomically.

        Parameters
        ----------
        path : str or Path, optional
            Target (``.csv``, ``.h5``, ``.hdf5``); default the text box's
            content, or :data:`DEFAULT_SAVE_PATH` in the current directory.

        Returns
        -------
        tuple of Path
            The files written (see :func:`rattle_lab.explorer.save_histories`).
        """
        if path is None:
            path = self._widgets.textbox.text.strip() or DEFAULT_SAVE_PATH
        written = save_histories(self.histories, path)
        self.status = "saved " + ", ".join(str(p) for p in written)
        self._redraw()
        return written

    def save_png(self, path: str | Path) -> Path:
        """Render the window as it is to an image (png/pdf/svg), atomically."""
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        from rattle_lab.plot import save_figure

        canvas = self.figure.canvas
        if not hasattr(canvas, "print_png"):
            FigureCanvasAgg(self.figure)
        return save_figure(self.figure, path)

    # ------------------------------------------------------------------ internals
    def _run(self, state: SDFState) -> None:
        self.histories = compute_histories(
            self._params, cycles=self._cycles, n_per_cycle=self._n_per_cycle, state=state,
            gap_m=self._gap_m, f_s_hz=self._f_s_hz, participation=self._participation)
        self._redraw()

    def _build_axes(self) -> None:
        fig = self.figure
        ax_x = fig.add_axes((0.07, 0.77, 0.53, 0.19))
        ax_v = fig.add_axes((0.07, 0.57, 0.53, 0.19), sharex=ax_x)
        ax_a = fig.add_axes((0.07, 0.37, 0.53, 0.19), sharex=ax_x)
        ax_p = fig.add_axes((0.72, 0.73, 0.26, 0.23))
        ax_i = fig.add_axes((0.72, 0.41, 0.26, 0.23))
        ax_s = fig.add_axes((0.72, 0.07, 0.26, 0.25))
        self._axes: dict[str, Axes] = {"x": ax_x, "v": ax_v, "a": ax_a, "phase": ax_p,
                                       "impacts": ax_i, "sweep": ax_s}
        self._lines: dict[tuple[Quantity, Part], Line2D] = {}
        for q in QUANTITIES:
            ax = self._axes[q]
            parts: tuple[Part, ...] = PARTS if q == "a" else PARTS[:3]
            for part in parts:
                (line,) = ax.plot([], [], label=_PART_LABELS[part], **_PART_STYLE[part])
                self._lines[(q, part)] = line
            ax.set_ylabel(_Y_LABELS[q])
            ax.grid(alpha=0.3)
            if q != "a":
                ax.tick_params(labelbottom=False)
        ax_x.axhline(1.0, color="tab:blue", lw=1.2, label="stop (x = 1)")
        ax_x.legend(loc="lower left", fontsize=7, ncol=4)
        ax_a.legend(loc="lower left", fontsize=7, ncol=4)
        (self._impact_marks,) = ax_v.plot([], [], "o", ms=3, mfc="none", color="tab:purple",
                                          label="v_in at impact")
        ax_a.set_xlabel("time t = omega_s t_s (nondimensional)")
        (self._phase_line,) = ax_p.plot([], [], color="black", lw=0.7)
        ax_p.axvline(1.0, color="tab:blue", lw=1.2)
        ax_p.set_xlabel("displacement x (nondimensional)")
        ax_p.set_ylabel("velocity dx/dt (nondimensional)")
        ax_p.set_title("phase portrait", fontsize=10)
        ax_p.grid(alpha=0.3)
        (self._impact_line,) = ax_i.plot([], [], "o", ms=3, color="tab:purple")
        self._no_impacts = ax_i.text(0.5, 0.5, "no impacts", transform=ax_i.transAxes,
                                     ha="center", va="center", color="gray")
        ax_i.set_ylabel("impact velocity v_in (nondimensional)")
        ax_i.grid(alpha=0.3)
        ax_s.set_title("sweep: press 'sweep'", fontsize=10)
        # [issue 17] say what the panel will hold instead of showing an empty frame
        self._sweep_hint = ax_s.text(
            0.5, 0.5, "no sweep yet: choose omega, F (or A) or e\nand press 'sweep' to sweep it "
            "up from the current state", transform=ax_s.transAxes, ha="center", va="center",
            color="gray", fontsize=8, wrap=True)
        ax_s.set_xlabel(_SWEEP_X_LABELS["omega"])
        ax_s.set_ylabel("impact velocity v_in (nondimensional)")
        ax_s.grid(alpha=0.3)
        self._info = fig.text(0.07, 0.975, "", fontsize=9, va="center")
        self._status_text = fig.text(0.07, 0.008, "", fontsize=8, color="tab:red")

    # widget-facing accessors (documented in the class docstring)
    @property
    def sliders(self) -> Mapping[str, Any]:
        return self._widgets.sliders

    @property
    def checks(self) -> Any:
        return self._widgets.checks

    @property
    def radios(self) -> Mapping[str, Any]:
        return self._widgets.radios

    @property
    def buttons(self) -> Mapping[str, Any]:
        return self._widgets.buttons

    @property
    def textbox(self) -> Any:
        return self._widgets.textbox

    def _redraw(self) -> None:
        h = self.histories
        data: dict[tuple[Quantity, Part], np.ndarray] = {
            ("x", "total"): h.x, ("x", "forced"): h.x_forced, ("x", "transient"): h.x_transient,
            ("v", "total"): h.v, ("v", "forced"): h.v_forced, ("v", "transient"): h.v_transient,
            ("a", "total"): h.a, ("a", "forced"): h.a_forced, ("a", "transient"): h.a_transient,
            ("a", "excitation"): h.excitation,
        }
        for key, line in self._lines.items():
            line.set_data(h.t, data[key])
            line.set_visible(self._visible[key[1]])
        imp = h.impacts
        self._impact_marks.set_data(imp.t, imp.v_in)
        self._impact_marks.set_visible(self._visible["total"])
        self._phase_line.set_data(h.x, h.v)
        ax_i = self._axes["impacts"]
        if self._impact_view == "time":
            self._impact_line.set_data(imp.t, imp.v_in)
            ax_i.set_xlabel("impact time t (nondimensional)")
            ax_i.set_title("impacts only: v_in against time", fontsize=10)
        else:
            self._impact_line.set_data(imp.phase, imp.v_in)
            ax_i.set_xlabel("forcing phase at impact omega t + phi [rad]")
            ax_i.set_title("impact map: v_in against phase", fontsize=10)
        for name in ("x", "v", "a", "phase", "impacts"):
            ax = self._axes[name]
            ax.relim(visible_only=True)
            ax.autoscale_view()
        if len(imp) == 0:  # nothing to scale to: do not keep the last run's limits
            ax_i.set_ylim(0.0, 1.0)
            if self._impact_view == "time":
                ax_i.set_xlim(h.t[0], h.t[-1])
        if self._impact_view == "phase":
            ax_i.set_xlim(0.0, TWO_PI)
        self._no_impacts.set_visible(len(imp) == 0)
        self._axes["x"].set_xlim(h.t[0], h.t[-1])
        p = self._params
        v_max = float(np.max(imp.v_in)) if len(imp) else 0.0
        self._info.set_text(
            f"F = {p.F:.4g} (A_e = {self.accel_ms2:.4g} m/s^2)   omega = {p.omega:.4g} "
            f"(f = {p.omega * self._f_s_hz:.4g} Hz, f_s = {self._f_s_hz:.4g} Hz)   "
            f"zeta = {p.zeta:.4g}   e = {p.e:.4g}   gap = {self._gap_m * 1e3:.4g} mm   |   "
            f"{len(imp)} impacts, max v_in = {v_max:.4g} "
            f"(= {v_max * self.omega_s_rad_s * self._gap_m:.4g} m/s)")
        self._refresh_legends()
        self._status_text.set_text(self.status)
        self._status_text.set_color("tab:red" if self.status.startswith("error") else "black")
        self.figure.canvas.draw_idle()

    def _refresh_legends(self) -> None:
        """Legends of the time-history axes that list only the curves shown (issue 17)."""
        for name in ("x", "a"):
            ax = self._axes[name]
            shown = [ln for ln in ax.get_lines()
                     if ln.get_visible() and not str(ln.get_label()).startswith("_")]
            ax.legend(handles=shown, loc="lower left", fontsize=7, ncol=4)

    def _draw_sweep(self) -> None:
        sw = self.last_sweep
        if sw is None:
            return
        ax = self._axes["sweep"]
        ax.cla()
        accel = sw.param == "F" and self._mode == "accel"

        def to_x(values: np.ndarray) -> np.ndarray:
            if accel:
                return np.asarray(accel_ms2_from_F(values, self._participation,
                                                   self.omega_s_rad_s, self._gap_m), dtype=float)
            return values

        xs = to_x(sw.values)
        pts = np.array([(x, v) for x, pt in zip(xs, sw.points) for v in pt.impact_velocities])
        pts = pts.reshape(-1, 2)  # (0, 2) without impacts: the line exists, empty
        ax.plot(pts[:, 0], pts[:, 1], ".", color="black", ms=2, label="v_in")
        ax.plot(xs, sw.mean_impact_velocity, "-", color="tab:blue", lw=0.8,
                label="mean v_in per forcing cycle")
        current = {"omega": self._params.omega, "F": self._params.F, "e": self._params.e}
        ax.axvline(float(to_x(np.array([current.get(sw.param, np.nan)]))[0]), color="tab:red",
                   lw=0.8, label="current value")
        ax.set_xlabel(_SWEEP_X_LABELS["accel" if accel else sw.param])
        ax.set_ylabel("impact velocity v_in (nondimensional)")
        ax.set_title(f"up-sweep of {'A_e' if accel else sw.param} from the current state",
                     fontsize=10)
        if pts.shape[0] == 0:  # [issue 17] an empty sweep says so
            ax.text(0.5, 0.5, "no impact at any value of this sweep", transform=ax.transAxes,
                    ha="center", va="center", color="gray", fontsize=8)
        ax.legend(loc="upper left", fontsize=7)
        ax.grid(alpha=0.3)


__all__ = ["Explorer", "display_available", "DEFAULT_SAVE_PATH", "PARAM_NAMES", "PARTS",
           "SWEEP_CHOICES", "IMPACT_VIEWS", "AMPLITUDE_MODES"]
