"""The thesis's own fixed-step integrator, kept as a faithful reference method.

This is a transcription of ``Impact_sys.evolve`` (thesis Appendix A.1, section
4.1) to the nondimensional SDF model (``m = 1``, ``b = 2 zeta``, ``k = 1``,
``A = F``, ``gap = 1``; the Java's angular frequency ``F`` is our ``omega``)::

    x'' = a(t, x, v) = F cos(theta(t)) - 2 zeta v - x,    theta(t) = theta0 + omega (t - t0)

One call of ``evolve(h)`` does, from ``(t, x, v)``:

1. Four slopes of the classical Runge-Kutta method on ``(x, v)``, written as in
   eq. (4.3) with ``l_i = h a(...)``::

       l1 = h a(t,       x,                        v)
       l2 = h a(t + h/2, x + h v/2,                v + l1/2)
       l3 = h a(t + h/2, x + h v/2 + h l1/4,       v + l2/2)
       l4 = h a(t + h,   x + h v + h l2/2,         v + l3)
       x_new = x + h (v + (l1 + l2 + l3)/6)
       v_new = v + (l1 + 2 l2 + 2 l3 + l4)/6

   The printed eq. (4.3) drops the ``+ l1/2`` in the velocity argument of
   ``l2`` and an ``h`` in ``x_new``; the Java (followed here) has both, and is
   exactly classical RK4 on the first-order system, so the error per step is
   O(h^5) and the global error O(h^4) while no impact occurs.

2. If ``x_new < gap``: accept the step (``a`` is then re-evaluated at the new
   point).

3. Else, if the mass was already on the stop at the start of the step
   (``stuck = x >= gap``): stay there for the whole step, ``x = gap``,
   ``v = a = 0``.  The mass leaves the stop at the first step whose RK4
   prediction from ``(gap, 0)`` falls below the gap.  This is the thesis's
   "stuck" rule: it resolves the release time only to within one step ``h``
   and never computes a chatter accumulation point; a chatter sequence is
   ended by the ``x > gap and v > 0`` guard of step 4 or by the rule above.

4. Else (an impact inside the step): the time to the stop is predicted
   linearly, ``h1 = (gap - x) / (v + (l1 + l2 + l3)/12)``, i.e. the distance
   left over a mean velocity taken from the full-step slopes.  An RK4 step of
   ``h1`` gives the impact state; it is *not* projected onto the stop, so
   ``x`` after it differs from ``gap`` by the error of the linear prediction,
   O(h1^2) in general.  The velocity is multiplied by ``-e``, and an RK4 step
   of ``h2 = h - h1`` finishes the step.  ``a`` is set to the mean
   ``(v - v_old)/h``.  If the mass then lies beyond the stop and still moves
   into it (``x > gap and v > 0``) it is put on the stop: ``x = gap``,
   ``v = a = 0``.

Where the thesis is approximate, and this transcription keeps it so:

* the impact time ``t + h1`` carries the error of the linear prediction, which
  is O(h^2) (not O(h^4)) for a transversal impact, so impact times and
  velocities converge only like h^2; the error grows without bound as the
  impact becomes grazing (``v -> 0``);
* ``h1`` can exceed ``h`` (up to about ``2 h`` when the mass reaches the stop
  with a small velocity under a positive acceleration); the remainder
  ``h2 = h - h1`` is then negative and the step integrates backwards.  The
  thesis does this and so does this code;
* at most one impact is detected per step; an excursion beyond the stop that
  starts and ends within one step (a grazing impact) is not seen at all;
* chatter and sticking are resolved to one step, as said above.

The impact velocity logged is the thesis's ``-v_lastimpact/e`` (its
``getimpactv``): the RK4-predicted velocity at the end of the ``h1`` step.
Upward crossings of ``x = 0`` are logged as the thesis's ``getx0v`` does:
``v_cross = v - a dt (x - 0)/(x - x_old)``, a linear interpolation back from
the end of the step that crossed, and the crossing time is interpolated
linearly the same way.  (The Java uses its nominal step ``h`` in that formula;
the step actually taken is used here, which is the same except for the last,
shortened step of a run.)

All quantities are nondimensional.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from rattle_lab.exceptions import ParameterError

__all__ = ["run_rk4_thesis"]

_TWO_PI = 2.0 * math.pi
_GAP = 1.0  # nondimensional stop position (thesis eq. 2.29)
_INITIAL_CAPACITY = 64


@numba.njit(cache=True)
def _acc(F: float, omega: float, two_zeta: float, theta0: float, s: float, x: float, v: float) -> float:
    # Thesis ``acceleration``: (A cos(F t + faye) - b v - k x)/m with m = k = 1.
    return F * math.cos(theta0 + omega * s) - two_zeta * v - x


@numba.njit(cache=True)
def _wrap_phase(theta: float) -> float:
    # Reduce to [0, 2 pi) (math.fmod is not available in numba).
    r = theta - _TWO_PI * math.floor(theta / _TWO_PI)
    return r if r < _TWO_PI else 0.0


@numba.njit(cache=True)
def _grow(a: np.ndarray) -> np.ndarray:
    b = np.empty(2 * a.size, dtype=a.dtype)
    b[: a.size] = a
    return b


@numba.njit(cache=True)
def _rk4_slopes(
    F: float, omega: float, two_zeta: float, theta0: float, s: float, x: float, v: float, mh: float
) -> tuple[float, float, float, float]:
    """The four slopes ``l_i = mh a(...)`` of one step of ``evolve`` (eq. 4.3 as in the Java).

    Parameters
    ----------
    F, omega, two_zeta, theta0 : float
        Forcing amplitude, frequency, ``2 zeta`` and phase at ``s = 0``, nondimensional.
    s, x, v : float
        Time since ``t0``, displacement and velocity at the start of the step.
    mh : float
        The step, nondimensional (negative for the thesis's backward remainder).

    Returns
    -------
    l1, l2, l3, l4 : float
        Velocity increments of the four stages.
    """
    l1 = mh * _acc(F, omega, two_zeta, theta0, s, x, v)
    l2 = mh * _acc(F, omega, two_zeta, theta0, s + mh / 2.0, x + mh * v / 2.0, v + l1 / 2.0)
    l3 = mh * _acc(F, omega, two_zeta, theta0, s + mh / 2.0, x + mh * v / 2.0 + mh * l1 / 4.0, v + l2 / 2.0)
    l4 = mh * _acc(F, omega, two_zeta, theta0, s + mh, x + mh * v + mh * l2 / 2.0, v + l3)
    return l1, l2, l3, l4


@numba.njit(cache=True)
def _rk4_increments(mh: float, v: float, l1: float, l2: float, l3: float, l4: float) -> tuple[float, float]:
    """Changes ``(dx, dv)`` of ``(x, v)`` over an RK4 step ``mh`` with slopes ``l1..l4``.

    Parameters
    ----------
    mh : float
        The step, nondimensional.
    v : float
        Velocity at the start of the step.
    l1, l2, l3, l4 : float
        Slopes from :func:`_rk4_slopes`.

    Returns
    -------
    dx, dv : float
        ``mh (v + (l1 + l2 + l3)/6)`` and ``(l1 + 2 l2 + 2 l3 + l4)/6``.
    """
    return mh * (v + (l1 + l2 + l3) / 6.0), (l1 + 2.0 * l2 + 2.0 * l3 + l4) / 6.0


@numba.njit(cache=True)
def _kernel(
    F: float,
    omega: float,
    zeta: float,
    e: float,
    t0: float,
    x0: float,
    v0: float,
    theta0: float,
    duration: float,
    steps_per_period: int,
    want_crossings: bool,
):  # type: ignore[no-untyped-def]
    two_zeta = 2.0 * zeta
    gap = _GAP
    # Thesis ``setF_related``: h = T_forcing / accurate_extend.
    h = _TWO_PI / omega / steps_per_period

    cap = _INITIAL_CAPACITY
    imp_t = np.empty(cap)
    imp_phase = np.empty(cap)
    imp_v_in = np.empty(cap)
    n_imp = 0
    ccap = _INITIAL_CAPACITY if want_crossings else 1
    cross_t = np.empty(ccap)
    cross_v = np.empty(ccap)
    n_cross = 0

    # Time is carried relative to t0 so that a large t0 costs no precision.
    s = 0.0
    x = x0
    v = v0
    a = 0.0
    # Steps are h, except a last one of (duration - s) when that is at most h
    # (up to a relative 1e-9, so that rounding in s never leaves a sliver step).
    while duration - s > 1e-12 * h:
        remaining = duration - s
        ih = h if remaining > h * (1.0 + 1e-9) else remaining
        x_old = x

        # ---- evolve(ih), thesis Appendix A.1 ----
        stuck = x >= gap
        mh = ih
        l1, l2, l3, l4 = _rk4_slopes(F, omega, two_zeta, theta0, s, x, v, mh)
        dx, dv = _rk4_increments(mh, v, l1, l2, l3, l4)
        if x + dx < gap:
            s += mh
            x += dx
            v += dv
            a = _acc(F, omega, two_zeta, theta0, s, x, v)
        elif stuck:
            s += mh
            x = gap
            v = 0.0
            a = 0.0
        else:
            v_old = v
            # Linear prediction of the time to the stop.
            mh = (gap - x) / (v + (l1 + l2 + l3) / 12.0)
            l1, l2, l3, l4 = _rk4_slopes(F, omega, two_zeta, theta0, s, x, v, mh)
            dx, dv = _rk4_increments(mh, v, l1, l2, l3, l4)
            s += mh
            x += dx
            v_in = v + dv
            v = -e * v_in
            if n_imp == imp_t.size:
                imp_t = _grow(imp_t)
                imp_phase = _grow(imp_phase)
                imp_v_in = _grow(imp_v_in)
            imp_t[n_imp] = t0 + s
            imp_phase[n_imp] = _wrap_phase(theta0 + omega * s)
            imp_v_in[n_imp] = v_in
            n_imp += 1
            mh = ih - mh
            l1, l2, l3, l4 = _rk4_slopes(F, omega, two_zeta, theta0, s, x, v, mh)
            dx, dv = _rk4_increments(mh, v, l1, l2, l3, l4)
            s += mh
            x += dx
            v += dv
            a = (v - v_old) / ih
            if x > gap and v > 0.0:
                a = 0.0
                v = 0.0
                x = gap
        # ---- end of evolve ----

        # Thesis ``getx0v``: upward crossing of x = 0 inside this step.
        if want_crossings and x_old < 0.0 and x > 0.0:
            frac = ih * (x - 0.0) / (x - x_old)
            if n_cross == cross_t.size:
                cross_t = _grow(cross_t)
                cross_v = _grow(cross_v)
            cross_t[n_cross] = t0 + s - frac
            cross_v[n_cross] = v - a * frac
            n_cross += 1

    # The loop ends within 1e-12 h of t0 + duration; report that time exactly.
    t_end = t0 + duration
    theta_end = _wrap_phase(theta0 + omega * duration)
    stuck_end = x >= gap and v == 0.0
    return (
        imp_t[:n_imp].copy(),
        imp_phase[:n_imp].copy(),
        imp_v_in[:n_imp].copy(),
        e * imp_v_in[:n_imp],
        cross_t[:n_cross].copy(),
        cross_v[:n_cross].copy(),
        t_end,
        x,
        v,
        theta_end,
        stuck_end,
    )


def run_rk4_thesis(
    F: float,
    omega: float,
    zeta: float,
    e: float,
    t0: float,
    x0: float,
    v0: float,
    theta0: float,
    duration: float,
    steps_per_period: int = 200,
    want_crossings: bool = False,
) -> tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float, float, float, float, bool
]:
    """Integrate the SDF impact oscillator with the thesis's RK4 and impact rule.

    A faithful transcription of ``Impact_sys.evolve`` (thesis Appendix A.1,
    section 4.1); see the module docstring for the algorithm and where it is
    approximate.  All quantities are nondimensional.

    Parameters
    ----------
    F, omega, zeta, e : float
        Forcing amplitude, forcing frequency, damping ratio and coefficient of
        restitution (nondimensional, as in :class:`~rattle_lab.model.sdf.SDFParams`).
    t0, x0, v0, theta0 : float
        Initial time, displacement (gap = 1), velocity and forcing phase; the
        forcing is ``F cos(theta0 + omega (t - t0))``.  ``x0 >= 1`` starts the
        mass on the stop, as the thesis's ``stuck = x >= gap`` does.
    duration : float
        Length of the run, >= 0.  Steps are ``h = 2 pi / (omega steps_per_period)``;
        the last step is shortened so that the run ends at ``t0 + duration``.
    steps_per_period : int, optional
        Steps per forcing period (the thesis's ``accurate_extend``, 200).
    want_crossings : bool, optional
        Log upward crossings of x = 0 (the thesis's ``getx0v``).

    Returns
    -------
    imp_t : ndarray
        Impact times ``t + h1`` (linear prediction, see the module docstring).
    imp_phase : ndarray
        Forcing phase at ``imp_t``, reduced to [0, 2 pi).
    imp_v_in : ndarray
        Incoming velocity predicted at the impact (> 0 for a regular impact).
    imp_v_out : ndarray
        ``e * imp_v_in``; the mass leaves with ``-imp_v_out``.
    cross_t, cross_v : ndarray
        Times and velocities of upward x = 0 crossings (empty unless
        ``want_crossings``).
    t_end, x_end, v_end, theta_end : float
        State at ``t0 + duration`` (``theta_end`` in [0, 2 pi)).  ``x_end`` is
        the thesis's: right after an impact step it may exceed 1 slightly
        (the impact state is not projected onto the stop).
    stuck_end : bool
        True if the run ends on the stop with ``x_end >= 1`` and ``v_end == 0``
        (the thesis's stuck assignment).

    Raises
    ------
    ParameterError
        If an argument is not finite, ``omega <= 0``, ``duration < 0`` or
        ``steps_per_period < 1``.

    Examples
    --------
    Without a reachable stop the run is plain RK4; compare with the free
    undamped solution ``x = cos t``:

    >>> import numpy as np
    >>> out = run_rk4_thesis(0.0, 1.0, 0.0, 0.5, 0.0, 0.5, 0.0, 0.0, 2 * np.pi)
    >>> bool(np.isclose(out[7], 0.5, atol=1e-9)), out[0].size
    (True, 0)
    """
    values = {
        "F": F, "omega": omega, "zeta": zeta, "e": e, "t0": t0,
        "x0": x0, "v0": v0, "theta0": theta0, "duration": duration,
    }  # fmt: skip
    for name, value in values.items():
        if not math.isfinite(float(value)):
            raise ParameterError(f"`{name}` must be finite, was {value}")
    if omega <= 0:
        raise ParameterError(f"`omega` must be > 0, was {omega}")
    if duration < 0:
        raise ParameterError(f"`duration` must be >= 0, was {duration}")
    if int(steps_per_period) != steps_per_period or steps_per_period < 1:
        raise ParameterError(f"`steps_per_period` must be an integer >= 1, was {steps_per_period}")
    return _kernel(  # type: ignore[no-any-return]
        float(F), float(omega), float(zeta), float(e), float(t0), float(x0), float(v0),
        float(theta0), float(duration), int(steps_per_period), bool(want_crossings),
    )  # fmt: skip
