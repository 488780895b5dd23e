"""Can e from velocity ratios be freed of the plate's higher modes?  A diagnostic (issue 15).

On ``synthetic/realistic_lab.toml`` the vibrometer also sees the plate's higher modes
(1.15, 1.77 and 2.76 times the fundamental, decaying in 4 ms) ringing after each impact;
their velocity jumps at the impact with the fundamental's, and ``e`` from the local fits
reads both.  This script measures, run by run, what whole-flight models recover:

* ``local``: the detector's fits either side of each impact (what ``rattle-lab fit`` uses);
* ``flight, no ringing``: one run-wide forced response (``c + (a0 + a1 u) cos w t +
  (b0 + b1 u) sin w t``; ``c``, the sensor offset, left out of the velocities) plus, per
  flight, the fundamental's free response at ``f_s`` (the scene's, with its damping);
* ``flight, oracle ringing``: the same plus the ringing modes at the scene's own
  frequencies and decay, free amplitudes per flight: an upper bound for a model whose
  ringing frequencies come from the plate (geometry declared) rather than from the record;
* ``record``: the flight model of :mod:`rattle_lab.detect._flights` (what
  ``velocity_model = "auto"``/``"flights"`` runs to measure the ringing's share): the same
  kind of model with the ringing modes searched in the record itself, each impact's ringing
  in proportion to its velocity change; its own per-impact velocities, its run time per run
  (``t record``) and the note it left.

It also prints the singular values of the stacked flights (Hankel matrices of the flights,
block-averaged by 4): how many components stand above the noise, i.e. whether the record
alone could resolve the ringing modes.  Truth: the record's ``/truth`` impacts; the base
velocity (absolute vibrometer) is taken off as ``rattle-lab fit`` does.

Usage: ``python benchmarks/ringing_separability.py``.  Timings under load.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from rattle_lab.detect import ImpactParams, detect_impacts
from rattle_lab.detect._flights import flight_velocities
from rattle_lab.detect._pairing import base_velocity_at
from rattle_lab.detect._chain import _fs_of, _t0_of, paired_plate_channels
from rattle_lab.rig import load_scene, synthesize
from rattle_lab.rig._build import resolve_modal

ROOT = Path(__file__).resolve().parents[1]
PAD = 10          # samples left out either side of an impact (contact and band limit)


def _free(tau: np.ndarray, f_hz: float, s: float) -> np.ndarray:
    env = np.exp(-s * tau)
    return np.column_stack([env * np.cos(2 * np.pi * f_hz * tau),
                            env * np.sin(2 * np.pi * f_hz * tau)])


def flight_fit(v: np.ndarray, fs: float, f_hz: float, k_imp: np.ndarray, free: tuple[float, float],
               ring: list[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """``(v_in, v_out)`` from the run-wide forced response and per-flight free response + ringing."""
    w, t_total, n_imp = 2 * np.pi * f_hz, v.size / fs, k_imp.size

    def glob(t: np.ndarray) -> np.ndarray:
        u, c, s = t / t_total, np.cos(w * t), np.sin(w * t)
        return np.column_stack([np.ones_like(t), c, s, u * c, u * s])

    segs = []
    for m in range(-1, n_imp):
        lo = int(np.ceil(k_imp[m] + PAD)) if m >= 0 else 0
        hi = int(np.floor(k_imp[m + 1] - PAD)) if m + 1 < n_imp else v.size - 1
        if hi - lo < 20:
            continue
        ref = k_imp[m] if m >= 0 else k_imp[0]
        k = np.arange(lo, hi + 1.0)
        z = [_free((k - ref) / fs, *free)]
        if m >= 0:
            z += [_free((k - ref) / fs, f, s) for f, s in ring]
        segs.append((m, ref, glob(k / fs), np.column_stack(z), v[lo:hi + 1]))
    a, b = np.zeros((5, 5)), np.zeros(5)
    for _, _, x, z, y in segs:          # the per-flight coefficients eliminated exactly
        q = np.linalg.qr(z)[0]
        a += x.T @ (x - q @ (q.T @ x))
        b += x.T @ (y - q @ (q.T @ y))
    beta = np.linalg.solve(a, b)
    forced = beta.copy()
    forced[0] = 0.0                       # the offset is no motion
    vin, vout = np.full(n_imp, np.nan), np.full(n_imp, np.nan)
    for m, ref, x, z, y in segs:
        g = np.linalg.lstsq(z, y - x @ beta, rcond=None)[0]
        for idx, out in ((m, vout), (m + 1, vin)):
            if 0 <= idx < n_imp:
                t_k = float(k_imp[idx])
                out[idx] = float((glob(np.array([t_k / fs])) @ forced)[0]
                                 + (_free(np.array([(t_k - ref) / fs]), *free) @ g[:2])[0])
    return vin, vout


def stacked_singular_values(v: np.ndarray, k_imp: np.ndarray, fs: float, f_hz: float,
                            n_sv: int = 8) -> np.ndarray:
    """Leading singular values (relative) of the flights' stacked Hankel matrices."""
    lo = np.ceil(k_imp[:-1] + PAD).astype(int)
    hi = np.floor(k_imp[1:] - PAD).astype(int)
    n = hi - lo + 1
    length = int(min(round(fs / f_hz), np.floor(0.9 * np.median(n))))
    nb = length // 4
    cols = [np.lib.stride_tricks.sliding_window_view(
        v[lo[i]:lo[i] + 4 * nb].reshape(nb, 4).mean(axis=1), nb // 2).T
        for i in np.flatnonzero(n >= length)]
    s = np.linalg.svd(np.hstack(cols), compute_uv=False)
    return s[:n_sv] / s[0]


def main() -> None:
    scene = load_scene(ROOT / "synthetic" / "realistic_lab.toml")
    modal, ring_hz = resolve_modal(scene)
    ring = [(f, 1.0 / scene.model.ringing_decay_s) for f in ring_hz]
    free = (modal.f_s_hz, modal.zeta * 2 * np.pi * modal.f_s_hz)
    record = synthesize(scene).record
    print(f"realistic_lab: ringing modes {', '.join(f'{f:.1f}' for f in ring_hz)} Hz "
          f"(decay {1e3 * scene.model.ringing_decay_s:g} ms), f_s {modal.f_s_hz:g} Hz, "
          f"true e {record.truth.e:g}")
    print(f"{'run':<10} {'n':>4}  {'e local':>8} {'e flight':>9} {'e oracle':>9} {'e record':>9}  "
          f"{'v_in err: local':>15} {'oracle':>7}  {'t oracle':>8} {'t record':>8}  "
          "modes found (Hz) / note")
    tot: dict[str, list[float]] = {"local": [], "flight": [], "oracle": [], "record": []}
    for run in record.runs:
        by_q = {c.quantity: c for c in reversed(run.channels)}
        vel, acc, base = (by_q["plate_velocity"], by_q.get("plate_acceleration"),
                          by_q["base_acceleration"])
        fs, t0, v, a = paired_plate_channels(run, vel, acc)
        f = float(run.excitation_freq_hz)
        log = detect_impacts(fs, velocity_m_s=v, accel_ms2=a, start_time_s=t0, excitation_freq_hz=f,
                             params=ImpactParams(velocity_model="local"))
        if log.n_impacts < 8:
            continue
        vb = base_velocity_at(base.read(), _fs_of(run, base), _t0_of(run, base), f, log.t_s)
        k_imp = (log.t_s - t0) * fs
        true = record.truth.impacts[run.run_id]
        j = np.clip(np.searchsorted(true.t_s, log.t_s), 1, true.t_s.size - 1)
        j = np.where(np.abs(true.t_s[j - 1] - log.t_s) < np.abs(true.t_s[j] - log.t_s), j - 1, j)
        ok = np.abs(true.t_s[j] - log.t_s) < 2e-4
        rows = {"local": (log.v_in_m_s, log.v_out_m_s)}
        rows["flight"] = flight_fit(v, fs, f, k_imp, free, [])
        t1 = time.perf_counter()
        rows["oracle"] = flight_fit(v, fs, f, k_imp, free, ring)
        dt = time.perf_counter() - t1
        t1 = time.perf_counter()
        fit_r = flight_velocities(v, fs, f, k_imp, np.full(k_imp.size, float(PAD)),
                                  log.v_in_m_s, log.v_out_m_s)
        dt_r = time.perf_counter() - t1
        rows["record"] = (fit_r.v_in_m_s, fit_r.v_out_m_s)
        e, verr = {}, {}
        for name, (vi, vo) in rows.items():
            vi, vo = vi - vb, vo - vb
            ee = -vo[ok] / vi[ok]
            e[name] = float(np.nanmean(ee))
            verr[name] = float(np.nanmedian(np.abs(vi[ok] / true.v_in_m_s[j[ok]] - 1)))
            tot[name].extend(ee[np.isfinite(ee)])
        print(f"{run.run_id:<10} {int(ok.sum()):>4}  {e['local']:>8.3f} {e['flight']:>9.3f} "
              f"{e['oracle']:>9.3f} {e['record']:>9.3f}  {100 * verr['local']:>14.2f}% "
              f"{100 * verr['oracle']:>6.2f}%  {dt:>7.2f}s {dt_r:>7.2f}s  "
              f"{fit_r.note or 'flight model'}")
    print("all impacts, mean e (0 < e < 1.5): " + ", ".join(
        f"{k} {np.mean([x for x in v if 0 < x < 1.5]):.3f}" for k, v in tot.items()))


if __name__ == "__main__":
    main()
