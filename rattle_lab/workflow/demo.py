"""``make demo`` / ``rattle-lab demo``: the main job on the embedded default scene.

simulate (synthetic rig, default scene) -> ingest -> detect, thresholds, fit -> report,
through the same pipeline as ``rattle-lab run`` (:mod:`rattle_lab.workflow.pipeline`), with
progress bars on a terminal.  It prints a table of the fitted values against the
rig's truth and ends with the PDF's path.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

from rattle_lab.exceptions import OutputError
from rattle_lab.fit import FitSummary, Fits

__all__ = ["run_demo", "truth_table"]

#: What the demo writes into its output directory.
RAW_NAME, STORE_NAME, REPORT_NAME = "raw.h5", "store.h5", "report.pdf"


def _row(name: str, unit: str, fitted: Any, stderr: Any, truth: Any) -> str:
    def fmt(x: Any) -> str:
        return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.5g}"

    err = "-"
    if isinstance(fitted, (int, float)) and math.isfinite(fitted) and truth:
        err = f"{100.0 * (fitted - truth) / truth:+.2f} %"
    return f"{name:<26} {fmt(fitted):>12} {fmt(stderr):>12} {fmt(truth):>12} {err:>10}  {unit}"


def truth_table(fits: Fits, truth: Any) -> list[str]:
    """Lines of the table of fitted values (:attr:`FitSummary.fits`) against the rig's truth:
    the rows of :meth:`FitSummary.table` ``("truth")``, laid out.

    Parameters
    ----------
    fits : Fits
        The fits of a fit summary (:func:`rattle_lab.fit.summarise_fits`).
    truth : Truth
        The synthetic record's truth (:attr:`rattle_lab.rig.Synthesis.record` ``.truth``).

    Returns
    -------
    list of str
        A header and one line per quantity: fitted value, standard error (for the
        SPL slope: half the 95 % interval), truth, relative error, unit.
    """
    lines = [
        f"{'quantity':<26} {'fitted':>12} {'std. error':>12} {'rig truth':>12} {'error':>10}  unit",
    ]
    known = {"gap_m": truth.gap_m, "f_s_hz": truth.f_s_hz, "zeta": truth.zeta, "e": truth.e,
             "spl_slope_first": float(truth.extra.get("acoustic_pa_per_m_s", float("nan")))}
    for row in FitSummary(n_runs=0, n_ok=0, fits=fits).table("truth", truth=known):
        lines.append(_row(row.quantity, row.unit, row.value, row.stderr, row.truth))
    return lines


def run_demo(out_dir: str | Path, *, quiet: bool = False, scene: str | Path = "default") -> int:
    """Run the demo into ``out_dir``; print the summary table and, last, the PDF path.

    Writes ``raw.h5`` (the simulated record, with truth), ``store.h5`` (the
    ingest store with ``/results``; made afresh each time) and ``report.pdf``.

    Parameters
    ----------
    out_dir : path-like
        Output directory (created if needed).
    quiet : bool
        No progress bars (they are drawn on a terminal only, in any case).
    scene : str or path-like
        The scene simulated: ``"default"`` (the embedded default scene), a shipped scene's
        name or a scene TOML file (see :func:`rattle_lab.rig.load_scene`).

    Returns
    -------
    int
        0.

    Raises
    ------
    OutputError
        If ``out_dir`` exists and is not a directory.
    """
    from rattle_lab.workflow.pipeline import parse_pipeline, run_pipeline
    from rattle_lab.store import read_results
    from rattle_lab.rig import load_scene

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out}: exists and is not a directory")
    rig_scene = load_scene(scene)   # a bad scene is refused before anything is written
    from rattle_lab.rig import write_synthetic
    out.mkdir(parents=True, exist_ok=True)
    raw, store = out / RAW_NAME, out / STORE_NAME

    def say(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    what = "embedded default scene" if str(scene) == "default" else f"scene {scene}"
    say(f"[1/4] simulate: {what} {rig_scene.campaign_id!r} -> {raw}")
    synthesis = write_synthetic(rig_scene, raw, quiet=quiet)
    truth = synthesis.record.truth
    assert truth is not None  # a synthetic record always carries its truth
    if store.exists():
        store.unlink()  # the demo starts from a clean store each time
    # The engineer knows the plate (its first mode gives the participation factor) and the
    # drive (it holds each ramp level for piece_periods forcing periods).
    fit = {"participation": float(synthesis.modal.participation),
           "level_hold_periods": int(rig_scene.simulation.piece_periods)}
    pipeline = parse_pipeline({
        "pipeline": {"name": "demo", "outputs": ["results", "report"]},
        "fit": fit, "report": {"model": True}}, "<demo>")
    steps = {"ingest": f"[2/4] ingest: {raw} -> {store}",
             "detect": "[3/4] detect impacts and sound peaks, per run",
             "thresholds": "      thresholds",
             "fit": "      fit: gap, f_s, zeta (eq. 3.4), e, SPL law",
             "report": f"[4/4] report: {out / REPORT_NAME}"}

    def log(line: str) -> None:  # a heading when a stage starts
        stage, _, what = line.partition(": ")
        if what == "running" and stage in steps:
            say(steps[stage])

    run = run_pipeline(pipeline, [raw], store=store, out_dir=out, report=out / REPORT_NAME,
                       quiet=quiet, log=log)
    fits = FitSummary.from_stored(read_results(store).summary).fits
    print("\nfitted values against the rig's truth:")
    print("\n".join(truth_table(fits, truth)))
    print(f"\nreport: {run.outputs['report'].resolve()}")
    return 0
