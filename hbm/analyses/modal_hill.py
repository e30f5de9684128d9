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
from ``60 w``.  The cut-off is ``(H + 1/2) w``, and at least ``2.5 w`` (at ``H = 1`` a
softening middle branch lies below its mode): a mode above ``(H + 1/2) w`` has no member of
its family in the strip ``|Im| <= w / 2`` within the retained harmonics (it would need
``|j| > H``), so the truncation cannot hold its kept exponent; below, it can.  On
``upd_like`` (H = 3, 349 points) that cut-off (``3.5 w``, the former ``(2 H + 1/2) w``
``= 6.5 w``) leaves 12 points that Hill calls unstable and the Floquet multipliers of the
period map call stable instead of 19, and no new disagreement; the spectra cost 2.5x less
(fewer dynamic modes).  Those modes enter statically, exactly as the reduction treats its
truncated modes, and the problem has ``2 m_dyn`` exponents, ``m_dyn`` the modes at or below
the cut-off (none: no dynamics left to lose stability, the point is stable).

**Through the stuck stiffness.**  ``(I + R J_nl)^{-1}`` is a dense system of ``n_coef n_c``
unknowns (a 64-contact patch at H = 3: 1344, 60 ms per point).  The elements' stiffness at
rest ``K_s`` (:attr:`ModalData.K_ref`) gives it on every coefficient row alike,
``A = I + R K_s`` (``n_c x n_c``), and ``J_nl = K_s + Delta`` differs from it only on the
rows ``S`` of contacts that slip or open during the period (``p`` of them; none when all
stick, and then exactly, since a stuck period is evaluated as linear).  With
``G = A^{-1} R`` and ``T_0 = A^{-1} Phi_c`` on every row, the Woodbury identity gives

.. math::

    (I + R J_{nl})^{-1} \Phi_c = T_0 - G_{:,S} (I_p + \Delta_{SS} G_{SS})^{-1} \Delta_{SS} T_{0,S},
    \qquad J_{nl} T = K_s T + \Delta_{:,S} T_S ,

a ``p x p`` system instead of the whole one (whose cost it matches near ``p = n / 2``; above
:data:`WHOLE_SHARE` of the rows the whole system is solved).  64-contact patch, H = 3, 174
points (152 stuck): Hill's systems 16.5 -> 3.1 s, the stability pass 18.8 -> 5.5 s.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.linalg as sla

from hbm.model.linear import fill_dynamic_stiffness

WHOLE_SHARE = 0.5     # above this share of slipping rows the whole system is solved (cheaper)


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
    K_ref : ndarray, shape (n_c, n_c), optional
        Stiffness of the elements at rest on the same coordinates (module doc); zeros if None.
    """

    omega: np.ndarray
    phi_c: np.ndarray
    R_cc: np.ndarray
    C_m: np.ndarray
    K_ref: np.ndarray | None = None


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
        Modes above this angular frequency enter statically; default
        ``max(H + 1/2, 5/2) w`` (module doc).

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
    dyn = modal.omega <= (max(max(basis.harmonics) + 0.5, 2.5) * w if cutoff is None else cutoff)
    m = int(dyn.sum())
    om, phi_c = modal.omega, modal.phi_c
    Cm = np.ascontiguousarray(modal.C_m[np.ix_(dyn, dyn)])
    J = fill_dynamic_stiffness(np.zeros((nco * m, nco * m)), np.diag(om[dyn] ** 2), Cm, np.eye(m), basis, w)
    if J_nl is None or m == 0:
        return J, np.eye(m), Cm
    hi = ~dyn
    R = modal.R_cc + (phi_c[:, hi] / om[hi] ** 2) @ phi_c[:, hi].T
    if not R.any():         # no static flexibility (every mode dynamic): K_eff = Phi_c^T J_nl Phi_c
        Y = (J_nl @ _on_every_row(phi_c[:, dyn], nco)).reshape(nco, -1, nco * m)
    else:
        Y = _element_response(R, J_nl, phi_c[:, dyn], nco,
                              np.zeros_like(R) if modal.K_ref is None else modal.K_ref)
    J += np.einsum("ca,icn->ian", phi_c[:, dyn], Y).reshape(nco * m, nco * m)   # Phi_c^T per coefficient row
    return J, np.eye(m), Cm


def _element_response(R, J_nl, pc, nco, Ks):
    """``J_nl (I + R J_nl)^{-1} Phi_c`` (module doc, through the stuck stiffness ``Ks``), as
    (n_coef, n_c, n_coef m): the element forces per unit modal perturbation.

    Parameters
    ----------
    R, Ks : ndarray, shape (n_c, n_c)
    J_nl : ndarray, shape (n_coef n_c, n_coef n_c)
    pc : ndarray, shape (n_c, m)
    nco : int
    """
    nc, m = pc.shape
    n = nco * nc
    S = rest_departures(J_nl, Ks, nco)
    if S.size > WHOLE_SHARE * n:             # most rows slip: the whole system is cheaper
        RJ = (R @ J_nl.reshape(nco, nc, n)).reshape(n, n)
        T = np.linalg.solve(np.eye(n) + RJ, _on_every_row(pc, nco))
        return (J_nl @ T).reshape(nco, nc, nco * m)
    Ainv = np.linalg.inv(np.eye(nc) + R @ Ks)
    G = Ainv @ R                                                  # per coefficient row
    T = _on_every_row(Ainv @ pc, nco)
    if S.size:
        k, a = np.divmod(S, nc)                   # coefficient and coordinate of each (k sorted)
        DS = np.array(J_nl[:, S])                                 # Delta's columns S, (n, p)
        DS.reshape(nco, nc, S.size)[k, :, np.arange(S.size)] -= Ks[:, a].T
        D = DS[S]
        # G's columns S hold G[:, a] in their coefficient's rows only: products by blocks
        spans = np.searchsorted(k, np.arange(nco + 1))
        blocks = [(q, slice(spans[q], spans[q + 1])) for q in range(nco) if spans[q + 1] > spans[q]]
        C = np.eye(S.size)
        for q, j in blocks:
            C[:, j] += D[:, j] @ G[np.ix_(a[j], a[j])]
        W = np.linalg.solve(C, D @ T[S])                          # (p, n_coef m)
        T3 = T.reshape(nco, nc, nco * m)
        for q, j in blocks:
            T3[q] -= G[:, a[j]] @ W[j]
    Y = (Ks @ T.reshape(nco, nc, nco * m)).reshape(nco * nc, nco * m)
    if S.size:
        Y += DS @ T[S]
    return Y.reshape(nco, nc, nco * m)


def rest_departures(J_nl: np.ndarray, Ks: np.ndarray, nco: int) -> np.ndarray:
    """Rows ``S`` (and columns) where ``J_nl`` (n_coef n_c, n_coef n_c) differs from ``Ks``
    (n_c, n_c) on every coefficient row, i.e. where ``Delta = J_nl - I x Ks`` is not zero;
    empty when the elements act as their stiffness at rest.  (Found from ``Delta``'s pattern:
    an ``n x n`` copy costs more.)"""
    nc = Ks.shape[0]
    nz = J_nl != 0.0
    r = np.arange(nco)
    nz.reshape(nco, nc, nco, nc)[r, :, r, :] = J_nl.reshape(nco, nc, nco, nc)[r, :, r, :] != Ks
    return np.flatnonzero(nz.any(axis=1) | nz.any(axis=0))


def _on_every_row(P: np.ndarray, nco: int) -> np.ndarray:
    """``P`` (a, b) on every coefficient row: the (nco a, nco b) matrix with ``P`` in its
    diagonal blocks."""
    a, b = P.shape
    B = np.zeros((nco, a, nco, b))
    r = np.arange(nco)
    B[r, :, r, :] = P
    return B.reshape(nco * a, nco * b)
