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
from .friction3d import n_states
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
    ns = n_states(nt)
    f = np.zeros((N, nl))
    df = np.zeros((N, nl, P))
    Kst = np.zeros((nl, nl))
    f0 = np.zeros(nl)
    counts = np.zeros(4, dtype=np.int64)
    un = np.empty(N)
    zb = np.empty((N, nt + 1))
    dzb = np.empty((N, nt + 1, P))
    pb = np.empty(5)                     # the friction3d record: kt, kn, mu, preload, nt
    pb[0], pb[1], pb[2], pb[4] = kt, kn, mu, nt
    ftr = _elastic_from_rest(kt, nt, z)
    worst = 0
    for b in range(pre.shape[0]):
        w = weight[b]
        p = pre[b]
        state = _bristle_state(kn, mu, nt, p, coef[b], z, ftr, un)
        if state == 0:                          # open all period: its rest force
            counts[0] += int(w)
            for c in range(nt, nl):
                f0[c] += w * coef[b, c] * (-p if p > 0.0 else 0.0)      # -max(p, 0)
            continue
        if state == 1:                          # loaded and stuck all period: linear
            counts[1] += int(w)
            _add_stuck(Kst, f0, w, kt, kn, nt, p, coef[b])
            continue
        counts[2] += int(w)
        _bristle_inputs(nt, coef[b], z, dz, un, zb, dzb)
        pb[3] = p
        fb, dfb, passes = march_newton(FRICTION3D, pb, ns, nt + 1, zb, dzb, start, max_passes, tol)
        if passes < 0:
            worst = passes if worst >= 0 or passes < worst else worst
        elif worst >= 0 and passes > worst:
            worst = passes
        _add_marched(f, df, w, nt, coef[b], fb, dfb)
    counts[3] = worst
    _add_linear(f, df, f0, Kst, z, dz)
    return f, df, counts


@nb.njit(cache=True)
def _elastic_from_rest(kt, nt, z):
    """``|kt u_t|`` per sample (N,): the elastic tangential force from rest (every bristle's)."""
    N = z.shape[0]
    ftr = np.empty(N)
    for j in range(N):
        g2 = 0.0
        for a in range(nt):
            g2 += (kt * z[j, a]) ** 2
        ftr[j] = np.sqrt(g2)
    return ftr


@nb.njit(cache=True)
def _bristle_state(kn, mu, nt, p, coef_b, z, ftr, un):
    """0: open all period, 1: loaded and inside its cone all period (never slips), 2: marched.
    Writes the bristle's approach ``u_{n,b}`` per sample into ``un`` (N,)."""
    N, nl = z.shape
    closed_all = True
    open_all = True
    stuck = True
    for j in range(N):
        s = 0.0
        for c in range(nt, nl):
            s += coef_b[c] * z[j, c]
        un[j] = s
        load = p + kn * s
        if load > 0.0:
            open_all = False
            if ftr[j] > mu * load:
                stuck = False
        else:
            closed_all = False
    if open_all:
        return 0
    return 1 if closed_all and stuck else 2


@nb.njit(cache=True)
def _add_stuck(Kst, f0, w, kt, kn, nt, p, coef_b):
    """A stuck bristle's stiffness into ``Kst`` (nl, nl) and its constant into ``f0`` (nl,)."""
    nl = f0.shape[0]
    off = p if p < 0.0 else 0.0            # min(p, 0): N_b - max(p, 0) = kn u_n + off
    for a in range(nt):
        Kst[a, a] += w * kt
    for c in range(nt, nl):
        f0[c] += w * coef_b[c] * off
        for d in range(nt, nl):
            Kst[c, d] += w * kn * coef_b[c] * coef_b[d]


@nb.njit(cache=True)
def _bristle_inputs(nt, coef_b, z, dz, un, zb, dzb):
    """The bristle's march inputs ``zb`` (N, nt+1) = ``[u_t, u_{n,b}]`` and their seeds ``dzb``."""
    N, nl = z.shape
    P = dz.shape[2]
    for j in range(N):
        for a in range(nt):
            zb[j, a] = z[j, a]
            for q in range(P):
                dzb[j, a, q] = dz[j, a, q]
        zb[j, nt] = un[j]
        for q in range(P):
            s = 0.0
            for c in range(nt, nl):
                s += coef_b[c] * dz[j, c, q]
            dzb[j, nt, q] = s


@nb.njit(cache=True)
def _add_marched(f, df, w, nt, coef_b, fb, dfb):
    """A marched bristle's forces ``fb`` (N, nt+1) and seeds into the resultants (module doc)."""
    N, nl = f.shape
    P = df.shape[2]
    for j in range(N):
        for a in range(nt):
            f[j, a] += w * fb[j, a]
            for q in range(P):
                df[j, a, q] += w * dfb[j, a, q]
        fn = fb[j, nt]
        for c in range(nt, nl):
            wc = w * coef_b[c]
            if wc != 0.0:
                f[j, c] += wc * fn
                for q in range(P):
                    df[j, c, q] += wc * dfb[j, nt, q]


@nb.njit(cache=True)
def _add_linear(f, df, f0, Kst, z, dz):
    """The stuck bristles' one linear map and the open/stuck constants: ``f += f0 + Kst z``."""
    N, nl = z.shape
    P = dz.shape[2]
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
