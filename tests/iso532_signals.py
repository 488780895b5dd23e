"""Test signals for ISO 532-1 loudness, and MoSQITo's loudness of them stored as the reference.

:func:`iso532_signals` makes synthetic signals of the kinds of ISO 532-1 annex B.4/B.5 with
NumPy from their definitions, including kinds the annex has no signal of (AM tone, impacts).
The comparison with the standard's own published results for its annex B test signals is
``tests/acoustics/test_iso532_annex_b.py``.
``tests/data/mosqito_loudness.npz`` holds MoSQITo's ``loudness_zwtv`` of each (free and
diffuse field): MoSQITo, the reference implementation, runs at about real time in Python
(36 s for these signals), so the suite compares with its stored output and checks on one
signal per run that the installed MoSQITo still gives it
(``test_stored_mosqito_reference_is_what_mosqito_computes``).  Regenerate it, after an
intended change to the signals or a new MoSQITo, explicitly::

    .venv/bin/python tests/iso532_signals.py

Each entry also stores its signal's length and root mean square, so a stored reference that
no longer belongs to its signal fails the comparison with a message naming this command.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

FS = 48000.0
P0 = 20e-6
REFERENCE = Path(__file__).resolve().parent / "data" / "mosqito_loudness.npz"
FIELDS = ("free", "diffuse")


def tone(freq_hz: float, level_db: float, duration_s: float, fs_hz: float = FS) -> np.ndarray:
    t = np.arange(round(duration_s * fs_hz)) / fs_hz
    return np.sqrt(2.0) * P0 * 10 ** (level_db / 20) * np.sin(2 * np.pi * freq_hz * t)


def iso532_signals() -> dict[str, np.ndarray]:
    """Synthetic signals of the kinds of ISO 532-1 annex B.4/B.5 (time-varying test signals):
    1 kHz tones at stated levels (the anchors 40 and 60 dB, 80 dB), tone pulses of 10 and
    100 ms at 70 dB, a 250 Hz tone rising in 10 dB steps from 30 to 80 dB, a 1 kHz tone
    amplitude-modulated at 4 Hz, pink noise at 60 dB, a 100 Hz tone at 80 dB (the
    low-frequency weighting) and decaying impacts in silence (rattle).  All generated here
    with NumPy from their definitions (the annex's own signals, with the standard's results,
    are in ``tests/acoustics/test_iso532_annex_b.py``)."""
    rng = np.random.default_rng(29)
    out = {"tone_1k_40dB": tone(1000.0, 40.0, 0.6), "tone_1k_60dB": tone(1000.0, 60.0, 0.6),
           "tone_1k_80dB": tone(1000.0, 80.0, 0.6), "tone_100_80dB": tone(100.0, 80.0, 0.6)}
    silence = np.zeros(int(0.15 * FS))
    for ms in (10, 100):
        out[f"pulse_1k_{ms}ms_70dB"] = np.concatenate(
            [silence, tone(1000.0, 70.0, ms / 1000), silence, silence])
    out["steps_250_30_to_80dB"] = np.concatenate(
        [tone(250.0, level, 0.1) for level in range(30, 90, 10)])
    t = np.arange(int(0.8 * FS)) / FS
    out["am_1k_4Hz_70dB"] = tone(1000.0, 70.0, 0.8) * (1 + np.sin(2 * np.pi * 4 * t)) / 1.5
    spec = np.fft.rfft(rng.standard_normal(int(0.8 * FS)))
    f = np.fft.rfftfreq(int(0.8 * FS), 1 / FS)
    spec[1:] /= np.sqrt(f[1:])
    spec[0] = 0
    pink = np.fft.irfft(spec, n=int(0.8 * FS))
    out["pink_60dB"] = pink * P0 * 10 ** (60 / 20) / np.sqrt(np.mean(pink**2))
    hits = np.zeros(int(0.6 * FS))
    for k, t0 in enumerate((0.05, 0.2, 0.26, 0.4)):
        i0 = int(t0 * FS)
        n = int(0.03 * FS)
        hits[i0:i0 + n] += (0.5 + k) * rng.standard_normal(n) * np.exp(-np.arange(n) / (0.004 * FS))
    out["impacts"] = hits
    return out



def mosqito_loudness(p: np.ndarray, field_type: str) -> tuple[np.ndarray, np.ndarray]:
    """MoSQITo's ``N(t)`` (sone) and time-averaged ``N'(z)`` (sone/Bark) of ``p`` at :data:`FS`."""
    from mosqito.sq_metrics import loudness_zwtv

    n_t, spec, _, _ = loudness_zwtv(p, FS, field_type=field_type)
    return np.asarray(n_t, dtype=float), np.mean(np.asarray(spec, dtype=float), axis=1)


def stored_reference(name: str, field_type: str, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The stored MoSQITo ``(N(t), mean N'(z))`` of signal ``name``, after checking that it was
    computed from this signal (same length, root mean square to 1e-9)."""
    with np.load(REFERENCE) as ref:
        n_t, spec = ref[f"{field_type}/{name}/n_t"], ref[f"{field_type}/{name}/spec_mean"]
        size, rms = ref[f"{name}/size"], ref[f"{name}/rms"]
    if int(size) != p.size or not abs(float(rms) / float(np.sqrt(np.mean(p * p))) - 1) < 1e-9:
        raise AssertionError(f"{REFERENCE.name}: the stored reference of {name!r} is not of this "
                             "signal; regenerate it: .venv/bin/python tests/iso532_signals.py")
    return n_t, spec


def main() -> int:
    out: dict[str, np.ndarray] = {}
    for name, p in iso532_signals().items():
        out[f"{name}/size"] = np.array(p.size)
        out[f"{name}/rms"] = np.array(np.sqrt(np.mean(p * p)))
        for field in FIELDS:
            out[f"{field}/{name}/n_t"], out[f"{field}/{name}/spec_mean"] = \
                mosqito_loudness(p, field)
    np.savez_compressed(REFERENCE, **out)
    print(f"wrote {REFERENCE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
