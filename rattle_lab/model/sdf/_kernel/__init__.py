"""Event-driven exact kernel of the SDF impact oscillator (scalar code).

This package is written once and loaded twice: as plain Python (the readable
reference path, ``method="exact-python"``) and compiled with numba
(``method="exact"``).  :mod:`rattle_lab.model.sdf._compiled` does the second load:
the same files as the package ``rattle_lab.model.sdf._kernel_jit``, with the
package global ``__rattle_jit__`` set; nothing else differs.  Every module imports
its siblings relatively, so each function calls the functions of its own build, and
each build's :mod:`._jit` makes ``@jit`` the identity (first build) or
``numba.njit`` (second build).

Modules, by concern:

* :mod:`._constants`: tolerances, budgets and the layout of the vectors ``P``
  (parameters) and ``S`` (the current flight);
* :mod:`._flight`: the closed-form free flight (parameters, start of a flight,
  evaluation, derivative bounds);
* :mod:`._search`: the rigorous search for the first reach of a level (chunks,
  bounds, the bracketed root finder);
* :mod:`._stop`: leaving the stop, micro-flights, elastic micro-bouncing;
* :mod:`._run`: the compensated time and :func:`run`, the event loop;
* :mod:`._drivers`: :func:`run_sweep`, :func:`run_pieces` and :func:`run_packed`
  (many runs, or one run's result packed, per compiled call).

Model (nondimensional, thesis eq. 2.33)::

    x'' + 2 zeta x' + x = F cos(theta),  theta = theta0 + omega s,   x < 1
    v -> -e v                                                       at x = 1

Free flight
    Closed form (see :mod:`rattle_lab.model.sdf._flow`): particular part plus the
    homogeneous part, for zeta < 1, = 1, > 1, and the undamped resonance.  No
    time step is taken.  Each flight is restarted ("rebased") at least once per
    window ``W = min(2 pi, 2 pi / omega)`` so that local times stay small and
    phases stay accurate to rounding.

Why no impact can be missed
    The impact is the earliest ``s`` in the window where ``g(s) = x(s) - 1 >= 0``.
    The window is cut into chunks and each chunk ``[s_a, s_b]`` is examined with
    rigorous bounds ``M_k >= |x^(k)|`` over the chunk (:func:`deriv_bound`), the
    smaller of two valid ones:

    * modal: the particular part has ``|x_p^(k)| <= R omega^k`` (R its
      amplitude); the homogeneous part ``y`` obeys
      ``d/ds (y^2 + y'^2) = -4 zeta y'^2 <= 0``, so ``rho = |(y, y')|`` never
      grows and ``|y^(k)| <= n_k rho(s_a)`` (``n_k`` the norm of the first row of
      the k-th power of the companion matrix; for zeta > 1 the two decaying
      modes are bounded separately);
    * energy: ``d/ds |(x, v)| <= F`` bounds ``|x|, |v|`` on the chunk, and the
      equation of motion bounds the higher derivatives; this one stays sharp
      near resonance, where the modal parts are large and cancel.

    With ``M2`` on the chunk, ``g`` lies below both parabolas
    ``g_a + g'_a u + M2 u^2 / 2`` and ``g_b - g'_b w + M2 w^2 / 2``; if the
    maximum of their lower envelope is below ``-GRAZE_TOL`` the chunk holds no
    impact.  If not, ``M3`` bounds ``x''``: if ``x''`` is provably negative the
    chunk holds at most one local maximum of ``x``, found as a bracketed root of
    ``v`` and compared with the stop; if ``x''`` is provably positive the
    maximum is at an end.  Otherwise the chunk is halved.  Near a tangency the
    curvature is bounded away from zero, so the concavity test settles it after
    a few halvings.  A maximum within ``GRAZE_TOL`` (4 ulp) of the stop is a
    grazing impact (``v_in`` is then the rounding-level velocity there): below
    that the distinction is lost in the rounding of ``x`` itself.  Sampling sign
    changes is never relied on.  Each chunk examines at most ``MAX_WORK``
    sub-intervals (a guard that has not been reached in any test); if it is,
    the caller is warned.

Flights that stay below the stop
    ``x = x_p + y`` with ``|x_p| <= R`` and ``|(y, y')|`` never growing, so where
    ``R + |(y, y')| < 1`` (less a margin of 64 ulp of the evaluations' scale for
    their rounding) the flight cannot reach the stop, not even within
    ``GRAZE_TOL``: the search for the stop returns at once
    (:func:`._search.below_stop_for_ever`; the steady motion without impact of a
    sweep's values spent most of its time proving this chunk by chunk).

Evaluations
    Each flight keeps its last ``N_MEMO`` evaluations in ``S``
    (:func:`._flight.evaluate`): the searches come back to points they have just
    evaluated (a root's end, the window's end, a crossing and its exit), and a
    memoised point returns the same numbers.

Impacts on and from the stop
    A flight that starts on the stop (after an impact, or on release from
    sticking) is evaluated near its start by its Taylor series about the start,
    ``x - 1 = sum_k d_k s^k / k!`` with ``d_k`` from the equation of motion, so
    that tiny chatter flights are resolved to relative rounding instead of being
    lost in the cancellation ``x_p + y - 1``.  The first instants are excluded by
    the leading nonzero derivative: ``g(u) <= d_k u^k / k! + M_{k+1} u^{k+1} /
    (k+1)! < 0`` for small ``u`` when ``d_k < 0``.  When the leading derivative
    pushes into the stop (v = 0 and F cos(theta) > 1), the mass sticks.

Chatter and sticking
    When the force pushes into the stop (``a_stop = F cos(theta) - 1 > 0`` at
    x = 1, v = 0) and flights shrink geometrically (complete chatter, Budd &
    Dux 1994; Nordmark & Piiroinen 2009), the remaining flight times form a
    geometric series.  Each micro-flight is solved from the Taylor series about
    the stop (:func:`micro_flight`, a proven single root), and after each
    micro-impact the tail ``tau_k q / (1 - q)`` (``q`` the measured ratio of the
    last two flight times, which tends to ``e``) is computed.  Once the tail,
    or its error estimate ``tail |q_k - q_(k-1)| / (1 - q)^2`` (q drifts by
    O(w) per flight), is below the time resolution ``16 ulp(t)``, or after
    ``N_CHATTER_MAX`` micro-impacts, the solver jumps to the accumulation point
    and sticks.  With e = 1 there is no accumulation point; elastic
    micro-bouncing is averaged (:func:`micro_bounce`) and reported.  While stuck (x = 1, v = 0) the net force
    ``F cos(theta) - 1`` pushes into the stop; the mass is released at the
    analytic phase ``theta = arccos(1 / F)`` where the force reverses.

Time
    Phases are kept reduced to [0, 2 pi); time is kept as a compensated sum
    ``t + t_lo`` (error-free two-sum of every flight time, :func:`_time_add`),
    so impact times stay within a few ulp of the exact time however many
    flights are summed (plain ``t += s`` drifted by 1e-8 after 1e4 forcing
    periods and 8e-7 after 1e5: the rounding of ``t + s`` with nearly equal
    ``s`` is biased).

The kernel never lets x exceed 1 (impacts set x = 1 exactly), and every loop is
bounded (``max_events``).
"""

from ._constants import (CHUNKS_PER_WINDOW, EPS, GRAZE_TOL, I_AC, I_AS, I_E, I_F, I_LAM, I_NK,
                         I_R, I_R1, I_R2, I_REG, I_RES, I_W, I_WD, I_WK, I_Z, J_MEMO,
                         J_MEMO_NEXT, J_ONSTOP, J_TAY, J_TH, J_Y, J_YD, MAX_LEVEL, MAX_WORK,
                         MEMO_WIDTH, N_CHATTER_MAX, N_MEMO, N_MICRO, N_P, N_S, N_TAYLOR,
                         TAU_EXIT, TAU_MICRO, TAYLOR_REACH, TWO_PI)
from ._drivers import N_HEAD, run_packed, run_pieces, run_sweep
from ._flight import (deriv_bound, evaluate, level_values, make_params, particular,
                      reduce_phase, start_segment, transition)
from ._run import run
from ._search import below_stop_for_ever, first_reach, new_work
from ._stop import (level_exit, micro_bounce, micro_flight, stop_clear, stop_exit, stop_sign,
                    taylor_velocity)

__all__ = [
    "CHUNKS_PER_WINDOW", "EPS", "GRAZE_TOL", "I_AC", "I_AS", "I_E", "I_F", "I_LAM", "I_NK",
    "I_R", "I_R1", "I_R2", "I_REG", "I_RES", "I_W", "I_WD", "I_WK", "I_Z", "J_MEMO",
    "J_MEMO_NEXT", "J_ONSTOP", "J_TAY", "J_TH", "J_Y", "J_YD", "MAX_LEVEL", "MAX_WORK",
    "MEMO_WIDTH", "N_CHATTER_MAX", "N_MEMO", "N_MICRO", "N_P", "N_S",
    "N_TAYLOR", "TAU_EXIT", "TAU_MICRO", "TAYLOR_REACH", "TWO_PI",
    "N_HEAD", "run_packed", "run_pieces", "run_sweep",
    "deriv_bound", "evaluate", "level_values", "make_params", "particular", "reduce_phase",
    "start_segment", "transition",
    "run",
    "below_stop_for_ever", "first_reach", "new_work",
    "level_exit", "micro_bounce", "micro_flight", "stop_clear", "stop_exit", "stop_sign",
    "taylor_velocity",
]
