"""Constants of the exact kernel: tolerances, budgets and the layout of ``P`` and ``S``.

``P`` (length ``N_P``) holds the parameters and the constants derived from them
(:func:`._flight.make_params`); ``S`` (length ``N_S``) the current free flight: its
start phase, homogeneous state and, for a flight from the stop, its Taylor
coefficients (:func:`._flight.start_segment`).  numba freezes these module globals
into the compiled code as constants.
"""

import math

TWO_PI = 2.0 * math.pi
EPS = 2.220446049250313e-16
#: Terms of the Taylor series used near a start on the stop.
N_TAYLOR = 20
#: Taylor series used while s * LAMBDA <= TAYLOR_REACH (remainder < 1e-25 relative).
TAYLOR_REACH = 0.5
#: Micro-impacts of one chatter sequence before jumping to its accumulation point.
N_CHATTER_MAX = 20000
#: Maximum halvings of a search chunk.
MAX_LEVEL = 60
#: Consecutive short elastic (e = 1) bounces before micro-bounce averaging.
N_MICRO = 1000
#: Elastic bounces shorter than TAU_MICRO (relative to the fastest time scale)
#: are averaged; averaging ends when the flight time grows to TAU_EXIT.
TAU_MICRO = 1e-4
TAU_EXIT = 1e-2
#: A local maximum of x within GRAZE_TOL of the stop is a grazing impact: the
#: distinction is below the rounding of x (4 ulp of 1.0).
GRAZE_TOL = 4.0 * EPS
#: Maximum sub-intervals examined in one search chunk.
MAX_WORK = 20000
#: A flight's window is searched in chunks of at most W / CHUNKS_PER_WINDOW.  The search
#: is rigorous (derivative bounds) whatever the chunk, so this only moves work: 2 (half a
#: period) costs 0.7-1.3 us per impact on the 1/1 orbit where 8 cost 2.4 us (fewer chunks
#: and bounds per flight; chatter, chaos and 1/3 motion also as fast or faster), with every
#: mpmath, thesis and grazing test unchanged (benchmarks/speed_goals.py).
CHUNKS_PER_WINDOW = 2.0

# Layout of the parameter vector P.
I_F, I_W, I_Z, I_E, I_AC, I_AS, I_R, I_RES, I_REG, I_WD, I_R1, I_R2, I_LAM = range(13)
I_NK = 13  # n_0 .. n_7 follow
I_WK = I_NK + 8  # omega^0 .. omega^7 follow (the particular part's derivative bounds)
N_P = I_WK + 8

# Layout of the segment vector S.
J_TH, J_Y, J_YD, J_ONSTOP = range(4)
J_TAY = 4  # Taylor coefficients t_0 .. t_N_TAYLOR (t_k = d_k / k!)
#: The flight's memo of its last evaluations (:func:`._flight.evaluate`): N_MEMO rows of
#: (s, x, v, a, y, yd, zstop) from J_MEMO on, then the row written next.  The searches
#: come back to points just evaluated (a root's end, the window's end, the crossing
#: found, its exit; 22 % of the evaluations of the Fig. 4-3 sweep were of one of the
#: last four points of the flight), and an evaluation is 5 transcendental functions.
J_MEMO = J_TAY + N_TAYLOR + 1
N_MEMO = 4
MEMO_WIDTH = 7
J_MEMO_NEXT = J_MEMO + MEMO_WIDTH * N_MEMO
N_S = J_MEMO_NEXT + 1
