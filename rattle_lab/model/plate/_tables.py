"""Tables 2.1 and 2.2 of the thesis: lambda, Q1, Q2 of the first 6 plate modes.

Transcribed from the thesis.  ``lam_fem`` are the thesis's ADINA values,
``lam_leissa`` the values it quotes from Leissa (None where the thesis prints
"no"), ``Q1``/``Q2`` the FEM values of eq. 2.18/2.19.  A starred entry (``*`` in
the thesis) is normalised by the maximum modal displacement because the plate
centre is a node; the others are normalised by the centre deflection.  The
thesis prints ``|Q1|``: with ``W = +1`` at the centre, ``Q1`` is negative for modes
whose outer lobes outweigh the centre one (e.g. CFCF b/a = 2 mode 6, CCCC b/a = 1
mode 6), which :func:`rattle_lab.model.plate.ritz_modes` reports with its sign.

Section 5.1.1 of the thesis says "checking Table 2.2" for its CFCF plate; the
numbers it uses (lambda = 27.4, Q1 = 0.5, Q2 = 0.402) are Table 2.1's b/a = 0.9
Leissa lambda and FEM Q1, Q2.

Table 2.2's CCCC b/a = 0.5 mode 1 quotes Leissa as 97.3.  That is very probably a
misprint of 98.3: Leissa's value for the clamped plate of aspect ratio 2 is 24.58 in
units of the long side, ``24.58 * 2**2 = 98.3`` in units of ``a`` (the converged
Ritz solution gives 98.31).  The entry is kept as printed, flagged by
:attr:`TableMode.note`, and no error should be reported against it.

Edge strings follow :mod:`rattle_lab.model.plate._edges` (edges y=0, x=a, y=b, x=0):
Table 2.1 is ``"CFCF"`` (the two sides of length ``a`` clamped) and Table 2.2
is ``"CCCC"``.
"""

from __future__ import annotations

from dataclasses import dataclass

from rattle_lab.exceptions import ParameterError
from ._edges import check_edges


@dataclass(frozen=True)
class TableMode:
    """One column of Table 2.1 or 2.2 of the thesis.

    Attributes
    ----------
    mode : int
        Mode number, 1-based, in the thesis's order.
    lam_fem : float
        ``lambda = omega a**2 sqrt(rho h_p / D)`` (eq. 2.25) from the thesis's FEM model.
    lam_leissa : float or None
        ``lambda`` quoted from Leissa; None where the thesis prints "no".
    Q1 : float
        ``int int W`` over the plate in units of ``a`` (eq. 2.18), FEM.
    Q2 : float
        ``int int W**2`` over the plate in units of ``a`` (eq. 2.19), FEM.
    starred : bool
        True when ``W`` is normalised by its maximum (the centre is a node; ``*`` in
        the thesis), False when it is normalised by the centre deflection.
    note : str
        Empty, or why an entry is not to be compared with (a probable misprint).
    """

    mode: int
    lam_fem: float
    lam_leissa: float | None
    Q1: float
    Q2: float
    starred: bool
    note: str = ""


# (lam_fem, lam_leissa, Q1, Q2, starred) for modes 1..6, keyed by b/a.
_RawRow = tuple[float, float | None, float, float, bool]

_TABLE_2_1_CFCF: dict[float, tuple[_RawRow, ...]] = {
    0.5: (
        (90.0, 89.0, 0.283, 0.232, False),
        (94.2, 93.4, 0.000, 0.064, True),
        (110.5, 110.0, 0.016, 0.107, False),
        (143.6, 142.0, 0.000, 0.054, True),
        (199.4, 194.4, 0.005, 0.102, False),
        (253.5, 245.6, 0.000, 0.120, True),
    ),
    0.9: (
        (27.7, 27.4, 0.500, 0.402, False),
        (31.7, 31.7, 0.000, 0.119, True),
        (48.7, 48.8, 0.022, 0.215, False),
        (78.0, 75.6, 0.000, 0.255, True),
        (83.7, 81.6, 0.000, 0.128, True),
        (85.6, 84.4, 0.000, 0.097, True),
    ),
    1.0: (
        (22.4, 22.2, 0.553, 0.443, False),
        (26.4, 26.4, 0.000, 0.133, True),
        (43.6, 43.6, 0.023, 0.244, False),
        (63.1, 61.2, 0.000, 0.290, True),
        (68.7, 67.2, 0.000, 0.144, True),
        (81.0, 79.8, 0.000, 0.108, True),
    ),
    2.0: (
        (5.55, 5.51, 1.073, 0.832, False),
        (8.88, 8.99, 0.000, 0.275, True),
        (15.6, 15.2, 0.000, 0.673, True),
        (20.8, 20.5, 0.000, 0.298, True),
        (27.4, 27.3, 0.030, 0.572, False),
        (31.8, 29.9, 0.527, 1.029, False),
    ),
}

_TABLE_2_2_CCCC: dict[float, tuple[_RawRow, ...]] = {
    0.5: (
        (99.4, 97.3, 0.145, 0.084, False),
        (128.4, 126.5, 0.000, 0.090, True),
        (181.3, 178.3, 0.062, 0.097, False),
        (258.5, 252.7, 0.000, 0.091, True),
        (264.1, 256.1, 0.000, 0.098, True),
        (292.2, 284.1, 0.000, 0.101, True),
    ),
    0.9: (
        (40.7, None, 0.254, 0.145, False),
        (78.9, None, 0.000, 0.165, True),
        (89.8, None, 0.000, 0.167, True),
        (124.5, None, 0.000, 0.183, True),
        (142.7, None, 0.121, 0.181, False),
        (169.6, None, 0.124, 0.176, False),
    ),
    1.0: (
        (36.4, 36.0, 0.282, 0.161, False),
        (75.4, 73.4, 0.000, 0.157, True),
        (75.4, 73.4, 0.000, 0.157, True),
        (111.2, 108.2, 0.000, 0.203, True),
        (139.3, 131.6, 0.000, 0.161, True),
        (140.0, 132.2, 0.136, 0.099, False),
    ),
}

_TABLES = {"CFCF": _TABLE_2_1_CFCF, "CCCC": _TABLE_2_2_CCCC}

#: Entries not to be compared with, keyed by (edges, b/a, mode).
_NOTES: dict[tuple[str, float, int], str] = {
    ("CCCC", 0.5, 1): ("lam_leissa 97.3 is very probably a misprint of 98.3 "
                       "(Leissa 24.58 x 2**2); do not report an error against it"),
}

#: The aspect ratios ``b/a`` each table gives, keyed by edge string.
TABLE_ASPECT_RATIOS: dict[str, tuple[float, ...]] = {k: tuple(v) for k, v in _TABLES.items()}


def table_modes(edges: str, aspect_ratio: float) -> tuple[TableMode, ...]:
    """The thesis's tabulated modal data (Table 2.1 for CFCF, Table 2.2 for CCCC).

    Parameters
    ----------
    edges : {"CFCF", "CCCC"}
        Boundary conditions, edges in the order y=0, x=a, y=b, x=0 (so ``"CFCF"`` has the
        two sides of length ``a`` clamped, as in Table 2.1).
    aspect_ratio : float
        ``b/a``; one of the tabulated values (CFCF: 0.5, 0.9, 1, 2; CCCC: 0.5, 0.9, 1).

    Returns
    -------
    tuple of TableMode
        The 6 modes in the thesis's order.

    Raises
    ------
    ParameterError
        If the edges or the aspect ratio are not tabulated.

    Examples
    --------
    >>> m = table_modes("CFCF", 0.9)[0]
    >>> (m.lam_leissa, m.Q1, m.Q2, m.starred)
    (27.4, 0.5, 0.402, False)
    """
    key = check_edges(edges)
    if key not in _TABLES:
        raise ParameterError(f"`edges` must be one of {sorted(_TABLES)} for the thesis tables, was {edges!r}")
    table = _TABLES[key]
    match = [r for r in table if abs(r - float(aspect_ratio)) <= 1e-9]
    if not match:
        raise ParameterError(
            f"`aspect_ratio` must be one of {list(table)} for edges {key}, was {aspect_ratio}"
        )
    ratio = match[0]
    return tuple(TableMode(i + 1, *row, note=_NOTES.get((key, ratio, i + 1), ""))
                 for i, row in enumerate(table[ratio]))
