r"""Exact derivative of one committed time step with respect to the state it started from.

The integrator state is ``y = [q, v, a, S]`` (``n + n + n + n_S``; ``S`` the law parts'
states, whose first ``n_local`` entries per part are its forces, ``P S``).  One step
(:func:`hbm.timedomain.time_kernels.step`) solves ``R(q_1; y_0) = 0`` with

.. math::

    R = M a_1 + (1+\alpha)(C v_1 + K q_1 + G^T P S_1) - \alpha (C v_0 + K q_0 + G^T P S_0) - F,

    a_1 = c_0 (q_1 - q_0 - h v_0) - c_a a_0, \qquad v_1 = v_0 + h(1-\gamma) a_0 + h \gamma a_1,

    S_1 = L(S_0, G q_1, G v_1), \quad dS_1 = A\, dS_0 + B_u G\, dq_1 + B_v G\, dv_1

(``c_0 = 1/(\beta h^2)``, ``c_1 = \gamma/(\beta h)``, ``c_a = 1/(2\beta) - 1``; ``A``,
``B = [B_u, B_v]`` the laws' exact tangents at the solution).  Differentiating ``R = 0``:

.. math::

    J\, dq_1 = -(D_q\, dq_0 + D_v\, dv_0 + D_a\, da_0 + G^T P ((1+\alpha) A - \alpha I)\, dS_0),

    J = c_0 M + (1+\alpha)(c_1 C + K + K_t), \quad \bar C = C + G^T P B_v G,

    D_q = -c_0 M - (1+\alpha) c_1 \bar C - \alpha K, \quad
    D_v = -c_0 h M + (1+\alpha)(1 - c_1 h) \bar C - \alpha C, \quad
    D_a = -c_a M + (1+\alpha) h (1 - \gamma - \gamma c_a) \bar C,

with ``J`` the step's own iteration matrix at the solution.  :func:`propagate` applies this
to ``Y = dy/dy_start`` (m, m), so after a period ``Y`` is the monodromy matrix of the
discrete period map.  Support DOFs follow a prescribed motion: their rows are zero.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from hbm.timedomain.time_kernels import _iteration_inverse, _n_input


@nb.njit(cache=True)
def _velocity_tangent(laws, keep_B, n):
    """``G^T P B_v G`` (n, n) over the parts that read velocities."""
    g_all, g_off, vel = laws[4], laws[5], laws[6]
    Cv = np.zeros((n, n))
    for e in range(vel.size):
        if vel[e] == 0:
            continue
        g0 = g_off[e]
        nl = g_off[e + 1] - g0
        for i in range(nl):
            for j in range(nl):
                b = keep_B[e, i, nl + j]
                if b == 0.0:
                    continue
                for k in range(n):
                    gk = g_all[g0 + i, k]
                    if gk == 0.0:
                        continue
                    for m in range(n):
                        Cv[k, m] += gk * b * g_all[g0 + j, m]
    return Cv


@nb.njit(cache=True)
def _part_rows(g_all, g0, nl, X):
    """``G_p X`` (nl, m) for the part's gather rows starting at ``g0``."""
    out = np.zeros((nl, X.shape[1]))
    for i in range(nl):
        for k in range(X.shape[0]):
            g = g_all[g0 + i, k]
            if g != 0.0:
                out[i] += g * X[k]
    return out


@nb.njit(cache=True)
def propagate(model, laws, opts, h, work, Y):
    """``Y <- (dy_1/dy_0) Y`` for the step of size ``h`` just committed (module docstring).

    ``work`` must hold the converged step: the tangent ``Kt`` (index 2) and the parts'
    ``A``, ``B`` (indices 12, 13).  ``Y`` has shape (3 n + n_S, m).
    """
    M, C, K, F2, fixed, ybase = model
    kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off = laws
    alpha = opts[0]
    n = M.shape[0]
    gamma = 0.5 - alpha
    beta = 0.25 * (1.0 - alpha) ** 2
    c0 = 1.0 / (beta * h * h)
    c1 = gamma / (beta * h)
    ca = 1.0 / (2.0 * beta) - 1.0
    _iteration_inverse(M, C, K, work[2], c0, c1, alpha, fixed, h, work)
    keep_A, keep_B = work[12], work[13]
    Cb = C + _velocity_tangent(laws, keep_B, n)
    Dq = -c0 * M - (1.0 + alpha) * c1 * Cb - alpha * K
    Dv = -c0 * h * M + (1.0 + alpha) * (1.0 - c1 * h) * Cb - alpha * C
    Da = -ca * M + (1.0 + alpha) * h * (1.0 - gamma - gamma * ca) * Cb
    Yq = np.ascontiguousarray(Y[:n])
    Yv = np.ascontiguousarray(Y[n:2 * n])
    Ya = np.ascontiguousarray(Y[2 * n:3 * n])
    E = Dq @ Yq + Dv @ Yv + Da @ Ya
    for e in range(kinds.size):
        g0, s0 = g_off[e], s_off[e]
        nl, ns = g_off[e + 1] - g0, s_off[e + 1] - s0
        W = (1.0 + alpha) * (np.ascontiguousarray(keep_A[e, :nl, :ns]) @ np.ascontiguousarray(Y[3 * n + s0:3 * n + s0 + ns]))
        W -= alpha * Y[3 * n + s0:3 * n + s0 + nl]
        for i in range(nl):
            for k in range(n):
                g = g_all[g0 + i, k]
                if g != 0.0:
                    E[k] += g * W[i]
    for i in range(n):
        if fixed[i] != 0:
            E[i] = 0.0
    Yq1 = -(work[8] @ E)
    Ya1 = c0 * (Yq1 - Yq - h * Yv) - ca * Ya
    Yv1 = Yv + h * (1.0 - gamma) * Ya + h * gamma * Ya1
    for i in range(n):
        if fixed[i] != 0:
            Yq1[i] = 0.0
            Ya1[i] = 0.0
            Yv1[i] = 0.0
    for e in range(kinds.size):
        g0, s0 = g_off[e], s_off[e]
        nl, ns = g_off[e + 1] - g0, s_off[e + 1] - s0
        nin = _n_input(nl, vel[e])
        YS = np.ascontiguousarray(Y[3 * n + s0:3 * n + s0 + ns])
        new = (np.ascontiguousarray(keep_A[e, :ns, :ns]) @ YS
               + np.ascontiguousarray(keep_B[e, :ns, :nl]) @ _part_rows(g_all, g0, nl, Yq1))
        if nin > nl:
            new += np.ascontiguousarray(keep_B[e, :ns, nl:nin]) @ _part_rows(g_all, g0, nl, Yv1)
        Y[3 * n + s0:3 * n + s0 + ns] = new
    Y[:n] = Yq1
    Y[n:2 * n] = Yv1
    Y[2 * n:3 * n] = Ya1
