"""Channel sensitivities from calibrator records in a campaign, and their drift.

A calibrator record is a run of the campaign whose attributes say what the
calibrator produced (the ``x_`` prefix is the schema's place for such attributes):

============================  ===============================================================
``x_calibrator_level_db``     microphone calibrator: level in dB re 20 uPa (94 or 114 dB)
``x_calibrator_accel_ms2``    accelerometer calibrator: RMS acceleration, m/s^2 (10 m/s^2)
``x_calibrator_freq_hz``      the calibrator's frequency (1000 Hz; 159.2 Hz); defaults to these
``x_calibration_phase``       ``"pre"`` or ``"post"``; otherwise from the run's place in the
                              campaign (before the first measurement run: pre; after: post)
``x_calibrator_channel``      the channel in the calibrator (optional when the run has one
                              channel of the quantity)
============================  ===============================================================

The RMS of the calibrator tone is read from a Hann-windowed spectrum, summed over
+-10 % around the calibrator's frequency (hum and noise outside do not count), in
the channel's stored units.  For a channel stored in volts the sensitivity is
``S = rms_volts / reference_rms_si`` (V/Pa or V/(m/s^2)); it replaces the declared
sensitivity of that channel (matched by ``sensor_serial`` when the calibrator's
channel has one, otherwise by name) in every run, from the pre-calibration (the
post-calibration where there is none).  With both, the drift
``20 log10(S_post / S_pre)`` is flagged when it exceeds 0.5 dB.  A channel stored in
SI units cannot take a sensitivity: its calibrator reading is recorded as a check
(``20 log10(measured / reference)``, flagged above 0.5 dB) and the declared
conversion is kept.  Without a calibrator record the declared sensitivity is used
and the provenance says so (``ingest_calibration_source = "declared"``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from rattle_lab.exceptions import SchemaError

P_REF_PA = 20e-6
#: Largest pre/post difference accepted, dB (IEC 61672-3 / ISO 1996-2 practice: 0.5 dB).
DRIFT_LIMIT_DB = 0.5
_MIC_QUANTITIES = ("sound_pressure",)
_ACC_QUANTITIES = ("base_acceleration", "plate_acceleration")
_SI_SENSITIVITY_UNITS = {"sound_pressure": "V/Pa", "base_acceleration": "V/(m/s^2)",
                         "plate_acceleration": "V/(m/s^2)"}
Source = Literal["calibrator", "declared", "none"]


@dataclass(frozen=True)
class ChannelCalibration:
    """How one channel (by name) of a campaign is calibrated.

    Attributes
    ----------
    channel, quantity : str
        Channel name and quantity.
    source : {"calibrator", "declared", "none"}
        ``"calibrator"``: the sensitivity comes from a calibrator record;
        ``"declared"``: the record's own sensitivity or SI units are used;
        ``"none"``: the channel is uncalibrated (full-scale units).
    sensitivity : float or None
        Sensitivity used, in ``sensitivity_units`` (None for a channel stored in SI units).
    sensitivity_units : str or None
        ``"V/Pa"``, ``"V/(m/s^2)"``, or the declared units.
    declared_sensitivity : float or None
        The sensitivity the record declared (in ``sensitivity_units``).
    pre_sensitivity, post_sensitivity : float or None
        From the pre- and post-calibration records (V per SI unit; None if absent).
    drift_db : float
        ``20 log10(post / pre)``, dB (NaN without both).
    check_db : float
        For a channel in SI units: ``20 log10(measured / calibrator)`` of the
        calibrator record, dB (NaN otherwise).
    flags : tuple of str
        ``"drift"`` when ``|drift_db| > 0.5``; ``"check"`` when ``|check_db| > 0.5``.
    calibrator_runs : tuple of str
        Run ids of the calibrator records used.
    """

    channel: str
    quantity: str
    source: Source
    sensitivity: float | None = None
    sensitivity_units: str | None = None
    declared_sensitivity: float | None = None
    pre_sensitivity: float | None = None
    post_sensitivity: float | None = None
    drift_db: float = float("nan")
    check_db: float = float("nan")
    flags: tuple[str, ...] = ()
    calibrator_runs: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """Plain dict (NaN kept; pass through a JSON cleaner before writing)."""
        d = dataclasses.asdict(self)
        d["flags"], d["calibrator_runs"] = list(self.flags), list(self.calibrator_runs)
        return d

    def attrs(self) -> dict[str, Any]:
        """Provenance attributes written on the channel (``ingest_calibration_*``).

        Values that do not apply (None, NaN) are left out (the schema wants finite numbers).
        """
        out: dict[str, Any] = {"ingest_calibration_source": self.source,
                               "ingest_calibration_flags": ",".join(self.flags),
                               "ingest_calibration_runs": ",".join(self.calibrator_runs)}
        for name in ("declared_sensitivity", "pre_sensitivity", "post_sensitivity", "drift_db",
                     "check_db"):
            value = getattr(self, name)
            if value is not None and math.isfinite(value):
                out[f"ingest_calibration_{name}"] = float(value)
        return out


def tone_rms(x: np.ndarray, fs_hz: float, freq_hz: float, rel_band: float = 0.1) -> float:
    """RMS of the tone near ``freq_hz`` (+-``rel_band``), from a Hann-windowed spectrum.

    The window's power gain (3/8 of N) is divided out, so a pure tone of amplitude
    ``a`` gives ``a / sqrt(2)``.
    """
    x = np.asarray(x, dtype=float)
    x = x - np.mean(x)
    n = x.size
    w = np.hanning(n)
    spec = np.abs(np.fft.rfft(x * w)) ** 2
    f = np.fft.rfftfreq(n, 1.0 / fs_hz)
    sel = (f >= freq_hz * (1 - rel_band)) & (f <= freq_hz * (1 + rel_band))
    # Parseval with a window: sum(|X_k|^2) over both sides = n * sum((x w)^2) ~= n * a^2/2 * sum(w^2)
    return float(np.sqrt(2.0 * np.sum(spec[sel]) / (n * np.sum(w**2))))


def _calibrator(run: Any) -> tuple[str, float, float] | None:
    """``(quantity kind, reference RMS in SI, frequency)`` of a calibrator run, or None."""
    ex = run.extra
    if "x_calibrator_level_db" in ex:
        level = float(ex["x_calibrator_level_db"])
        return "mic", P_REF_PA * 10 ** (level / 20), float(ex.get("x_calibrator_freq_hz", 1000.0))
    if "x_calibrator_accel_ms2" in ex:
        return ("acc", float(ex["x_calibrator_accel_ms2"]),
                float(ex.get("x_calibrator_freq_hz", 159.2)))
    return None


def is_calibrator_run(run: Any) -> bool:
    """True for a run that records a calibrator (see the module docstring)."""
    return _calibrator(run) is not None


def _fs(ch: Any, where: str) -> float:
    if ch.sample_rate_hz is None:
        raise SchemaError(f"{where}: attribute 'sample_rate_hz': a calibrator record needs "
                          "regular sampling")
    return float(ch.sample_rate_hz)


def _si_per_volt(ch: Any) -> float | None:
    """Declared sensitivity of a volts channel, in V per SI unit (None if not in volts)."""
    if ch.units != "V" or ch.sensitivity is None:
        return None
    return 1.0 / ch.scale_to_si


def campaign_calibration(record: Any) -> dict[str, ChannelCalibration]:
    """Per channel name, the calibration the campaign's calibrator records give.

    Raises
    ------
    SchemaError
        A calibrator run without a channel of its quantity, or naming a channel it lacks.
    """
    runs = list(record.runs)
    measure_idx = [i for i, r in enumerate(runs) if not is_calibrator_run(r)]
    first, last = (min(measure_idx), max(measure_idx)) if measure_idx else (0, -1)
    readings: dict[str, dict[str, list[tuple[str, float, Any]]]] = {}
    for i, run in enumerate(runs):
        cal = _calibrator(run)
        if cal is None:
            continue
        kind, ref_si, freq = cal
        where = f"/runs/{run.run_id}"
        wanted = _MIC_QUANTITIES if kind == "mic" else _ACC_QUANTITIES
        name = run.extra.get("x_calibrator_channel")
        chans = [c for c in run.channels if (c.name == name if name else c.quantity in wanted)]
        if len(chans) != 1:
            raise SchemaError(f"{where}: attribute 'x_calibrator_channel': the calibrator run "
                              f"needs exactly one {'/'.join(wanted)} channel (or this attribute "
                              f"naming it), found {len(chans)}")
        ch = chans[0]
        phase = str(run.extra.get("x_calibration_phase", "pre" if i < first else
                                  "post" if i > last else "pre")).lower()
        if phase not in ("pre", "post"):
            raise SchemaError(f"{where}: attribute 'x_calibration_phase': must be 'pre' or "
                              f"'post', was {phase!r}")
        rms = tone_rms(ch.read(si=False), _fs(ch, where), freq)
        key = str(ch.sensor_serial) if ch.sensor_serial else ch.name
        readings.setdefault(key, {"pre": [], "post": []})[phase].append((run.run_id, rms / ref_si,
                                                                         ch))
    out: dict[str, ChannelCalibration] = {}
    for run in runs:
        if is_calibrator_run(run):
            continue
        for ch in run.channels:
            if ch.name in out or ch.quantity not in _MIC_QUANTITIES + _ACC_QUANTITIES:
                continue
            found = readings.get(str(ch.sensor_serial)) if ch.sensor_serial else None
            found = found or readings.get(ch.name)
            out[ch.name] = _channel_calibration(ch, found)
    return out


def _channel_calibration(ch: Any, found: dict[str, list[tuple[str, float, Any]]] | None
                         ) -> ChannelCalibration:
    declared = _si_per_volt(ch)
    if not found:
        src: Source = "none" if ch.uncalibrated else "declared"
        return ChannelCalibration(ch.name, ch.quantity, src, ch.sensitivity, ch.sensitivity_units,
                                  ch.sensitivity)
    pre = [v for _, v, _ in found["pre"]]
    post = [v for _, v, _ in found["post"]]
    runs = tuple(r for r, _, _ in found["pre"] + found["post"])
    s_pre = float(np.mean(pre)) if pre else None
    s_post = float(np.mean(post)) if post else None
    drift = 20 * math.log10(s_post / s_pre) if s_pre and s_post else float("nan")
    flags = ("drift",) if abs(drift) > DRIFT_LIMIT_DB else ()
    s_use = s_pre if s_pre is not None else s_post
    if ch.units == "V":
        units = _SI_SENSITIVITY_UNITS[ch.quantity]
        return ChannelCalibration(ch.name, ch.quantity, "calibrator", s_use, units, declared,
                                  s_pre, s_post, drift, float("nan"), flags, runs)
    # stored in SI units (or full scale): what was read is (stored units) / (SI unit)
    if ch.uncalibrated:
        return ChannelCalibration(ch.name, ch.quantity, "none", None, None, None, s_pre, s_post,
                                  drift, float("nan"), flags, runs)
    assert s_use is not None  # a calibrator reading exists on this path
    check = 20 * math.log10(float(s_use) * ch.scale_to_si)
    if abs(check) > DRIFT_LIMIT_DB:
        flags = (*flags, "check")
    return ChannelCalibration(ch.name, ch.quantity, "declared", ch.sensitivity,
                              ch.sensitivity_units, ch.sensitivity, s_pre, s_post, drift, check,
                              flags, runs)


def apply_campaign_calibration(record: Any) -> Any:
    """The record with calibrator-derived sensitivities applied and provenance attached.

    Every transducer channel (microphone, accelerometers) of every run gets
    ``ingest_calibration_*`` attributes (:meth:`ChannelCalibration.attrs`); a channel in
    volts with a calibrator reading gets the derived ``sensitivity`` (V/Pa or
    V/(m/s^2)).  The record root gets ``ingest_calibration`` (JSON: channel ->
    :meth:`ChannelCalibration.to_dict`).  A record without calibrator runs is
    returned with the "declared" provenance only.
    """
    cals = campaign_calibration(record)
    runs = []
    for run in record.runs:
        chans = []
        for ch in run.channels:
            cal = cals.get(ch.name)
            if cal is None or is_calibrator_run(run):
                chans.append(ch)
                continue
            change: dict[str, Any] = {"extra": {**ch.extra, **cal.attrs()}}
            if cal.source == "calibrator":
                change.update(sensitivity=cal.sensitivity, sensitivity_units=cal.sensitivity_units)
            chans.append(dataclasses.replace(ch, **change))
        runs.append(dataclasses.replace(run, channels=tuple(chans)))
    summary = {name: {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
                      for k, v in cal.to_dict().items()} for name, cal in cals.items()}
    return dataclasses.replace(record, runs=tuple(runs),
                               extra={**record.extra, "ingest_calibration": json.dumps(summary)})


__all__ = ["ChannelCalibration", "DRIFT_LIMIT_DB", "apply_campaign_calibration",
           "campaign_calibration", "is_calibrator_run", "tone_rms"]
