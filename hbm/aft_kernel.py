r"""Fused AFT of one law on DFT matrices: synthesis, seeded march, analysis and gather in one call.

For a law acting on local coordinates ``u = G q`` (``G`` (n_l, n_nl) on the nonlinear DOFs)
with coefficients ``U = X G^T`` (n_coef, n_l):

.. math::

    u = E U,\ \dot u = w\, E' U, \qquad (f, \partial f) = \text{march}(u, \dot u), \qquad
    F \mathrel{+}= (P f)\, G, \qquad
    \frac{\partial F_{k i}}{\partial X_{m j}} \mathrel{+}=
        \sum_{a b} G_{a i}\, \frac{\partial (P f)_{k a}}{\partial U_{m b}}\, G_{b j},

with the march seeded by ``du_{j a}/dU_{m b} = E_{j m} \delta_{a b}`` (and, for velocity
laws, ``d\dot u/dU = w E'``, ``d\dot u/dw = E' U``).  When the law is linear over the whole
period (:func:`elements.law_march.linear_shortcut`: ``f = f_0 + K z``), the coefficients
follow without marching or transforming, ``P f = K U + f_0 e_0`` (``e_0`` the mean row) and
``\partial (P f)/\partial U = K \otimes I``, because ``P E = I`` on an alias-free grid.

This is the path :class:`hbm.aft.NonlinearForces` takes for law elements when the
transform is the DFT matrix (few harmonics); it returns the same numbers as the generic path
(element ``march`` between transform calls), to round-off.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from elements.law_march import start_sample, linear_shortcut, march_law


@nb.njit(cache=True)
def _coordinates(G, X, w, E, dE, velocity):
    """``U = X G^T`` (n_coef, n_l), inputs ``z`` (N, n_z) and ``E' U`` (N, n_l)."""
    nc, nn = X.shape
    nl = G.shape[0]
    N = E.shape[0]
    U = np.zeros((nc, nl))
    for a in range(nl):
        for i in range(nn):
            g = G[a, i]
            if g != 0.0:
                for k in range(nc):
                    U[k, a] += X[k, i] * g
    nz = 2 * nl if velocity else nl
    z = np.empty((N, nz))
    z[:, :nl] = E @ U
    dth = np.zeros((N, nl))
    if velocity:
        dth[:, :] = dE @ U
        z[:, nl:] = w * dth
    return U, z, dth


@nb.njit(cache=True)
def _gather_forces(G, Fe, F):
    """``F += Fe G``: (n_coef, n_l) local coefficients onto the nonlinear DOFs (n_coef, n_nl)."""
    nl, nn = G.shape
    for a in range(nl):
        for i in range(nn):
            g = G[a, i]
            if g != 0.0:
                for k in range(Fe.shape[0]):
                    F[k, i] += Fe[k, a] * g


@nb.njit(cache=True)
def aft_law_forces(kind, p, n_state, closure, start_rule, n_start, velocity, max_passes, tol,
                   G, X, w, E, dE, P, row0, F):
    """Forces only: ``F += (P f) G`` (arguments as :func:`aft_law`), no derivative seeds."""
    nl = G.shape[0]
    N = E.shape[0]
    U, z, dth = _coordinates(G, X, w, E, dE, velocity)
    nz = z.shape[1]
    K = np.zeros((nl, nz))
    f0 = np.zeros(nl)
    passes = 0
    if (not velocity) and linear_shortcut(kind, p, z, K, f0):
        Fe = np.zeros((U.shape[0], nl))
        for a in range(nl):
            for b in range(nl):
                if K[a, b] != 0.0:
                    for k in range(U.shape[0]):
                        Fe[k, a] += K[a, b] * U[k, b]
            if row0 >= 0:
                Fe[row0, a] += f0[a]
    else:
        dz = np.zeros((N, nz, 1))
        start = start_sample(start_rule, n_start, z)
        f, _, passes = march_law(kind, p, n_state, nl, closure, start, z, dz, max_passes, tol)
        Fe = P @ f
    _gather_forces(G, Fe, F)
    return passes


@nb.njit(cache=True)
def aft_law(kind, p, n_state, closure, start_rule, n_start, velocity, max_passes, tol,
            G, X, w, E, dE, P, row0, F, J4, dFdw):
    """Add one law's harmonic forces and exact derivatives (module doc).

    Parameters
    ----------
    kind, p, n_state, closure, start_rule, n_start, velocity, max_passes, tol
        The law (:class:`elements.base.LawSpec`).
    G : ndarray, shape (n_l, n_nl)
    X : ndarray, shape (n_coef, n_nl)
        Coefficients of the nonlinear DOFs.
    w : float
    E, dE : ndarray, shape (N, n_coef)
        Synthesis matrix and its derivative in the phase.
    P : ndarray, shape (n_coef, N)
        Analysis matrix.
    row0 : int
        Row of the mean (harmonic 0) in the coefficients, -1 if absent.
    F, dFdw : ndarray, shape (n_coef, n_nl)
        Accumulated in place.
    J4 : ndarray, shape (n_coef, n_nl, n_coef, n_nl)
        Accumulated in place.

    Returns
    -------
    passes : int
        Periods marched (0: linear shortcut; negative: the loop did not close).
    """
    nc, nn = X.shape
    nl = G.shape[0]
    N = E.shape[0]
    U, z, dth = _coordinates(G, X, w, E, dE, velocity)
    nz = z.shape[1]
    Fe = np.zeros((nc, nl))
    K = np.zeros((nl, nz))
    f0 = np.zeros(nl)
    Pc = nc * nl + 1
    dFe = np.zeros((nc, nl, Pc))
    passes = 0
    if (not velocity) and linear_shortcut(kind, p, z, K, f0):
        for a in range(nl):
            for b in range(nl):
                kab = K[a, b]
                if kab != 0.0:
                    for k in range(nc):
                        Fe[k, a] += kab * U[k, b]
                        dFe[k, a, k * nl + b] = kab
            if row0 >= 0:
                Fe[row0, a] += f0[a]
    else:
        dz = np.zeros((N, nz, Pc))
        for j in range(N):
            for a in range(nl):
                for m in range(nc):
                    dz[j, a, m * nl + a] = E[j, m]
            if velocity:
                for a in range(nl):
                    for m in range(nc):
                        dz[j, nl + a, m * nl + a] = w * dE[j, m]
                    dz[j, nl + a, Pc - 1] = dth[j, a]
        start = start_sample(start_rule, n_start, z)
        f, df, passes = march_law(kind, p, n_state, nl, closure, start, z, dz, max_passes, tol)
        Fe[:, :] = P @ f
        dFe[:, :, :] = (P @ df.reshape(N, nl * Pc)).reshape(nc, nl, Pc)
    # gather: F += Fe G, dFdw += dFe[..., -1] G, J4 += G^T dFe G per harmonic pair
    _gather_forces(G, Fe, F)
    _gather_forces(G, np.ascontiguousarray(dFe[:, :, Pc - 1]), dFdw)
    for k in range(nc):
        for a in range(nl):
            for m in range(nc):
                for b in range(nl):
                    d = dFe[k, a, m * nl + b]
                    if d == 0.0:
                        continue
                    for i in range(nn):
                        ga = G[a, i]
                        if ga == 0.0:
                            continue
                        for j in range(nn):
                            gb = G[b, j]
                            if gb != 0.0:
                                J4[k, i, m, j] += ga * d * gb
    return passes
