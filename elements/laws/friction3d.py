r"""Point contact with Coulomb friction, normal-load variation and separation (macroslip).

Local coordinates ``z = [u_t (nt), u_n]`` with ``nt = 2`` (t1, t2, n) or ``nt = 1`` (t1, n).
Parameters ``p = [kt, kn, mu, N0, nt]``.

Normal law (no memory), ``u_n > 0`` closes the contact:

.. math::

    N = \max(N_0 + k_n u_n, 0), \qquad f_n = N - N_0

so the element force is zero at rest and ``-N0`` while the contact is open (the static load
that creates ``N0`` is balanced elsewhere: forces are dynamic forces about equilibrium).

Tangential law: an incremental return mapping with a circular slip limit ``mu N``:

.. math::

    f^{tr} = f_{prev} + k_t (u_t - u_{t,prev}), \qquad
    f_t = \begin{cases} f^{tr} & |f^{tr}| \le \mu N \ \text{(stick)} \\
          \mu N\, f^{tr} / |f^{tr}| & \text{(slip, radial return)} \\
          0 & N = 0 \ \text{(open: the slider follows the contact point)} \end{cases}

After an open step ``f_prev = 0`` and ``u_{t,prev}`` is the current position, so the contact
re-sticks unloaded at re-contact.

State ``s = [f_t (nt), f_n, u_{t,prev} (nt)]`` (``ns = 2 nt + 1``); the first ``nt + 1``
entries are the element forces in the order of the coordinates.

Exact Jacobians.  With ``d = f^{tr}/|f^{tr}|`` and ``M = (mu N / |f^{tr}|)(I - d d^T)``:
stick ``df_t/df_prev = I``, ``df_t/du_prev = -kt I``, ``df_t/du_t = kt I``; slip
``df_t/df_prev = M``, ``df_t/du_prev = -kt M``, ``df_t/du_t = kt M``,
``df_t/du_n = mu kn d`` (tangential-normal coupling); open: all tangential derivatives zero.
``df_n/du_n = kn`` while closed, 0 while open; ``du_prev/du_t = I`` always.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np


@nb.njit(cache=True)
def _tangential(kt, mu, Nload, kn, ft_trial, nt, s_new, J, G):
    """Return mapping of a trial force: writes ``s_new[:nt]``, ``J = df_t/df_trial`` (nt, nt)
    and ``G = df_t/du_n`` (nt,); returns True if slipping."""
    limit = mu * Nload
    g2 = 0.0
    for a in range(nt):
        g2 += ft_trial[a] * ft_trial[a]
    g = math.sqrt(g2)
    for a in range(nt):
        G[a] = 0.0
        for b in range(nt):
            J[a, b] = 0.0
    if g <= limit:
        for a in range(nt):
            s_new[a] = ft_trial[a]
            J[a, a] = 1.0
        return False
    # g > limit >= 0, so g > 0: radial return onto the circle of radius mu N
    r = limit / g
    for a in range(nt):
        da = ft_trial[a] / g
        s_new[a] = limit * da
        G[a] = mu * kn * da
        for b in range(nt):
            db = ft_trial[b] / g
            J[a, b] = r * ((1.0 if a == b else 0.0) - da * db)
    return True


@nb.njit(cache=True)
def friction3d_step(p, s, z, s_new, A, B):
    """One return-mapping step; ``A = ds_new/ds`` (ns, ns), ``B = ds_new/dz`` (ns, nt + 1)."""
    kt = p[0]
    kn = p[1]
    mu = p[2]
    N0 = p[3]
    nt = int(p[4])
    un = z[nt]
    A[:, :] = 0.0
    B[:, :] = 0.0
    n_row = nt          # row of f_n in the state
    w0 = nt + 1         # first row of u_t,prev
    for a in range(nt):
        s_new[w0 + a] = z[a]
        B[w0 + a, a] = 1.0
    Nload = N0 + kn * un
    if Nload <= 0.0:
        for a in range(nt):
            s_new[a] = 0.0
        s_new[n_row] = -N0
        return
    s_new[n_row] = kn * un
    B[n_row, nt] = kn
    ft_trial = np.empty(nt)
    for a in range(nt):
        ft_trial[a] = s[a] + kt * (z[a] - s[w0 + a])
    J = np.empty((nt, nt))
    G = np.empty(nt)
    _tangential(kt, mu, Nload, kn, ft_trial, nt, s_new, J, G)
    for a in range(nt):
        for b in range(nt):
            A[a, b] = J[a, b]
            A[a, w0 + b] = -kt * J[a, b]
            B[a, b] = kt * J[a, b]
        B[a, nt] = G[a]


@nb.njit(cache=True)
def friction3d_init(p, z0, s0, C0):
    """Rest state reached at ``z0`` from ``q = 0`` without reversal, ``C0 = ds0/dz0``.

    The tangential force is ``kt u_t0`` returned radially onto the circle ``mu N(u_n0)``;
    zero if the contact is open.
    """
    kt = p[0]
    kn = p[1]
    mu = p[2]
    N0 = p[3]
    nt = int(p[4])
    un = z0[nt]
    C0[:, :] = 0.0
    n_row = nt
    w0 = nt + 1
    for a in range(nt):
        s0[w0 + a] = z0[a]
        C0[w0 + a, a] = 1.0
    Nload = N0 + kn * un
    if Nload <= 0.0:
        for a in range(nt):
            s0[a] = 0.0
        s0[n_row] = -N0
        return
    s0[n_row] = kn * un
    C0[n_row, nt] = kn
    ft_trial = np.empty(nt)
    for a in range(nt):
        ft_trial[a] = kt * z0[a]
    J = np.empty((nt, nt))
    G = np.empty(nt)
    _tangential(kt, mu, Nload, kn, ft_trial, nt, s0, J, G)
    for a in range(nt):
        for b in range(nt):
            C0[a, b] = kt * J[a, b]
        C0[a, nt] = G[a]

