"""Period detection of impact sequences: none, ``m/n`` periodic, aperiodic, or unsettled.

Split from :mod:`rattle_lab.model.analysis.sweep` (which re-exports every name here) so
that sweeps and maps share it: :func:`classify_impacts` finds the smallest
period within a tolerance, and :func:`classify_settled` accepts an ``m/n`` match
only when it is settled (:func:`periodic_label_settled`), running the motion
longer otherwise.  All quantities are nondimensional.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numba
import numpy as np
from numpy.typing import ArrayLike

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.sdf import SDFParams, SDFState, simulate

RegimeKind = Literal["no-impact", "periodic", "aperiodic", "unsettled"]

#: Integer codes of the regime kinds in arrays (maps).
KIND_CODES: dict[RegimeKind, int] = {"no-impact": 0, "periodic": 1, "aperiodic": 2,
                                     "unsettled": 3}
KIND_NAMES: tuple[RegimeKind, ...] = ("no-impact", "periodic", "aperiodic", "unsettled")

#: Default relative tolerance of the period detection (see :func:`classify_impacts`).
PERIOD_RTOL = 1e-4
#: Extra forcing periods a periodic label that has not settled is run for before
#: the motion is called "unsettled" (see :func:`classify_settled`).
SETTLE_CYCLES = 1000

__all__ = [
    "Regime",
    "classify_impacts",
    "classify_settled",
    "periodic_label_settled",
    "KIND_CODES",
    "KIND_NAMES",
    "PERIOD_RTOL",
    "SETTLE_CYCLES",
]


# ---------------------------------------------------------------------------
# Period detection
# ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Regime:
    """Classification of a motion from its impacts.

    Attributes
    ----------
    kind : {"no-impact", "periodic", "aperiodic", "unsettled"}
        No impact in the window; ``m/n`` periodic; neither; or a periodic
        match in the window that is a transient still converging (to a
        shorter period, or away from the match) and did not settle when run
        longer (:func:`classify_settled`): no period is claimed.
    m : int
        Impacts per period (0 unless periodic).
    n : int
        Forcing periods per period, the smallest found (0 unless periodic).
    """

    kind: RegimeKind
    m: int = 0
    n: int = 0

    @property
    def label(self) -> str:
        """``"no impact"``, ``"m/n"``, ``"aperiodic"`` or ``"unsettled"``."""
        if self.kind == "periodic":
            return f"{self.m}/{self.n}"
        return "no impact" if self.kind == "no-impact" else self.kind

    @property
    def code(self) -> int:
        """Integer code of ``kind`` (:data:`KIND_CODES`)."""
        return KIND_CODES[self.kind]

    def to_dict(self) -> dict[str, object]:
        """JSON-ready dictionary."""
        return {"kind": self.kind, "m": self.m, "n": self.n, "label": self.label}


@numba.njit(cache=True, nogil=True)
def _classify(t: np.ndarray, v: np.ndarray, t_start: float, t_stop: float, period: float,
              n_max: int, rtol: float) -> tuple[int, int, int]:
    """(kind code, m, n); see :func:`classify_impacts`."""
    N = t.shape[0]
    if N == 0:
        return 0, 0, 0
    vscale = 0.0
    for i in range(N):
        vscale = max(vscale, abs(v[i]))
    tol_t = rtol * period
    tol_v = rtol * max(vscale, 1e-300)
    for n in range(1, n_max + 1):
        P = n * period
        if t_start + 2.0 * P > t_stop + tol_t:
            break  # two periods no longer fit in the window
        if t[0] - P > t_start + tol_t:
            continue  # a whole period without impact, then impacts: not n-periodic
        m = 0
        while m < N and t[m] < t[0] + P - tol_t:
            m += 1
        if m >= N:
            continue
        ok = True
        for i in range(N):
            if i + m < N:
                if abs(t[i + m] - t[i] - P) > tol_t or abs(v[i + m] - v[i]) > tol_v:
                    ok = False
                    break
            elif t[i] + P < t_stop - tol_t:
                ok = False  # the repeat of impact i is missing from the window
                break
        if ok:
            return 1, m, n
    return 2, 0, 0


def classify_impacts(t: ArrayLike, v_in: ArrayLike, *, t_start: float, t_stop: float,
                     omega: float, n_max: int = 12, rtol: float = PERIOD_RTOL) -> Regime:
    """Classify the motion in ``[t_start, t_stop]`` from its impacts: none, m/n or aperiodic.

    The motion is ``m/n`` periodic when, for the smallest ``n <= n_max``, the
    impact sequence repeats after ``m`` impacts and ``n`` forcing periods
    ``T = 2 pi / omega``: for every impact ``i`` with a successor ``i + m`` in
    the window ``|t_{i+m} - t_i - n T| <= rtol T`` and
    ``|v_{i+m} - v_i| <= rtol max(v)``, and every impact whose repeat would
    fall inside the window has one.  Only ``n`` with two full periods in the
    window are tried (``2 n T <= t_stop - t_start``).

    Why ``rtol = 1e-4``: after the discarded transient, the distance to a
    periodic attractor decays like ``|mu|^k`` (``mu`` its leading Floquet
    multiplier); a tolerance far above rounding lets orbits close to a
    bifurcation (``|mu|`` near 1) count as periodic as they would on the
    thesis's plots, while a chaotic sequence matching itself to 1e-4 over
    a whole window (two periods or more) does not happen in practice: the
    Lyapunov exponent, not this test, is the evidence of chaos.

    Parameters
    ----------
    t, v_in : array_like
        Impact times (sorted) and incoming velocities in the window.
    t_start, t_stop : float
        The window (nondimensional time).
    omega : float
        Forcing frequency (nondimensional).
    n_max : int
        Largest period, in forcing periods, to try (>= 1).
    rtol : float
        Relative tolerance (> 0), see above.

    Returns
    -------
    Regime

    Raises
    ------
    ParameterError
        On an invalid argument.

    Examples
    --------
    >>> import numpy as np
    >>> T = 2 * np.pi
    >>> t = np.arange(10) * 2 * T + 0.3          # one impact every two periods
    >>> classify_impacts(t, np.full(10, 0.5), t_start=0.0, t_stop=20 * T, omega=1.0).label
    '1/2'
    >>> classify_impacts([], [], t_start=0.0, t_stop=20 * T, omega=1.0).label
    'no impact'
    """
    tt = np.ascontiguousarray(t, dtype=float).ravel()
    vv = np.ascontiguousarray(v_in, dtype=float).ravel()
    if tt.shape != vv.shape:
        raise ParameterError(f"`t` and `v_in` must have the same length, were {tt.size} and {vv.size}")
    if tt.size > 1 and np.any(np.diff(tt) < 0):
        raise ParameterError("`t` must be sorted")
    if not (math.isfinite(omega) and omega > 0):
        raise ParameterError(f"`omega` must be finite and > 0, was {omega}")
    _check_int("n_max", n_max, 1)
    if not (math.isfinite(rtol) and rtol > 0):
        raise ParameterError(f"`rtol` must be finite and > 0, was {rtol}")
    if not t_stop > t_start:
        raise ParameterError(f"`t_stop` must be > t_start = {t_start}, was {t_stop}")
    kind, m, n = _classify(tt, vv, float(t_start), float(t_stop), 2.0 * math.pi / omega,
                           int(n_max), float(rtol))
    return Regime(kind=KIND_NAMES[kind], m=int(m), n=int(n))


@numba.njit(cache=True, nogil=True)
def _repeat_residuals(t: np.ndarray, v: np.ndarray, m: int, n: int, period: float,
                      vscale: float) -> np.ndarray:
    """Largest relative mismatch of the ``m``-impact, ``n``-period repeat, per repeat.

    Entry ``j`` is the maximum over impacts ``i`` of the ``j``-th group of ``m``
    of ``max(|t_{i+m} - t_i - n T| / T, |v_{i+m} - v_i| / vscale)`` (NaN if any
    term is NaN, as numpy's ``maximum`` and ``max``).
    """
    N = t.shape[0]
    if N <= m:
        return np.empty(0)
    groups = (N - m) // m
    out = np.empty(groups)
    nT = n * period
    for j in range(groups):
        best = -math.inf
        for i in range(j * m, (j + 1) * m):
            a = abs(t[i + m] - t[i] - nT) / period
            b = abs(v[i + m] - v[i]) / vscale
            d = a if a >= b else b
            if a != a or b != b:
                d = math.nan
            if d > best or d != d:
                best = d
            if best != best:
                break
        out[j] = best
    return out


@numba.njit(cache=True, nogil=True)
def _decays_to_zero(d: np.ndarray) -> bool:
    """``d`` (a residual per repeat) decreases geometrically towards zero.

    Three equally spaced entries ``d1 > d2 > d3`` of ``q + c r^j`` give its
    limit exactly (Aitken): ``q = (d1 d3 - d2^2) / (d1 + d3 - 2 d2)``.  The
    sequence is decaying to zero when that limit is below half the last value.
    """
    if d.shape[0] < 3:
        return False
    h = (d.shape[0] - 1) // 2
    d1 = d[d.shape[0] - 1 - 2 * h]
    d2 = d[d.shape[0] - 1 - h]
    d3 = d[d.shape[0] - 1]
    if not (d1 > d2 and d2 > d3):
        return False
    den = d1 + d3 - 2.0 * d2
    if den <= 0.0:  # decreasing but not convex: not a geometric decay
        return False
    return (d1 * d3 - d2 * d2) / den < 0.5 * d3


@numba.njit(cache=True, nogil=True)
def _settled(t: np.ndarray, v: np.ndarray, m: int, n: int, period: float, rtol: float) -> bool:
    """:func:`periodic_label_settled` on contiguous float arrays, ``m, n >= 1``."""
    vmax = 0.0
    for i in range(v.shape[0]):
        a = abs(v[i])
        if a > vmax or a != a:
            vmax = a
        if vmax != vmax:
            break
    vscale = 1e-300 if 1e-300 > vmax else vmax  # max(vmax, 1e-300), NaN kept
    own = _repeat_residuals(t, v, m, n, period, vscale)
    if own.shape[0] >= 2 and own[-1] > 4.0 * own[0] and own[-1] > 1e-3 * rtol:
        return False
    a = m
    b = n
    while b:  # g = gcd(m, n)
        a, b = b, a % b
    g = a
    for k in range(2, g + 1):
        if g % k == 0 and _decays_to_zero(
                _repeat_residuals(t, v, m // k, n // k, period, vscale)):
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _classify_windows(t: np.ndarray, v: np.ndarray, off: np.ndarray, t_start: np.ndarray,
                      t_stop: np.ndarray, period: np.ndarray, n_max: int,
                      rtol: float) -> np.ndarray:
    """:func:`_classify` and, for an ``m/n`` match, :func:`_settled`, of many windows.

    Window ``i`` holds the impacts ``t[off[i]:off[i + 1]]`` (``v`` likewise) of
    ``[t_start[i], t_stop[i]]`` at forcing period ``period[i]``.  Returns rows
    (kind code, m, n, settled), settled 1 unless an ``m/n`` match has not settled:
    exactly what :func:`classify_settled` computes first for each window.
    """
    n_win = t_start.shape[0]
    out = np.zeros((n_win, 4), dtype=np.int64)
    for i in range(n_win):
        tt = t[off[i]:off[i + 1]]
        vv = v[off[i]:off[i + 1]]
        kind, m, n = _classify(tt, vv, t_start[i], t_stop[i], period[i], n_max, rtol)
        out[i, 0] = kind
        out[i, 1] = m
        out[i, 2] = n
        out[i, 3] = 1
        if kind == 1 and not _settled(tt, vv, m, n, period[i], rtol):
            out[i, 3] = 0
    return out


def periodic_label_settled(t: ArrayLike, v_in: ArrayLike, *, m: int, n: int, omega: float,
                           rtol: float = PERIOD_RTOL) -> bool:
    """Whether an ``m/n`` match of the impacts ``(t, v_in)`` is a settled orbit.

    The period detection (:func:`classify_impacts`) accepts a repeat within
    ``rtol``; a transient can pass it with the wrong period.  Two cases are
    refused here:

    * a shorter period is being approached: for a proper divisor ``k`` of
      ``gcd(m, n)`` the mismatch of the ``(m/k)/(n/k)`` repeat decays
      geometrically towards zero across the window (for example a 1/3 orbit
      whose multiplier is near -1 matches 2/6 long before it matches 1/3);
    * the match is being left: its own mismatch grows more than fourfold
      across the window and exceeds ``rtol / 1000`` (far above rounding).

    Parameters
    ----------
    t, v_in : array_like
        Impact times and incoming velocities in the window (sorted).
    m, n : int
        The matched impacts per period and forcing periods per period.
    omega : float
        Forcing frequency (nondimensional).
    rtol : float
        The tolerance the match was found with.

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> T = 2 * np.pi
    >>> k = np.arange(12)
    >>> v = 0.5 + 1e-5 * (-0.9) ** k            # 1/1 orbit approached, mu = -0.9
    >>> periodic_label_settled(k * T, v, m=2, n=2, omega=1.0)
    False
    >>> periodic_label_settled(k * T, 0.5 + 1e-5 * (-1.0) ** k, m=2, n=2, omega=1.0)
    True
    """
    tt = np.ascontiguousarray(t, dtype=float).ravel()
    vv = np.ascontiguousarray(v_in, dtype=float).ravel()
    if tt.shape != vv.shape:
        raise ParameterError(f"`t` and `v_in` must have the same length, were {tt.size} and {vv.size}")
    m_i = _check_int("m", m, 1)
    n_i = _check_int("n", n, 1)
    return bool(_settled(tt, vv, m_i, n_i, 2.0 * math.pi / float(omega), float(rtol)))


def classify_settled(params: SDFParams, t: np.ndarray, v_in: np.ndarray, *, t_start: float,
                     end_state: SDFState, n_max: int, rtol: float = PERIOD_RTOL,
                     settle_cycles: float = SETTLE_CYCLES,
                     converging: bool = False) -> tuple[Regime, float]:
    """Classify the impacts of ``[t_start, end_state.t]``, running longer until settled.

    An ``m/n`` match that is not settled (:func:`periodic_label_settled`) is
    not reported.  Instead the motion is continued from ``end_state`` (a side
    run: the caller's state is not changed) in windows as long as the given
    one and each window is classified again, until a settled label (or no
    impact, or aperiodic motion) is found or ``settle_cycles`` extra forcing
    periods are spent; then the regime is ``"unsettled"``.

    Parameters
    ----------
    params : SDFParams
        The model parameters.
    t, v_in : ndarray
        Impact times and incoming velocities in the window.
    t_start : float
        Start of the window; it ends at ``end_state.t``.
    end_state : SDFState
        The state at the end of the window.
    n_max, rtol : int, float
        As for :func:`classify_impacts`.
    settle_cycles : float
        Most extra forcing periods to run (>= 0).
    converging : bool
        The motion is known to converge (a negative Lyapunov exponent): an aperiodic
        window is then a transient, not chaos, and is run on like an unsettled match.

    Returns
    -------
    regime : Regime
    extra_cycles : float
        Forcing periods run beyond the window to settle it (0 if settled at once).
    """
    period = params.period
    kind, m, n = _classify(np.ascontiguousarray(t, dtype=float),
                           np.ascontiguousarray(v_in, dtype=float), float(t_start),
                           float(end_state.t), period, int(n_max), float(rtol))
    def final(kind: int, m: int, n: int, t: np.ndarray, v_in: np.ndarray) -> bool:
        if kind == 1:
            return bool(_settled(np.ascontiguousarray(t, dtype=float),
                                 np.ascontiguousarray(v_in, dtype=float), int(m), int(n),
                                 2.0 * math.pi / params.omega, float(rtol)))
        return not (converging and KIND_NAMES[kind] == "aperiodic")

    if final(kind, m, n, t, v_in):
        return Regime(kind=KIND_NAMES[kind], m=int(m), n=int(n)), 0.0
    window = (end_state.t - t_start) / period
    if abs(window - round(window)) < 1e-6 * max(1.0, window):
        window = float(round(window))  # whole forcing periods, as sweeps and maps keep
    state = end_state
    extra = 0.0
    while extra + window <= settle_cycles + 1e-9:
        t0 = state.t
        res = simulate(params, cycles=window, state=state)
        state = res.state
        extra += window
        imp = res.impacts
        kind, m, n = _classify(imp.t, imp.v_in, t0, state.t, period, int(n_max), float(rtol))
        if final(kind, m, n, imp.t, imp.v_in):
            return Regime(kind=KIND_NAMES[kind], m=int(m), n=int(n)), extra
    return Regime(kind="unsettled"), extra


def _check_int(name: str, value: object, lo: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) < lo:
        raise ParameterError(f"`{name}` must be an integer >= {lo}, was {value!r}")
    return int(value)
