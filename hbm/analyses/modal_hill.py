r"""Hill's stability problem in modal coordinates, for every model (full or condensed).

Every linear part is written in its modes: kept modal coordinates ``eta`` (``m`` of them,
mass-normalised, natural frequencies ``Omega``, modal damping ``C_m``) and a static residual
flexibility ``R`` on the nonlinear coordinates ``u`` (zero for a full model, whose every mode
is kept; the truncated modes' flexibility for a condensed one, :mod:`hbm.balance.condensed`):

.. math::

    \ddot\eta + C_m \dot\eta + \Omega^2 \eta = \Phi_c^T (-f_{nl}) + \Phi_e^T F_e , \qquad
    u = \Phi_c \eta + R_{cc} (-f_{nl}) + R_{ce} F_e .

A perturbation ``(delta eta, delta u)`` of a periodic solution, with the element forces
linearised as ``delta f_nl = J_nl delta u`` (``J_nl`` the AFT Jacobian of the force
harmonics, as in AFT-Hill), satisfies ``(I + R_cc J_nl) delta u = Phi_c delta eta`` (``R_cc``
on every coefficient row: the residual term is static), so the modal equation is

.. math::

    \ddot{\delta\eta} + C_m \dot{\delta\eta} + \Omega^2 \delta\eta
    + \underbrace{\Phi_c^T J_{nl} (I + R_{cc} J_{nl})^{-1} \Phi_c}_{K_{eff}} \delta\eta = 0 ,

Hill's quadratic eigenproblem of :mod:`hbm.analyses.stability` with mass ``I``, damping ``C_m`` and the
Jacobian ``J = Z_m(w) + K_eff`` (``Z_m`` the modal dynamic stiffness,
:func:`hbm.model.linear.fill_dynamic_stiffness`).

**Modes far above the retained harmonics are static.**  A truncated Hill problem on harmonics
up to ``H`` represents a mode of frequency ``Omega_k`` by the members of its exponent family
``lambda - i j w`` with ``|j| <= H``; a mode far above ``H w`` is represented only by members
whose eigenvectors the truncation distorts, and with the non-smooth coupling of a friction
contact these come out with large spurious real parts.  Measured on
``benchmarks/upd_like.toml`` at 248.32 Hz (H = 3, 30 kept modes up to ``102 w``): exponents of
``0.88 w`` (growth by ``e^{5.5}`` per period) while a time integration from rest settles on
the solution (change per period 1e-6 after 300 periods).  With the modes above a cut-off
moved into the static flexibility, ``R_cc + Phi_hi Omega_hi^{-2} Phi_hi^T``, the largest real
part is ``-9e-5 w`` (stable) for every cut-off from ``3.5 w`` to ``30 w``, and spurious again
from ``60 w``.  The cut-off is ``(2 H + 1/2) w``: well inside that range for ``H = 3``, and at
``H = 1`` it still keeps modes up to ``2.5 w`` dynamic (a softening middle branch lies below
its mode).  Those modes enter statically, exactly as the reduction treats its truncated
modes, and the problem has ``2 m_dyn`` exponents, ``m_dyn`` the modes at or below the
cut-off (none: no dynamics left to lose stability, the point is stable).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.linalg as sla

from hbm.model.linear import fill_dynamic_stiffness


class ModalData(NamedTuple):
    """A linear part in modal form, seen from its nonlinear coordinates.

    Attributes
    ----------
    omega : ndarray, shape (m,)
        Natural angular frequencies of the kept modes, rad/s, ascending.
    phi_c : ndarray, shape (n_c, m)
        Mode shapes at the nonlinear coordinates.
    R_cc : ndarray, shape (n_c, n_c)
        Static residual flexibility at the nonlinear coordinates (zeros if none).
    C_m : ndarray, shape (m, m)
        Modal damping matrix.
    """

    omega: np.ndarray
    phi_c: np.ndarray
    R_cc: np.ndarray
    C_m: np.ndarray


def modal_data_of(M, K, C, rows: np.ndarray) -> ModalData:
    """Every mode of a dense model ``(M, K, C)`` seen from its coordinates ``rows``.

    Parameters
    ----------
    M, K, C : ndarray, shape (n, n)
        ``M`` positive definite.
    rows : ndarray of int, shape (n_c,)

    Returns
    -------
    ModalData
        ``R_cc = 0`` (no mode is truncated).
    """
    lam, phi = sla.eigh(K, M)
    C_m = phi.T @ C @ phi
    return ModalData(np.sqrt(np.clip(lam, 0.0, None)), phi[rows], np.zeros((rows.size, rows.size)), C_m)


def _block_rows(P: np.ndarray, n_coef: int) -> np.ndarray:
    """The right-hand side ``Phi_c`` on every coefficient row, a (n_coef a, n_coef b) matrix
    holding ``P`` (a, b) in its diagonal blocks."""
    a, b = P.shape
    B = np.zeros((n_coef, a, n_coef, b))
    r = np.arange(n_coef)
    B[r, :, r, :] = P
    return B.reshape(n_coef * a, n_coef * b)


def modal_hill_system(modal: ModalData, J_nl, basis, w: float, cutoff: float | None = None):
    """Jacobian, mass and damping of the modal Hill problem (module doc) at a point.

    Parameters
    ----------
    modal : ModalData
    J_nl : ndarray, shape (n_coef n_c, n_coef n_c), or None
        ``dF_nl/dU`` at the point on the nonlinear coordinates (``None``: no elements).
    basis : FourierBasis
    w : float
        Angular frequency, rad/s.
    cutoff : float, optional
        Modes above this angular frequency enter statically; default ``(2 H + 1/2) w``.

    Returns
    -------
    J : ndarray, shape (n_coef m_dyn, n_coef m_dyn)
        ``Z_m(w) + K_eff`` on the coefficients of the modes at or below the cut-off.
    M : ndarray, shape (m_dyn, m_dyn)
        Identity (mass-normalised modes).
    C : ndarray, shape (m_dyn, m_dyn)
        Their modal damping.
    """
    nco = basis.n_coef
    dyn = modal.omega <= ((2 * max(basis.harmonics) + 0.5) * w if cutoff is None else cutoff)
    m = int(dyn.sum())
    om, phi_c = modal.omega, modal.phi_c
    Cm = np.ascontiguousarray(modal.C_m[np.ix_(dyn, dyn)])
    J = fill_dynamic_stiffness(np.zeros((nco * m, nco * m)), np.diag(om[dyn] ** 2), Cm, np.eye(m), basis, w)
    if J_nl is None or m == 0:
        return J, np.eye(m), Cm
    nc = phi_c.shape[0]
    hi = ~dyn
    R = modal.R_cc + (phi_c[:, hi] / om[hi] ** 2) @ phi_c[:, hi].T
    pc = phi_c[:, dyn]
    RJ = (R @ J_nl.reshape(nco, nc, nco * nc)).reshape(nco * nc, nco * nc)
    T = np.linalg.solve(np.eye(nco * nc) + RJ, _block_rows(pc, nco))     # delta u per delta eta
    Y = (J_nl @ T).reshape(nco, nc, nco * m)
    J += np.einsum("ca,icn->ian", pc, Y).reshape(nco * m, nco * m)        # Phi_c^T per coefficient row
    return J, np.eye(m), Cm
