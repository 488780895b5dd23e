"""The summary page's text: the fitted-parameter table, data-quality flags, provenance.

Content, not drawing: the lines are built here from the gathered data (every fitted
number from ``/results``, in the rows of :meth:`rattle_lab.fit.FitSummary.table`; a missing
interval is the Student t interval of :func:`rattle_lab.fit.student_t_ci`), wrapped to the
report's text width, and drawn by the report as given.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Mapping
from typing import Any

import numpy as np

from rattle_lab.fit import SIGNIFICANCE_K, FitSummary, negative_hysteresis
from rattle_lab.report import TEXT_WIDTH, fmt, wrapped
from ._gather import ReportData

_COLS = (("quantity", 34), ("value", 11), ("std. error", 11), ("95 % CI", 27), ("unit", 0))


def _finite(x: Any) -> float | None:
    try:
        xf = float(x)
    except (TypeError, ValueError):
        return None
    return xf if math.isfinite(xf) else None


def _digits(value: Any, ci: tuple[Any, Any] | None, stderr: Any) -> int:
    """Significant digits that show the interval's half width (or the error) to two digits.

    At least 4; e.g. ``96.0123 +/- 0.0051`` needs 6, so that the bounds differ.
    """
    vals = [abs(v) for v in (_finite(value), *(ci or ())) if _finite(v) is not None]
    if ci is not None and _finite(ci[0]) is not None and _finite(ci[1]) is not None:
        spread = abs(float(ci[1]) - float(ci[0])) / 2
    else:
        spread = abs(_finite(stderr) or 0.0)
    vals = [abs(float(v)) for v in vals if _finite(v) is not None]
    if not vals or spread <= 0 or max(vals) == 0:
        return 4
    return int(min(10, max(4, math.floor(math.log10(max(vals))) -
                               math.floor(math.log10(spread)) + 2)))


def _row(quantity: str, value: Any = None, stderr: Any = None,
         ci: tuple[Any, Any] | None = None, unit: str = "", note: str = "",
         scale: float = 1.0) -> list[str]:
    """One aligned row of the parameter table (and its note, wrapped, below it).

    Value and interval bounds carry the digits their interval needs (:func:`_digits`);
    the standard error two or three significant digits.
    """
    def sc(x: Any) -> Any:
        return None if x is None else float(x) * scale

    ci_s = None if ci is None or None in ci else (sc(ci[0]), sc(ci[1]))
    err_s = None if isinstance(stderr, str) else sc(stderr)
    d = f".{_digits(sc(value), ci_s, err_s)}g"
    ci_txt = "-" if ci_s is None else f"[{fmt(ci_s[0], d)}, {fmt(ci_s[1], d)}]"
    err_txt = stderr if isinstance(stderr, str) else fmt(err_s, ".3g")
    cells = (quantity, fmt(sc(value), d), err_txt, ci_txt, unit)
    line = "  " + " ".join(c.ljust(w) if w else c for c, (_, w) in zip(cells, _COLS))
    out = [line.rstrip()]
    if note:
        out.extend(textwrap.wrap(note, TEXT_WIDTH, initial_indent="      ",
                                 subsequent_indent="      "))
    return out


#: the fits the parameter table names as "not fitted" when the store has no /results
_TABLE_FITS = ("grazing", "restitution_ratio", "restitution_down", "spl_law_first",
               "spl_law_max", "spl_law_rms")


def parameter_lines(data: ReportData) -> list[str]:
    """The table of fitted parameters: value, standard error, 95 % interval, unit.

    The rows of :meth:`FitSummary.table` ``("recommended")``, laid out: the recommended
    value of each quantity first (gap and zeta ramp-corrected where that fit exists, with
    its notes); the eq. (3.4) fit of the measured onsets follows, labelled as such, with the
    biases the fit names.
    """
    header = "  " + " ".join(n.ljust(w) if w else n for n, w in _COLS)
    lines = [header, "  " + "-" * (len(header) - 2)]
    summary = data.summary
    if summary is None:  # every fit "not fitted", for the reason the results are missing
        why = data.missing.get("results", "no results")
        summary = FitSummary(n_runs=0, n_ok=0, not_fitted=dict.fromkeys(_TABLE_FITS, why))
    rows = summary.table("recommended")
    main = [r for r in rows if r.section != "eq34"]
    eq34 = [r for r in rows if r.section == "eq34"]
    for r in main:
        lines += _row(r.quantity, r.value, "fixed" if r.fixed else r.stderr,
                      None if r.fixed else r.ci, r.unit, r.note)
    if any(r.quantity for r in eq34):
        lines += ["", "Eq. (3.4) fit of the measured onsets (for reference: the ramp lag reads as "
                  "gap and damping; recommended values above)"]
    for r in eq34:
        if r.quantity:
            lines += _row(r.quantity, r.value, "fixed" if r.fixed else r.stderr,
                          None if r.fixed else r.ci, r.unit, r.note)
        else:
            lines += textwrap.wrap(r.note, TEXT_WIDTH, initial_indent="      ",
                                   subsequent_indent="      ")
    return lines


def _number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def shock_lines(channels: Any, indent: str = "") -> list[str]:
    """The shock rows of a transient run, one line per channel, then its clocks named.

    Onsets and peaks are given in samples of the channel's own clock (and in seconds on
    it); a delay in seconds only between channels on one clock, across clocks in samples
    of each (the response's onset sample less the cause's).
    """
    lines = []
    clocks: dict[str, tuple[float, list[str]]] = {}
    cause = channels[0] if channels else {}
    for c in channels:
        clock, fs = c.get("clock"), c.get("fs_hz")
        if clock is not None and _number(fs):
            clocks.setdefault(str(clock), (float(fs), []))[1].append(str(c["channel"]))
        where = f"clock {clock}" if clock is not None else "its clock"
        head = f"{indent}{c.get('role', ''):<8} {c['channel']} ({c['quantity']}, {where})"
        if not c["found"]:
            lines.append(f"{head}: no shock above the noise")
            continue
        if c.get("onset_sample") is not None:
            text = (f"{head}: onset sample {c['onset_sample']} ({c['onset_s']:.4f} s), peak "
                    f"sample {c['peak_sample']} ({c['peak_s']:.4f} s)")
        else:
            text = f"{head}: onset {c['onset_s']:.4f} s, peak {c['peak_s']:.4f} s"
        if c.get("role") == "response" and cause.get("found"):
            n = c.get("delay_samples")
            if _number(c.get("delay_s")):
                text += (f"; {n:+d} samples, {1e3 * c['delay_s']:+.3f} ms after the cause"
                         if n is not None else f"; {1e3 * c['delay_s']:+.3f} ms after the cause")
            elif n is not None:
                text += (f"; {n:+d} samples after the cause's onset sample (clock "
                         f"{c.get('clock')} against {cause.get('clock')}: no delay in seconds "
                         "across clocks)")
        lines.append(text)
    if len(clocks) > 1:
        rates = [fs for fs, _ in clocks.values()]
        spread = 100.0 * (max(rates) / min(rates) - 1.0)
        named = "; ".join(f"{k} {fs:.6g} Hz ({', '.join(names)})"
                          for k, (fs, names) in clocks.items())
        lines.append(f"{indent}clocks: {named}; their rates differ by {spread:.1f} %, so "
                     "times on different clocks are not compared")
    elif clocks:
        ((k, (fs, _)),) = clocks.items()
        lines.append(f"{indent}clock {k}: {fs:.6g} Hz, shared by every channel")
    return lines


def summary_lines(data: ReportData, version: str) -> list[str]:
    """Text lines of the summary page (fitted values, flags, provenance), <= TEXT_WIDTH wide."""
    lines = [f"store: {data.store.name}"]
    if data.summary is not None:
        summ = data.summary
        n_imp = sum(r.n_impacts for r in summ.runs)
        lines.append(f"runs: {summ.n_runs} ({summ.n_ok} analysed, "
                     f"{len(summ.skipped)} skipped), {n_imp} impacts detected")
    if data.summary is not None and data.summary.shocks_only:

        lines += ["", "Transient records (single shocks): no rattle fits (the grazing curve, "
                  "restitution and SPL laws need shaker runs). The shock found in each channel, "
                  "the cause (force or drive) first; sample numbers on each channel's own clock"]
        for tr in data.summary.transients:
            lines += ["", f"  {tr.input_key}/{tr.run_id}"]
            lines += shock_lines(tr.channels, indent="    ")
    else:
        lines += ["", "Recommended values (ramp-corrected gap and zeta where fitted; 95 % CI: as "
                  "the fit gives it, e.g. profile likelihood for eq. (3.4); else Student t from "
                  "the standard error; OLS t for the SPL laws)"]
        lines += parameter_lines(data)
    lines += ["", "Data-quality flags (catalogue)"]
    cat = data.catalogue
    flagged = cat[cat["flags"].astype(str) != ""]
    negative = report_negative_hysteresis(data)
    if len(flagged) == 0 and not negative:
        lines.append("  none")
    for f_hz, h in negative:
        lines.append(f"  thresholds: NEGATIVE hysteresis at {f_hz:g} Hz ({h:.3g} m/s^2): the "
                     f"disappearance lies above the onset by more than {SIGNIFICANCE_K:g} "
                     "standard uncertainties")
    for _, row in flagged.head(12).iterrows():
        lines.append(f"  {row['input_key']}/{row['run_id']}/{row['channel']}: {row['flags']}")
    if len(flagged) > 12:
        lines.append(f"  ... and {len(flagged) - 12} more flagged channels")
    if data.summary is not None:  # issue 15: the fit's own flags (e.g. participation_assumed)
        part = data.summary.participation
        for flag in data.summary.data_quality:
            lines.append(f"  fit: {flag} (participation {part.value if part else None} from "
                         f"{part.source if part else '?'})" if flag.startswith("participation")
                         else f"  fit: {flag}")
    skipped = data.summary.skipped if data.summary is not None else ()
    for item in skipped[:6]:
        lines.append(f"  run skipped by the fit: {item.input_key}/{item.run_id}: "
                     f"{item.reason}")
    lines += ["", "Provenance", f"  report: rattle_lab {version} (rattle_lab.workflow.write_report)"]
    if data.results is not None:
        prov = data.results.provenance
        via = f" via {prov['via']} ({prov.get('pipeline', '')})" if prov.get("via") else ""
        lines.append(f"  results: {prov.get('function', '?')}{via}, rattle_lab "
                     f"{prov.get('rattle_lab_version', data.results.rattle_lab_version)}, "
                     f"written {data.results.created_iso}")
        params = prov.get("parameters") or {}
        for table in ("detect", "fit"):
            if isinstance(params.get(table), Mapping):
                text = ", ".join(f"{k} = {v}" for k, v in sorted(params[table].items()))
                lines.append(f"  [{table}] {text or '(defaults)'}")
    versions = sorted({str(e.get("rattle_lab_version", "?")) for e in data.provenance_log})
    lines.append(f"  ingest: {len(data.provenance_log)} logged call(s), rattle_lab "
                 f"{', '.join(versions) or '?'}")
    inputs = cat.drop_duplicates("input_key")
    hash_col = "file_hash" if "file_hash" in cat.columns else "file_sha256"
    for _, row in inputs.head(10).iterrows():
        lines.append(f"  input {row['input_key']}: {row['file']} ({row['campaign_id']}, "
                     f"{row['source']}), {row[hash_col]}")
    if len(inputs) > 10:
        lines.append(f"  ... and {len(inputs) - 10} more inputs")
    return [w for line in lines for w in wrapped(line)]


def threshold_arrays(data: ReportData) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``freq_hz, up_ms2, down_ms2`` as ``/results/thresholds`` holds them (NaN: not measured)."""
    th = data.results.thresholds
    f = np.asarray(th.get("freq_hz", []), dtype=float)
    up = np.asarray(th.get("up_ms2", np.full(f.size, np.nan)), dtype=float)
    down = np.asarray(th.get("down_ms2", np.full(f.size, np.nan)), dtype=float)
    return f, up, down


def threshold_uncertainties(data: ReportData) -> tuple[np.ndarray, np.ndarray]:
    """``up_se_ms2, down_se_ms2`` of ``/results/thresholds`` (NaN where a store from before
    they were kept has none: then no hysteresis is called negative)."""
    th = data.results.thresholds
    n = np.asarray(th.get("freq_hz", []), dtype=float).size
    return tuple(np.asarray(th.get(k, np.full(n, np.nan)), dtype=float)  # type: ignore[return-value]
                 for k in ("up_se_ms2", "down_se_ms2"))


def report_negative_hysteresis(data: ReportData) -> list[tuple[float, float]]:
    """``(freq_hz, onset - disappearance)`` of the stored thresholds where it is negative by
    more than its uncertainty (:func:`rattle_lab.fit.negative_hysteresis`)."""
    if data.results is None:
        return []
    return negative_hysteresis(*threshold_arrays(data), *threshold_uncertainties(data))
