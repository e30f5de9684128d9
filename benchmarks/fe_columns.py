r"""Two clamped steel columns of 8-node bricks meeting end to end on a friction patch.

A generated finite-element model for the contact-patch benchmark (:mod:`contact_patch`):
column A stands on ``z = 0`` (clamped), column B hangs from ``z = 2 L`` (clamped), and
their free end faces touch at ``z = L``.  Each column is an ``n_s x n_s x n_z`` mesh of
trilinear bricks (isotropic linear elasticity, consistent mass, 2 x 2 x 2 Gauss points):

.. math::

    K_e = \sum_g B_g^T D B_g\, |J| w_g, \qquad M_e = \rho \sum_g N_g^T N_g\, |J| w_g .

The two interface faces are separate nodes at the same points; ``n_c`` of the node pairs,
spread over the face by farthest-point sampling from the centre, carry the contacts
(``friction3d``: ``t1 = u_x^A - u_x^B``, ``t2 = u_y^A - u_y^B``, ``n = u_z^A - u_z^B``,
closing when positive).  All bricks are the same box, so one element matrix serves all.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

# local node order of a brick: (i, j, k) in {0, 1}^3, x fastest
_CORNERS = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)


def brick_matrices(dx, dy, dz, E, nu, rho):
    """Stiffness and consistent mass of one ``dx x dy x dz`` brick, each (24, 24)
    (DOF order: node-major, ``ux, uy, uz`` per node)."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    g = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    s = 2 * _CORNERS - 1                                   # corner signs (8, 3)
    h = np.array([dx, dy, dz])
    detJ = np.prod(h) / 8.0
    K, M = np.zeros((24, 24)), np.zeros((24, 24))
    for xi in g:
        for eta in g:
            for zeta in g:
                p = np.array([xi, eta, zeta])
                f = 1 + s * p                               # (8, 3)
                N = np.prod(f, axis=1) / 8.0
                dN = np.empty((8, 3))                       # d N / d(x, y, z)
                for a in range(3):
                    o = [b for b in range(3) if b != a]
                    dN[:, a] = s[:, a] * f[:, o[0]] * f[:, o[1]] / 8.0 * (2.0 / h[a])
                B = np.zeros((6, 24))
                for a in range(3):
                    B[a, a::3] = dN[:, a]
                B[3, 0::3], B[3, 1::3] = dN[:, 1], dN[:, 0]     # gamma_xy
                B[4, 1::3], B[4, 2::3] = dN[:, 2], dN[:, 1]     # gamma_yz
                B[5, 0::3], B[5, 2::3] = dN[:, 2], dN[:, 0]     # gamma_xz
                K += B.T @ D @ B * detJ
                Nm = np.zeros((3, 24))
                for a in range(3):
                    Nm[a, a::3] = N
                M += rho * Nm.T @ Nm * detJ
    return K, M


@dataclass(frozen=True)
class ColumnPair:
    """The assembled model (clamped DOFs removed).

    Attributes
    ----------
    M, K : scipy.sparse.csr_matrix, shape (n, n)
    dof_names : tuple of str
        ``"A.n<node>.ux"`` etc.
    pairs : ndarray of int, shape (n_face, 2)
        Interface node pairs (node of A, node of B), farthest-point order (the first ``n_c``
        are the contacts of an ``n_c``-contact model).
    drive : str
        DOF name of the excitation and output: column A, mid-height corner node, x.
    """

    M: sp.csr_matrix
    K: sp.csr_matrix
    dof_names: tuple
    pairs: np.ndarray
    drive: str


def _spread_order(xy):
    """Farthest-point order of the face points ``xy`` (n, 2), starting nearest the centre."""
    c = xy.mean(axis=0)
    order = [int(np.argmin(np.linalg.norm(xy - c, axis=1)))]
    d = np.linalg.norm(xy - xy[order[0]], axis=1)
    for _ in range(len(xy) - 1):
        i = int(np.argmax(d))
        order.append(i)
        d = np.minimum(d, np.linalg.norm(xy - xy[i], axis=1))
    return np.array(order)


def column_pair(n_s=14, n_z=6, side=0.02, length=0.05, E=2.1e11, nu=0.3, rho=7800.0) -> ColumnPair:
    """Assemble the two columns (module docstring); ``n_s`` bricks across, ``n_z`` along each."""
    Ke, Me = brick_matrices(side / n_s, side / n_s, length / n_z, E, nu, rho)
    ns1, nz1 = n_s + 1, n_z + 1
    per_col = ns1 * ns1 * nz1

    def node(col, i, j, k):
        return col * per_col + (k * ns1 + j) * ns1 + i

    i, j, k = np.meshgrid(np.arange(n_s), np.arange(n_s), np.arange(n_z), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    conn = []
    for col in (0, 1):
        corners = [node(col, i + a, j + b, k + c) for a, b, c in _CORNERS.astype(int)]
        conn.append(np.stack(corners, axis=1))
    conn = np.vstack(conn)                                     # (n_el, 8)
    dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(len(conn), 24)
    rows = np.repeat(dofs, 24, axis=1).ravel()
    cols = np.tile(dofs, (1, 24)).ravel()
    n = 6 * per_col
    K = sp.coo_matrix((np.tile(Ke.ravel(), len(conn)), (rows, cols)), shape=(n, n)).tocsr()
    M = sp.coo_matrix((np.tile(Me.ravel(), len(conn)), (rows, cols)), shape=(n, n)).tocsr()
    # column A occupies z in [0, L] (k = 0 clamped), column B z in [L, 2L] (k = n_z clamped)
    fi, fj = np.meshgrid(np.arange(ns1), np.arange(ns1), indexing="ij")
    fi, fj = fi.ravel(), fj.ravel()
    clamped = np.concatenate([node(0, fi, fj, 0), node(1, fi, fj, n_z)])
    keep = np.setdiff1d(np.arange(n), (3 * clamped[:, None] + np.arange(3)).ravel())
    K, M = K[keep][:, keep].tocsr(), M[keep][:, keep].tocsr()
    names = []
    for d in keep:
        nd, comp = divmod(int(d), 3)
        col, local = divmod(nd, per_col)
        names.append(f"{'AB'[col]}.n{local}.{'xyz'[comp]}")
    top_a, bottom_b = node(0, fi, fj, n_z), node(1, fi, fj, 0)
    order = _spread_order(np.stack([fi, fj], axis=1).astype(float))
    pairs = np.stack([top_a[order], bottom_b[order] - per_col], axis=1)
    drive = f"A.n{node(0, n_s, n_s, n_z // 2)}.x"
    return ColumnPair(K=K, M=M, dof_names=tuple(names), pairs=pairs, drive=drive)
