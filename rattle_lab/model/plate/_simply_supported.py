"""Closed-form modes of a simply supported rectangular plate (thesis eq. 2.20-2.25)."""

from __future__ import annotations

import math

from ._checks import check_aspect_ratio, check_count
from ._modes import PlateMode


def simply_supported_mode(m: int, n: int, aspect_ratio: float) -> PlateMode:
    """Mode (m, n) of a simply supported plate in closed form (eq. 2.20-2.25).

    ``W_mn = sin(m pi x/a) sin(n pi y/b)`` (eq. 2.20) and, from eq. 2.21 and 2.25,
    ``lambda = pi**2 (m**2 + n**2 (a/b)**2)``.

    Normalisation follows the tables and the Ritz solver: ``W = 1`` at the centre,
    or, when the centre is a node (m or n even), at a maximum of ``|W|``.  For m, n
    both odd ``W_mn(centre) = sin(m pi/2) sin(n pi/2) = +-1``, so ``Q1`` is eq. 2.23
    times that sign (eq. 2.23 itself uses eq. 2.20 unnormalised); ``|Q1|`` is eq. 2.23.

    Parameters
    ----------
    m, n : int
        Half-wave numbers along x and y, >= 1.
    aspect_ratio : float
        ``b/a``, > 0.

    Returns
    -------
    PlateMode
        ``lam`` (eq. 2.21, 2.25), ``Q1`` (eq. 2.23, with the sign above), ``Q2 = b/(4a)``
        (eq. 2.24).

    Raises
    ------
    ParameterError
        If ``m`` or ``n`` is not an integer >= 1 or ``aspect_ratio <= 0``.

    Examples
    --------
    >>> import numpy as np
    >>> mode = simply_supported_mode(1, 1, 1.0)
    >>> bool(np.isclose(mode.lam, 2 * np.pi**2)), bool(np.isclose(mode.Q1, 4 / np.pi**2))
    (True, True)
    """
    m = check_count("m", m)
    n = check_count("n", n)
    r = check_aspect_ratio(aspect_ratio)
    # Eq. (2.21) in the nondimensional form of eq. (2.25); the thesis's sqrt(D/rho) means
    # sqrt(D/(rho h_p)), the mass per area.
    lam = math.pi**2 * (m**2 + n**2 / r**2)
    at_max = (m % 2 == 0) or (n % 2 == 0)
    # Eq. (2.23): Q1 = (b/a) / (m n pi^2) [1 - (-1)^m][1 - (-1)^n]
    q1 = r / (m * n * math.pi**2) * (1 - (-1) ** m) * (1 - (-1) ** n)
    if at_max:
        # Centre is a node; W = +1 at the first crest (1/(2m), 1/(2n)).
        ref = (1.0 / (2 * m), 1.0 / (2 * n))
    else:
        ref = (0.5, 0.5)
        sign = (1 if m % 4 == 1 else -1) * (1 if n % 4 == 1 else -1)  # sin(m pi/2) sin(n pi/2)
        q1 *= sign
    # Eq. (2.24)
    q2 = r / 4.0
    return PlateMode(lam=lam, Q1=q1, Q2=q2, at_max=at_max, ref_xi=ref[0], ref_eta=ref[1], m=m, n=n)


def simply_supported_modes(aspect_ratio: float, n_modes: int = 6) -> tuple[PlateMode, ...]:
    """The first ``n_modes`` closed-form modes of a simply supported plate, by increasing ``lam``.

    Parameters
    ----------
    aspect_ratio : float
        ``b/a``, > 0.
    n_modes : int
        Number of modes, >= 1.

    Returns
    -------
    tuple of PlateMode
        Sorted by ``lam``; equal ``lam`` sorted by ``(m, n)``.

    Raises
    ------
    ParameterError
        If an argument is out of range.

    Examples
    --------
    >>> [(mode.m, mode.n) for mode in simply_supported_modes(1.0, 3)]
    [(1, 1), (1, 2), (2, 1)]
    """
    r = check_aspect_ratio(aspect_ratio)
    k = check_count("n_modes", n_modes)
    # The k lowest modes have m <= k and n <= k.
    cands = sorted((math.pi**2 * (m**2 + n**2 / r**2), m, n)
                    for m in range(1, k + 1) for n in range(1, k + 1))
    return tuple(simply_supported_mode(m, n, r) for _, m, n in cands[:k])
