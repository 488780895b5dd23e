"""Edge conventions shared by the plate solvers.

A plate occupies ``0 <= x <= a``, ``0 <= y <= b``.  Its boundary conditions are a
string of four letters, one per edge, taken counter-clockwise from the bottom:

====== ======== ==============
index  edge     edge length
====== ======== ==============
0      y = 0    a
1      x = a    b
2      y = b    a
3      x = 0    b
====== ======== ==============

Letters: ``C`` clamped, ``S`` simply supported, ``F`` free.  So ``"CFCF"`` is
the thesis's "clamped-free-clamped-free (length a sides clamped)" plate of
Table 2.1: the two edges of length ``a`` (y = 0 and y = b) are clamped and the
two edges of length ``b`` are free.
"""

from __future__ import annotations

from rattle_lab.exceptions import ParameterError

EDGE_ORDER = ("y=0", "x=a", "y=b", "x=0")
_LETTERS = frozenset("CSF")


def check_edges(edges: str, name: str = "edges") -> str:
    """Validate a four-letter edge string and return it upper-cased.

    Raises
    ------
    ParameterError
        If ``edges`` is not four letters from C, S, F.
    """
    if not isinstance(edges, str):
        raise ParameterError(f"`{name}` must be a string of 4 letters from C, S, F, was {edges!r}")
    up = edges.upper()
    if len(up) != 4 or not set(up) <= _LETTERS:
        raise ParameterError(
            f"`{name}` must be 4 letters from C (clamped), S (simply supported), F (free) "
            f"for the edges y=0, x=a, y=b, x=0; was {edges!r}"
        )
    return up


def x_ends(edges: str) -> tuple[str, str]:
    """End conditions of the beam functions in x: (at x = 0, at x = a)."""
    return edges[3], edges[1]


def y_ends(edges: str) -> tuple[str, str]:
    """End conditions of the beam functions in y: (at y = 0, at y = b)."""
    return edges[0], edges[2]
