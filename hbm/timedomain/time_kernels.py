r"""Compiled kernels of the time-domain reference (:mod:`hbm.timedomain.timesim` is the driver).

One HHT-alpha step of size ``h`` solves, for ``q_{n+1}``,

.. math::

    M a_{n+1} + (1+\alpha)(C v_{n+1} + K q_{n+1} + f_{n+1})
              - \alpha (C v_n + K q_n + f_n) = (1+\alpha) F_{n+1} - \alpha F_n,

with ``a_{n+1} = (q_{n+1} - q_n - h v_n)/(\beta h^2) - (1/(2\beta) - 1) a_n``,
``v_{n+1} = v_n + h((1-\gamma) a_n + \gamma a_{n+1})``, ``gamma = 1/2 - alpha``,
``beta = (1 - alpha)^2 / 4``, by Newton's method; ``f = sum_p G_p^T f_p(G_p q, G_p v)`` sums
the law parts (one law each, stepped from the last committed state).  The scheme, the
transition refinement and the periodicity test are described in :mod:`hbm.timedomain.timesim`.

The arrays travel in tuples, each built once by the driver:

- ``model = (M, C, K, F2, fixed, ybase)``: matrices (n, n), the load's cosine and sine
  amplitudes (2, n), support flags (n,) int64 and support amplitudes (n,);
- ``laws = (kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off)``: per law part its id,
  parameters, states, gather rows (n_rows, n) and stored-tangent slots, with offsets;
- ``state = (q, v, a, fnl, S, D, Dref)``: updated in place when a step is committed;
- ``opts = (alpha, newton_tol, max_iter, max_level, jump_tol)``;
- ``rec = (mode, rec_q, rec_f, rec_u, rec_v, r_all, r_off, o_off, g_out)``: the recorded
  rows and the map from part forces to element forces, ``f_e = sum_p R_p^T f_p``
  (``R_p`` (n_part, n_local) flattened at ``r_off[p]``, element columns from ``o_off[p]``)
  and the element coordinates ``u_e = g_out q``.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from elements.kernels import law_step, law_init


@nb.njit(cache=True)
def _n_input(nl, velocity):
    return 2 * nl if velocity != 0 else nl


@nb.njit(cache=True)
def _gather(g_all, row, x):
    s = 0.0
    for k in range(x.size):
        g = g_all[row, k]
        if g != 0.0:
            s += g * x[k]
    return s


@nb.njit(cache=True)
def init_states(laws, q, v, S, D, Dref):
    """Rest states at coordinates ``G q`` (velocities ``G v``) and their tangents ``D``."""
    kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off = laws
    for e in range(kinds.size):
        g0 = g_off[e]
        nl = g_off[e + 1] - g0
        ns = s_off[e + 1] - s_off[e]
        nin = _n_input(nl, vel[e])
        z = np.zeros(nin)
        for i in range(nl):
            z[i] = _gather(g_all, g0 + i, q)
            if vel[e] != 0:
                z[nl + i] = _gather(g_all, g0 + i, v)
        C0 = np.zeros((ns, nin))
        law_init(kinds[e], p_all[p_off[e]:p_off[e + 1]], z, S[s_off[e]:s_off[e + 1]], C0)
        m = 0.0
        for i in range(nl):
            for j in range(nin):
                D[d_off[e] + i * nin + j] = C0[i, j]
                m = max(m, abs(C0[i, j]))
        Dref[e] = m


@nb.njit(cache=True)
def element_forces(laws, S, fnl):
    """``fnl = sum_p G_p^T f_p`` from the states ``S``."""
    s_off, g_all, g_off = laws[3], laws[4], laws[5]
    fnl[:] = 0.0
    for e in range(g_off.size - 1):
        g0 = g_off[e]
        for i in range(g_off[e + 1] - g0):
            fi = S[s_off[e] + i]
            for k in range(fnl.size):
                g = g_all[g0 + i, k]
                if g != 0.0:
                    fnl[k] += g * fi


@nb.njit(cache=True)
def _scatter_tangent(g_all, g0, nl, Keff, Kt):
    """``Kt += G_p^T Keff G_p`` over the nonzeros of the part's gather rows."""
    n = Kt.shape[0]
    for i in range(nl):
        for k in range(n):
            g = g_all[g0 + i, k]
            if g == 0.0:
                continue
            for j in range(nl):
                kij = g * Keff[i, j]
                if kij == 0.0:
                    continue
                for m in range(n):
                    g2 = g_all[g0 + j, m]
                    if g2 != 0.0:
                        Kt[k, m] += kij * g2


@nb.njit(cache=True)
def _eval_elements(q, v, c1, laws, S, work, fnl):
    """Trial states from the committed ``S`` at ``(q, v)``: forces ``fnl``, tangent ``Kt``."""
    kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off = laws
    S_trial, D_trial, Kt, z, Abuf, Bbuf, Keff = work[0], work[1], work[2], work[3], work[4], work[5], work[6]
    fnl[:] = 0.0
    Kt[:, :] = 0.0
    for e in range(kinds.size):
        g0 = g_off[e]
        nl = g_off[e + 1] - g0
        s0 = s_off[e]
        ns = s_off[e + 1] - s0
        nin = _n_input(nl, vel[e])
        for i in range(nl):
            z[i] = _gather(g_all, g0 + i, q)
            if vel[e] != 0:
                z[nl + i] = _gather(g_all, g0 + i, v)
        A = Abuf[:ns, :ns]
        B = Bbuf[:ns, :nin]
        law_step(kinds[e], p_all[p_off[e]:p_off[e + 1]], S[s0:s0 + ns], z[:nin],
                 S_trial[s0:s0 + ns], A, B)
        if work[12].shape[0] > 0:           # kept for the step's sensitivity (when carried)
            work[12][e, :ns, :ns] = A
            work[13][e, :ns, :nin] = B
        d0 = d_off[e]
        for i in range(nl):
            for j in range(nin):
                D_trial[d0 + i * nin + j] = B[i, j]
            for j in range(nl):
                Keff[i, j] = B[i, j]
                if vel[e] != 0:
                    Keff[i, j] += c1 * B[i, nl + j]
            fi = S_trial[s0 + i]
            for k in range(q.size):
                g = g_all[g0 + i, k]
                if g != 0.0:
                    fnl[k] += g * fi
        _scatter_tangent(g_all, g0, nl, Keff, Kt)


@nb.njit(cache=True)
def _max_abs(x):
    m = 0.0
    for i in range(x.size):
        a = abs(x[i])
        if a > m:
            m = a
    return m


@nb.njit(cache=True)
def _kinematics(q0, v0, a0, q1, v1, a1, h, gamma, beta, fixed, ybase, w, th1):
    """Velocity and acceleration at the step's end from the Newmark relations (free DOFs) or
    the prescribed support motion ``ybase cos(th1)`` (support DOFs)."""
    c0 = 1.0 / (beta * h * h)
    ca = 1.0 / (2.0 * beta) - 1.0
    cth, sth = np.cos(th1), np.sin(th1)
    for i in range(q0.size):
        if fixed[i] != 0:
            a1[i] = -w * w * ybase[i] * cth
            v1[i] = -w * ybase[i] * sth
        else:
            a1[i] = c0 * (q1[i] - q0[i] - h * v0[i]) - ca * a0[i]
            v1[i] = v0[i] + h * ((1.0 - gamma) * a0[i] + gamma * a1[i])


@nb.njit(cache=True)
def _residual(M, C, K, alpha, q1, v1, a1, f1, tmp, fixed, R):
    """``R`` (zero on support rows) and the residual's max norm and largest force terms."""
    rnorm = big_i = big_r = 0.0
    n = q1.size
    for i in range(n):
        inert = 0.0
        restore = f1[i]
        for j in range(n):
            inert += M[i, j] * a1[j]
            restore += C[i, j] * v1[j] + K[i, j] * q1[j]
        R[i] = inert + (1.0 + alpha) * restore + tmp[i]
        if fixed[i] != 0:
            R[i] = 0.0
            continue
        rnorm = max(rnorm, abs(R[i]))
        big_i = max(big_i, abs(inert))
        big_r = max(big_r, abs(restore))
    return rnorm, big_i + big_r


@nb.njit(cache=True)
def _iteration_inverse(M, C, K, Kt, c0, c1, alpha, fixed, h, work):
    """``Jinv`` of ``c0 M + (1+alpha)(c1 C + K + Kt)`` (identity on support rows), kept while
    ``h`` and ``Kt`` are unchanged."""
    Jinv, Kt_c, h_c = work[8], work[9], work[10]
    same = h == h_c[0]
    if same:
        for i in range(Kt.shape[0]):
            for j in range(Kt.shape[1]):
                if Kt[i, j] != Kt_c[i, j]:
                    same = False
                    break
            if not same:
                break
    if same:
        return
    J = c0 * M + (1.0 + alpha) * (c1 * C + K + Kt)
    for i in range(fixed.size):
        if fixed[i] != 0:
            J[i, :] = 0.0
            J[:, i] = 0.0
            J[i, i] = 1.0
    Jinv[:, :] = np.linalg.inv(J)
    Kt_c[:, :] = Kt
    h_c[0] = h


@nb.njit(cache=True)
def step(model, laws, opts, x0, x1, F0, F1, h, w, th1, S, work):
    """One HHT/Newmark step of size ``h`` by Newton; returns iterations, or -1 on failure.

    ``x0 = (q0, v0, a0, f0)`` is the committed state; ``x1`` holds the predictor on entry and
    the solution on return.  ``work`` (trial states ``S_trial`` and tangents ``D_trial`` at
    the solution first) is scratch; nothing committed changes.  Support DOFs take the
    prescribed motion ``ybase cos(th1)`` with its exact velocity and acceleration; their
    residual rows are dropped (identity rows in the iteration matrix).
    """
    M, C, K, F2, fixed, ybase = model
    alpha, newton_tol, max_iter = opts[0], opts[1], opts[2]
    q0, v0, a0, f0 = x0
    q1, v1, a1, f1 = x1
    Kt, R, tmp = work[2], work[7], work[11]
    n = q0.size
    for i in range(n):
        if fixed[i] != 0:
            q1[i] = ybase[i] * np.cos(th1)
    gamma = 0.5 - alpha
    beta = 0.25 * (1.0 - alpha) ** 2
    c0 = 1.0 / (beta * h * h)
    c1 = gamma / (beta * h)
    mrow = 0.0
    for i in range(n):
        if fixed[i] != 0:       # a support's own row is not solved: its mass plays no part
            continue
        r = 0.0
        for j in range(n):
            r += abs(M[i, j])
        mrow = max(mrow, r)
    # old-time part of the residual: -alpha (C v0 + K q0 + f0) + alpha F0 - (1 + alpha) F1
    for i in range(n):
        old = f0[i]
        for j in range(n):
            old += C[i, j] * v0[j] + K[i, j] * q0[j]
        tmp[i] = -alpha * old + alpha * F0[i] - (1.0 + alpha) * F1[i]
    for it in range(max_iter + 1):
        _kinematics(q0, v0, a0, q1, v1, a1, h, gamma, beta, fixed, ybase, w, th1)
        _eval_elements(q1, v1, c1, laws, S, work, f1)
        rnorm, forces = _residual(M, C, K, alpha, q1, v1, a1, f1, tmp, fixed, R)
        if not math.isfinite(rnorm):
            return -1
        # relative to the largest force term, including c0 |M| |q|: the inertia term is a
        # difference of displacements times c0 = 1/(beta h^2), so its round-off grows as h^-2
        # (the test then bounds the displacement error by about newton_tol |q|)
        scale = forces + _max_abs(F1) + c0 * mrow * _max_abs(q1) + 1e-300
        if rnorm <= newton_tol * scale:
            return it
        if it == max_iter:
            return -1
        _iteration_inverse(M, C, K, Kt, c0, c1, alpha, fixed, h, work)
        Jinv = work[8]
        for i in range(n):
            dq = 0.0
            for j in range(n):
                dq += Jinv[i, j] * R[j]
            q1[i] -= dq
    return -1
