"""``rattle-lab export store.h5 -o runs.uff``: a thin layer over :func:`rattle_lab.exchange.export_uff`.

Writes the store's runs (every regularly sampled channel, in SI units) and, when
the store has been fitted, the fitted results (impact velocities, first sound
peaks, third-octave spectra, threshold curves) as UFF dataset 58, which NVH
suites open.  The number of datasets is printed on stderr, the path on stdout.
"""

from __future__ import annotations

import argparse
import sys


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "export", help="export runs and fitted results to UFF dataset 58",
        description="Write the runs of an ingest store (channels in SI units) and its fitted "
                    "results (impact velocities, first sound peaks, third-octave spectra, "
                    "threshold curves) as Universal File Format dataset 58 (binary), for NVH "
                    "suites. The file is written atomically.")
    parser.add_argument("store", metavar="STORE", help="an ingest store (.h5)")
    parser.add_argument("-o", "--output", required=True, metavar="FILE.uff",
                        help="the UFF file to write")
    parser.add_argument("--no-channels", action="store_true", help="leave out the time signals")
    parser.add_argument("--no-results", action="store_true", help="leave out the fitted results")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.exchange import export_uff

    n = export_uff(args.store, args.output, channels=not args.no_channels,
                   results=not args.no_results)
    print(f"rattle-lab: wrote {n} UFF 58 datasets", file=sys.stderr)
    print(args.output)
    return 0
