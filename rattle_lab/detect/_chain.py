"""The measurement chain of one run: channels on one time base, measurands, transient shocks.

Moved from :mod:`rattle_lab.fit._chain` (issue 29: detection in one room).  Per run: each
channel's samples at their physical times (``start_time_s`` less the declared
``group_delay_s``), two plate channels at different rates or offsets resampled onto one grid
before they are paired, an absolute vibrometer's impact velocities made relative to the
striker with the base, its delay and measurand checked against the impacts, named
data-quality flags of the chain and the shock of a transient run in every channel (the
cause chosen by what each channel measures).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rattle_lab.exceptions import ParameterError
from rattle_lab.records import (FLAG_MEASURAND_ABSOLUTE, FLAG_MEASURAND_UNDECLARED,
                                channel_time_offset_s)
from ._pairing import base_velocity_at, onto_grid
from ._ringing import RINGING_RESIDUAL_RATIO
from ._shock import detect_shock
from ._timing import DelayEstimate, delay_contradicted, measurand_share

#: Quantities that cause a shock (the hammer's force, the drive's command, the drop table or
#: shaker base), in the order a transient record's cause is chosen; the other channels are
#: its responses.  A force or drive channel comes first: the base responds to the drive.
CAUSE_QUANTITIES = ("excitation_force", "drive_signal", "base_acceleration")
#: Two channels run on one clock when their rates agree to this relative tolerance.
SAME_CLOCK_RTOL = 1e-6
#: Quantities a transient record's shock is looked for in.
SHOCK_QUANTITIES = CAUSE_QUANTITIES + ("plate_acceleration", "plate_velocity", "sound_pressure")


def _fs_of(run: Any, ch: Any) -> float:
    if ch.sample_rate_hz is not None:
        return float(ch.sample_rate_hz)
    t = run.timestamps[ch.timestamps].read(0, min(ch.n_samples, 10000))
    return float(1.0 / np.median(np.diff(t)))


def _start_of(run: Any, ch: Any) -> float:
    if ch.start_time_s is not None:
        return float(ch.start_time_s)
    if ch.timestamps is not None:
        return float(run.timestamps[ch.timestamps].read(0, 1)[0])
    return 0.0


def _t0_of(run: Any, ch: Any) -> float:
    """Physical time of a channel's first sample: start time less the filters' group delay."""
    return _start_of(run, ch) + channel_time_offset_s(ch)


def paired_plate_channels(run: Any, vel: Any, acc: Any
                          ) -> tuple[float, float, np.ndarray | None, np.ndarray | None]:
    """``(fs_hz, t0_s, velocity, acceleration)`` on one time base (SI; either may be None).

    Each channel's samples are placed at their physical times (``start_time_s`` less
    ``group_delay_s``).  With both channels, the slower (or, at equal rates, the
    acceleration) is resampled onto the other's grid (:func:`~rattle_lab.detect._pairing.onto_grid`)
    and both are cut to the span they share.
    """
    if vel is None or acc is None:
        ch = vel if vel is not None else acc
        data = ch.read()
        out = (data, None) if vel is not None else (None, data)
        return _fs_of(run, ch), _t0_of(run, ch), out[0], out[1]
    fs_v, fs_a = _fs_of(run, vel), _fs_of(run, acc)
    t0_v, t0_a = _t0_of(run, vel), _t0_of(run, acc)
    v, a = vel.read(), acc.read()
    same = abs(fs_v - fs_a) <= 1e-9 * fs_v and abs(t0_v - t0_a) * fs_v < 1e-6
    if same:
        n = min(v.size, a.size)
        return fs_v, t0_v, v[:n], a[:n]
    if fs_a > fs_v * (1 + 1e-9):
        fs, t0 = fs_a, t0_a
        v = onto_grid(v, fs_v, t0_v, fs, t0, a.size)
    else:
        fs, t0 = fs_v, t0_v
        a = onto_grid(a, fs_a, t0_a, fs, t0, v.size)
    n = min(v.size, a.size)
    v, a = v[:n], a[:n]
    ok = np.isfinite(v) & np.isfinite(a)
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        raise ParameterError(f"run {run.run_id!r}: channels {vel.name!r} and {acc.name!r} do not "
                             "overlap in time")
    lo, hi = int(idx[0]), int(idx[-1]) + 1
    return fs, t0 + lo / fs, np.asarray(v[lo:hi]), np.asarray(a[lo:hi])


def relative_to_striker(run: Any, log: Any, base: Any, freq_hz: float | None) -> Any:
    """``log`` with the base velocity taken off ``v_in``/``v_out`` (an absolute vibrometer).

    The striker sits on the shaker base: the impact velocities of the SDF model are the
    panel's relative to it.  Without a base accelerometer or a constant excitation
    frequency the log is returned unchanged (and :func:`run_chain_flags` says so).
    """
    if base is None or freq_hz is None or log.n_impacts == 0:
        return log
    vb = base_velocity_at(base.read(), _fs_of(run, base), _t0_of(run, base), freq_hz, log.t_s)
    vin, vout = log.v_in_m_s - vb, log.v_out_m_s - vb
    with np.errstate(divide="ignore", invalid="ignore"):
        e = np.where(vin != 0, -vout / vin, np.nan)
    return dataclasses.replace(log, v_in_m_s=vin, v_out_m_s=vout, e=e)


#: Data-quality flag: the vibrometer's delay was not declared and was measured from the impacts.
FLAG_DELAY_ESTIMATED = "channel_delay_estimated"
#: Data-quality flag: the vibrometer's decoder was identified from the impacts' velocity steps
#: and equalised (:mod:`rattle_lab.detect._decoder`).
FLAG_FILTER_IDENTIFIED = "channel_filter_identified"
#: Data-quality flag: the declared delay is contradicted by the impacts (the declared is used).
FLAG_DELAY_CONTRADICTED = "channel_delay_contradicted"
#: Data-quality flag: the measurand was not declared and was inferred from the data.
FLAG_MEASURAND_INFERRED = "measurand_inferred"
#: Data-quality flag: the measurand was not declared and the data cannot tell (e withheld).
FLAG_MEASURAND_UNDETERMINED = "measurand_undetermined"
#: How a measurand taken from the campaign's other runs is noted (``measurand_if_undetermined``).
CAMPAIGN_MEASURAND_NOTE = "as established by the campaign's other runs or given"


def velocity_delay_flags(log: Any, declared: bool) -> tuple[str, ...]:
    """Flags (with their notes) of the vibrometer's delay measured from the impacts.

    Undeclared and applied (beyond its uncertainty,
    :func:`rattle_lab.detect._timing.delay_significant`): :data:`FLAG_DELAY_ESTIMATED`;
    declared and contradicted by the data beyond its uncertainty and a whole sample
    (:func:`rattle_lab.detect._timing.delay_contradicted`): :data:`FLAG_DELAY_CONTRADICTED`
    (the declaration is still used).  Nothing where there was nothing to measure (one
    channel, too few impacts), where an undeclared delay is indistinguishable from zero
    (its uncertainty still widens e's interval: :func:`delay_systematic`), where the
    plate's higher modes ring in the vibrometer (its step centroid is then not a measure
    of the delay) or where the declaration holds.
    """
    d, se, n = log.velocity_delay_s, log.velocity_delay_stderr_s, log.velocity_delay_n
    if not np.isfinite(d):
        return ()
    fs = log.fs_hz
    flights = getattr(log, "velocity_delay_method", "steps") == "flights"
    how = ("the instant where the flight model's displacements either side of the impact "
           "meet" if flights else "velocity step centroid") + " less contact pulse centroid"
    what = (f"{1e6 * d:.2f} +- {1e6 * se:.2f} us ({d * fs:.3f} samples) from {n} impacts "
            f"({how}, median)")
    decoder = getattr(log, "decoder", "")
    if decoder and not declared:
        # the identified decoder's delay, equalised away; what the impacts measure after it
        # checks it (its error is e's, :func:`rattle_lab.fit._chain.delay_systematic`)
        rest = d - log.velocity_delay_applied_s
        return (f"{FLAG_FILTER_IDENTIFIED}: the vibrometer's decoder reads as {decoder}",
                f"{FLAG_DELAY_ESTIMATED}: the velocity lags the plate accelerometer by "
                f"{1e6 * log.velocity_delay_applied_s:.2f} us "
                f"({log.velocity_delay_applied_s * fs:.3f} samples), the identified decoder's "
                f"delay; after it the {how} is {rest * fs:+.3f} +- {se * fs:.3f} samples")
    if not declared:
        if not log.velocity_delay_applied_s:
            return ()
        return (f"{FLAG_DELAY_ESTIMATED}: the velocity lags the plate accelerometer by {what}; "
                "the velocities are read at the impact time plus it",)
    if log.ringing_ratio >= RINGING_RESIDUAL_RATIO and not flights:
        # the plate's higher modes ring in the vibrometer after each impact: they move the
        # velocity step's centroid (by up to 2 samples on the independent generator), so
        # the steps cannot check the declaration (the flights' instants can)
        return ()
    if delay_contradicted(DelayEstimate(d * fs, se * fs, n)):
        used = "the declared delay is used"
        return (f"{FLAG_DELAY_CONTRADICTED}: after the declared delay (group_delay_s, or the "
                f"declared filter's) the velocity "
                f"still lags the plate accelerometer by {what}; {used}",)
    return ()


def infer_measurand(run: Any, log: Any, v_si: np.ndarray, fs: float, t0: float, base: Any,
                    freq_hz: float | None, if_undetermined: str = ""
                    ) -> tuple[Any, tuple[str, ...]]:
    """An undeclared vibrometer's measurand from the data; the log made relative if absolute.

    The integrated velocity at the impacts against the base displacement there
    (:func:`rattle_lab.detect._timing.measurand_share`).  Relative: the log unchanged;
    absolute: the base velocity taken off (:func:`relative_to_striker`); both flagged
    :data:`FLAG_MEASURAND_INFERRED` with the evidence.  Undetermined (impacts at one phase
    of the base motion, too few impacts): the relative reading is kept (the convention for
    an undeclared vibrometer) and the absolute reading's difference recorded
    (:attr:`~rattle_lab.detect.ImpactLog.e_measurand_diff`, which widens e's interval:
    :func:`measurand_systematic`), flagged :data:`FLAG_MEASURAND_UNDETERMINED` (or
    :data:`FLAG_MEASURAND_UNDECLARED` where the two readings agree within their noise).
    Only where no absolute reading can be formed (no base accelerometer, no constant
    excitation frequency) are the run's ratios withheld, with the reason.

    ``if_undetermined`` (``[detect] measurand_if_undetermined``): where it names a measurand
    and this run's data do not establish one (:data:`FLAG_MEASURAND_UNDETERMINED`), that
    reading is taken and flagged :data:`FLAG_MEASURAND_INFERRED`, with this run's evidence
    (the campaign's other runs established it: :func:`campaign_measurand`).
    """
    if log.n_impacts == 0:
        return log, (FLAG_MEASURAND_UNDECLARED,)
    if base is None or freq_hz is None:
        why = "no base accelerometer" if base is None else "no constant excitation frequency"
        return _undetermined(run, log, base, freq_hz, why)
    t_v = log.t_s + log.velocity_delay_applied_s
    # (impacts without both velocities are left out: their jump, the part of the step the
    # integral ends in, is not known.  Taken as 0 before 29 Nov 2026, seventeenth session,
    # a trigger in a record's last samples, kept as an impact with v_out NaN, put the
    # coefficient at 6-11 for an absolute vibrometer, 1.1-1.2 without it)
    share = measurand_share(v_si, fs, t0, t_v, base.read(), _fs_of(run, base), _t0_of(run, base),
                            freq_hz, jumps_m_s=log.v_out_m_s - log.v_in_m_s,
                            ring_modes=tuple(getattr(log, "ring_modes", ()) or ()))
    ev = (f"coefficient of the base displacement in the integrated velocity at {share.n} "
          f"impacts {share.value:.3f} +- {share.stderr:.3f} (0: relative, 1: absolute; base "
          f"displacement spread {1e6 * share.spread_m:.1f} um)")
    if share.verdict == "relative":
        return log, (f"{FLAG_MEASURAND_INFERRED}: relative to the striker: {ev}",)
    if share.verdict == "absolute":
        return (relative_to_striker(run, log, base, freq_hz),
                (f"{FLAG_MEASURAND_INFERRED}: panel_absolute, made relative with the base: {ev}",))
    out, flags = _undetermined(run, log, base, freq_hz, f"the data cannot tell: {ev}")
    if (if_undetermined and any(f.startswith(FLAG_MEASURAND_UNDETERMINED) for f in flags)
            and float(getattr(out, "e_measurand_diff", 0.0) or 0.0) != 0.0):
        # (both readings physical and apart: the one named is taken; where a run's ratios
        # are withheld, neither reading is)
        why = (f"{CAMPAIGN_MEASURAND_NOTE}; this run's data cannot tell: {ev}")
        if if_undetermined == "panel_absolute":
            return (relative_to_striker(run, log, base, freq_hz),
                    (f"{FLAG_MEASURAND_INFERRED}: panel_absolute, made relative with the base: "
                     f"{why}",))
        return log, (f"{FLAG_MEASURAND_INFERRED}: relative to the striker: {why}",)
    return out, flags


#: A reading of e is not physical where its median over the run's impacts lies beyond 1 (or
#: below 0) by more than this many of its standard errors.
_UNPHYSICAL_SIGMAS = 4.0


def median_and_error(e: np.ndarray) -> tuple[float, float]:
    """Median of the finite ratios and its standard error (``1.2533 * 1.4826 MAD / sqrt n``)."""
    e = e[np.isfinite(e)]
    med = float(np.median(e))
    return med, 1.2533 * 1.4826 * float(np.median(np.abs(e - med))) / math.sqrt(e.size)


def _physical(med: float, se: float) -> bool:
    return -_UNPHYSICAL_SIGMAS * se <= med <= 1.0 + _UNPHYSICAL_SIGMAS * se


def _undetermined(run: Any, log: Any, base: Any, freq_hz: float | None, why: str
                  ) -> tuple[Any, tuple[str, ...]]:
    """Measurand not established by the regression: by physics, else both readings kept.

    A coefficient of restitution lies in [0, 1]: where exactly one reading's median e does
    (beyond :data:`_UNPHYSICAL_SIGMAS` standard errors), that reading is the measurand
    (:data:`FLAG_MEASURAND_INFERRED`); where neither does, nothing can be established and
    the run's ratios are withheld.  Otherwise the relative reading is kept and the
    absolute reading's difference recorded (``e_measurand_diff``: it widens e's interval).
    """
    alt = relative_to_striker(run, log, base, freq_hz) if base is not None and freq_hz else None
    if alt is not None:
        e0, e1 = np.asarray(log.e, dtype=float), np.asarray(alt.e, dtype=float)
        both = np.isfinite(e0) & np.isfinite(e1)
        if both.sum() >= 5:
            (m0, s0), (m1, s1) = median_and_error(e0[both]), median_and_error(e1[both])
            ok0, ok1 = _physical(m0, s0), _physical(m1, s1)
            readings = (f"median e read as relative {m0:.4f} +- {s0:.4f}, as absolute "
                        f"{m1:.4f} +- {s1:.4f}")
            if ok0 and not ok1:
                return log, (f"{FLAG_MEASURAND_INFERRED}: relative to the striker: the absolute "
                             f"reading gives a coefficient of restitution outside [0, 1] "
                             f"({readings}); {why}",)
            if ok1 and not ok0:
                return alt, (f"{FLAG_MEASURAND_INFERRED}: panel_absolute, made relative with "
                             f"the base: the relative reading gives a coefficient of restitution "
                             f"outside [0, 1] ({readings}); {why}",)
            if not (ok0 or ok1):
                nan = np.full(log.n_impacts, np.nan)
                return (dataclasses.replace(log, e=nan, v_out_m_s=nan), (
                    f"{FLAG_MEASURAND_UNDETERMINED}: {why}; neither reading gives a coefficient "
                    f"of restitution within [0, 1] ({readings}): this run's ratios are "
                    "withheld",))
            diff = m1 - m0
            kept = dataclasses.replace(log, e_measurand_diff=diff, e_measurand_alt_se=s1)
            if abs(diff) <= math.hypot(s0, s1):
                return kept, (f"{FLAG_MEASURAND_UNDECLARED}: {why}; read as relative (the "
                              f"absolute reading agrees within the noise: {readings})",)
            return kept, (f"{FLAG_MEASURAND_UNDETERMINED}: {why}; read as relative to the "
                          f"striker ({readings}): e's interval is widened by the difference",)
    nan = np.full(log.n_impacts, np.nan)
    return (dataclasses.replace(log, e=nan, v_out_m_s=nan), (
        f"{FLAG_MEASURAND_UNDETERMINED}: {why}; an absolute vibrometer cannot be made relative "
        "here, nor the difference bounded: this run's ratios are withheld",))


def run_chain_flags(run: Any) -> list[str]:
    """Named data-quality flags of a run's measurement chain (schema v2 metadata)."""
    flags = []
    vel = next((c for c in run.channels if c.quantity == "plate_velocity"), None)
    if vel is not None:
        measurand = getattr(vel, "measurand", None)
        if measurand is None:
            flags.append(FLAG_MEASURAND_UNDECLARED)
        elif measurand == "panel_absolute":
            has_base = any(c.quantity == "base_acceleration" for c in run.channels)
            f_end = getattr(run, "freq_end_hz", None)
            if not has_base or not run.excitation_freq_hz or (f_end and f_end != run.excitation_freq_hz):
                flags.append(FLAG_MEASURAND_ABSOLUTE)
    return flags


def transient_shocks(run: Any, *, on: float = 12.0, channel: str | None = None
                     ) -> list[dict[str, Any]]:
    """The shock in each channel of a transient run, the cause first, responses paired to it.

    The cause is ``channel`` (or the run's ``detect_channel``) when given, else the first
    channel measuring a quantity of :data:`CAUSE_QUANTITIES` (force before drive before
    base) that has a shock, else the first channel with a shock.  Each row: ``channel``,
    ``quantity``, ``role`` (``"cause"``/``"response"``), ``found``, ``onset_s``, ``peak_s``
    (physical times: ``start_time_s`` less ``group_delay_s``), ``peak_value`` (SI),
    ``strength`` (noise units), ``clock`` (``"A"``, ``"B"``, ...: channels whose sample rates
    agree to :data:`SAME_CLOCK_RTOL` share one), ``fs_hz``, ``onset_sample`` and
    ``peak_sample`` (indices on the channel's own clock; None when not found) and, for
    responses, ``delay_samples`` = response onset sample - cause onset sample and
    ``delay_s`` = response onset - cause onset: seconds only between channels on one
    clock (NaN across clocks: their rates disagree, and a time difference would carry
    that disagreement times the onset time).

    Raises
    ------
    ParameterError
        If ``channel`` names no channel of the run.
    """
    wanted = channel or getattr(run, "detect_channel", None)
    chans = [c for c in run.channels if c.quantity in SHOCK_QUANTITIES]
    if wanted is not None:
        if wanted not in {c.name for c in run.channels}:
            raise ParameterError(f"run {run.run_id!r}: no channel {wanted!r} to detect on "
                                 f"(has: {', '.join(c.name for c in run.channels)})")
        chans = [c for c in run.channels if c.name == wanted] + \
            [c for c in chans if c.name != wanted]
    rows = []
    rates: list[float] = []
    for c in chans:
        fs, t0 = _fs_of(run, c), _t0_of(run, c)
        shock = detect_shock(c.read(), fs, start_time_s=t0, on=on)
        clock = next((k for k, r in enumerate(rates) if abs(fs - r) <= SAME_CLOCK_RTOL * r),
                     None)
        if clock is None:
            rates.append(fs)
            clock = len(rates) - 1
        rows.append({"channel": c.name, "quantity": c.quantity, "found": shock.found,
                     "onset_s": shock.onset_s, "peak_s": shock.peak_s,
                     "peak_value": shock.peak_value, "strength": shock.strength,
                     "clock": chr(ord("A") + clock % 26), "fs_hz": fs,
                     "onset_sample": (int(round((shock.onset_s - t0) * fs))
                                      if shock.found else None),
                     "peak_sample": (int(round((shock.peak_s - t0) * fs))
                                     if shock.found else None)})
    if not rows:
        return rows
    if wanted is None:
        n_q = len(CAUSE_QUANTITIES)
        rank = [(next((i for i, q in enumerate(CAUSE_QUANTITIES) if r["quantity"] == q), n_q),
                 not r["found"]) for r in rows]
        best = min(range(len(rows)), key=lambda i: (rank[i][1], rank[i][0]))
        rows.insert(0, rows.pop(best))
    cause = rows[0]
    cause["role"] = "cause"
    for r in rows[1:]:
        r["role"] = "response"
        both = r["found"] and cause["found"]
        r["delay_samples"] = (r["onset_sample"] - cause["onset_sample"]) if both else None
        r["delay_s"] = (r["onset_s"] - cause["onset_s"]) if both and \
            r["clock"] == cause["clock"] else float("nan")
    return rows


__all__ = ["CAUSE_QUANTITIES", "FLAG_DELAY_CONTRADICTED", "FLAG_DELAY_ESTIMATED",
           "FLAG_FILTER_IDENTIFIED",
           "FLAG_MEASURAND_INFERRED", "FLAG_MEASURAND_UNDETERMINED", "SAME_CLOCK_RTOL",
           "SHOCK_QUANTITIES", "infer_measurand",
           "median_and_error", "paired_plate_channels", "relative_to_striker",
           "run_chain_flags", "transient_shocks", "velocity_delay_flags"]
