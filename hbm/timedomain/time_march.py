r"""Compiled march over whole periods: dyadic sub-steps at element transitions, the records and
the periodicity test (the scheme is in :mod:`hbm.timedomain.timesim`, one step in :mod:`hbm.timedomain.time_kernels`,
whose docstring lists the tuples ``model``, ``laws``, ``state``, ``opts``, ``rec``).

A trial step is rejected and halved when a part's tangent block changes by more than
``jump_tol`` of the largest tangent it has shown,

.. math::

    \max |D_{new} - D_{old}| > \text{jump\_tol} \cdot D_{ref},

down to ``dt / 2**max_level``; sub-steps grow back as soon as they are aligned.  With
``check``, a period ``p`` ends the run when ``max|q_p - q_{p-1}| / max|q_p| <= tol`` over the
output grid.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from hbm.timedomain.time_kernels import _n_input, step
from hbm.timedomain.time_sensitivity import propagate


@nb.njit(cache=True)
def record(row, laws, q, v, S, rec):
    """Row ``row`` of the records: ``q``, element forces ``sum_p R_p^T f_p``, element
    coordinates and velocities ``g_out q``, ``g_out v``."""
    s_off, g_off = laws[3], laws[5]
    rec_q, rec_f, rec_u, rec_v, r_all, r_off, o_off, g_out = (rec[1], rec[2], rec[3], rec[4], rec[5],
                                                              rec[6], rec[7], rec[8])
    rec_q[row, :] = q
    rec_f[row, :] = 0.0
    for p in range(g_off.size - 1):
        n_p = g_off[p + 1] - g_off[p]
        n_o = (r_off[p + 1] - r_off[p]) // n_p
        for i in range(n_p):
            fi = S[s_off[p] + i]
            for j in range(n_o):
                rec_f[row, o_off[p] + j] += r_all[r_off[p] + i * n_o + j] * fi
    for c in range(g_out.shape[0]):
        su = 0.0
        sv = 0.0
        for k in range(q.size):
            g = g_out[c, k]
            if g != 0.0:
                su += g * q[k]
                sv += g * v[k]
        rec_u[row, c] = su
        rec_v[row, c] = sv


@nb.njit(cache=True)
def _jumped(laws, D, D_trial, Dref, jump_tol):
    """Whether some part's tangent changed status inside the trial step."""
    vel, g_off, d_off = laws[6], laws[5], laws[7]
    for e in range(vel.size):
        nl = g_off[e + 1] - g_off[e]
        m = nl * _n_input(nl, vel[e])
        jump = 0.0
        big = Dref[e]
        for r in range(m):
            jump = max(jump, abs(D_trial[d_off[e] + r] - D[d_off[e] + r]))
            big = max(big, abs(D_trial[d_off[e] + r]))
        if big > 0.0 and jump > jump_tol * big:
            return True
    return False


@nb.njit(cache=True)
def _commit(laws, state, x1, work):
    """The converged trial step becomes the state (kinematics, forces, law states, tangents)."""
    q, v, a, fnl, S, D, Dref = state
    vel, g_off, d_off = laws[6], laws[5], laws[7]
    q[:] = x1[0]
    v[:] = x1[1]
    a[:] = x1[2]
    fnl[:] = x1[3]
    S[:] = work[0]
    D[:] = work[1]
    for e in range(vel.size):
        nl = g_off[e + 1] - g_off[e]
        for r in range(nl * _n_input(nl, vel[e])):
            Dref[e] = max(Dref[e], abs(D[d_off[e] + r]))


@nb.njit(cache=True)
def _output_step(model, laws, opts, state, x1, work, loads, w, t_off, N, k, stats, Y):
    """One output step from global index ``k`` to ``k + 1`` in dyadic sub-steps; returns
    ``(0, 0.0)``, or ``(-1, t)`` when Newton fails at the finest sub-step starting at ``t``."""
    F2 = model[3]
    max_level, jump_tol = opts[3], opts[4]
    q, v, a, fnl, S, D, Dref = state
    F0, F1 = loads
    unit = 1 << max_level
    dt = 2.0 * np.pi / w / N
    kk = k % N
    pos = 0
    lev = 0
    while pos < unit:
        size = unit >> lev
        h = dt / (1 << lev)
        t0 = (k * unit + pos) * (dt / unit)
        t1 = (k * unit + pos + size) * (dt / unit)
        th0 = 2.0 * np.pi * (kk * unit + pos) / (N * unit)
        th1 = 2.0 * np.pi * (kk * unit + pos + size) / (N * unit)
        on0 = 1.0 if t0 <= t_off else 0.0
        on1 = 1.0 if t1 <= t_off else 0.0
        cs0, sn0, cs1, sn1 = np.cos(th0), np.sin(th0), np.cos(th1), np.sin(th1)
        for i in range(q.size):   # the load Fc cos + Fs sin at both ends; constant-acceleration predictor
            F0[i] = on0 * (cs0 * F2[0, i] + sn0 * F2[1, i])
            F1[i] = on1 * (cs1 * F2[0, i] + sn1 * F2[1, i])
            x1[0][i] = q[i] + h * v[i] + 0.5 * h * h * a[i]
        its = step(model, laws, opts, (q, v, a, fnl), x1, F0, F1, h, w, th1, S, work)
        if its < 0:
            stats[3] += 1
            if lev >= max_level:
                return -1, t0
            lev += 1
            continue
        stats[0] += its
        if lev < max_level and _jumped(laws, D, work[1], Dref, jump_tol):
            stats[2] += 1
            lev += 1
            continue
        stats[1] += 1
        _commit(laws, state, x1, work)
        if Y.shape[0] > 0:
            propagate(model, laws, opts, h, work, Y)
        pos += size
        while lev > 0 and pos % (size << 1) == 0:
            lev -= 1
            size <<= 1
    return 0, 0.0


@nb.njit(cache=True)
def _work(laws, n, S, D, keep):
    """Scratch of one step: ``(S_trial, D_trial, Kt, z, A, B, Keff, R, Jinv, Kt_c, h_c, tmp,
    A per part, B per part)``; the last two have no parts unless ``keep`` (sensitivities)."""
    s_off, g_off, vel = laws[3], laws[5], laws[6]
    ns_max = 1
    nin_max = 1
    for e in range(vel.size):
        ns_max = max(ns_max, s_off[e + 1] - s_off[e])
        nin_max = max(nin_max, _n_input(g_off[e + 1] - g_off[e], vel[e]))
    n_keep = vel.size if keep else 0
    return (S.copy(), D.copy(), np.zeros((n, n)), np.zeros(nin_max), np.zeros((ns_max, ns_max)),
            np.zeros((ns_max, nin_max)), np.zeros((nin_max, nin_max)), np.zeros(n), np.zeros((n, n)),
            np.full((n, n), np.nan), np.array([np.nan]), np.zeros(n),
            np.zeros((n_keep, ns_max, ns_max)), np.zeros((n_keep, ns_max, nin_max)))


@nb.njit(cache=True)
def _period_change(prev, cur):
    diff = 0.0
    scale = 0.0
    for j in range(cur.shape[0]):
        for i in range(cur.shape[1]):
            diff = max(diff, abs(cur[j, i] - prev[j, i]))
            scale = max(scale, abs(cur[j, i]))
    prev[:, :] = cur
    return diff / scale if scale > 0.0 else 0.0


@nb.njit(cache=True)
def march(model, laws, opts, run, state, rec, prev, cur, stats, Y):
    """Integrate ``n_periods`` whole periods of ``N`` steps from global step ``k0``.

    ``run = (w, t_off, N, k0, n_periods, check, tol, have_prev)``.  The ``state`` tuple is
    updated in place.  ``rec[0]`` (mode) 0 records the current period in rows ``0..N``
    (overwritten every period); 1 records row ``k`` for global step ``k``.  With ``check``,
    stops as soon as a period repeats the previous one to ``tol``.  ``Y`` (m, m') is carried
    through every committed step, ``Y <- (dy_1/dy_0) Y`` (:mod:`hbm.timedomain.time_sensitivity`); an
    array with no rows switches that off.

    Returns
    -------
    status : int
        1 periodic (converged), 0 all periods done, -1 Newton failed at the finest sub-step.
    periods : int
        Periods completed in this call.
    change : float
        Relative change of the last completed period against the one before (-1 if none).
    t_fail : float
        Time of the failed step (status -1), else 0.
    """
    w, t_off, N, k0, n_periods, check, tol, have_prev = run
    q, v, S, D = state[0], state[1], state[4], state[5]
    n = q.size
    work = _work(laws, n, S, D, Y.shape[0] > 0)
    x1 = (np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n))
    loads = (np.zeros(n), np.zeros(n))
    n_rec = rec[1].shape[0]
    change = -1.0
    k = k0
    for pp in range(n_periods):
        row = 0 if rec[0] == 0 else k
        if row < n_rec:
            record(row, laws, q, v, S, rec)
        for j in range(1, N + 1):
            status, t_fail = _output_step(model, laws, opts, state, x1, work, loads, w, t_off, N, k, stats, Y)
            if status < 0:
                return -1, pp, change, t_fail
            k += 1
            if check:
                cur[j - 1, :] = q
            row = j if rec[0] == 0 else k
            if row < n_rec:
                record(row, laws, q, v, S, rec)
        if check:
            ch = _period_change(prev, cur)
            if have_prev:
                change = ch
                if change <= tol:
                    return 1, pp + 1, change, 0.0
            have_prev = True
    return 0, n_periods, change, 0.0
