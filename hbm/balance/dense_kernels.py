r"""Residual and Jacobian of a small dense harmonic-balance model in one compiled call.

With the three matrices of :class:`hbm.balance.dense_part.DenseLinear` stored once
(:math:`Z(w) = Z_0 + w Z_1 - w^2 Z_2` on the unknowns ``x``, harmonic-major) and the load
``F(w)`` with its derivative:

.. math::

    R = Z(w)\, x - F + F_{nl}, \qquad
    \frac{\partial R}{\partial x} = Z(w) + \frac{\partial F_{nl}}{\partial x}, \qquad
    \frac{\partial R}{\partial w} = (Z_1 - 2 w Z_2)\, x - F' + \frac{\partial F_{nl}}{\partial w},

in one pass over the matrices instead of a dozen NumPy calls (each a few microseconds, a
large part of a small model's Newton iteration).
"""
from __future__ import annotations

import numba as nb


@nb.njit(cache=True)
def dense_residual(Z0, Z1, Z2, w, x, F, dF, Fn, dFw, J, R, dRw):
    """Write ``R`` (n_u,) and ``dRw = dR/dw`` (n_u,) and add ``Z(w)`` to ``J`` (n_u, n_u), which
    holds ``dF_nl/dx`` on entry (module doc).

    Parameters
    ----------
    Z0, Z1, Z2 : ndarray, shape (n_u, n_u)
        Stiffness, damping and mass parts of the dynamic stiffness.
    w : float
        Fundamental angular frequency.
    x : ndarray, shape (n_u,)
        Unknowns.
    F, dF : ndarray, shape (n_u,)
        Load and its ``w``-derivative.
    Fn, dFw : ndarray, shape (n_u,)
        Nonlinear forces and their ``w``-derivative on the unknowns.
    J : ndarray, shape (n_u, n_u)
    R, dRw : ndarray, shape (n_u,)
        Outputs (views allowed).
    """
    n = x.size
    w2 = w * w
    for i in range(n):
        r = 0.0
        dr = 0.0
        for j in range(n):
            z = Z0[i, j] + w * Z1[i, j] - w2 * Z2[i, j]
            xj = x[j]
            r += z * xj
            dr += (Z1[i, j] - 2.0 * w * Z2[i, j]) * xj
            J[i, j] += z
        R[i] = (r - F[i]) + Fn[i]
        dRw[i] = (dr - dF[i]) + dFw[i]
