"""The explorer's widgets: sliders, check and radio buttons, buttons and the save box.

Each callback is a thin call into a public method of :class:`~rattle_lab.explorer.Explorer`;
the explorer keeps the model state, this object only the matplotlib widgets.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from rattle_lab.exceptions import RattleLabError
from rattle_lab.model.scaling import accel_ms2_from_F

from ._choices import (_AMPLITUDE_LABELS, _IMPACT_VIEW_LABELS, _PART_LABELS, _RANGES,
                       _SWEEP_LABELS, AMPLITUDE_MODES, DEFAULT_SAVE_PATH, IMPACT_VIEWS, PARTS,
                       SWEEP_CHOICES)

if TYPE_CHECKING:
    from ._window import Explorer


class Widgets:
    """The widgets of one :class:`~rattle_lab.explorer.Explorer`, built on its figure."""

    def __init__(self, explorer: Explorer) -> None:
        self._ex = explorer
        self._syncing = False
        from matplotlib.widgets import Button, CheckButtons, RadioButtons, Slider, TextBox

        ex = explorer
        fig = ex.figure
        p = ex.params
        accel_hi = float(accel_ms2_from_F(_RANGES["F"][1], ex._participation,
                                          ex.omega_s_rad_s, ex.gap_m))
        specs: list[tuple[str, str, tuple[float, float], float]] = [
            ("F", "F (nondim.)", _RANGES["F"], p.F),
            ("accel_ms2", "A_e [m/s^2]", (0.0, accel_hi), ex.accel_ms2),
            ("omega", "omega (nondim.)", _RANGES["omega"], p.omega),
            ("zeta", "zeta (nondim.)", _RANGES["zeta"], p.zeta),
            ("e", "e (nondim.)", _RANGES["e"], p.e),
            ("gap_mm", "gap h [mm]", _RANGES["gap_mm"], ex.gap_m * 1e3),
        ]
        ys = {"F": 0.25, "accel_ms2": 0.25, "omega": 0.205, "zeta": 0.16, "e": 0.115,
              "gap_mm": 0.07}
        self._sliders: dict[str, Slider] = {}
        for key, label, (lo, hi), value in specs:
            lo, hi = min(lo, value), max(hi, value)  # widen, never clamp the start value
            ax = fig.add_axes((0.13, ys[key], 0.2, 0.03))
            slider = Slider(ax, label, lo, hi, valinit=value)
            slider.on_changed(self._slider_callback(key))
            self._sliders[key] = slider
        self._sliders["F"].ax.set_visible(ex.amplitude_mode == "F")
        self._sliders["accel_ms2"].ax.set_visible(ex.amplitude_mode == "accel")

        self._checks = CheckButtons(fig.add_axes((0.40, 0.14, 0.1, 0.14)),
                                    [_PART_LABELS[q] for q in PARTS],
                                    [ex.visible_parts[q] for q in PARTS])
        self._checks.on_clicked(self._on_check)
        self._radios: dict[str, RadioButtons] = {
            "amplitude": RadioButtons(fig.add_axes((0.40, 0.03, 0.1, 0.09)),
                                      [_AMPLITUDE_LABELS[m] for m in AMPLITUDE_MODES],
                                      active=AMPLITUDE_MODES.index(ex.amplitude_mode)),
            "impact_view": RadioButtons(fig.add_axes((0.51, 0.19, 0.09, 0.09)),
                                        [_IMPACT_VIEW_LABELS[v] for v in IMPACT_VIEWS]),
            "sweep": RadioButtons(fig.add_axes((0.51, 0.06, 0.09, 0.11)),
                                  [_SWEEP_LABELS[c] for c in SWEEP_CHOICES]),
        }
        self._radios["amplitude"].on_clicked(self._radio_callback("amplitude"))
        self._radios["impact_view"].on_clicked(self._radio_callback("impact_view"))
        self._radios["sweep"].on_clicked(self._radio_callback("sweep"))
        self._buttons: dict[str, Button] = {}
        for i, (key, label, action) in enumerate((
                ("sweep", "sweep", lambda: ex.run_sweep()),
                ("advance", "advance", ex.advance),
                ("restart", "restart", ex.restart),
                ("save", "save data", lambda: ex.save()))):
            button = Button(fig.add_axes((0.615, 0.25 - 0.05 * i, 0.06, 0.04)), label)
            button.on_clicked(self._guarded(action))
            self._buttons[key] = button
        self._textbox = TextBox(fig.add_axes((0.13, 0.02, 0.2, 0.03)), "save to ",
                                initial=DEFAULT_SAVE_PATH)

    @property
    def sliders(self) -> Mapping[str, Any]:
        return dict(self._sliders)

    @property
    def checks(self) -> Any:
        return self._checks

    @property
    def radios(self) -> Mapping[str, Any]:
        return dict(self._radios)

    @property
    def buttons(self) -> Mapping[str, Any]:
        return dict(self._buttons)

    @property
    def textbox(self) -> Any:
        return self._textbox

    def _guarded(self, action: Callable[[], object]) -> Callable[[Any], None]:
        """Wrap a callback: a RattleLabError or OSError becomes the status line."""
        def callback(_event: Any) -> None:
            try:
                action()
            except (RattleLabError, OSError) as exc:
                self._ex.status = "error: " + " ".join(str(exc).split())
                self._ex._redraw()
        return callback

    def _slider_callback(self, key: str) -> Callable[[float], None]:
        def on_changed(value: float) -> None:
            if self._syncing:
                return
            if key == "gap_mm":
                self._guarded(lambda: self._ex.set_param("gap_m", value * 1e-3))(None)
            else:
                self._guarded(lambda: self._ex.set_param(key, value))(None)  # type: ignore[arg-type]
        return on_changed

    def _radio_callback(self, which: str) -> Callable[[str | None], None]:
        def on_clicked(label: str | None) -> None:
            if self._syncing or label is None:
                return
            if which == "amplitude":
                mode = next(m for m in AMPLITUDE_MODES if _AMPLITUDE_LABELS[m] == label)
                self._guarded(lambda: self._ex.set_amplitude_mode(mode))(None)
            elif which == "impact_view":
                view = next(v for v in IMPACT_VIEWS if _IMPACT_VIEW_LABELS[v] == label)
                self._guarded(lambda: self._ex.set_impact_view(view))(None)
            else:
                self._ex._sweep_choice = next(c for c in SWEEP_CHOICES
                                             if _SWEEP_LABELS[c] == label)
        return on_clicked

    def _on_check(self, label: str | None) -> None:
        part = next(q for q in PARTS if _PART_LABELS[q] == label)
        self._ex.toggle(part, self._checks.get_status()[PARTS.index(part)])

    def sync_radio(self, which: str, index: int) -> None:
        radio = self._radios[which]
        if radio.index_selected != index:
            self._syncing = True
            try:
                radio.set_active(index)
            finally:
                self._syncing = False

    def sync_sliders(self) -> None:
        ex = self._ex
        values = {"F": ex.params.F, "accel_ms2": ex.accel_ms2, "omega": ex.params.omega,
                  "zeta": ex.params.zeta, "e": ex.params.e, "gap_mm": ex.gap_m * 1e3}
        self._syncing = True
        try:
            for key, value in values.items():
                slider = self._sliders[key]
                if slider.val != value:
                    slider.set_val(value)
        finally:
            self._syncing = False
