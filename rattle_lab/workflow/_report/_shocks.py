"""The transient records of a store in its report: per channel onset, peak and delay, and
the waveforms around each shock, aligned on each channel's onset.

The shocks are those the fit found (:func:`rattle_lab.fit._chain.transient_shocks`, stored in
the fit summary's ``transients``); here they are only read, put into lines of text
(:func:`shock_lines`, also what ``rattle-lab fit`` prints) and cut out of the stored channels.
"""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np

from rattle_lab.report import ShockContent, ShockRun, ShockTrace
from ._content import Missing, require_results
from ._gather import ReportData
from ._summary import shock_lines

#: Transient runs drawn (one page each); more are listed on the summary page only.
MAX_SHOCK_PAGES = 6
#: Characters per line of a shock page's text (7.5 pt monospace on A4 landscape).
SHOCK_TEXT_WIDTH = 165


def _trace(row: dict[str, Any], ch: Any, span: int, cause_sample: int | None) -> ShockTrace:
    """The channel's samples from 1/4 of ``span`` before its onset to 3/4 after."""
    fs = float(row.get("fs_hz") or ch.sample_rate_hz or 1.0)
    found = bool(row["found"]) and row.get("onset_sample") is not None
    centre = int(row["onset_sample"]) if found else (cause_sample or 0)
    i0 = max(0, centre - span // 4)
    i1 = min(int(ch.n_samples), centre + span - span // 4)
    y = np.asarray(ch.read(i0, i1), dtype=float)
    t_ms = 1e3 * (np.arange(i0, i0 + y.size) - centre) / fs
    peak = (1e3 * (int(row["peak_sample"]) - centre) / fs
            if found and row.get("peak_sample") is not None else None)
    return ShockTrace(str(row["channel"]), str(row["quantity"]), str(ch.units or "1"),
                      str(row.get("role", "")), str(row.get("clock", "")), fs, found, t_ms, y,
                      peak)


def shock_content(data: ReportData) -> ShockContent:
    """The shocks of the store's transient runs (raises :class:`Missing` where there are none)."""
    from rattle_lab.store import open_stored_record

    require_results(data)
    transients = data.summary.transients if data.summary is not None else ()
    if not transients:
        raise Missing("no transient run")
    runs = []
    for tr in transients[:MAX_SHOCK_PAGES]:
        rows = [dict(c) for c in tr.channels]
        found = [r for r in rows if r["found"] and r.get("onset_sample") is not None]
        # the window: three times the longest rise (onset to peak), at least 64 samples
        rise = max((int(r["peak_sample"]) - int(r["onset_sample"]) for r in found), default=0)
        span = max(64, 3 * rise + rise // 3)
        cause_sample = int(rows[0]["onset_sample"]) if rows and rows[0]["found"] and \
            rows[0].get("onset_sample") is not None else None
        traces = []
        with open_stored_record(data.store, tr.input_key) as record:
            by_name = {c.name: c for c in record.run(tr.run_id).channels}
            for r in rows:
                ch = by_name.get(str(r["channel"]))
                if ch is not None:
                    traces.append(_trace(r, ch, span, cause_sample))
        lines = [w for line in shock_lines(rows)
                 for w in textwrap.wrap(line, SHOCK_TEXT_WIDTH, subsequent_indent=" " * 13)]
        runs.append(ShockRun(tr.input_key, tr.run_id, tuple(lines), tuple(traces)))
    return ShockContent(tuple(runs))


__all__ = ["MAX_SHOCK_PAGES", "shock_content"]
