"""Small valid rattle records for the schema, ingest and reader tests (not a test module).

Signals are hand-built with an explicit ``np.random.default_rng(seed)`` so that
the expected SI values are known exactly.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
from conftest import RATTLE_LAB  # the one entry-point finder

from rattle_lab.records import (Channel, ImpactTable, Record, Rig, Run, Sensor, ThresholdTable,
                                Truth, write_record)

FS_HZ = 51200.0
N_SAMPLES = 4096


def plate_rig() -> Rig:
    """The thesis rig: 0.254 x 0.2286 m aluminium plate, 0.96 mm, CFCF, mic at 0.3 m."""
    return Rig(
        apparatus="plate_striker", plate_length_m=0.254, plate_width_m=0.2286,
        plate_thickness_m=0.00096, plate_material="aluminium", edge_conditions="CFCF",
        striker_x_m=0.127, striker_y_m=0.1143, gap_m=0.00034, mic_distance_m=0.3,
        sensors=(Sensor("base_acc", (0.127, 0.1143, -0.02), "base"),
                 Sensor("mic", (0.127, 0.1143, 0.3), "stand")))


def noisy_sine(seed: int, n: int = N_SAMPLES, amplitude: float = 1.0, freq_hz: float = 94.0,
               dtype: Any = np.float32) -> np.ndarray:
    """A sine plus small noise: no flat runs, no clipping."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS_HZ
    x = amplitude * np.sin(2 * np.pi * freq_hz * t) + 0.01 * amplitude * rng.standard_normal(n)
    return x.astype(dtype)


def channels(seed: int = 0, n: int = N_SAMPLES) -> list[Channel]:
    """The five channels of the rig; base and mic in raw volts with sensitivities."""
    common = {"sample_rate_hz": FS_HZ, "start_time_s": 0.0}
    return [
        Channel("base", "base_acceleration", "V", noisy_sine(seed, n, 0.5), sensitivity=100.0,
                sensitivity_units="mV/g", sensor_id="base_acc", sensor_model="PCB 352C33",
                sensor_serial="LW123", calibration_date="2024-01-15", range_min=-10.0,
                range_max=10.0, **common),
        Channel("plate", "plate_acceleration", "m/s^2", noisy_sine(seed + 1, n, 20.0), **common),
        Channel("velocity", "plate_velocity", "V", noisy_sine(seed + 2, n, 2.0), sensitivity=25.0,
                sensitivity_units="(mm/s)/V", **common),
        Channel("mic", "sound_pressure", "V", noisy_sine(seed + 3, n, 0.2), sensitivity=50.0,
                sensitivity_units="mV/Pa", sensor_id="mic", **common),
        Channel("drive", "drive_signal", "V", noisy_sine(seed + 4, n, 1.0), **common),
    ]


def make_record(campaign_id: str = "plate96", run_ids: tuple[str, ...] = ("dwell_094",),
                seed: int = 0, n: int = N_SAMPLES, synthetic: bool = False) -> Record:
    """A valid measured (or synthetic, with truth) record."""
    runs = [Run(run_id, "sine_dwell", channels(seed + 10 * i, n), excitation_freq_hz=94.0,
                nominal_level=2.0, nominal_level_units="m/s^2",
                start_time_iso="2024-03-01T14:10:00Z", notes="fan on")
            for i, run_id in enumerate(run_ids)]
    truth = None
    if synthetic:
        truth = Truth(gap_m=0.00034, f_s_hz=98.0, zeta=0.0085, e=0.8, participation=1.2,
                      acoustic_law="p_pa = 0.5 * v_in_m_s (delayed by distance / 343 m/s)",
                      impacts={run_ids[0]: ImpactTable(np.array([0.01, 0.02]), np.array([0.1, 0.11]),
                                                       np.array([-0.08, -0.09]))},
                      thresholds=ThresholdTable(np.array([90.0, 94.0]), np.array([2.0, 1.5]),
                                                np.array([1.0, np.nan]), "m/s^2"),
                      extra={"acoustic_delay_s": 0.00087})
    return Record(campaign_id, "synthetic" if synthetic else "measured", plate_rig(), runs,
                  truth=truth, description="test campaign", operator="tester")


def replace_channel(record: Record, run_id: str, name: str, **changes: Any) -> Record:
    """A copy of ``record`` with one channel's fields changed (e.g. ``data=...``)."""
    runs = []
    for run in record.runs:
        chans = tuple(dataclasses.replace(c, **changes) if (run.run_id == run_id and c.name == name)
                      else c for c in run.channels)
        runs.append(dataclasses.replace(run, channels=chans))
    return dataclasses.replace(record, runs=tuple(runs))


def write(tmp_path: Path, name: str = "rec.h5", record: Record | None = None) -> Path:
    """Write ``record`` (default :func:`make_record`) to ``tmp_path / name``."""
    return write_record(tmp_path / name, record if record is not None else make_record())


def run_cli_on_terminal(*args: str, timeout: float = 300) -> tuple[int, str]:
    """Run the installed ``rattle-lab`` with a pseudo-terminal as stdin, stdout and stderr.

    Returns the exit status and everything it wrote (progress bars included).
    """
    import fcntl
    import pty
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    proc = subprocess.Popen([str(RATTLE_LAB), *args], stdin=slave, stdout=slave, stderr=slave,
                            close_fds=True)
    os.close(slave)
    chunks = []
    while True:
        try:
            data = os.read(master, 1 << 16)
        except OSError:  # EIO: the program exited and closed the terminal
            break
        if not data:
            break
        chunks.append(data)
    os.close(master)
    return proc.wait(timeout=timeout), b"".join(chunks).decode("utf-8", "replace")


def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """Run the installed ``rattle-lab`` entry point."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
    return subprocess.run([str(RATTLE_LAB), *args], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=120)


def run_command(*args: str) -> subprocess.CompletedProcess[str]:
    """Run one ``rattle-lab`` command in this process: :func:`rattle_lab.cli.main`, the code
    behind the entry point, from argument parsing to the exit status and the one-line errors.

    For the tests of what a command computes (a chain's fit, a reader's refusal): they pay
    the command's work but not a new interpreter's start (about 3 s of imports and numba's
    start for ``fit``, most of such a test's time).  What only a process shows (the installed
    script, signals, a terminal, concurrent writers, another folder) stays in ``tests/cli``
    and the store tests, through :func:`run_cli`.  Warnings are filtered as in a fresh
    interpreter and printed to the captured stderr, as the entry point would, not raised by
    the suite's warning filter.
    """
    import contextlib
    import io
    import warnings

    from rattle_lab.cli import main

    out, err = io.StringIO(), io.StringIO()

    def show(message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
        err.write(warnings.formatwarning(message, category, filename, lineno, line))

    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        # the filters of a fresh interpreter (Python's defaults), printed to the stderr
        warnings.simplefilter("default")
        for quiet in (DeprecationWarning, PendingDeprecationWarning, ImportWarning,
                      ResourceWarning):
            warnings.simplefilter("ignore", quiet)
        warnings.showwarning = show
        try:
            code = main(list(args))
        except SystemExit as exc:  # argparse's usage errors
            code = exc.code if isinstance(exc.code, int) else 2
    return subprocess.CompletedProcess(["rattle-lab", *args], code, out.getvalue(),
                                       err.getvalue())
