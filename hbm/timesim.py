r"""Time-domain reference: implicit integration of a case to its periodic steady state.

Equations of motion (the same model, elements and excitation as the harmonic balance):

.. math::

    M \ddot q + C \dot q + K q + \sum_e G_e^T f_e = F_c \cos(w t) + F_s \sin(w t) \quad (t \le t_{off}),
    \qquad F = 0 \ \text{after} \ t_{off}.

Base (support) excitation (``[excitation] base``): the support DOFs ``b`` follow the prescribed
motion ``q_b(t) = A_b cos(w t)`` with ``v_b = -w A_b sin(w t)``, ``a_b = -w^2 A_b cos(w t)``
exactly at every (sub-)step end; only the free DOFs are unknowns (their rows of the equations
above), and the supports drive them through the coupling terms of ``M``, ``C``, ``K`` and
through every element attached to them (the elements see ``G q`` with the supports' motion).
The support reactions are not computed.  The run starts with the supports at ``A_b`` and the
free DOFs at the quasi-static position ``K_ff q_f = -K_fb A_b`` (elements stuck).

Scheme
------
HHT-alpha (Hilber-Hughes-Taylor) with ``alpha`` in [-1/3, 0]; ``alpha = 0`` (the default) is
Newmark's average-acceleration (trapezoidal) rule, ``gamma = 1/2``, ``beta = 1/4``.  In general
``gamma = 1/2 - alpha``, ``beta = (1 - alpha)^2 / 4`` and each step of size ``h`` solves

.. math::

    M a_{n+1} + (1+\alpha)(C v_{n+1} + K q_{n+1} + f_{n+1})
              - \alpha (C v_n + K q_n + f_n) = (1+\alpha) F_{n+1} - \alpha F_n

for ``q_{n+1}``, with ``a_{n+1} = (q_{n+1} - q_n - h v_n)/(\beta h^2) - (1/(2\beta) - 1) a_n``
and ``v_{n+1} = v_n + h((1-\gamma) a_n + \gamma a_{n+1})``, by Newton's method.  The element
forces come from the law's incremental return mapping (:func:`elements.kernels.law_step`),
always from the *last committed* state to the trial coordinates, so a Newton iterate never
pollutes the history; the states are committed only when the step has converged.  The
consistent tangent is ``df/du + gamma/(beta h) df/dv`` read from the law's ``B = ds_new/dz``
(``df/du = B[:n_local, :n_local]``, ``df/dv = B[:n_local, n_local:]`` for velocity laws).

Transitions (stick/slip, open/closed, static -> kinetic)
--------------------------------------------------------
Generic, law-agnostic: the integrator compares every element's tangent block
``D = B[:n_local, :]`` at the end of a trial step with the tangent committed at its start.
A jump ``max|D_new - D_old| > jump_tol * D_ref`` (``D_ref`` the largest tangent magnitude the
element has shown) means the element changed status inside the step (e.g. Jenkins stick ->
slip: ``kt -> 0``; a static -> kinetic Coulomb law also drops its stick stiffness).  Such a
step is rejected and retried as two halves, recursively (dyadic sub-steps), down to
``dt / 2**max_level``: the transition is located to within that sub-step, the sub-steps
around it grow back to ``dt`` as soon as they are aligned.  A step whose Newton iteration
fails is halved the same way; failure at the finest level stops the run with the time.
Smooth laws (cubic spring, a mildly regularised Coulomb law) do not trigger it except when
their tangent changes by a large fraction within a step.  The output grid is always the
``steps`` equal steps per period.

Periodic steady state
---------------------
From rest (``q = 0``, ``q' = 0``, element rest states from :func:`elements.kernels.law_init`
at zero coordinates), whole periods are integrated until the relative change of ``q`` (all
DOFs, all samples of the step grid) between successive periods,
``max|q_p - q_{p-1}| / max|q_p|``, is at most ``tol`` (default 1e-8), or ``max_periods``.
Outputs per case output: ``h1 = sqrt(a^2 + b^2)`` with ``a, b = 2/N sum q_j (cos, sin)(2 pi j/N)``
over the last period's step grid, and ``max = max |q_j|`` over the same samples.

Error estimate by step halving: :func:`timesim` runs with ``steps = n``, then continues from
that steady state with ``2 n`` steps per period to steady state again, and reports the results
of the ``2 n`` run with the relative change ``|y_2n - y_n| / |y_2n|`` (largest over the
outputs' ``h1`` and ``max``) as its error estimate.  The scheme is second order, so this
overestimates the error of the ``2 n`` result (by about 3x for smooth motion).

Everything per time step runs in one numba kernel (:func:`_march`); Python only loops over
chunks of whole periods (for progress output).
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numba as nb
import numpy as np

from elements.kernels import law_step, law_init

from .budget import MEMORY_SHARE, machine_memory
from .case import Case, CaseError


# --------------------------------------------------------------------------------------
# numba kernels
# --------------------------------------------------------------------------------------

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
def _init_states(kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off, q, v, S, D, Dref):
    """Rest states at coordinates ``G q`` (velocities ``G v``) and their tangents ``D``."""
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
def _element_forces(S, s_off, g_all, g_off, q, fnl):
    """``fnl = sum_e G_e^T f_e`` from the states ``S``."""
    fnl[:] = 0.0
    for e in range(g_off.size - 1):
        g0 = g_off[e]
        for i in range(g_off[e + 1] - g0):
            fi = S[s_off[e] + i]
            for k in range(q.size):
                g = g_all[g0 + i, k]
                if g != 0.0:
                    fnl[k] += g * fi


@nb.njit(cache=True)
def _eval_elements(q, v, c1, kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off,
                   S, S_trial, D_trial, fnl, Kt, z, Abuf, Bbuf, Keff):
    """Trial states from the committed ``S`` at ``(q, v)``: forces ``fnl``, tangent ``Kt``."""
    n = q.size
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
        d0 = d_off[e]
        for i in range(nl):
            for j in range(nin):
                D_trial[d0 + i * nin + j] = B[i, j]
            for j in range(nl):
                Keff[i, j] = B[i, j]
                if vel[e] != 0:
                    Keff[i, j] += c1 * B[i, nl + j]
        for i in range(nl):
            fi = S_trial[s0 + i]
            for k in range(n):
                g = g_all[g0 + i, k]
                if g == 0.0:
                    continue
                fnl[k] += g * fi
                for j in range(nl):
                    kij = g * Keff[i, j]
                    if kij == 0.0:
                        continue
                    for m in range(n):
                        g2 = g_all[g0 + j, m]
                        if g2 != 0.0:
                            Kt[k, m] += kij * g2


@nb.njit(cache=True)
def _max_abs(x):
    m = 0.0
    for i in range(x.size):
        a = abs(x[i])
        if a > m:
            m = a
    return m


@nb.njit(cache=True)
def _step(M, C, K, F0, F1, h, alpha, newton_tol, max_iter,
          q0, v0, a0, f0, q1, v1, a1, f1,
          kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off,
          S, S_trial, D_trial, Kt, z, Abuf, Bbuf, Keff, R, Jinv, Kt_c, h_c, tmp,
          fixed, ybase, w, th1):
    """One HHT/Newmark step of size ``h`` by Newton; returns iterations, or -1 on failure.

    ``q1`` enters as the predictor and leaves as the solution; ``S_trial``/``D_trial`` hold the
    element states/tangents at the solution (not committed here).  ``Jinv`` caches the inverse
    iteration matrix for the step size ``h_c[0]`` and element tangent ``Kt_c``.

    Support DOFs (``fixed[i] != 0``) take the prescribed motion ``ybase[i] cos(th1)`` with its
    exact velocity and acceleration at the step's end; their rows of the residual are dropped
    (identity rows and columns in the iteration matrix), so only the free DOFs are unknowns.
    """
    n = q0.size
    cth = np.cos(th1)
    sth = np.sin(th1)
    for i in range(n):
        if fixed[i] != 0:
            q1[i] = ybase[i] * cth
    gamma = 0.5 - alpha
    beta = 0.25 * (1.0 - alpha) ** 2
    c0 = 1.0 / (beta * h * h)
    c1 = gamma / (beta * h)
    ca = 1.0 / (2.0 * beta) - 1.0
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
        for i in range(n):
            if fixed[i] != 0:
                a1[i] = -w * w * ybase[i] * cth
                v1[i] = -w * ybase[i] * sth
            else:
                a1[i] = c0 * (q1[i] - q0[i] - h * v0[i]) - ca * a0[i]
                v1[i] = v0[i] + h * ((1.0 - gamma) * a0[i] + gamma * a1[i])
        _eval_elements(q1, v1, c1, kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off,
                       S, S_trial, D_trial, f1, Kt, z, Abuf, Bbuf, Keff)
        rnorm = 0.0
        big_i = 0.0
        big_r = 0.0
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
        if not math.isfinite(rnorm):
            return -1
        # relative to the largest force term, including c0 |M| |q|: the inertia term is a
        # difference of displacements times c0 = 1/(beta h^2), so its round-off grows as h^-2
        # (the test then bounds the displacement error by about newton_tol |q|)
        scale = big_i + big_r + _max_abs(F1) + c0 * mrow * _max_abs(q1) + 1e-300
        if rnorm <= newton_tol * scale:
            return it
        if it == max_iter:
            return -1
        same = h == h_c[0]
        if same:
            for i in range(n):
                for j in range(n):
                    if Kt[i, j] != Kt_c[i, j]:
                        same = False
                        break
                if not same:
                    break
        if not same:
            J = c0 * M + (1.0 + alpha) * (c1 * C + K + Kt)
            for i in range(n):
                if fixed[i] != 0:
                    J[i, :] = 0.0
                    J[:, i] = 0.0
                    J[i, i] = 1.0
            Jinv[:, :] = np.linalg.inv(J)
            Kt_c[:, :] = Kt
            h_c[0] = h
        for i in range(n):
            dq = 0.0
            for j in range(n):
                dq += Jinv[i, j] * R[j]
            q1[i] -= dq
    return -1


@nb.njit(cache=True)
def _record(row, q, v, S, s_off, g_all, g_off, rec_q, rec_f, rec_u, rec_v):
    rec_q[row, :] = q
    c = 0
    for e in range(g_off.size - 1):
        for i in range(g_off[e + 1] - g_off[e]):
            rec_f[row, c] = S[s_off[e] + i]
            rec_u[row, c] = _gather(g_all, g_off[e] + i, q)
            rec_v[row, c] = _gather(g_all, g_off[e] + i, v)
            c += 1


@nb.njit(cache=True)
def _march(M, C, K, F2, w, t_off, N, k0, n_periods, check, tol, have_prev,
           q, v, a, fnl, S, D, Dref,
           kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off,
           alpha, newton_tol, max_iter, max_level, jump_tol,
           rec_mode, rec_q, rec_f, rec_u, rec_v, prev, cur, stats, fixed, ybase):
    """Integrate ``n_periods`` whole periods of ``N`` steps from global step ``k0``.

    The state ``q, v, a, fnl, S, D, Dref`` is updated in place.  ``rec_mode`` 0 records the
    current period in rows ``0..N`` (overwritten every period); 1 records row ``k`` for global
    step ``k``.  With ``check``, stops as soon as a period repeats the previous one to ``tol``.

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
    n = q.size
    T = 2.0 * np.pi / w
    dt = T / N
    unit = 1 << max_level
    n_el = kinds.size
    ns_max = 1
    nin_max = 1
    for e in range(n_el):
        ns_max = max(ns_max, s_off[e + 1] - s_off[e])
        nin_max = max(nin_max, _n_input(g_off[e + 1] - g_off[e], vel[e]))
    Abuf = np.zeros((ns_max, ns_max))
    Bbuf = np.zeros((ns_max, nin_max))
    Keff = np.zeros((nin_max, nin_max))
    z = np.zeros(nin_max)
    S_trial = S.copy()
    D_trial = D.copy()
    Kt = np.zeros((n, n))
    Kt_c = np.full((n, n), np.nan)
    Jinv = np.zeros((n, n))
    h_c = np.array([np.nan])
    R = np.zeros(n)
    tmp = np.zeros(n)
    q1 = np.zeros(n)
    v1 = np.zeros(n)
    a1 = np.zeros(n)
    f1 = np.zeros(n)
    F0 = np.zeros(n)
    F1 = np.zeros(n)
    change = -1.0
    k = k0
    for pp in range(n_periods):
        if rec_mode == 0:
            _record(0, q, v, S, s_off, g_all, g_off, rec_q, rec_f, rec_u, rec_v)
        elif k < rec_q.shape[0]:
            _record(k, q, v, S, s_off, g_all, g_off, rec_q, rec_f, rec_u, rec_v)
        for j in range(1, N + 1):
            # one output step from global index k to k + 1, in dyadic sub-steps
            pos = 0
            lev = 0
            kk = k % N
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
                for i in range(n):   # the load Fc cos + Fs sin at both ends of the step
                    F0[i] = on0 * (cs0 * F2[0, i] + sn0 * F2[1, i])
                    F1[i] = on1 * (cs1 * F2[0, i] + sn1 * F2[1, i])
                for i in range(n):   # predictor: constant acceleration
                    q1[i] = q[i] + h * v[i] + 0.5 * h * h * a[i]
                its = _step(M, C, K, F0, F1, h, alpha, newton_tol, max_iter,
                            q, v, a, fnl, q1, v1, a1, f1,
                            kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off,
                            S, S_trial, D_trial, Kt, z, Abuf, Bbuf, Keff, R, Jinv, Kt_c, h_c, tmp,
                            fixed, ybase, w, th1)
                if its < 0:
                    stats[3] += 1
                    if lev >= max_level:
                        return -1, pp, change, t0
                    lev += 1
                    continue
                stats[0] += its
                # status change of an element inside the step: refine to locate it
                jumped = False
                for e in range(n_el):
                    nl = g_off[e + 1] - g_off[e]
                    m = nl * _n_input(nl, vel[e])
                    d0 = d_off[e]
                    jump = 0.0
                    big = Dref[e]
                    for r in range(m):
                        jump = max(jump, abs(D_trial[d0 + r] - D[d0 + r]))
                        big = max(big, abs(D_trial[d0 + r]))
                    if big > 0.0 and jump > jump_tol * big:
                        jumped = True
                if jumped and lev < max_level:
                    stats[2] += 1
                    lev += 1
                    continue
                # commit
                stats[1] += 1
                for i in range(n):
                    q[i] = q1[i]
                    v[i] = v1[i]
                    a[i] = a1[i]
                    fnl[i] = f1[i]
                S[:] = S_trial
                D[:] = D_trial
                for e in range(n_el):
                    nl = g_off[e + 1] - g_off[e]
                    m = nl * _n_input(nl, vel[e])
                    for r in range(m):
                        Dref[e] = max(Dref[e], abs(D[d_off[e] + r]))
                pos += size
                while lev > 0 and pos % (size << 1) == 0:
                    lev -= 1
                    size <<= 1
            k += 1
            if check:
                cur[j - 1, :] = q
            if rec_mode == 0:
                _record(j, q, v, S, s_off, g_all, g_off, rec_q, rec_f, rec_u, rec_v)
            elif k < rec_q.shape[0]:
                _record(k, q, v, S, s_off, g_all, g_off, rec_q, rec_f, rec_u, rec_v)
        if check:
            diff = 0.0
            scale = 0.0
            for j in range(N):
                for i in range(n):
                    diff = max(diff, abs(cur[j, i] - prev[j, i]))
                    scale = max(scale, abs(cur[j, i]))
            prev[:, :] = cur
            if have_prev:
                change = diff / scale if scale > 0.0 else 0.0
                if change <= tol:
                    return 1, pp + 1, change, 0.0
            have_prev = True
    return 0, n_periods, change, 0.0


# --------------------------------------------------------------------------------------
# Python layer
# --------------------------------------------------------------------------------------

@dataclass(frozen=True)
class TimeSimOptions:
    """Settings of the time integration.

    Attributes
    ----------
    steps : int
        Steps per excitation period ``n`` (the error estimate also runs ``2 n``).
    tol : float
        Periodicity tolerance: relative max change of ``q`` between successive periods.
    max_periods : int
        Most periods integrated per run (steady-state mode).
    alpha : float
        HHT parameter in [-1/3, 0]; 0 is Newmark average acceleration.
    max_level : int
        Finest sub-step ``dt / 2**max_level`` for locating element transitions.
    jump_tol : float
        Relative tangent jump that counts as an element status change.
    newton_tol : float
        Newton tolerance on the residual, relative to its largest term.
    max_iter : int
        Newton iterations per (sub-)step before the step is halved.
    """

    steps: int = 512
    tol: float = 1e-8
    max_periods: int = 5000
    alpha: float = 0.0
    max_level: int = 6
    jump_tol: float = 0.3
    newton_tol: float = 1e-10
    max_iter: int = 30

    def validate(self):
        if not (isinstance(self.steps, (int, np.integer)) and self.steps >= 8):
            raise CaseError(f"steps per period must be an integer >= 8, got {self.steps!r}")
        if not (self.tol > 0 and math.isfinite(self.tol)):
            raise CaseError(f"periodicity tolerance must be > 0, got {self.tol!r}")
        if not (isinstance(self.max_periods, (int, np.integer)) and self.max_periods >= 2):
            raise CaseError(f"max periods must be an integer >= 2, got {self.max_periods!r}")
        if not -1.0 / 3.0 - 1e-12 <= self.alpha <= 0.0:
            raise CaseError(f"HHT alpha must be in [-1/3, 0], got {self.alpha!r}")
        if not 0 <= self.max_level <= 20:
            raise CaseError(f"max_level must be in 0..20, got {self.max_level!r}")


@dataclass(frozen=True)
class History:
    """Sampled time history.

    Attributes
    ----------
    t : ndarray, shape (n_rows,)
        Time, s.
    q : ndarray, shape (n_rows, n_dof)
    forces : ndarray, shape (n_rows, n_forces)
        Element forces (every element's ``n_local`` components, in case order).
    disp : ndarray, shape (n_rows, n_forces)
        The matching element coordinates ``G q``.
    force_names : tuple of str
    vel : ndarray, shape (n_rows, n_forces)
        The element coordinates' velocities ``G v`` (e.g. the relative sliding velocity).
    """

    t: np.ndarray
    q: np.ndarray
    forces: np.ndarray
    disp: np.ndarray
    force_names: tuple
    vel: np.ndarray | None = None


@dataclass(frozen=True)
class Run:
    """One integration at ``steps`` steps per period.

    ``h1``/``max`` (per output name) are of the last period on the step grid.  ``converged``
    is whether the periodicity test passed (steady mode; always False in transient mode, where
    ``change`` is -1).  ``history`` is the last period (steady) or the whole run (transient).
    """

    freq_hz: float
    steps: int
    periods: int
    converged: bool
    change: float
    h1: dict
    max: dict
    history: History
    stats: dict
    seconds: float


@dataclass(frozen=True)
class TimeSimResult:
    """Result of :func:`timesim`: the ``2 n`` run's values with the ``n`` vs ``2 n`` estimate.

    Attributes
    ----------
    h1, max : dict of str -> float
        Per output, from the fine run.
    error_estimate : float
        Largest relative change of any output's ``h1`` or ``max`` between ``n`` and ``2 n``.
    errors : dict of str -> (float, float)
        Relative changes of ``(h1, max)`` per output.
    periods : int
        Periods integrated in total (both runs).
    converged : bool
        Both runs periodic to ``tol`` (steady mode); True in transient mode.
    mode : str
        ``"steady"`` or ``"transient"``.
    """

    freq_hz: float
    h1: dict
    max: dict
    error_estimate: float
    errors: dict
    periods: int
    converged: bool
    mode: str
    coarse: Run
    fine: Run
    seconds: float
    switch_off_at: float | None = None

    @property
    def history(self) -> History:
        return self.fine.history


@dataclass
class _Packed:
    kinds: np.ndarray
    p_all: np.ndarray
    p_off: np.ndarray
    s_off: np.ndarray
    g_all: np.ndarray
    g_off: np.ndarray
    vel: np.ndarray
    d_off: np.ndarray
    names: tuple = field(default=())

    def args(self):
        return (self.kinds, self.p_all, self.p_off, self.s_off, self.g_all, self.g_off,
                self.vel, self.d_off)


def _time_parts(element):
    """``[(gather rows (n_part, n_dof), LawSpec, force names), ...]``: the laws the element
    steps through in time (its :meth:`law_parts`: a wedge's flank contacts, one law for a
    plain element)."""
    parts = element.law_parts()
    if not parts:
        raise CaseError(f"element {element.name}: {type(element).__name__} has no time-step law; "
                        f"the time-domain reference does not support it")
    names = tuple(element.coord_names) if len(element.coord_names) == element.n_local else \
        tuple(str(i) for i in range(element.n_local))
    out = []
    for rows, spec in parts:
        rows = np.asarray(rows, dtype=np.int64)
        if element.n_local == 1:
            labels = (f"{element.name}_f",)
        else:
            labels = tuple(f"{element.name}_f_{names[r]}" for r in rows)
        out.append((element.gather[rows], spec, labels))
    return out


def pack_elements(elements, n_dof: int) -> _Packed:
    """Flat arrays of the elements' law parts for the kernel (kinds, params/states/gathers
    with offsets, one entry per part: :func:`_time_parts`)."""
    parts = [p for e in elements for p in _time_parts(e)]
    n_el = len(parts)
    kinds = np.array([spec.kind for _, spec, _ in parts], dtype=np.int64)
    p_off = np.zeros(n_el + 1, dtype=np.int64)
    s_off = np.zeros(n_el + 1, dtype=np.int64)
    g_off = np.zeros(n_el + 1, dtype=np.int64)
    d_off = np.zeros(n_el + 1, dtype=np.int64)
    names = []
    for i, (G, spec, labels) in enumerate(parts):
        n_local = G.shape[0]
        p_off[i + 1] = p_off[i] + spec.params.size
        s_off[i + 1] = s_off[i] + spec.n_state
        g_off[i + 1] = g_off[i] + n_local
        d_off[i + 1] = d_off[i] + n_local * n_local * (2 if spec.velocity else 1)
        names += labels
    p_all = np.concatenate([spec.params for _, spec, _ in parts]) if n_el else np.zeros(0)
    g_all = np.vstack([G for G, _, _ in parts]) if n_el else np.zeros((0, n_dof))
    vel = np.array([1 if spec.velocity else 0 for _, spec, _ in parts], dtype=np.int64)
    return _Packed(kinds, np.ascontiguousarray(p_all, dtype=float), p_off, s_off,
                   np.ascontiguousarray(g_all, dtype=float), g_off, vel, d_off, tuple(names))


def _support(case: Case):
    """``fixed`` (n,) int64 flags of the support DOFs and ``ybase`` (n,) their amplitudes."""
    n = case.n_dof
    fixed = np.zeros(n, dtype=np.int64)
    ybase = np.zeros(n)
    if case.excitation.base is not None:
        bd, ba = case.excitation.base
        fixed[np.asarray(bd, dtype=int)] = 1
        ybase[np.asarray(bd, dtype=int)] = np.asarray(ba, dtype=float)
    return fixed, ybase


class _State:
    """The integrator state carried between chunks (and from the n run to the 2n run).

    Start: at rest, except that support DOFs start at their prescribed position ``A`` (cosine
    at ``t = 0``, velocity 0, acceleration ``-A w^2``) and the free DOFs at the quasi-static
    position that follows it, ``K_ff q_f = -K_fs A`` with ``K`` including the elements'
    stuck stiffness (a rigid translation when the supports carry the structure), so that the
    run does not begin with a jolt.
    """

    def __init__(self, case: Case, packed: _Packed, F: np.ndarray, w: float = 0.0):
        n = case.n_dof
        K = case.model.K
        fixed, ybase = _support(case)
        fx = np.flatnonzero(fixed)
        fr = np.flatnonzero(fixed == 0)
        self.q = np.zeros(n)
        self.v = np.zeros(n)
        if fx.size:
            self.q[fx] = ybase[fx]
            Ks = K + sum((e.gather.T @ e.linear_stiffness() @ e.gather for e in case.elements),
                         np.zeros_like(K))
            self.q[fr] = -np.linalg.lstsq(Ks[np.ix_(fr, fr)], Ks[np.ix_(fr, fx)] @ ybase[fx], rcond=None)[0]
        self.S = np.zeros(int(packed.s_off[-1]))
        self.D = np.zeros(int(packed.d_off[-1]))
        self.Dref = np.zeros(packed.kinds.size)
        _init_states(*packed.args(), self.q, self.v, self.S, self.D, self.Dref)
        self.fnl = np.zeros(n)
        self.a = np.zeros(n)
        self.rebalance(case, packed, F, w)

    def rebalance(self, case: Case, packed: _Packed, F: np.ndarray, w: float) -> None:
        """Element forces from the states and the acceleration that balances the equations
        at phase 0 (load ``F``), for the present ``q``, ``v``, ``S``."""
        M, C, K = case.model.M, case.model.C, case.model.K
        fixed, ybase = _support(case)
        fx = np.flatnonzero(fixed)
        fr = np.flatnonzero(fixed == 0)
        _element_forces(self.S, packed.s_off, packed.g_all, packed.g_off, self.q, self.fnl)
        self.a[fx] = -w * w * ybase[fx]
        rhs = F - C @ self.v - K @ self.q - self.fnl - M[:, fx] @ self.a[fx]
        self.a[fr] = np.linalg.solve(M[np.ix_(fr, fr)], rhs[fr])

    def copy(self):
        other = object.__new__(_State)
        for k, val in self.__dict__.items():
            setattr(other, k, val.copy())
        return other


def _check_supported(case: Case, switch_off_at=None) -> None:
    if case.excitation.base is not None and switch_off_at is not None:
        raise CaseError(f"{case.path}: a switch-off time is not supported with [excitation] base "
                        f"(support motion cannot stop abruptly)")


FREQ_RANGE = (1e-9, 1e12)      # Hz: beyond, 1/(beta h^2) or h itself leaves double precision


def _check_freq(freq_hz):
    try:
        f = float(freq_hz)
    except (TypeError, ValueError):
        raise CaseError(f"frequency must be a number, got {freq_hz!r}") from None
    if not (f > 0 and math.isfinite(f)):
        raise CaseError(f"frequency must be > 0 Hz, got {freq_hz!r}")
    if not FREQ_RANGE[0] <= f <= FREQ_RANGE[1]:
        raise CaseError(f"frequency {f:g} Hz is outside {FREQ_RANGE[0]:g} .. {FREQ_RANGE[1]:g} Hz: its time "
                        f"step would overflow or underflow the integrator's arithmetic")
    return f


def _amplitudes(case: Case, hist: History, N: int):
    """``h1`` and ``max`` per output over the last ``N + 1`` rows (one period)."""
    q = hist.q[-(N + 1):]
    th = 2.0 * np.pi * np.arange(1, N + 1) / N
    h1, mx = {}, {}
    for name, g in case.analysis.outputs.items():
        xo = q @ g
        x = xo[1:]
        a = 2.0 / N * np.dot(x, np.cos(th))
        b = 2.0 / N * np.dot(x, np.sin(th))
        h1[name] = float(np.hypot(a, b))
        mx[name] = float(np.abs(xo).max())
    return h1, mx


def _integrate(case, freq_hz, opts: TimeSimOptions, steps, periods, check, t_off, state,
               progress, period_offset=0):
    """Run up to ``periods`` periods from ``state`` (updated in place); returns a :class:`Run`."""
    w = 2.0 * np.pi * freq_hz
    N = int(steps)
    n = case.n_dof
    packed = pack_elements(case.elements, n)
    n_f = int(packed.g_off[-1])
    M = np.ascontiguousarray(case.model.M, dtype=float)
    C = np.ascontiguousarray(case.model.C, dtype=float)
    K = np.ascontiguousarray(case.model.K, dtype=float)
    F2 = np.ascontiguousarray(case.excitation.cos_sin, dtype=float)
    rows = N + 1 if check else periods * N + 1
    need = 8.0 * rows * (n + 3 * n_f) + 8.0 * 4 * n * n
    if need > MEMORY_SHARE * machine_memory():
        raise CaseError(f"the time history of {rows} steps needs about {need / 1e9:.3g} GB "
                        f"(this machine has {machine_memory() / 1e9:.3g} GB): fewer steps or periods")
    rec_q = np.zeros((rows, n))
    rec_f = np.zeros((rows, n_f))
    rec_u = np.zeros((rows, n_f))
    rec_v = np.zeros((rows, n_f))
    fixed, ybase = _support(case)
    prev = np.zeros((N if check else 1, n))
    cur = np.zeros_like(prev)
    stats = np.zeros(4, dtype=np.int64)
    t_off = np.inf if t_off is None else float(t_off)
    T = 1.0 / freq_hz
    t0 = time.perf_counter()
    done, status, change, chunk = 0, 0, -1.0, 1
    while done < periods:
        chunk = min(chunk, periods - done)
        tc = time.perf_counter()
        status, pp, ch, t_fail = _march(
            M, C, K, F2, w, t_off, N, done * N, chunk, check, opts.tol, done > 0,
            state.q, state.v, state.a, state.fnl, state.S, state.D, state.Dref,
            *packed.args(), float(opts.alpha), float(opts.newton_tol), int(opts.max_iter),
            int(opts.max_level), float(opts.jump_tol),
            0 if check else 1, rec_q, rec_f, rec_u, rec_v, prev, cur, stats, fixed, ybase)
        done += pp
        if ch >= 0:
            change = ch
        if status < 0:
            raise RuntimeError(
                f"time integration failed at t = {t_fail:.6g} s (period {period_offset + done + 1}) at "
                f"{freq_hz:.6g} Hz: Newton did not converge even with sub-step dt/{2 ** opts.max_level}")
        if status == 1:
            break
        if progress is not None:
            progress(period_offset + done, change)
        per = (time.perf_counter() - tc) / max(pp, 1)
        chunk = int(max(1, min(1000, 0.5 / max(per, 1e-9))))
    secs = time.perf_counter() - t0
    if check:
        t = (period_offset + done - 1) * T + np.arange(N + 1) * (T / N)
    else:
        t = np.arange(rows) * (T / N)
    hist = History(t, rec_q, rec_f, rec_u, packed.names, rec_v)
    h1, mx = _amplitudes(case, hist, N)
    st = {"newton_iterations": int(stats[0]), "substeps": int(stats[1]),
          "refinements": int(stats[2]), "newton_failures": int(stats[3])}
    return Run(freq_hz, N, done, bool(status == 1), float(change), h1, mx, hist, st, secs)


def steady_state(case: Case, freq_hz: float, options: TimeSimOptions | None = None,
                 progress=None) -> Run:
    """Periodic steady state at ``freq_hz`` from rest with ``options.steps`` steps per period.

    Parameters
    ----------
    case : Case
    freq_hz : float
        Excitation frequency, Hz (> 0).
    options : TimeSimOptions, optional
    progress : callable, optional
        ``progress(periods_done, relative_change)`` every chunk of periods (about 0.5 s).

    Returns
    -------
    Run
        ``converged`` says whether the periodicity tolerance was met within ``max_periods``.
    """
    opts = options or TimeSimOptions()
    opts.validate()
    f = _check_freq(freq_hz)
    _check_supported(case)
    state = _State(case, pack_elements(case.elements, case.n_dof), case.excitation.force, 2 * np.pi * f)
    return _integrate(case, f, opts, opts.steps, opts.max_periods, True, None, state, progress)


def transient(case: Case, freq_hz: float, periods: int, switch_off_at: float | None = None,
              options: TimeSimOptions | None = None, progress=None) -> Run:
    """Response from rest over ``periods`` periods; the force is zero after ``switch_off_at`` s.

    Returns
    -------
    Run
        ``history`` holds every step (``periods * steps + 1`` rows); ``h1``/``max`` are of the
        last period.
    """
    opts = options or TimeSimOptions()
    opts.validate()
    f = _check_freq(freq_hz)
    if not (isinstance(periods, (int, np.integer)) and periods >= 1):
        raise CaseError(f"periods must be an integer >= 1, got {periods!r}")
    if switch_off_at is not None and not (switch_off_at >= 0 and math.isfinite(switch_off_at)):
        raise CaseError(f"switch-off time must be >= 0 s, got {switch_off_at!r}")
    _check_supported(case, switch_off_at)
    state = _State(case, pack_elements(case.elements, case.n_dof), case.excitation.force, 2 * np.pi * f)
    return _integrate(case, f, opts, opts.steps, int(periods), False, switch_off_at, state, progress)


def _relative_changes(coarse: Run, fine: Run):
    errs = {}
    for name in fine.h1:
        e = []
        for key in ("h1", "max"):
            y2, y1 = getattr(fine, key)[name], getattr(coarse, key)[name]
            e.append(abs(y2 - y1) / abs(y2) if y2 != 0 else abs(y1 - y2))
        errs[name] = tuple(e)
    est = max((max(e) for e in errs.values()), default=0.0)
    return errs, float(est)


def timesim(case: Case, freq_hz: float, options: TimeSimOptions | None = None,
            periods: int | None = None, switch_off_at: float | None = None,
            progress=None) -> TimeSimResult:
    """Time-domain reference at one frequency with a step-halving error estimate.

    Steady mode (``periods`` None): steady state with ``n = options.steps`` steps per period
    from rest, then continued with ``2 n`` until periodic again.  Transient mode: two runs
    from rest over ``periods`` periods (force off after ``switch_off_at`` s) with ``n`` and
    ``2 n`` steps.  Values reported are the ``2 n`` run's.

    Raises
    ------
    CaseError
        Bad options (non-positive frequency, steps < 8, ...).
    RuntimeError
        Newton failure at the finest sub-step (message gives the time).
    """
    opts = options or TimeSimOptions()
    opts.validate()
    f = _check_freq(freq_hz)
    _check_supported(case, switch_off_at)
    t0 = time.perf_counter()
    if periods is None:
        packed = pack_elements(case.elements, case.n_dof)
        state = _State(case, packed, case.excitation.force, 2 * np.pi * f)
        coarse = _integrate(case, f, opts, opts.steps, opts.max_periods, True, None, state, progress)
        fine = _integrate(case, f, opts, 2 * opts.steps, opts.max_periods, True, None, state,
                          progress, period_offset=coarse.periods)
        mode, conv, total = "steady", coarse.converged and fine.converged, coarse.periods + fine.periods
    else:
        coarse = transient(case, f, periods, switch_off_at, opts, progress)
        fine = transient(case, f, periods, switch_off_at,
                         dataclasses.replace(opts, steps=2 * opts.steps), progress)
        mode, conv, total = "transient", True, int(periods)
    errs, est = _relative_changes(coarse, fine)
    if not all(math.isfinite(v) for v in list(fine.h1.values()) + list(fine.max.values())):
        raise RuntimeError(f"the integration at {f:g} Hz produced non-finite amplitudes (overflow): "
                           f"check the model's units and the frequency")
    return TimeSimResult(f, dict(fine.h1), dict(fine.max), est, errs, int(total), bool(conv), mode,
                         coarse, fine, time.perf_counter() - t0, switch_off_at)
