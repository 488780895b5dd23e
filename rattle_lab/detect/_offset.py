"""The vibrometer's DC offset from the impacts, and the reversal test that tells an impact
from ringing, hum or a glitch (:func:`~rattle_lab.detect.detect_impacts`, steps 6-7)."""

from __future__ import annotations

import numpy as np


#: Least span from the first to the last impact over which :func:`velocity_offset` is measured, s.
OFFSET_MIN_SPAN_S = 0.05


def velocity_offset(v: np.ndarray, k_imp: np.ndarray, fs_hz: float,
                    scale_m_s: float) -> float:
    """The velocity channel's DC offset: its mean from the first impact to the last, m/s.

    At every impact the plate is at the gap, so its velocity relative to the striker
    integrates to zero between any two impacts; an absolute vibrometer adds the base's
    velocity, whose integral (the base displacement, tens of micrometres) is as small.
    What remains of the mean is the sensor's offset: on the realistic lab scene (3 mm/s
    offset) it was 12 % of the slowest runs' impact velocity and moved their ``e`` by up
    to 15 % (issue 15).  The higher modes' ringing integrates to a small part of each
    velocity change (``sum a_j s_j / (s_j^2 + w_j^2)``) and is left in it.  0 with fewer
    than 3 impacts or a span under :data:`OFFSET_MIN_SPAN_S` (a single shock has no
    second contact to close the integral), and 0 where the flights' own mean velocities
    scatter by more than :data:`OFFSET_CONSISTENCY` times ``scale_m_s`` (the impact
    speed): then the contacts are not at one displacement and the premise fails.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(20000) / 10000.0
    >>> v = 0.2 * np.cos(2 * np.pi * 10 * t) + 0.003          # gap reached every 0.1 s
    >>> round(velocity_offset(v, np.array([0.0, 5000.0, 10000.0, 15000.0]), 1e4, 0.2), 6)
    0.003
    """
    k = np.sort(np.asarray(k_imp, dtype=float)[np.isfinite(k_imp)])
    if k.size < 3 or (k[-1] - k[0]) / fs_hz < OFFSET_MIN_SPAN_S:
        return 0.0
    # the integral of v from sample 0 to any fractional index, by the trapezoid rule
    vv = np.asarray(v, dtype=float)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (vv[1:] + vv[:-1]))])
    i0 = np.clip(np.floor(k).astype(int), 0, vv.size - 2)
    frac = k - i0
    at = cum[i0] + frac * vv[i0] + 0.5 * frac**2 * (vv[i0 + 1] - vv[i0])
    flights = np.diff(at) / np.diff(k)            # mean velocity of each flight
    c = float((at[-1] - at[0]) / (k[-1] - k[0]))
    # the premise: every flight's mean is the offset (a record whose flights disagree by
    # more than OFFSET_CONSISTENCY of the impact speeds does not close at the gap)
    spread = 1.4826 * float(np.median(np.abs(flights - np.median(flights))))
    if not spread <= OFFSET_CONSISTENCY * scale_m_s:
        return 0.0
    return c


#: Largest robust spread of the flights' mean velocities, relative to the median impact
#: speed, for which :func:`velocity_offset` takes the records' flights to close at the gap.
OFFSET_CONSISTENCY = 0.02


def _reverses(vin: np.ndarray, vout: np.ndarray, min_reversal: float) -> np.ndarray:
    """Triggers that are impacts by their velocities (see step 6 of the module docstring).

    Kept: a jump ``v_out - v_in`` opposite to ``v_in`` of at least ``min_reversal |v_in|``,
    approaching from the striker's side (the sign of most such ``v_in``).  A trigger whose
    velocities could not be fitted (record edge: NaN) is kept.
    """
    if min_reversal == 0.0 or vin.size == 0:
        return np.ones(vin.size, dtype=bool)
    with np.errstate(invalid="ignore"):
        reversal = -(vout - vin) * np.sign(vin) >= min_reversal * np.abs(vin)
        unknown = ~(np.isfinite(vin) & np.isfinite(vout))
        side = np.sign(np.sum(np.sign(vin[reversal & ~unknown])))
        toward = (np.sign(vin) == side) if side != 0 else np.ones(vin.size, dtype=bool)
    return unknown | (reversal & toward)


def _reversed_at_ends(vin: np.ndarray, vout: np.ndarray, keep: np.ndarray, vin_e: np.ndarray,
                      vout_e: np.ndarray, sign_a: np.ndarray, min_reversal: float) -> np.ndarray:
    """Triggers that :func:`_reverses` did not keep but that are impacts by the velocity fits
    at their contact pulse's ends (``vin_e`` at first touch, ``vout_e`` at separation).

    A contact lasting ``T`` changes the free flight's velocity by ``a T`` besides its own
    impulse; read at the centroid, a slow approach (``|v_in| < |a| T / 2``) then shows no
    reversal.  Kept here: the same reversal as :func:`_reverses` between the two ends,
    approaching from the striker's side of the impacts kept, with a contact pulse of the
    sign theirs have relative to their approach (the accelerometer may be mounted either
    way round).  Without kept impacts the candidates that reverse at their ends set both.
    """
    none = np.zeros(vin.size, dtype=bool)
    if min_reversal == 0.0 or vin.size == 0:
        return none
    with np.errstate(invalid="ignore"):
        cand = ~keep & np.isfinite(vin_e) & np.isfinite(vout_e) & (sign_a != 0)
        rev_e = cand & (-(vout_e - vin_e) * np.sign(vin_e) >= min_reversal * np.abs(vin_e))
        ref = keep & np.isfinite(vin) & (sign_a != 0)
        v_ref = vin
        if not ref.any():
            ref, v_ref = rev_e, vin_e
        side = float(np.sign(np.sum(np.sign(v_ref[ref]))))
        polarity = float(np.sign(np.sum(sign_a[ref] * np.sign(v_ref[ref]))))
        if side == 0.0 or polarity == 0.0:
            return none
        return rev_e & (np.sign(vin_e) == side) & (sign_a * side == polarity)


def _reversed_by_samples(v: np.ndarray, keep: np.ndarray, a_lo: np.ndarray, a_hi: np.ndarray,
                         sign_a: np.ndarray, min_reversal: float) -> np.ndarray:
    """Triggers that neither velocity-fit test kept but that are impacts by the velocity
    samples themselves just outside their contact pulse.

    Where the plate rings in many lightly damped modes (a converged multi-mode plate: every
    mode at 0.85 % of critical damping rings through the next flight), the local fits either
    side of an impact read the ringing and the forced swing, not the approach and rebound.
    The samples are what they are: the one before first touch (``floor(a_lo) - 1``) holds the
    approach, the one after separation (``ceil(a_hi) + 1``) the rebound (``a_lo``, ``a_hi``:
    the contact pulse's ends in the velocity's samples).  Kept here: triggers with a pulse
    whose two samples show :func:`_reverses`' reversal, approaching from the side and with
    the pulse polarity of most triggers whose samples reverse (decided by the samples, not by
    the fits, which on such records can put the approach on the wrong side).

    Returns
    -------
    ndarray of bool
        The triggers to add (none of ``keep``).
    """
    none = np.zeros(keep.size, dtype=bool)
    if min_reversal == 0.0 or keep.size == 0 or keep.all():
        return none
    pulsed = np.isfinite(a_lo) & np.isfinite(a_hi) & (sign_a != 0)
    i_lo = np.where(pulsed, np.floor(np.where(pulsed, a_lo, 0.0)) - 1, 0).astype(np.int64)
    i_hi = np.where(pulsed, np.ceil(np.where(pulsed, a_hi, 0.0)) + 1, 0).astype(np.int64)
    pulsed &= (i_lo >= 0) & (i_hi < v.size)
    vb = np.where(pulsed, v[np.clip(i_lo, 0, v.size - 1)], np.nan)
    va = np.where(pulsed, v[np.clip(i_hi, 0, v.size - 1)], np.nan)
    with np.errstate(invalid="ignore"):
        rev = pulsed & (-(va - vb) * np.sign(vb) >= min_reversal * np.abs(vb)) & (vb != 0)
    side = float(np.sign(np.sum(np.sign(vb[rev]))))
    polarity = float(np.sign(np.sum(sign_a[rev] * np.sign(vb[rev]))))
    if side == 0.0 or polarity == 0.0:
        return none
    return rev & ~keep & (np.sign(vb) == side) & (sign_a * side == polarity)

