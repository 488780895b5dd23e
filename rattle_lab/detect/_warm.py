"""Compile the detection's numba kernels into numba's on-disk cache (:func:`warm_cache`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from ._flights import campaign_ring_modes, flight_velocities, ringing_problem
from ._impacts import ImpactParams, detect_impacts


def _bouncing(fs_hz: float, f_hz: float, seconds: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A made-up plate velocity (m/s) and acceleration (m/s^2) with one impact a forcing
    period (+0.07 m/s after it, -0.1 m/s before the next), a mode ringing after each, and
    noise; and the impact times in samples."""
    rng = np.random.default_rng(0)
    t = np.arange(int(seconds * fs_hz)) / fs_hz
    period = 1.0 / f_hz
    tau = np.mod(t - 0.25 * period, period)          # time since the last impact
    v = 0.07 - 0.17 * tau / period
    v += 0.005 * np.exp(-tau / 3e-3) * np.sin(2 * np.pi * 310.0 * tau)
    v += 1e-4 * rng.standard_normal(t.size)
    a = np.gradient(v) * fs_hz + 0.5 * rng.standard_normal(t.size)
    k_imp = (0.25 * period + np.arange(1, int(seconds * f_hz) - 1) * period) * fs_hz
    return v, a, k_imp


#: The compiled functions :func:`kernels_cold` looks for in numba's cache (one of each kind).
_PROBES = ("local_lstsq", "free_sums", "added_sums", "tail_columns", "jump_fits_batch")


def kernels_cold() -> bool:
    """Whether numba's on-disk cache lacks some of the detection's compiled functions (a
    detection would compile them first, about 15 s).  False where it cannot tell (a numba
    without this cache layout): no notice is better than a wrong one."""
    from . import _flight_kernels, _jump_kernels

    for name in _PROBES:
        try:
            module = _jump_kernels if hasattr(_jump_kernels, name) else _flight_kernels
            index = getattr(module, name)._cache._cache_file._load_index()
        except Exception:  # noqa: BLE001 - numba internals: unknown means "do not say"
            return False
        if not index:
            return True
    return False


def warm_cache() -> None:
    """Compile the per-run analysis's numba kernels now, and write numba's on-disk cache.

    The trigger's local fits, the flight model, its ringing searches (one run's and the
    campaign's), the ringing modes carried over impacts, and the run's acoustics (ISO 532-1
    loudness), each called once on a made-up record of 0.6 s (``python -m rattle_lab._warmup``
    runs it after installing, and a first ``rattle-lab fit`` where :func:`kernels_cold`;
    without it the first detection compiles them silently, about 15-18 s).
    """
    from rattle_lab.acoustics import run_acoustics

    fs, f = 20000.0, 100.0
    v, a, k_imp = _bouncing(fs, f, 0.6)
    params = ImpactParams()
    for given in (dataclasses.replace(params, velocity_model="flights"),
                  dataclasses.replace(params, ring_modes=((310.0, 333.0),))):
        detect_impacts(fs, velocity_m_s=v, accel_ms2=a, params=given, excitation_freq_hz=f)
    # samples read from a file come read-only (numba compiles them apart)
    v.flags.writeable = False
    detect_impacts(fs, velocity_m_s=v, excitation_freq_hz=f)
    pad = np.full(k_imp.size, 10.0)
    v_in, v_out = np.full(k_imp.size, -0.1), np.full(k_imp.size, 0.07)
    flight_velocities(v, fs, f, k_imp, pad, v_in, v_out)
    problem = ringing_problem(v, fs, f, k_imp, pad, v_in, v_out)
    if problem is not None:
        campaign_ring_modes([problem, problem])
    mic = 1e-3 * np.random.default_rng(1).standard_normal(v.size)
    run_acoustics(mic, fs, k_imp / fs)
