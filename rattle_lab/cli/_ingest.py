"""``rattle-lab ingest FILE... -o store.h5``: a thin layer over :func:`rattle_lab.store.ingest`.

Prints the catalogue rows of the given inputs as a table (or JSON with
``--json``) on stdout; data-quality warnings go to stderr, one line each.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from typing import Any


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "ingest", help="validate record files and ingest them into an HDF5 store",
        description="Validate record files (rattle HDF5, or HDF5/MATLAB v7.3, TDMS, WAV, LabVIEW "
                    ".lvm, NumPy .npy through a mapping), check their data, work out the conversion "
                    "to SI and add them to a store with a catalogue. Inputs are opened read-only; "
                    "the store is written atomically; inputs already in the store are skipped. "
                    "Datasets of HDF5 inputs are linked, not copied (HDF5 virtual datasets): keep "
                    "the inputs where they are, or use --copy.")
    parser.add_argument("files", nargs="+", metavar="FILE", help="record files to ingest")
    parser.add_argument("-o", "--output", required=True, metavar="STORE",
                        help="the store (.h5): created, or appended to")
    parser.add_argument("--mapping", metavar="FILE.toml",
                        help="TOML mapping for foreign layouts, a file or the name of a shipped "
                             "mapping (see data_schema/mappings/); applied to every non-native FILE")
    parser.add_argument("--allow-flagged", action="store_true",
                        help="ingest data with NaN, Inf, clipping, dropouts, rate mismatch, "
                             "non-monotonic timestamps or empty channels, flagged, instead of "
                             "failing")
    parser.add_argument("--copy", action="store_true",
                        help="copy every sample into the store, so that it stands alone (default: "
                             "link the datasets of HDF5 inputs, copy the rest)")
    parser.add_argument("--replace", action="store_true",
                        help="a run already in the store from another input (e.g. this file, "
                             "changed since it was ingested) is replaced: the stored input that "
                             "holds it is removed, with all its runs")
    parser.add_argument("--allow-links", action="store_true",
                        help="resolve HDF5 external links, virtual datasets and external storage "
                             "of the inputs, but only to files inside the input's folder (they "
                             "are hashed and copied); default: refuse any reference out of an "
                             "input")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_run)


def _warn(finding: Any) -> None:
    print(f"rattle-lab: warning: {finding.warning_class.__name__}: {finding.message}",
          file=sys.stderr)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.exceptions import RattleLabWarning
    from rattle_lab.store import ingest

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RattleLabWarning)
        report = ingest(args.files, args.output, mapping=args.mapping,
                        storage="copy" if args.copy else "link",
                        allow_flagged=args.allow_flagged, quiet=args.quiet, on_warning=_warn,
                        replace=args.replace, allow_links=args.allow_links)
    for w in caught:  # options that did not apply, etc.: one line each
        print(f"rattle-lab: warning: {w.category.__name__}: {' '.join(str(w.message).split())}",
              file=sys.stderr)
    if args.json:
        print(json.dumps(_as_json(report), indent=2, allow_nan=False))
    else:
        print(_as_table(report))
    return 0


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if hasattr(value, "item"):
        return _clean(value.item())
    return value


def _as_json(report: Any) -> dict[str, Any]:
    return {
        "store": str(report.store),
        "changed": report.changed,
        "inputs": [{
            "path": str(r.path), "file_hash": r.file_hash, "input_key": r.input_key, "status": r.status,
            "format": r.format,
            "skipped": [{"source": s.source, "reason": s.reason} for s in r.skipped],
            "findings": [{"flag": f.flag, "path": f.path, "field": f.field,
                          "sample_index": f.sample_index, "n_samples": f.n_samples,
                          "detail": f.detail, "fatal": f.fatal} for f in r.findings],
        } for r in report.inputs],
        "catalogue": [{k: _clean(v) for k, v in row.items()}
                      for row in report.catalogue.to_dict(orient="records")],
    }


TABLE_COLUMNS = ("campaign_id", "run_id", "protocol", "channel", "quantity", "units",
                 "sample_rate_hz", "n_samples", "duration_s", "flags")


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return "-" if not math.isfinite(value) else f"{value:.6g}"
    return str(value) if value != "" else "-"


def _as_table(report: Any) -> str:
    rows = [[_fmt(_clean(row[c])) for c in TABLE_COLUMNS]
            for row in report.catalogue.to_dict(orient="records")]
    widths = [max([len(c)] + [len(r[i]) for r in rows]) for i, c in enumerate(TABLE_COLUMNS)]
    lines = ["  ".join(c.ljust(w) for c, w in zip(TABLE_COLUMNS, widths)),
             "  ".join("-" * w for w in widths)]
    lines += ["  ".join(v.ljust(w) for v, w in zip(r, widths)) for r in rows]
    lines.append("")
    for r in report.inputs:
        lines.append(f"{r.status}: {r.path} ({r.format}, {r.input_key})")
        for s in r.skipped:
            lines.append(f"  skipped {s.source}: {s.reason}")
    counts = {status: sum(r.status == status for r in report.inputs)
              for status in ("added", "updated", "unchanged")}
    lines.append(f"{report.store}: " + ", ".join(f"{n} {status}" for status, n in counts.items()
                                                  if n or status != "updated"))
    return "\n".join(lines)
