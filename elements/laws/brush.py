r"""Brush (discretised Winkler foundation) contact: one march over all bristles.

Each bristle ``b`` is a friction3d point contact (:mod:`elements.laws.friction3d`, stepped
through :func:`elements.closure.march_newton`, which closes its loop) with stiffnesses
``kt``, ``kn``, friction ``mu`` and the "preload" parameter

.. math::

    p_b = k_n (\delta_0 - h_b),

the normal load at rest (negative for a bristle that is open at rest: its gap).  Its inputs
are the element's tangential coordinates ``u_t`` (all bristles move together tangentially)
and its own approach, linear in the element coordinates ``z``:

.. math::

    u_{n,b} = c_b \cdot z \qquad (c_b = [0_{nt}, 1, y_b, -x_b] \text{ for } [u_t, u_n, \theta_1, \theta_2]),

so ``N_b = max(p_b + k_n u_{n,b}, 0)``; friction3d returns the bristle's dynamic normal force
about rest, ``N_b - max(p_b, 0)`` (zero at rest whether the bristle is loaded or clear at
rest).  The element forces are the resultants

.. math::

    f_t = \sum_b w_b f_{t,b}, \qquad f_{c} = \sum_b w_b\, c_{b,c}\, (N_b - \max(p_b, 0))
    \quad (c \ge nt),

(normal force and the moments about the two tangential axes), ``w_b`` the number of
identical bristles ``b`` stands for.  Seeds: ``dz_b = [dz_t, c_b \cdot dz]`` and the force
seeds are summed the same way, so the Jacobian is exact.

Shortcuts (both exact, the march gives the same numbers): a bristle whose load is zero at
every sample contributes its constant rest force; a bristle loaded at every sample whose
elastic force from rest stays inside its cone, ``k_t |u_t(t)| \le \mu N_b(t)``, never slips
(the march from the rest state ``k_t u_t`` would keep sticking), so it is linear,
``f_{t,b} = k_t u_t``, ``N_b - p_b = k_n u_{n,b}``; these are summed into one stiffness
matrix applied once.  Only the remaining bristles are marched.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from ..closure import march_newton
from .registry import FRICTION3D


@nb.njit(cache=True)
def brush_march(kt, kn, mu, nt, pre, weight, coef, z, dz, start, max_passes, tol):
    """Resultant forces of all bristles over one period, with seeded derivatives.

    Parameters
    ----------
    kt, kn, mu : float
        Per-bristle tangential and normal stiffness, friction coefficient.
    nt : int
        Tangential directions (1 or 2); element coordinates are ``[u_t (nt), u_n, rotations]``.
    pre : ndarray, shape (nb,)
        ``p_b = kn (delta0 - h_b)`` per bristle.
    weight : ndarray, shape (nb,)
        Multiplicity of each bristle.
    coef : ndarray, shape (nb, n_local)
        ``c_b``: bristle approach ``u_{n,b} = coef[b] @ z`` (zero on the tangential columns).
    z : ndarray, shape (N, n_local)
    dz : ndarray, shape (N, n_local, P)
    start : int
        Start sample of every bristle's march.
    max_passes : int
    tol : float
        Closure tolerance of the per-bristle march.

    Returns
    -------
    f : ndarray, shape (N, n_local)
    df : ndarray, shape (N, n_local, P)
    counts : ndarray of int, shape (4,)
        Bristles (with multiplicity) open all period, stuck all period, marched; and the
        worst pass count of the marched ones (negative if a loop did not close).
    """
    N, nl = z.shape
    P = dz.shape[2]
    nb_ = pre.shape[0]
    ns = 2 * nt + 1
    f = np.zeros((N, nl))
    df = np.zeros((N, nl, P))
    Kst = np.zeros((nl, nl))
    f0 = np.zeros(nl)
    counts = np.zeros(4, dtype=np.int64)
    un = np.empty(N)
    zb = np.empty((N, nt + 1))
    dzb = np.empty((N, nt + 1, P))
    pb = np.empty(5)
    pb[0] = kt
    pb[1] = kn
    pb[2] = mu
    pb[4] = nt
    # elastic tangential force magnitude from rest, per sample (same for every bristle)
    ftr = np.empty(N)
    for j in range(N):
        g2 = 0.0
        for a in range(nt):
            g2 += (kt * z[j, a]) ** 2
        ftr[j] = np.sqrt(g2)
    worst = 0
    for b in range(nb_):
        w = weight[b]
        p = pre[b]
        closed_all = True
        open_all = True
        stuck = True
        for j in range(N):
            s = 0.0
            for c in range(nt, nl):
                s += coef[b, c] * z[j, c]
            un[j] = s
            load = p + kn * s
            if load > 0.0:
                open_all = False
                if ftr[j] > mu * load:
                    stuck = False
            else:
                closed_all = False
        rest = -p if p > 0.0 else 0.0          # -max(p, 0)
        off = p if p < 0.0 else 0.0            # min(p, 0): N_b - max(p, 0) = kn u_n + off
        if open_all:
            counts[0] += int(w)
            for c in range(nt, nl):
                f0[c] += w * coef[b, c] * rest
            continue
        if closed_all and stuck:
            counts[1] += int(w)
            for a in range(nt):
                Kst[a, a] += w * kt
            for c in range(nt, nl):
                f0[c] += w * coef[b, c] * off
                for d in range(nt, nl):
                    Kst[c, d] += w * kn * coef[b, c] * coef[b, d]
            continue
        counts[2] += int(w)
        for j in range(N):
            for a in range(nt):
                zb[j, a] = z[j, a]
                for q in range(P):
                    dzb[j, a, q] = dz[j, a, q]
            zb[j, nt] = un[j]
            for q in range(P):
                s = 0.0
                for c in range(nt, nl):
                    s += coef[b, c] * dz[j, c, q]
                dzb[j, nt, q] = s
        pb[3] = p
        fb, dfb, passes = march_newton(FRICTION3D, pb, ns, nt + 1, zb, dzb, start, max_passes, tol)
        if passes < 0:
            worst = passes if worst >= 0 or passes < worst else worst
        elif worst >= 0 and passes > worst:
            worst = passes
        for j in range(N):
            for a in range(nt):
                f[j, a] += w * fb[j, a]
                for q in range(P):
                    df[j, a, q] += w * dfb[j, a, q]
            fn = fb[j, nt]
            for c in range(nt, nl):
                wc = w * coef[b, c]
                if wc != 0.0:
                    f[j, c] += wc * fn
                    for q in range(P):
                        df[j, c, q] += wc * dfb[j, nt, q]
    counts[3] = worst
    # stuck bristles: one linear map; open/stuck constants
    for j in range(N):
        for a in range(nl):
            s = f0[a]
            for c in range(nl):
                s += Kst[a, c] * z[j, c]
            f[j, a] += s
            for c in range(nl):
                k = Kst[a, c]
                if k != 0.0:
                    for q in range(P):
                        df[j, a, q] += k * dz[j, c, q]
    return f, df, counts
