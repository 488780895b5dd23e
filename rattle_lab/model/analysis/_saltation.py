"""Linearisation of the SDF impact oscillator across an impact (saltation matrices).

State ``z = (x, v)``; between impacts ``z' = f(z, t) = (v, F cos(theta) - 2 zeta v - x)``.
The impact surface is ``h(z) = x - 1 = 0`` with normal ``n = (1, 0)``; the
reset is ``z+ = R z-`` with ``R = diag(1, -e)``.  A perturbation crossing the
surface a little early or late picks up the difference of the vector fields,
which gives the saltation matrix (Aizerman & Gantmacher; di Bernardo et al.)::

    S = R + (f+ - R f-) n^T / (n^T f-)

With ``f- = (u, a-)``, ``f+ = (-e u, a+)`` (``u`` the incoming velocity,
``a-- = F cos(theta) - 1 - 2 zeta u``, ``a+ = F cos(theta) - 1 + 2 zeta e u``)
this is, in closed form::

    S = [[-e,                                 0 ],
         [(1 + e)(F cos(theta) - 1) / u,     -e ]]

Between impacts the variational equation is the free (homogeneous) one, so
the flight's linearisation over a time ``s`` is the transition matrix
``Phi(s) = [[Ec + zeta Es, Es], [-Es, Ec - zeta Es]]``.  The monodromy matrix of
a periodic orbit with ``m`` impacts, from just after one impact to just after
the same impact a period later, is ``prod_k S_k Phi(s_k)``; its eigenvalues
are the Floquet multipliers.  ``det S = e^2`` and ``det Phi(s) = exp(-2 zeta s)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from rattle_lab.model.sdf import homogeneous_transition


def saltation_matrix(f_minus: ArrayLike, f_plus: ArrayLike, reset: ArrayLike,
                     normal: ArrayLike) -> np.ndarray:
    """General saltation matrix ``S = R + (f+ - R f-) n^T / (n^T f-)``.

    Parameters
    ----------
    f_minus, f_plus : array_like, shape (..., d)
        Vector field just before and just after the event.
    reset : array_like, shape (..., d, d)
        Jacobian ``R`` of the reset map.
    normal : array_like, shape (..., d)
        Gradient ``n`` of the event function.

    Returns
    -------
    ndarray, shape (..., d, d)

    Examples
    --------
    >>> import numpy as np
    >>> S = saltation_matrix([2.0, -0.5], [-1.2, 0.1], np.diag([1.0, -0.6]), [1.0, 0.0])
    >>> bool(np.allclose(S, [[-0.6, 0.0], [(0.1 - 0.6 * 0.5) / 2.0, -0.6]]))
    True
    """
    fm = np.asarray(f_minus, dtype=float)
    fp = np.asarray(f_plus, dtype=float)
    R = np.asarray(reset, dtype=float)
    n = np.asarray(normal, dtype=float)
    jump = fp - np.einsum("...ij,...j->...i", R, fm)
    denom = np.einsum("...i,...i->...", n, fm)
    return R + jump[..., :, None] * n[..., None, :] / denom[..., None, None]


def impact_saltation(F: ArrayLike, zeta: ArrayLike, e: ArrayLike, theta: ArrayLike,
                     v_in: ArrayLike) -> np.ndarray:
    """Saltation matrix of an impact at forcing phase ``theta`` with incoming velocity ``v_in``.

    Closed form of :func:`saltation_matrix` for the SDF oscillator (module
    docstring); shape ``(..., 2, 2)``.  Singular (infinite) at ``v_in = 0``:
    the grazing singularity.
    """
    F, zeta, e, theta, u = np.broadcast_arrays(*(np.asarray(q, dtype=float)
                                                for q in (F, zeta, e, theta, v_in)))
    S = np.zeros(F.shape + (2, 2))
    S[..., 0, 0] = -e
    S[..., 1, 1] = -e
    with np.errstate(divide="ignore", invalid="ignore"):
        S[..., 1, 0] = (1.0 + e) * (F * np.cos(theta) - 1.0) / u
    return S


def transition_matrix(zeta: ArrayLike, s: ArrayLike) -> np.ndarray:
    """Transition matrix ``Phi(s)`` of the free flight (shape ``(..., 2, 2)``)."""
    z = np.asarray(zeta, dtype=float)
    Ec, Es = homogeneous_transition(z, s)
    z = np.broadcast_to(z, np.shape(Ec))
    Phi = np.empty(np.shape(Ec) + (2, 2))
    Phi[..., 0, 0] = Ec + z * Es
    Phi[..., 0, 1] = Es
    Phi[..., 1, 0] = -Es
    Phi[..., 1, 1] = Ec - z * Es
    return Phi


def impact_map_jacobian(F: float, zeta: float, e: float, theta0: float, v_in0: float,
                        s: float, theta1: float, v_in1: float) -> np.ndarray:
    """Jacobian of the impact map ``(t_k, u_k) -> (t_{k+1}, u_{k+1})`` for one flight.

    ``t`` is the impact time and ``u`` the incoming velocity.  A perturbation
    ``(dt0, du0)`` of the impact leaves the state just after it, moved back to
    the unperturbed impact time, at ``dz0 = (e u0 dt0, -e du0 - a0+ dt0)``;
    it is carried by ``Phi(s)`` to ``dz1`` at the unperturbed next impact,
    where the crossing shifts by ``dt1 = -dz1[0] / u1`` and the incoming
    velocity by ``du1 = dz1[1] + a1- dt1``::

        J = [[-1/u1, 0], [-a1-/u1, 1]] Phi(s) [[e u0, 0], [-a0+, -e]]

    Its determinant is ``e^2 (u0 / u1) exp(-2 zeta s)``; over a periodic orbit
    the product of the ``J`` is similar to the monodromy ``prod S_k Phi(s_k)``.
    """
    a0_plus = F * np.cos(theta0) - 1.0 + 2.0 * zeta * e * v_in0
    a1_minus = F * np.cos(theta1) - 1.0 - 2.0 * zeta * v_in1
    before = np.array([[e * v_in0, 0.0], [-a0_plus, -e]])
    after = np.array([[-1.0 / v_in1, 0.0], [-a1_minus / v_in1, 1.0]])
    return after @ transition_matrix(zeta, s) @ before
