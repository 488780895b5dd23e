"""``rattle-lab verify STORE``: re-hash every input of a store and report each mismatch.

A thin layer over :func:`rattle_lab.store.verify_store`.  One line per
mismatch on stdout; exit status 0 when every file the store reads samples
from is unchanged, 2 otherwise (a changed copied input is reported, but the
store holds its own copy and the status stays 0).
"""

from __future__ import annotations

import argparse
import json


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser(
        "verify", help="re-hash the inputs of a store and report each mismatch",
        description="Re-hash (XXH3-128, whole file) every input a store was made from, and the "
                    "files they link to, and compare with the hashes taken at ingest. Exit "
                    "status 2 if a file the store reads samples from (a linked input) is missing "
                    "or changed, with the command that re-ingests it "
                    "(`rattle-lab ingest --replace RECORD -o STORE`, with their paths).")
    parser.add_argument("store", metavar="STORE", help="the store (.h5)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of lines")
    parser.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from rattle_lab.store import record_attrs_count, verify_store

    mismatches = verify_store(args.store)
    n_inputs = record_attrs_count(args.store)
    bad = [m for m in mismatches if m.linked]
    if args.json:
        print(json.dumps({"store": args.store, "n_inputs": n_inputs, "ok": not bad,
                          "mismatches": [{"input_key": m.input_key, "path": m.path,
                                          "problem": m.problem, "expected": m.expected,
                                          "found": m.found, "linked": m.linked}
                                         for m in mismatches]}, indent=2))
    else:
        from rattle_lab.store import reingest_advice
        from rattle_lab.store import record_attrs

        attrs = record_attrs(args.store) if bad else {}
        advised: set[str] = set()
        for m in mismatches:
            note = "" if m.linked else " (copied into the store: the store is not affected)"
            print(f"{'MISMATCH' if m.linked else 'note'}: {m.message}{note}")
            if m.linked and m.input_key not in advised:
                advised.add(m.input_key)
                source = str(attrs.get(m.input_key, {}).get("ingest_input_path", m.path))
                print(f"  {reingest_advice(source, args.store, m.problem == 'missing')}")
        print(f"{args.store}: {n_inputs} inputs verified, {len(bad)} mismatches")
    return 2 if bad else 0
