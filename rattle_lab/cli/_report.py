"""``rattle-lab report store.h5 -o report.pdf``: a thin layer over :func:`rattle_lab.workflow.write_report`.

Sections whose data are missing are listed on stderr (and on the summary
page); the PDF path is printed on stdout at the end.
"""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "report", help="write a multi-page PDF report of a store (after ingest and fit)",
        description="Write a reproducible multi-page PDF: summary of the fitted gap, zeta, f_s, "
                    "e and SPL law with uncertainties, data-quality flags and provenance; the "
                    "rig and calibration table; thresholds with the eq. (3.4) fit; impact "
                    "patterns; example waveforms; the SPL law; model predictions at the fitted "
                    "parameters. Sections without data are left out, and the summary says why.")
    parser.add_argument("store", metavar="STORE", help="an ingest store (.h5)")
    parser.add_argument("-o", "--output", required=True, metavar="REPORT.pdf",
                        help="the PDF to write (atomically)")
    parser.add_argument("--no-model", action="store_true",
                        help="leave out the model predictions (bifurcation sets and sweeps)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.store import read_catalogue

    # a missing or foreign store is refused (StoreError) before the report's own imports
    # (matplotlib, the fits, the model), which take seconds
    read_catalogue(args.store)
    from rattle_lab.workflow import write_report

    result = write_report(args.store, args.output, model=not args.no_model, quiet=args.quiet)
    for name, why in result.missing.items():
        print(f"rattle-lab: note: section {name!r} left out: {' '.join(why.split())}",
              file=sys.stderr)
    print(result.path)
    return 0
