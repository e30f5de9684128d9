r"""Contact coordinates of a condensed model: independent rows spanning every element's gather.

With the elements' gather matrices ``G_e`` (n_local, n_dof) stacked, the contact coordinates
``u_c = G_c q`` are a maximal set of independent rows taken in order (Gram-Schmidt with a
relative rank tolerance), and each element reads ``u_e = A_e u_c`` with

.. math::

    A_e = G_e\, G_c^{+}, \qquad A_e G_c = G_e \ \text{(checked to 1e-9)},

so the condensed balance (:mod:`hbm.balance.condensed`) sees the same element forces
``G_e^T f_e = G_c^T A_e^T f_e``.
"""
from __future__ import annotations

import copy

import numpy as np

_RANK_TOL = 1e-10


def contact_coordinates(elements, n_dof: int):
    """Independent contact rows ``G_c`` and each element's rows on them, ``A_e``.

    Rows are taken from the elements' gather matrices in order, skipping any row in the span
    of those already taken, so the coordinates are the elements' own (relative) coordinates
    when these are independent.

    Parameters
    ----------
    elements : sequence of Element
        Gather matrices of shape (n_local, n_dof).
    n_dof : int

    Returns
    -------
    G_c : ndarray, shape (n_c, n_dof)
    A : list of ndarray
        ``A_e`` (n_local, n_c) with ``gather_e = A_e G_c``.
    """
    rows = np.vstack([e.gather for e in elements])
    if rows.shape[1] != n_dof:
        raise ValueError(f"element gather has {rows.shape[1]} columns, the model has {n_dof} DOFs")
    cols = np.flatnonzero(np.any(rows != 0.0, axis=0))
    S = rows[:, cols]
    chosen, Q = [], np.zeros((0, cols.size))
    for i, s in enumerate(S):
        v = s - Q.T @ (Q @ s)
        v = v - Q.T @ (Q @ v)
        nv = np.linalg.norm(v)
        if nv > _RANK_TOL * max(np.linalg.norm(s), 1e-300):
            chosen.append(i)
            Q = np.vstack([Q, v / nv])
    G_c = rows[chosen]
    P = np.linalg.pinv(G_c[:, cols])
    A = []
    for e in elements:
        Ae = e.gather[:, cols] @ P
        err = np.abs(Ae @ G_c[:, cols] - e.gather[:, cols]).max(initial=0.0)
        if err > 1e-9 * max(np.abs(e.gather).max(), 1e-300):
            raise ValueError(f"element {e.name}: its coordinates are not spanned by the contact rows")
        A.append(Ae)
    return G_c, A


def regathered(element, A):
    """A copy of ``element`` reading its coordinates from the contact coordinates: gather ``A``."""
    e = copy.copy(element)
    G = np.array(A, dtype=float)
    G[np.abs(G) < 1e-14 * max(np.abs(G).max(initial=0.0), 1e-300)] = 0.0
    G.setflags(write=False)
    e.gather = G
    return e
