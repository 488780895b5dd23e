"""Runs and fitted results of an ingest store as Universal File Format dataset 58 (via pyuff).

UFF 58 ("function at nodal DOF") is what NVH suites (Simcenter Testlab, ME'scope,
ARTeMIS, ...) exchange.  What is written, one dataset per function, binary
(``58b``, double precision), SI units throughout (no dataset 164: SI is the default):

=====================  =========  ===============  ===============  ============================
function               func_type  abscissa         ordinate         ID line 2
=====================  =========  ===============  ===============  ============================
channel of a run       1 (time)   17 time, even    quantity's type  ``run=R ch=C q=QUANTITY``
impact velocities      1 (time)   17, uneven       11 velocity      ``run=R result=v_in_m_s``
first sound peaks      1 (time)   17, uneven       15 pressure      ``run=R result=p_first_pa``
third-octave spectrum  0 (gen.)   18 freq, uneven  15 pressure RMS  ``run=R result=third_octave``
threshold curves       0 (gen.)   18 freq, uneven  12 acceleration  ``result=threshold_up_ms2``
=====================  =========  ===============  ===============  ============================

Response DOFs: node ``1000 * run_number + k`` (``k`` = channel number, 101 impact
velocities, 102 sound peaks, 103 spectrum; nodes 1 and 2 the threshold curves), direction
0 (scalar).  ID line 1 is ``rattle_lab CAMPAIGN``; line 3 the run's protocol, excitation
frequency and level (``p=... f=... l=... u=...``); line 4 its start time; line 5 the
store's input key.  ID lines are cut at 80 characters (the format's width).
Ordinate types: 15 pressure (Pa), 12 acceleration (m/s^2), 11 velocity (m/s),
13 excitation force (N), 1 general (drive volts).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rattle_lab._atomic import atomic_path
from rattle_lab.exceptions import OutputError

if TYPE_CHECKING:
    from rattle_lab.fit import RunRow

#: UFF specific data types (records 8/9, field 1) of the record quantities.
UFF_TYPE_OF_QUANTITY = {"sound_pressure": 15, "base_acceleration": 12, "plate_acceleration": 12,
                        "plate_velocity": 11, "excitation_force": 13, "drive_signal": 1}
_UNITS = {15: "Pa", 12: "m/s^2", 11: "m/s", 13: "N", 1: "V", 17: "s", 18: "Hz"}


def _id(text: str) -> str:
    return text[:80]


def _fmt(x: Any) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:g}" if isinstance(x, (int, float)) else str(x)


def _set(data: np.ndarray, x: np.ndarray | None, *, dt: float | None, t0: float, func_type: int,
         abscissa: int, ordinate: int, ids: tuple[str, str, str, str, str], node: int,
         direction: int, name: str) -> dict[str, Any]:
    import pyuff

    even = x is None
    xs = (t0 + np.arange(data.size) * float(dt or 0.0) if even  # dt is given when x is None
          else np.asarray(x, dtype=float))
    return pyuff.prepare_58(
        binary=1, id1=_id(ids[0]), id2=_id(ids[1]), id3=_id(ids[2]), id4=_id(ids[3]),
        id5=_id(ids[4]), func_type=func_type, rsp_ent_name=name[:10], rsp_node=node,
        rsp_dir=direction, ref_ent_name="NONE", ref_node=0, ref_dir=0,
        abscissa_spacing=1 if even else 0, abscissa_spec_data_type=abscissa,
        abscissa_axis_units_lab=_UNITS[abscissa], ordinate_spec_data_type=ordinate,
        ordinate_axis_units_lab=_UNITS[ordinate], orddenom_spec_data_type=0,
        data=np.asarray(data, dtype=float), x=xs)


def uff_sets(store: str | os.PathLike[str], *, channels: bool = True,
             results: bool = True) -> list[dict[str, Any]]:
    """The UFF 58 datasets (pyuff dicts) of a store's runs and, if fitted, its results."""
    from rattle_lab.fit import FitSummary
    from rattle_lab.store import StoreError, open_stored_record, read_catalogue, read_results

    store = Path(store)
    catalogue = read_catalogue(store, level="runs")
    keys = list(dict.fromkeys(catalogue["input_key"]))
    stored = None
    if results:
        try:
            stored = read_results(store)
        except StoreError:
            stored = None
    rows = {(r.input_key, r.run_id): r
            for r in (FitSummary.from_stored(stored.summary).runs if stored else ())}
    sets: list[dict[str, Any]] = []
    node = 0
    campaign = ""
    for key in keys:
        record = open_stored_record(store, key)
        try:
            campaign = record.campaign_id
            for run in record.runs:
                node += 1
                id1 = f"rattle_lab {record.campaign_id}"
                id3 = (f"p={run.protocol} f={_fmt(run.excitation_freq_hz)} "
                       f"f1={_fmt(run.freq_end_hz)} l={_fmt(run.nominal_level)} "
                       f"l1={_fmt(run.level_end)} u={_fmt(run.nominal_level_units)}")
                id4 = f"t0={_fmt(run.start_time_iso)}"
                if channels:
                    for k, ch in enumerate(run.channels, start=1):
                        if ch.sample_rate_hz is None:
                            continue  # irregular sampling: no even-abscissa time function
                        full_scale = ch.units == "1"
                        ordinate = 1 if full_scale else UFF_TYPE_OF_QUANTITY.get(ch.quantity, 1)
                        q = f"{ch.quantity}(full-scale)" if full_scale else ch.quantity
                        sets.append(_set(ch.read(), None, dt=1.0 / ch.sample_rate_hz,
                                         t0=float(ch.start_time_s or 0.0), func_type=1,
                                         abscissa=17, ordinate=ordinate,
                                         ids=(id1, f"run={run.run_id} ch={ch.name} q={q}", id3,
                                              id4, f"input={key}"),
                                         node=1000 * node + k, direction=0, name=ch.name))
                if stored is not None:
                    sets.extend(_result_sets(stored, rows.get((key, run.run_id)), key, run.run_id,
                                             (id1, id3, id4), node))
        finally:
            record.close()
    if stored is not None:
        th = stored.thresholds
        f = np.asarray(th.get("freq_hz", []), dtype=float)
        for name in ("up_ms2", "down_ms2"):
            y = np.asarray(th.get(name, []), dtype=float)
            ok = np.isfinite(y)
            if ok.any():
                sets.append(_set(y[ok], f[ok], dt=None, t0=0.0, func_type=0, abscissa=18,
                                 ordinate=12, ids=(f"rattle_lab {campaign}",
                                                   f"result=threshold_{name}", "", "", ""),
                                 node=1 if name == "up_ms2" else 2, direction=0,
                                 name="threshold"))
    return sets


def _result_sets(stored: Any, row: RunRow | None, key: str, run_id: str,
                 ids: tuple[str, str, str], node: int) -> list[dict[str, Any]]:
    out: list[dict[str, Any]] = []
    res = stored.runs.get((key, run_id))
    id1, id3, id4 = ids
    if res is not None and res.get("status") == "ok" and "t_s" in res and len(res["t_s"]):
        t = np.asarray(res["t_s"], dtype=float)
        for name, arr_key, ordinate, direction in (("v_in_m_s", "v_in_m_s", 11, 101),
                                                   ("p_first_pa", "p_first_pa", 15, 102)):
            if arr_key in res and len(res[arr_key]) == t.size:
                y = np.asarray(res[arr_key], dtype=float)
                ok = np.isfinite(y)
                if ok.any():
                    out.append(_set(y[ok], t[ok], dt=None, t0=0.0, func_type=1, abscissa=17,
                                    ordinate=ordinate, ids=(id1, f"run={run_id} result={name}",
                                                            id3, id4, f"input={key}"),
                                    node=1000 * node + direction, direction=0, name=name))
    bands = ((row.acoustics if row is not None else None) or {}).get("third_octave_db") or {}
    pairs = [(float(f), 20e-6 * 10 ** (db / 20)) for f, db in bands.items() if db is not None]
    if pairs:
        f, p = np.array(pairs).T
        # func_type 0 (general): pyuff writes no "spectrum" (12) type; band RMS, Pa
        out.append(_set(p, f, dt=None, t0=0.0, func_type=0, abscissa=18, ordinate=15,
                        ids=(id1, f"run={run_id} result=third_octave", id3, id4, f"input={key}"),
                        node=1000 * node + 103, direction=0, name="octave3"))
    return out


def export_uff(store: str | os.PathLike[str], output: str | os.PathLike[str], *,
               channels: bool = True, results: bool = True) -> int:
    """Write a store's runs (and fitted results) to a UFF file of datasets 58, atomically.

    Parameters
    ----------
    store : path-like
        An ingest store (with ``/results`` for the fitted functions).
    output : path-like
        The ``.uff`` file to write (replaced atomically).
    channels, results : bool
        Write the runs' channels; write the fitted results (when the store has them).

    Returns
    -------
    int
        The number of datasets written.

    Raises
    ------
    StoreError
        If ``store`` is not an ingest store.
    OutputError
        If the output cannot be written, or there is nothing to write.
    """
    import pyuff

    sets = uff_sets(store, channels=channels, results=results)
    if not sets:
        raise OutputError(f"{output}: nothing to export from {store} (no regularly sampled "
                          "channel and no results)")
    try:
        with atomic_path(output) as tmp:
            tmp.unlink(missing_ok=True)  # pyuff's "overwrite" leaves an empty block first
            pyuff.UFF(str(tmp)).write_sets(sets, mode="add")
    except OSError as exc:
        raise OutputError(f"{output}: cannot write: {exc}") from exc
    return len(sets)


__all__ = ["UFF_TYPE_OF_QUANTITY", "export_uff", "uff_sets"]
