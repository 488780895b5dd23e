"""Does the plate the rig declares fit the data?  The plate model's f1 against the fitted f_s.

A record's ``/rig`` may describe its plate (dimensions, material, edges); the plate model
(:func:`rattle_lab.records._chain.plate_model_f1`) then gives the first natural frequency
``f1`` and the participation ``Q1/Q2`` of that plate.  When ``f1`` and the fitted ``f_s``
are further apart than :data:`PLATE_F1_TOLERANCE` of ``f_s`` *plus*
:data:`PLATE_F1_SIGMAS` standard errors of ``f_s`` (decided by significance: a plate 4.9 %
off is not flagged because its fit came out a last digit lower), the plate described is
not the plate measured (edges in the wrong order, another thickness or material), and the
data-quality flag :data:`FLAG_PLATE_MODEL_DISAGREES` is raised with both values in the
participation's ``note``.  The tolerance is what the plate model's inputs leave open: a
sheet's thickness (f1 goes as h) and an alloy's E/rho (f1 goes as its square root) are
known to a few per cent.

A participation that came from that plate model is then not used: the fit is repeated with
``Q1/Q2 = 1`` flagged ``participation_assumed`` (what the fit does when nothing is known:
the gap it reports is then gap/(Q1/Q2)).  A participation given on the command line, by a
pipeline or as the rig's ``modal_participation`` is kept, and the note says so.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import Any

from rattle_lab.records import (FLAG_PARTICIPATION_ASSUMED, Participation, PlateF1,
                                plate_model_f1)

#: Data-quality flag: the rig's plate model's f1 and the fitted f_s disagree.
FLAG_PLATE_MODEL_DISAGREES = "plate_model_disagrees"
#: Relative difference of f1 and f_s above which they disagree (the plate model's material
#: constants and thickness alone make a few per cent).
PLATE_F1_TOLERANCE = 0.05
#: ... plus this many standard errors of the fitted f_s.
PLATE_F1_SIGMAS = 2.0


@dataclasses.dataclass(frozen=True)
class PlateCheck:
    """The comparison of the plate model's ``f1`` with the fitted ``f_s`` (Hz)."""

    plate: PlateF1
    f_s_hz: float
    f_s_stderr_hz: float | None
    disagrees: bool

    @property
    def rel(self) -> float:
        """``f1 / f_s - 1``."""
        return self.plate.f1_hz / self.f_s_hz - 1.0


def compare_plate(plate: PlateF1, f_s_hz: float, f_s_stderr_hz: float | None) -> PlateCheck:
    """Compare ``plate``'s f1 with a fitted ``f_s``: they disagree when
    ``|f1 - f_s| > PLATE_F1_TOLERANCE * f_s + PLATE_F1_SIGMAS * stderr(f_s)`` (a standard
    error that is unknown or not finite counts as 0)."""
    sigma = f_s_stderr_hz if f_s_stderr_hz is not None and math.isfinite(f_s_stderr_hz) else 0.0
    allowed = PLATE_F1_TOLERANCE * f_s_hz + PLATE_F1_SIGMAS * sigma
    return PlateCheck(plate, f_s_hz, f_s_stderr_hz, abs(plate.f1_hz - f_s_hz) > allowed)


def _fitted_f_s(summary: Any) -> tuple[float, float | None] | None:
    fits = summary.fits
    for entry in (fits.grazing_ramp, fits.grazing):   # the ramp-corrected fit first
        if entry is not None and entry.f_s_hz.value is not None \
                and math.isfinite(entry.f_s_hz.value) and entry.f_s_hz.value > 0:
            return float(entry.f_s_hz.value), entry.f_s_hz.stderr
    return None


def check_plate_model(summary: Any, rigs: Sequence[Any], participation: Participation,
                      refit: Callable[[Participation], Any]) -> Any:
    """``summary`` with :data:`FLAG_PLATE_MODEL_DISAGREES` when the rigs' plate disagrees.

    ``refit(participation)`` repeats the fits with another participation (used when the
    participation came from the disagreeing plate model).  Rigs that do not declare a
    complete plate (or a material the model knows) are not checked.
    """
    fitted = _fitted_f_s(summary)
    if fitted is None:
        return summary
    plates = [p for p in (plate_model_f1(r) for r in rigs) if p is not None]
    if not plates:
        return summary
    checks = [compare_plate(p, *fitted) for p in plates]
    bad = next((c for c in checks if c.disagrees), None)
    if bad is None:
        return summary
    err = "" if bad.f_s_stderr_hz is None else f" +- {bad.f_s_stderr_hz:.3g}"
    head = (f"the rig's plate ({bad.plate.description}) has f1 = {bad.plate.f1_hz:.4g} Hz in "
            f"the plate model, the fitted f_s is {bad.f_s_hz:.4g}{err} Hz ({100 * bad.rel:+.1f} "
            f"%, beyond {100 * PLATE_F1_TOLERANCE:g} % plus {PLATE_F1_SIGMAS:g} standard "
            "errors): the plate described is not the plate measured (edge order, thickness, "
            "material?)")
    if participation.source.startswith("plate model"):
        note = (f"{head}; its participation Q1/Q2 = {bad.plate.participation:.4g} is not "
                "used: 1 is assumed (the gap is gap/(Q1/Q2)); give --participation or the "
                "rig's modal_participation")
        summary = refit(Participation(1.0, "assumed (the rig's plate model disagrees with "
                                           "the data)",
                                      (FLAG_PARTICIPATION_ASSUMED, FLAG_PLATE_MODEL_DISAGREES)))
    else:
        note = (f"{head}; the participation used is {participation.value:.4g} "
                f"({participation.source}), not the plate model's {bad.plate.participation:.4g}")
        summary = dataclasses.replace(
            summary, data_quality=(FLAG_PLATE_MODEL_DISAGREES, *summary.data_quality))
    return dataclasses.replace(summary, participation=dataclasses.replace(
        summary.participation, note=note))


__all__ = ["FLAG_PLATE_MODEL_DISAGREES", "PLATE_F1_SIGMAS", "PLATE_F1_TOLERANCE", "PlateCheck",
           "check_plate_model", "compare_plate"]
