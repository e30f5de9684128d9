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
re-sticks unloaded at re-contact.  The instant of re-contact is placed between the samples:
with the normal load's trial values ``N_p = N_0 + k_n u_{n,prev} <= 0`` before and
``N > 0`` now, the load crosses zero at the share ``theta = N_p / (N_p - N)`` of the step,
where the slider sits at ``u_{t,prev} + theta (u_t - u_{t,prev})``, so

.. math::

    f^{tr} = f_{prev} + g\, k_t (u_t - u_{t,prev}), \qquad g = 1 - \theta

(``g = 1`` when the previous sample was closed).  Without it the slider re-stuck at the last
open sample, and the stuck tangential force of the whole closed stretch jumped by
``k_t`` times one sample's tangential motion whenever the re-contact crossed a sample: the
balance was discontinuous in the unknowns, and Newton stalled at a residual of 1e-8 to 1e-2
of the force on separating contacts.

State ``s = [f_t (nt), f_n, u_{t,prev} (nt), N_p]`` (``ns = 2 nt + 2``, :func:`n_states`); the
first ``nt + 1`` entries are the element forces in the order of the coordinates, the last is
the trial normal load ``N_0 + k_n u_n`` of the sample.

Exact Jacobians.  With ``d = f^{tr}/|f^{tr}|`` and ``M = (mu N / |f^{tr}|)(I - d d^T)``:
stick ``df_t/df_prev = I``, ``df_t/du_prev = -kt I``, ``df_t/du_t = kt I``; slip
``df_t/df_prev = M``, ``df_t/du_prev = -kt M``, ``df_t/du_t = kt M``,
``df_t/du_n = mu kn d`` (tangential-normal coupling); open: all tangential derivatives zero.
``df_n/du_n = kn`` while closed, 0 while open; ``du_prev/du_t = I``, ``dN_p/du_n = kn`` always.
At re-contact the ``k_t`` terms carry ``g``, and ``df^{tr}/dN_p = -k_t (u_t - u_{t,prev})
d theta / d N_p``, ``df^{tr}/du_n = -k_t (u_t - u_{t,prev}) k_n d theta / d N``, with
``d theta / d N_p = -N / (N_p - N)^2`` and ``d theta / d N = N_p / (N_p - N)^2``, both through
``J``.
"""
from __future__ import annotations

import math

import numba as nb


@nb.njit(cache=True)
def n_states(nt):
    """State size of the law with ``nt`` tangential directions (module doc)."""
    return 2 * nt + 2


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
def _write_tangential(kt, mu, kn, nt, w0, f0, f1, r, d0, d1, slipping, s_new, A, B, with_A, g, e0, e1, c0, c1):
    """Tangential forces into ``s_new`` and their derivatives (module doc) into ``A``
    (if ``with_A``: ``df_t/df_prev = J``, ``df_t/du_prev = -g kt J``, ``df_t/dN_p = J e``) and
    ``B`` (``df_t/du_t = g kt J``, ``df_t/du_n = mu kn d + J c``), ``J = r (I - d d^T)`` or
    ``I``; ``e``, ``c``: the trial force's derivatives by ``N_p`` and ``u_n`` at re-contact."""
    s_new[0] = f0
    if nt == 2:
        s_new[1] = f1
    for a in range(nt):
        da = d0 if a == 0 else d1
        je, jc = 0.0, 0.0
        for b in range(nt):
            db = d0 if b == 0 else d1
            if slipping:
                J = r * ((1.0 if a == b else 0.0) - da * db)
            else:
                J = 1.0 if a == b else 0.0
            if with_A:
                A[a, b] = J
                A[a, w0 + b] = -g * kt * J
            B[a, b] = g * kt * J
            je += J * (e0 if b == 0 else e1)
            jc += J * (c0 if b == 0 else c1)
        if with_A:
            A[a, 2 * nt + 1] = je
        B[a, nt] = (mu * kn * da if slipping else 0.0) + jc


@nb.njit(cache=True)
def _normal_and_slider(p, z, s_new, B):
    """Slider positions ``u_t,prev = u_t``, the normal force and the trial normal load ``N_p``
    into ``s_new`` with their derivatives in ``B`` (zeroed first); returns the normal load
    ``N`` (<= 0: open, then the tangential forces are zero too)."""
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
    s_new[2 * nt + 1] = Nload
    B[2 * nt + 1, nt] = kn
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
    Np = s[2 * nt + 1]
    Nload = _normal_and_slider(p, z, s_new, B)
    if Nload <= 0.0:
        return
    g, dth_p, dth_n = 1.0, 0.0, 0.0
    if Np <= 0.0:                      # re-contact within the step (module doc)
        q = Np - Nload
        g = 1.0 - Np / q
        dth_p, dth_n = -Nload / (q * q), Np / (q * q) * p[1]
    v0 = z[0] - s[w0]
    v1 = z[1] - s[w0 + 1] if nt == 2 else 0.0
    f0, f1, r, d0, d1, slipping = _radial_return(p[2] * Nload, s[0] + g * kt * v0,
                                                 s[1] + g * kt * v1 if nt == 2 else 0.0)
    _write_tangential(kt, p[2], p[1], nt, w0, f0, f1, r, d0, d1, slipping, s_new, A, B, True, g,
                      -kt * v0 * dth_p, -kt * v1 * dth_p, -kt * v0 * dth_n, -kt * v1 * dth_n)


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
    _write_tangential(kt, p[2], p[1], nt, nt + 1, f0, f1, r, d0, d1, slipping, s0, C0, C0, False,
                      1.0, 0.0, 0.0, 0.0, 0.0)


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
