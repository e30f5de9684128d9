r"""Point contact with Coulomb friction, normal-load variation and separation (macroslip).

Local coordinates ``z = [u_t (nt), u_n]`` with ``nt = 2`` (t1, t2, n) or ``nt = 1`` (t1, n).
Parameters ``p = [kt, kn, mu, N0, nt]``.

Normal law (no memory), ``u_n > 0`` closes the contact:

.. math::

    N = \max(N_0 + k_n u_n, 0), \qquad f_n = N - \max(N_0, 0)

so the element force is zero at rest and ``-N0`` while the contact is open (the static load
that creates ``N0`` is balanced elsewhere: forces are dynamic forces about equilibrium).
``N0 < 0`` is a gap of ``-N0 / kn`` at rest (a brush bristle clear of the indenter, or a
friction3d element with ``normal_gap > 0``: ``N0 = N_pre - kn g``): the contact is open at
rest and ``f_n = N``, again zero at rest.

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


@nb.njit(cache=True)
def _radial_return(limit, t0, t1):
    """Return mapping of the trial force ``(t0, t1)`` (``t1 = 0`` for one direction) onto the
    circle of radius ``limit``: ``(f0, f1, r, d0, d1, slipping)`` with ``d = f^{tr}/|f^{tr}|``
    and ``r = limit / |f^{tr}|`` (``r = 1``, ``d = 0`` while sticking)."""
    g = math.sqrt(t0 * t0 + t1 * t1)
    if g <= limit:
        return t0, t1, 1.0, 0.0, 0.0, False
    # g > limit >= 0, so g > 0
    r = limit / g
    d0 = t0 / g
    d1 = t1 / g
    return limit * d0, limit * d1, r, d0, d1, True


@nb.njit(cache=True)
def _write_tangential(kt, mu, kn, nt, w0, f0, f1, r, d0, d1, slipping, s_new, A, B, with_A):
    """Tangential forces into ``s_new`` and their derivatives (module doc) into ``A``
    (if ``with_A``: ``df_t/df_prev = J``, ``df_t/du_prev = -kt J``) and ``B``
    (``df_t/du_t = kt J``, ``df_t/du_n = mu kn d``), ``J = r (I - d d^T)`` or ``I``."""
    s_new[0] = f0
    if nt == 2:
        s_new[1] = f1
    for a in range(nt):
        da = d0 if a == 0 else d1
        for b in range(nt):
            db = d0 if b == 0 else d1
            if slipping:
                J = r * ((1.0 if a == b else 0.0) - da * db)
            else:
                J = 1.0 if a == b else 0.0
            if with_A:
                A[a, b] = J
                A[a, w0 + b] = -kt * J
            B[a, b] = kt * J
        B[a, nt] = mu * kn * da if slipping else 0.0


@nb.njit(cache=True)
def _normal_and_slider(p, z, s_new, B):
    """Slider positions ``u_t,prev = u_t`` and the normal force into ``s_new`` with their
    derivatives in ``B`` (zeroed first); returns the normal load ``N`` (<= 0: open, then the
    tangential forces are zero too)."""
    kn = p[1]
    N0 = p[3]
    nt = int(p[4])
    w0 = nt + 1
    for i in range(B.shape[0]):      # explicit loops: a slice fill costs more per sample
        for k in range(B.shape[1]):
            B[i, k] = 0.0
    for a in range(nt):
        s_new[w0 + a] = z[a]
        B[w0 + a, a] = 1.0
    Nload = N0 + kn * z[nt]
    if Nload <= 0.0:
        for a in range(nt):
            s_new[a] = 0.0
        s_new[nt] = -N0 if N0 > 0.0 else 0.0            # -max(N0, 0)
    else:
        s_new[nt] = kn * z[nt] + (N0 if N0 < 0.0 else 0.0)   # N - max(N0, 0)
        B[nt, nt] = kn
    return Nload


@nb.njit(cache=True, inline="always")
def friction3d_step(p, s, z, s_new, A, B):
    """One return-mapping step; ``A = ds_new/ds`` (ns, ns), ``B = ds_new/dz`` (ns, nt + 1)."""
    kt = p[0]
    nt = int(p[4])
    w0 = nt + 1         # first row of u_t,prev (row nt: f_n)
    for i in range(A.shape[0]):      # explicit loops: a slice fill costs more per sample
        for k in range(A.shape[1]):
            A[i, k] = 0.0
    Nload = _normal_and_slider(p, z, s_new, B)
    if Nload <= 0.0:
        return
    t0 = s[0] + kt * (z[0] - s[w0])
    t1 = s[1] + kt * (z[1] - s[w0 + 1]) if nt == 2 else 0.0
    f0, f1, r, d0, d1, slipping = _radial_return(p[2] * Nload, t0, t1)
    _write_tangential(kt, p[2], p[1], nt, w0, f0, f1, r, d0, d1, slipping, s_new, A, B, True)


@nb.njit(cache=True, inline="always")
def friction3d_init(p, z0, s0, C0):
    """Rest state reached at ``z0`` from ``q = 0`` without reversal, ``C0 = ds0/dz0``.

    The tangential force is ``kt u_t0`` returned radially onto the circle ``mu N(u_n0)``;
    zero if the contact is open.
    """
    kt = p[0]
    nt = int(p[4])
    Nload = _normal_and_slider(p, z0, s0, C0)
    if Nload <= 0.0:
        return
    t1 = kt * z0[1] if nt == 2 else 0.0
    f0, f1, r, d0, d1, slipping = _radial_return(p[2] * Nload, kt * z0[0], t1)
    _write_tangential(kt, p[2], p[1], nt, nt + 1, f0, f1, r, d0, d1, slipping, s0, C0, C0, False)


@nb.njit(cache=True, inline="always")
def friction3d_linear(p, z, K, f0):
    """True when the contact is linear at every sample: closed and stuck from rest
    (``K = diag(kt, ..., kt, kn)``, ``f0 = [0, ..., min(N0, 0)]``), or open throughout
    (``K = 0``, ``f0 = [0, ..., -max(N0, 0)]``): the normal law's ``N - max(N0, 0)``."""
    kt = p[0]
    kn = p[1]
    mu = p[2]
    N0 = p[3]
    nt = int(p[4])
    N = z.shape[0]
    n_open = 0
    for j in range(N):
        Nload = N0 + kn * z[j, nt]
        if Nload <= 0.0:
            n_open += 1
            continue
        if n_open > 0:
            return False
        g2 = 0.0
        for a in range(nt):
            g2 += (kt * z[j, a]) ** 2
        if math.sqrt(g2) > mu * Nload:
            return False
    K[:, :] = 0.0
    f0[:] = 0.0
    if n_open == N:
        f0[nt] = -N0 if N0 > 0.0 else 0.0
        return True
    if n_open > 0:
        return False
    for a in range(nt):
        K[a, a] = kt
    K[nt, nt] = kn
    f0[nt] = N0 if N0 < 0.0 else 0.0
    return True
