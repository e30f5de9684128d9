r"""Exact harmonic forces of a (t1, n) point contact from its events, not from samples.

For the coordinates ``u_t(theta)``, ``u_n(theta)`` (trigonometric polynomials,
``theta = w t``) the ``friction3d`` law with one tangential direction is, with the normal load
``N = N_0 + k_n u_n``,

.. math::

    f_n = \max(N, 0) - \max(N_0, 0), \qquad
    f_t = \begin{cases} 0 & N \le 0 \ \text{(open)} \\
          f_a + k_t (u_t - u_t(a)) & \text{stick, from } (a, f_a) \\
          d\, \mu N & \text{slip in direction } d = \pm 1 \end{cases}

and its state changes at events, roots of trigonometric polynomials located to machine
precision: re-contact (``N`` rises through 0) into stick with ``f_a = 0``, or straight into
slip when ``k_t |u_t'| > \mu N'`` there; slip onset where ``g_d = f_t - d \mu N`` reaches 0;
the end of a slip where ``s_d = d k_t u_t' - \mu N'`` falls through 0 (the slider stops), into
stick with ``f_a = d \mu N(a)``; opening where ``N`` falls through 0.  Between the events
``f_t`` and ``f_n`` are trigonometric polynomials of degree ``2 H`` times ``phi_r``, so their
harmonics ``F_r = c_r \int f \phi_r`` (``c_r = 1/pi``, ``1/2pi`` for the mean) are integrated
exactly by Gauss-Legendre rules.  ``f`` is continuous at every event, so the events' motion
adds nothing to ``dF/dU`` except through the start of a stick segment:

.. math::

    \frac{\partial f}{\partial U} = k_t \big(\phi(\theta) - \phi(a)\big)_t + D_a, \qquad
    D_a = \begin{cases} d \mu k_n \phi(a)_n & \text{after a slip} \\
          k_t k_n u_t'(a) \phi(a)_n / N'(a) & \text{after re-contact} \end{cases}

(after a slip the terms in ``da/dU`` cancel because ``s_d(a) = 0``; after re-contact
``da/dU = -k_n \phi(a)_n / N'(a)``).  Steady loop: a contact that opens forgets its state at
re-contact; one that stays closed has a stuck periodic state with slider ``s`` exactly when
``M_+ = \max (k_t u_t - \mu N) \le m_- = \min (k_t u_t + \mu N)`` (``k_t s`` in between).
Then the slider at rest (``s = 0``) is kept if admissible, as the sampled march keeps it (the
caller marches: the loop is linear), otherwise the nearest end of the interval, in closed form
(``f_t = k_t (u_t - s)``, ``ds/dU`` by the envelope theorem).  When ``M_+ > m_-`` the contact
must slip: two passes from ``argmax (k_t u_t - \mu N)`` with ``f = \mu N`` there, the first
forgets that start at its first slip, the second is integrated.
"""
from __future__ import annotations

import math

import numba as nb
import numpy as np

from .jenkins_events import _dot_phi, _phi, _phi_diff, _root

OPEN, STICK, SLIP_P, SLIP_N = 0, 1, 2, 3


@nb.njit(cache=True)
def _diff_value(h, is_sin, V, theta, a, c0, work):
    """``V . (phi(theta) - phi(a)) + c0`` (the difference exact near ``a``)."""
    _phi_diff(h, is_sin, theta, a, work)
    v = c0
    for r in range(h.size):
        v += V[r] * work[r]
    return v


@nb.njit(cache=True)
def _extreme(h, is_sin, V, grid, sign, work):
    """``(theta, value)`` of the largest (``sign = 1``) or smallest (``-1``) value of
    ``V . phi``: the grid's best, refined on the root of the derivative beside it."""
    step = 2.0 * math.pi / grid
    best, jb = -np.inf, 0
    for j in range(grid):
        v = sign * _dot_phi(h, is_sin, V, j * step, 0, work)
        if v > best:
            best, jb = v, j
    x = jb * step
    for lo, hi in ((x - step, x), (x, x + step)):
        dlo = sign * _dot_phi(h, is_sin, V, lo, 1, work)
        dhi = sign * _dot_phi(h, is_sin, V, hi, 1, work)
        if dlo > 0.0 >= dhi:
            r = _root(h, is_sin, V, 1, 0.0, lo, hi, sign < 0, work)
            v = sign * _dot_phi(h, is_sin, V, r, 0, work)
            if v > best:
                best, x = v, r
    return x % (2.0 * math.pi), sign * best


@nb.njit(cache=True)
def _segment(h, is_sin, Ut, Un, p, state, a, fa, Da, lo, hi, gx, gw, phi, dphi, F, J):
    """Add ``int_lo^hi f phi_r`` and its ``U``-derivative for one segment of ``state`` into
    ``F`` (nc, 2) and ``J`` (nc, 2, nc, 2); ``Da`` (nc, 2) the stick start's derivative."""
    kt, kn, mu, N0 = p[0], p[1], p[2], p[3]
    nc = h.size
    n = min(int(math.ceil(h.max() * (hi - lo))) + 20, gx.shape[0] - 1)
    half, mid = 0.5 * (hi - lo), 0.5 * (hi + lo)
    d = 1.0 if state == SLIP_P else -1.0
    for q in range(n):
        th = mid + half * gx[n, q]
        wq = half * gw[n, q]
        _phi(h, is_sin, th, 0, phi)
        un = 0.0
        for m in range(nc):
            un += Un[m] * phi[m]
        Nq = N0 + kn * un
        if state == STICK:
            _phi_diff(h, is_sin, th, a, dphi)
            du = 0.0
            for m in range(nc):
                du += Ut[m] * dphi[m]
            ft = fa + kt * du
        else:
            ft = d * mu * Nq
        for r in range(nc):
            pr = wq * phi[r]
            F[r, 0] += ft * pr
            F[r, 1] += Nq * pr
            for m in range(nc):
                J[r, 1, m, 1] += pr * kn * phi[m]
                if state == STICK:
                    J[r, 0, m, 0] += pr * (kt * dphi[m] + Da[m, 0])
                    J[r, 0, m, 1] += pr * Da[m, 1]
                else:
                    J[r, 0, m, 1] += pr * d * mu * kn * phi[m]


@nb.njit(cache=True)
def _stuck_at_edge(h, is_sin, Ut, Un, p, th, sign, F, J, work):
    """Closed loop stuck with the slider at the end ``k_t s = k_t u_t(th) - sign mu N(th)``
    of its admissible interval (module doc): ``F`` (nc, 2), ``J`` (nc, 2, nc, 2) written."""
    kt, kn, mu, N0 = p[0], p[1], p[2], p[3]
    nc = h.size
    _phi(h, is_sin, th, 0, work)
    ks = kt * _dot_phi(h, is_sin, Ut, th, 0, work) - sign * mu * (N0 + kn * _dot_phi(h, is_sin, Un, th, 0, work))
    _phi(h, is_sin, th, 0, work)
    for r in range(nc):
        F[r, 0] = kt * Ut[r]
        F[r, 1] = kn * Un[r]
        J[r, 0, r, 0] = kt
        J[r, 1, r, 1] = kn
    if h[0] != 0:
        return
    F[0, 0] -= ks
    F[0, 1] += N0 - max(N0, 0.0)
    for m in range(nc):
        J[0, 0, m, 0] -= kt * work[m]
        J[0, 0, m, 1] += sign * mu * kn * work[m]


CLOSE, OPENING, ONSET_P, ONSET_N, STOP = 0, 1, 2, 3, 4


@nb.njit(cache=True)
def _crossing(h, is_sin, V, order, target, x, y, vx, vy, rising, work, ref=0.0):
    """Where ``g`` (:func:`elements.jenkins_events._root`'s form) passes ``target`` upwards
    (``rising``) or downwards in ``(x, y]``: ``x`` itself if it is past already at ``x``
    (round-off at an event just found), inf if not past at ``y``."""
    s = 1.0 if rising else -1.0
    if not s * (vy - target) > 0.0:
        return np.inf
    if s * (vx - target) > 0.0:
        return x
    return _root(h, is_sin, V, order, target, x, y, rising, work, ref)


@nb.njit(cache=True)
def _next_event(h, is_sin, Un, Vp, Vn, p, state, a, fa, x, y, work):
    """``(theta, kind)`` of the first event of ``state`` in ``(x, y]`` (its event functions
    compared at the ends, the root refined to machine precision), or ``(inf, -1)``."""
    kn, mu, N0 = p[1], p[2], p[3]
    tn = -N0 / kn
    nx, ny = _dot_phi(h, is_sin, Un, x, 0, work), _dot_phi(h, is_sin, Un, y, 0, work)
    best = _crossing(h, is_sin, Un, 0, tn, x, y, nx, ny, state == OPEN, work)
    kind = (CLOSE if state == OPEN else OPENING) if best < np.inf else -1
    if state == OPEN:
        return best, kind
    if state == STICK:
        Na = N0 + kn * _dot_phi(h, is_sin, Un, a, 0, work)
        for d in (1.0, -1.0):
            V = Vp if d > 0 else Vn
            c0 = fa - d * mu * Na
            gx_, gy = _diff_value(h, is_sin, V, x, a, c0, work), _diff_value(h, is_sin, V, y, a, c0, work)
            r = _crossing(h, is_sin, V, -1, -c0, x, y, gx_ - c0, gy - c0, d > 0, work, a)
            # no slip at the stick's start: the transitions into stick exclude it, so a root
            # there is the round-off of the event that started it (a touch, not a crossing)
            if r < best and r > a + 4e-16 * (1.0 + abs(a)):
                best, kind = r, (ONSET_P if d > 0 else ONSET_N)
        return best, kind
    # slip d: the slider stops where s_d = d kt u_t' - mu kn u_n' falls through 0
    W = Vp if state == SLIP_P else Vn
    sx, sy = _dot_phi(h, is_sin, W, x, 1, work), _dot_phi(h, is_sin, W, y, 1, work)
    r = _crossing(h, is_sin, W, 1, 0.0, x, y, sx, sy, state == SLIP_N, work)
    if r < best:
        best, kind = r, STOP
    return best, kind


@nb.njit(cache=True)
def _stick_from_slip(h, is_sin, Un, p, d, te, Da, work):
    """Stick start after a slip in direction ``d`` ends at ``te``: ``f_a = d mu N(te)``,
    ``Da = d mu kn phi(te)`` on ``n`` (module doc); returns ``f_a``."""
    kn, mu, N0 = p[1], p[2], p[3]
    _phi(h, is_sin, te, 0, work)
    for m in range(h.size):
        Da[m, 0] = 0.0
        Da[m, 1] = d * mu * kn * work[m]
    return d * mu * (N0 + kn * _dot_phi(h, is_sin, Un, te, 0, work))


@nb.njit(cache=True)
def _recontact(h, is_sin, Ut, Un, p, te, Da, work):
    """State entered at re-contact ``te``: slip when ``kt |u_t'| > mu N'``, else stick with
    ``f_a = 0`` and ``Da = kt u_t' phi / u_n'`` on ``n`` (module doc)."""
    kt, kn, mu = p[0], p[1], p[2]
    vt = kt * _dot_phi(h, is_sin, Ut, te, 1, work)
    vn = _dot_phi(h, is_sin, Un, te, 1, work)
    if vt > mu * kn * vn:
        return SLIP_P
    if vt < -mu * kn * vn:
        return SLIP_N
    _phi(h, is_sin, te, 0, work)
    for m in range(h.size):
        Da[m, 0] = 0.0
        Da[m, 1] = vt * work[m] / vn if vn > 0.0 else 0.0
    return STICK


@nb.njit(cache=True)
def _start(h, is_sin, Un, Vp, Vn, p, grid, F, J, Ut, work):
    """``(theta0, state, f_a, forgotten)`` of the two passes, or ``state = -1`` when the
    forces are final (a stuck loop at an end of its interval, written into ``F``, ``J``) and
    ``-2`` when the caller should march (stuck with the slider at rest)."""
    kn, mu, N0 = p[1], p[2], p[3]
    step = 2.0 * math.pi / grid
    nmin, jmin = np.inf, 0
    for j in range(grid):
        v = _dot_phi(h, is_sin, Un, j * step, 0, work)
        if v < nmin:
            nmin, jmin = v, j
    if N0 + kn * nmin <= 0.0:
        return jmin * step, OPEN, 0.0, True
    thp, Mp = _extreme(h, is_sin, Vp, grid, 1.0, work)
    thm, mm = _extreme(h, is_sin, Vn, grid, -1.0, work)
    Mp -= mu * N0
    mm += mu * N0
    if Mp <= mm:
        if Mp <= 0.0 <= mm:
            return 0.0, -2, 0.0, False
        if Mp > 0.0:
            _stuck_at_edge(h, is_sin, Ut, Un, p, thp, 1.0, F, J, work)
        else:
            _stuck_at_edge(h, is_sin, Ut, Un, p, thm, -1.0, F, J, work)
        return 0.0, -1, 0.0, False
    return thp, STICK, mu * (N0 + kn * _dot_phi(h, is_sin, Un, thp, 0, work)), False


@nb.njit(cache=True)
def contact_harmonics(h, is_sin, U, p, grid, gx, gw, F, J):
    """Harmonic forces ``F`` (nc, 2) and ``dF/dU`` (nc, 2, nc, 2) of a (t1, n) contact
    (module doc) from the coefficients ``U`` (nc, 2) of ``(u_t, u_n)``; ``p = [kt, kn, mu,
    N0]`` (``N0`` net of the gap).  Returns False (``F``, ``J`` then meaningless) when the
    caller should march the law: a loop stuck with the slider at rest, or events the grid of
    ``grid`` cells per period could not sort out."""
    kt, kn, mu, N0 = p[0], p[1], p[2], p[3]
    nc = h.size
    Ut, Un = np.ascontiguousarray(U[:, 0]), np.ascontiguousarray(U[:, 1])
    Vp, Vn = kt * Ut - mu * kn * Un, kt * Ut + mu * kn * Un
    work, phi, dphi = np.empty(nc), np.empty(nc), np.empty(nc)
    Da = np.zeros((nc, 2))
    F[:, :] = 0.0
    J[:, :, :, :] = 0.0
    th0, state, fa, forgotten = _start(h, is_sin, Un, Vp, Vn, p, grid, F, J, Ut, work)
    if state < 0:
        return state == -1
    a = th0
    step = 2.0 * math.pi / grid
    t_rec = th0 + 2.0 * math.pi
    x = seg = th0
    for j in range(2 * grid):
        y = th0 + (j + 1) * step
        for _ in range(32):
            te, kind = _next_event(h, is_sin, Un, Vp, Vn, p, state, a, fa, x, y, work)
            if kind < 0:
                break
            if te > t_rec and state != OPEN:
                _segment(h, is_sin, Ut, Un, p, state, a, fa, Da, max(seg, t_rec), te, gx, gw, phi, dphi, F, J)
            if kind == CLOSE:
                state = _recontact(h, is_sin, Ut, Un, p, te, Da, work)
                a, fa = te, 0.0
            elif kind == OPENING:
                state = OPEN
            elif kind == STOP:
                fa = _stick_from_slip(h, is_sin, Un, p, 1.0 if state == SLIP_P else -1.0, te, Da, work)
                state, a = STICK, te
            else:
                d = 1.0 if kind == ONSET_P else -1.0
                state = SLIP_P if d > 0 else SLIP_N
                if d * _dot_phi(h, is_sin, Vp if d > 0 else Vn, te, 1, work) <= 0.0:
                    fa = _stick_from_slip(h, is_sin, Un, p, d, te, Da, work)      # a slip of no length
                    state, a = STICK, te
            forgotten = forgotten or te < t_rec       # every event sets the state anew
            seg = x = te
        else:
            return False
        x = y
        if j == grid - 1 and not forgotten:
            return False
    if state != OPEN:
        _segment(h, is_sin, Ut, Un, p, state, a, fa, Da, max(seg, t_rec), t_rec + 2.0 * math.pi, gx, gw,
                 phi, dphi, F, J)
    for r in range(nc):
        c = 1.0 / (2.0 * math.pi) if h[r] == 0 else 1.0 / math.pi
        for i in range(2):
            F[r, i] *= c
            for m in range(nc):
                for k in range(2):
                    J[r, i, m, k] *= c
    if h[0] == 0:
        F[0, 1] -= max(N0, 0.0)
    return True


def compile_kernels() -> None:
    """Compile the event-based AFT kernels (this module's and the Jenkins element's) once, on
    a small slipping loop, so that a run which switches to them (``hbm.analyses.aft_retry``)
    does not compile mid-run; ``make setup`` calls it."""
    from .jenkins_events import gauss_table, jenkins_harmonics, row_kinds
    h, s = row_kinds(np.array([0, 1, 1, 2, 2, 3, 3]))
    gx, gw = gauss_table(3)
    U = np.zeros((h.size, 2))
    U[1] = [1.0, 0.2]
    F, J = np.empty((h.size, 2)), np.empty((h.size, 2, h.size, 2))
    contact_harmonics(h, s, U, np.array([10.0, 1.0, 0.3, 1.0]), 64, gx, gw, F, J)
    jenkins_harmonics(h, s, np.ascontiguousarray(U[:, 0]), 10.0, 0.3, 64, gx, gw, F[:, 0].copy(),
                      np.empty((h.size, h.size)))
