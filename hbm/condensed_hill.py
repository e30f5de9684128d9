r"""Hill stability of a condensed (modal + residual flexibility) harmonic-balance solution.

The condensed problem (:mod:`hbm.condensed`) solves on the contact coordinates ``u`` only.
Its time-domain equations are those of the reduced structure: kept modal coordinates
``eta`` (``m`` of them, mass-normalised) and the static residual flexibility ``R`` of the
truncated modes,

.. math::

    \ddot\eta + C_m \dot\eta + \Omega^2 \eta = \Phi_c^T (-f_{nl}) + \Phi_e^T F_e , \qquad
    u = \Phi_c \eta + R_{cc} (-f_{nl}) + R_{ce} F_e .

A perturbation ``(delta eta, delta u)`` of a periodic solution, with the element forces
linearised as ``delta f_nl = J_nl delta u`` (``J_nl`` the AFT Jacobian of the force
harmonics, as in the full model's Hill method), satisfies the algebraic relation
``(I + R_cc J_nl) delta u = Phi_c delta eta`` (``R_cc`` applied to every coefficient row:
the residual term is static) and so the modal equation

.. math::

    \ddot{\delta\eta} + C_m \dot{\delta\eta} + \Omega^2 \delta\eta
    + \underbrace{\Phi_c^T J_{nl} (I + R_{cc} J_{nl})^{-1} \Phi_c}_{K_{eff}} \delta\eta = 0 .

In harmonic-balance form this is Hill's quadratic eigenproblem of :mod:`hbm.stability` with
mass ``I``, damping ``C_m`` and the Jacobian ``J = Z_m(w) + K_eff``, ``Z_m`` the modal dynamic
stiffness (:func:`hbm.linear.fill_dynamic_stiffness`).  It is exact for the reduced model:
the same Floquet exponents as the full model restricted to the kept modes plus the static
residual, and it has ``2 m`` exponents (the contact coordinates carry no inertia).  Its size
is ``2 n_coef m`` whatever the size of the finite-element model.
"""
from __future__ import annotations

import numpy as np

from .linear import fill_dynamic_stiffness


def _block_rows(P: np.ndarray, n_coef: int) -> np.ndarray:
    """The right-hand side ``Phi_c`` on every coefficient row, a (n_coef a, n_coef b) matrix
    holding ``P`` (a, b) in its diagonal blocks."""
    a, b = P.shape
    B = np.zeros((n_coef, a, n_coef, b))
    r = np.arange(n_coef)
    B[r, :, r, :] = P
    return B.reshape(n_coef * a, n_coef * b)


def modal_hill_system(problem, X: np.ndarray, w: float):
    """Jacobian, mass and damping of the modal Hill problem (module doc) at a point.

    Parameters
    ----------
    problem : hbm.condensed.CondensedHarmonicBalance
    X : ndarray, shape (n_coef, n_c)
        Contact-coordinate coefficients of a converged point.
    w : float
        Angular frequency, rad/s.

    Returns
    -------
    J : ndarray, shape (n_coef m, n_coef m)
        ``Z_m(w) + K_eff`` on the modal coefficients (harmonic-major).
    M : ndarray, shape (m, m)
        Identity (mass-normalised modes).
    C : ndarray, shape (m, m)
        Modal damping ``C_m``.
    """
    reduced, basis = problem.reduced, problem.basis
    nco, nc = basis.n_coef, problem.n_dof
    m = reduced.n_modes
    om2 = reduced.omega ** 2
    Cm = np.asarray(reduced.modal_c, dtype=float)
    J = fill_dynamic_stiffness(np.zeros((nco * m, nco * m)), np.diag(om2), Cm, np.eye(m), basis, w)
    Jnl = problem.nonlinear_jacobian(X, w)                       # (nco nc, nco nc)
    if Jnl is None:
        return J, np.eye(m), Cm
    phi_c, R_cc = problem.contact_modes()
    RJ = (R_cc @ Jnl.reshape(nco, nc, nco * nc)).reshape(nco * nc, nco * nc)
    T = np.linalg.solve(np.eye(nco * nc) + RJ, _block_rows(phi_c, nco))   # delta u per delta eta
    Y = (Jnl @ T).reshape(nco, nc, nco * m)
    J += np.einsum("ca,icn->ian", phi_c, Y).reshape(nco * m, nco * m)      # Phi_c^T per coefficient row
    return J, np.eye(m), Cm
