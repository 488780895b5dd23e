"""``make demo`` / ``rattle-lab demo``: the main job on the embedded default scene.

simulate (synthetic rig, default scene) -> ingest -> fit -> report, ending with the
PDF's path; a table compares the fitted values with the rig's truth.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

from .exceptions import OutputError


def _row(name: str, unit: str, fitted: Any, stderr: Any, truth: float) -> str:
    def fmt(x: Any) -> str:
        return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.5g}"

    err = "-"
    if isinstance(fitted, (int, float)) and math.isfinite(fitted) and truth:
        err = f"{100.0 * (fitted - truth) / truth:+.2f} %"
    return f"{name:<26} {fmt(fitted):>12} {fmt(stderr):>12} {fmt(truth):>12} {err:>10}  {unit}"


def run_demo(out_dir: str | Path, *, quiet: bool = False) -> int:
    """Run the demo into ``out_dir``; print the summary and, last, the PDF path.

    Raises
    ------
    OutputError
        If ``out_dir`` exists and is not a directory.
    """
    from .fit import fit_store
    from .ingest import ingest
    from .rig import load_scene, write_synthetic

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise OutputError(f"{out}: exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    raw = out / "raw.h5"
    store = out / "store.h5"

    scene = load_scene("default")
    print(f"[1/4] simulate: embedded default scene {scene.campaign_id!r} -> {raw}", file=sys.stderr)
    synthesis = write_synthetic(scene, raw, quiet=quiet)
    truth = synthesis.record.truth
    assert truth is not None
    print(f"[2/4] ingest: {raw} -> {store}", file=sys.stderr)
    if store.exists():
        store.unlink()  # the demo starts from a clean store each time
    ingest([raw], store, quiet=quiet)
    print(f"[3/4] fit: {store}", file=sys.stderr)
    # the engineer knows the plate: its first mode gives the participation factor
    result = fit_store(store, fit={"participation": float(synthesis.modal.participation)})
    fits = result.summary["fits"]

    lines = [
        f"{'quantity':<26} {'fitted':>12} {'std. error':>12} {'rig truth':>12} {'error':>10}  unit",
    ]
    graz = fits.get("grazing") or {}
    for key, name, unit, true in (("gap_m", "gap", "m", truth.gap_m),
                                  ("f_s_hz", "f_s", "Hz", truth.f_s_hz),
                                  ("zeta", "zeta", "1", truth.zeta)):
        p = graz.get(key) or {}
        lines.append(_row(name, unit, p.get("value"), p.get("stderr"), true))
    for key, name in (("restitution_ratio", "e (velocity ratios)"),
                      ("restitution_down", "e (down thresholds)")):
        p = fits.get(key) or {}
        lines.append(_row(name, "1", p.get("value"), p.get("stderr"), truth.e))
    law = (fits.get("spl_law_first") or {}).get("linear") or {}
    ci = law.get("slope_ci") or [None, None]
    half = 0.5 * (ci[1] - ci[0]) if None not in ci else None
    lines.append(_row("SPL slope, 1st peak (95%)", "Pa/(m/s)", law.get("slope"), half,
                      float(truth.extra.get("acoustic_pa_per_m_s", float("nan")))))
    print("\nfitted values against the rig's truth:")
    print("\n".join(lines))

    print("[4/4] report", file=sys.stderr)
    pdf = out / "report.pdf"
    try:
        from .report import write_report  # type: ignore[attr-defined]
    except ImportError:
        print(f"\nreport: not available in this version; results are in {store.resolve()}")
        return 0
    write_report(store, pdf)
    print(f"\nreport: {pdf.resolve()}")
    return 0
