"""``rattle-lab fit store.h5 [--pipeline FILE] [--json]``: a thin layer over :func:`rattle_lab.workflow.fit_store`.

Detects impacts, sound peaks, patterns and ramp thresholds in every run of an
ingest store, fits the grazing curve, the restitution and the SPL laws, and
writes them under ``/results`` of the store (atomically, with provenance).
Prints a summary table (or ``--json``) on stdout.
"""

from __future__ import annotations

import argparse
import json
import math
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rattle_lab.fit import FitSummary


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "fit", help="detect impacts and sound peaks, fit thresholds, restitution and SPL law",
        description="Detect impacts, sound peaks, impact patterns and ramp thresholds in every "
                    "run of an ingest store; fit the grazing curve (eq. 3.4), the coefficient of "
                    "restitution and the SPL law; write them under /results of the store "
                    "(atomically, with provenance). Runs lacking a channel are reported as "
                    "skipped; when every run is skipped the exit status is 2, with the reasons.")
    parser.add_argument("store", metavar="STORE", help="an ingest store (.h5)")
    parser.add_argument("--pipeline", metavar="FILE.toml",
                        help="parameters from a pipeline TOML: [detect] and [fit] tables of "
                             "keyword parameters")
    parser.add_argument("--participation", type=float, default=None, metavar="Q",
                        help="modal participation factor Q1/Q2 at the measurement point "
                             "(thesis eq. 2.27); overrides the pipeline's and the records' "
                             "(rig modal_participation, or the plate model from the rig's "
                             "geometry); without any, 1.0 is assumed and flagged")
    parser.add_argument("--detect-channel", metavar="NAME", default=None,
                        help="the channel to detect events on, in every run (overrides the "
                             "pipeline's [detect] channel and the records' detect_channel; by "
                             "default chosen by what each channel measures: a transient run's "
                             "cause is its force, else its base)")
    parser.add_argument("--scheduler", metavar="ADDRESS", default=None,
                        help="dask.distributed scheduler address (tcp://host:8786): detect the "
                             "runs on that cluster's workers; 'local' or 'local:N': on a cluster "
                             "of a worker process per core (or N) started on this machine "
                             "(default: serial, in this process)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.fit import load_pipeline
    from rattle_lab.workflow import fit_store

    params = load_pipeline(args.pipeline)
    source = "pipeline"
    if args.detect_channel is not None:
        params["detect"]["channel"] = args.detect_channel
    if args.participation is not None:
        params["fit"]["participation"] = args.participation
        source = "command line"
    result = fit_store(args.store, detect=params["detect"], fit=params["fit"], quiet=args.quiet,
                       participation_source=source, scheduler=args.scheduler)
    if args.json:
        print(json.dumps(result.summary.to_dict(), indent=2, allow_nan=False))
    else:
        print(as_table(result.summary))
    return _all_skipped_status(result.summary)


def _all_skipped_status(summary: FitSummary) -> int:
    """2, with the reasons on stderr, when runs exist and every one was skipped; else 0."""
    import sys

    skipped = summary.skipped
    if summary.n_ok or not skipped:
        return 0
    reasons: dict[str, list[str]] = {}
    for s in skipped:
        reasons.setdefault(s.reason, []).append(f"{s.input_key}/{s.run_id}")
    text = "; ".join(f"{why} ({len(runs)} run{'s' if len(runs) > 1 else ''}: "
                     f"{', '.join(runs[:3])}{', ...' if len(runs) > 3 else ''})"
                     for why, runs in reasons.items())
    print(f"rattle-lab: error: nothing to fit: every run ({len(skipped)}) was skipped: {text}",
          file=sys.stderr)
    return 2


def _num(x: Any, fmt: str = ".6g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return format(x, fmt) if isinstance(x, (int, float)) else str(x)


def as_table(summary: FitSummary) -> str:
    """Human summary: fitted values with units and uncertainties, then runs and skips."""
    lines = ["quantity                          value          stderr         unit",
             "--------------------------------  -------------  -------------  ----------------"]
    fits = summary.fits
    for row in summary.table():
        lines.append(f"{row.quantity:<32}  {_num(row.value):<13}  {_num(row.stderr):<13}  "
                     f"{row.unit}")
    part = summary.participation
    if part is not None and not all(r.protocol == "transient" for r in summary.runs):
        lines.append(f"participation Q1/Q2 = {_num(part.value)} ({part.source})")
    for flag in summary.data_quality:
        lines.append(f"data-quality flag: {flag}")
    if fits.grazing is not None:
        for note in fits.grazing.unidentifiable:
            lines.append(f"note: {note}")
        for name in ("gap_m", "zeta"):
            bias_note = getattr(fits.grazing, name).bias_note
            if bias_note:
                lines.append(f"note: grazing.{name}: {bias_note}")
    for key, entry in (("restitution_ratio", fits.restitution_ratio),
                       ("damping_ramp", fits.damping_ramp),
                       ("restitution_down", fits.restitution_down)):
        for note in entry.notes if entry is not None else ():
            lines.append(f"note: {key}: {note}")
    if summary.shocks_only:
        lines.append("transient records only (single shocks): no rattle fits (the grazing "
                     "curve, restitution and SPL laws need shaker runs)")
    else:
        for key, why in summary.not_fitted.items():
            lines.append(f"not fitted: {key}: {why}")
    lines.append("")
    lines.append(f"runs: {summary.n_ok} analysed, {len(summary.skipped)} skipped")
    for r in summary.runs:
        if r.protocol == "transient":
            lines.append(f"  {r.input_key}/{r.run_id}: transient, {r.n_impacts} shock"
                         f"{'' if r.n_impacts == 1 else 's'}")
            continue
        lines.append(f"  {r.input_key}/{r.run_id}: {r.n_impacts} impacts, "
                     f"pattern {r.pattern or '-'}, threshold {_num(r.threshold_accel_ms2)} m/s^2")
    for s in summary.skipped:
        lines.append(f"  skipped {s.input_key}/{s.run_id}: {s.reason}")
    for tr in summary.transients:
        lines.append(f"  transient {tr.input_key}/{tr.run_id}: one shock per channel, the cause "
                     "first")
        from rattle_lab.workflow import shock_lines

        lines += shock_lines(tr.channels, indent="    ")
    return "\n".join(lines)

