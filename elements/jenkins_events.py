r"""Exact harmonic forces of a Jenkins element from its events, not from samples.

For one coordinate ``u(theta) = sum_m U_m phi_m(theta)`` (``theta = w t``, ``phi`` the real
Fourier basis: 1, ``cos h theta``, ``sin h theta``) the Jenkins force is, between two
reversals ``theta_i`` and ``theta_{i+1}`` (``u'(theta_i) = 0``) along which ``u`` moves in the
direction ``d_i``,

.. math::

    f(\theta) = \begin{cases} f_i + k_t (u(\theta) - u_i) & \theta < \theta^*_i \ \text{(stick)} \\
                               d_i F_s & \theta \ge \theta^*_i \ \text{(slip)} \end{cases}
    \qquad u(\theta^*_i) = u_i + (d_i F_s - f_i) / k_t,

with ``f_{i+1}`` its value at ``theta_{i+1}``.  Its harmonics

.. math::

    F_r = c_r \int_0^{2\pi} f \phi_r \, d\theta
        = c_r \sum_{\text{stick}} \Big[k_t \int_a^b \phi_r \phi_m\, d\theta\, U_m
          + (f_i - k_t u_i) \int_a^b \phi_r \Big] + c_r \sum_{\text{slip}} d_i F_s \int_a^b \phi_r,

``c_r = 1/pi`` (``1/2pi`` for the mean), are integrals of products of trigonometric
functions over the segments: closed forms, so the switches sit exactly where they are (a
sampled AFT moves them to the grid, an error of order ``1/N`` that stiff contacts cannot
average out, and makes ``F(U)`` a staircase on which Newton stalls).  ``f`` is continuous,
so the segment ends contribute nothing to the derivative, and ``u_i = u(theta_i)`` varies
as ``phi(theta_i)`` (``u'(theta_i) = 0``):

.. math::

    \frac{\partial F_r}{\partial U_m} = c_r \sum_{\text{stick}} \Big[k_t \int_a^b \phi_r \phi_m
      + \Big(\frac{\partial f_i}{\partial U_m} - k_t \phi_m(\theta_i)\Big) \int_a^b \phi_r\Big],

with ``df_{i+1}/dU = df_i/dU + kt (phi(theta_{i+1}) - phi(theta_i))`` after a stick segment
and 0 after a slip.  The steady loop: two passes round the reversals from the largest ``u``
with ``f = F_s``; the first pass slips at least once if the loop slips at all (a periodic
slider slips both ways), which forgets the start, and the second is recorded.  A loop that
never slips (stuck for the whole period, a non-unique state) is left to the sampled march.
"""
from __future__ import annotations

import functools
import math

import numba as nb
import numpy as np


def row_kinds(h_of_row):
    """``(h, is_sin)`` of a coefficient layout (rows ``[0], c_1, s_1, c_2, s_2, ...``):
    shapes (nc,), float and bool."""
    h = np.asarray(h_of_row, dtype=float)
    is_sin = np.zeros(h.size, dtype=bool)
    is_sin[1:] = (h[1:] == h[:-1]) & (h[1:] > 0)
    return h, is_sin


@nb.njit(cache=True)
def _phi(h, is_sin, theta, order, out):
    """``d^order phi / dtheta^order`` at ``theta`` into ``out`` (nc,); the rows' harmonics
    ascend, so ``cos h theta``, ``sin h theta`` come by rotation from ``cos theta``,
    ``sin theta`` (two trigonometric calls, not ``2 nc``; error ``~ h eps``)."""
    c1, s1 = math.cos(theta), math.sin(theta)
    c, s, cur = 1.0, 0.0, 0
    q = order % 4
    for r in range(h.size):
        target = int(h[r])
        while cur < target:
            c, s = c * c1 - s * s1, s * c1 + c * s1
            cur += 1
        if is_sin[r]:
            v = s if q == 0 else (c if q == 1 else (-s if q == 2 else -c))
        else:
            v = c if q == 0 else (-s if q == 1 else (-c if q == 2 else s))
        out[r] = v * h[r] ** order if order > 0 else v


@nb.njit(cache=True)
def _dot_phi(h, is_sin, U, theta, order, work):
    """``d^order u / dtheta^order`` at ``theta`` (``work``: scratch of shape (nc,))."""
    _phi(h, is_sin, theta, order, work)
    v = 0.0
    for r in range(h.size):
        v += work[r] * U[r]
    return v


@nb.njit(cache=True)
def _trig_integrals(kmax, a, b, Ic, Is):
    """``Ic[k] = int_a^b cos k theta``, ``Is[k] = int_a^b sin k theta``, ``k = 0 .. kmax``."""
    Ic[0] = b - a
    Is[0] = 0.0
    for k in range(1, kmax + 1):
        Ic[k] = (math.sin(k * b) - math.sin(k * a)) / k
        Is[k] = (math.cos(k * a) - math.cos(k * b)) / k


@nb.njit(cache=True)
def _means(h, is_sin, a, b, Ic, Is, C):
    """``C[r] = int_a^b phi_r`` in closed form."""
    _trig_integrals(Ic.size - 1, a, b, Ic, Is)
    for r in range(h.size):
        hr = int(h[r])
        C[r] = Is[hr] if is_sin[r] else Ic[hr]


@nb.njit(cache=True)
def _phi_diff(h, is_sin, theta, a, out):
    """``phi(theta) - phi(a)`` into ``out`` (nc,) by the sum-to-product identities, exact to
    round-off relative to the difference (not to ``phi``) when ``theta`` is near ``a``; the
    half-sum and half-difference angles rotate harmonic by harmonic as in :func:`_phi`."""
    cm1, sm1 = math.cos(0.5 * (theta + a)), math.sin(0.5 * (theta + a))
    cd1, sd1 = math.cos(0.5 * (theta - a)), math.sin(0.5 * (theta - a))
    cm, sm, cd, sd, cur = 1.0, 0.0, 1.0, 0.0, 0
    for r in range(h.size):
        target = int(h[r])
        while cur < target:
            cm, sm = cm * cm1 - sm * sm1, sm * cm1 + cm * sm1
            cd, sd = cd * cd1 - sd * sd1, sd * cd1 + cd * sd1
            cur += 1
        out[r] = 2.0 * cm * sd if is_sin[r] else -2.0 * sm * sd


@nb.njit(cache=True)
def _stick(h, is_sin, U, kt, f_i, a, b, df_i, gx, gw, Fa, Ja, dphi, phi):
    """Add ``int_a^b f phi_r`` and its ``U``-derivative over a stick segment, ``f = f_i + kt
    (u - u(a))``, by Gauss-Legendre with ``ceil(H (b - a)) + 20`` nodes (the integrand is a
    trigonometric polynomial of degree ``2 H``: exact to round-off), ``u - u(a)`` from
    :func:`_phi_diff` so that a stiff ``kt`` does not amplify the round-off of ``u``."""
    nc = h.size
    n = min(int(math.ceil(h.max() * (b - a))) + 20, gx.shape[0] - 1)
    half, mid = 0.5 * (b - a), 0.5 * (b + a)
    for q in range(n):
        th = mid + half * gx[n, q]
        wq = half * gw[n, q]
        _phi_diff(h, is_sin, th, a, dphi)
        _phi(h, is_sin, th, 0, phi)
        du = 0.0
        for m in range(nc):
            du += U[m] * dphi[m]
        fq = f_i + kt * du
        for r in range(nc):
            pr = wq * phi[r]
            Fa[r] += fq * pr
            for m in range(nc):
                Ja[r, m] += pr * (kt * dphi[m] + df_i[m])


def gauss_table(h_max: int):
    """Gauss-Legendre nodes and weights on [-1, 1]: row ``n`` holds the ``n``-point rule
    (padded with zeros), ``n = 0 .. ceil(2 pi h_max) + 20``; shapes (n_max + 1, n_max)."""
    n_max = int(math.ceil(2.0 * math.pi * max(h_max, 1))) + 20
    gx, gw = np.zeros((n_max + 1, n_max)), np.zeros((n_max + 1, n_max))
    for n in range(1, n_max + 1):
        gx[n, :n], gw[n, :n] = np.polynomial.legendre.leggauss(n)
    return gx, gw


gauss_rules = functools.lru_cache(maxsize=8)(gauss_table)    # one table per H, shared by the elements


@nb.njit(cache=True)
def _root(h, is_sin, U, order, target, lo, hi, neg_lo, work, ref=0.0):
    """Root of ``g = d^order u - target`` (``order = -1``: ``g = u - u(ref) - target``, the
    difference by :func:`_phi_diff`) in ``(lo, hi)`` with ``g(lo) < 0`` iff ``neg_lo``:
    Newton steps kept inside the bracket, bisection otherwise, to the last bit."""
    x = 0.5 * (lo + hi)
    for _ in range(200):
        if order < 0:
            _phi_diff(h, is_sin, x, ref, work)
            v = -target
            for r in range(h.size):
                v += U[r] * work[r]
        else:
            v = _dot_phi(h, is_sin, U, x, order, work) - target
        if v == 0.0:
            return x
        if (v < 0.0) == neg_lo:
            lo = x
        else:
            hi = x
        dv = _dot_phi(h, is_sin, U, x, max(order, 0) + 1, work)
        xn = x - v / dv if dv != 0.0 else lo - 1.0
        if not (lo < xn < hi):
            xn = 0.5 * (lo + hi)
        if abs(xn - x) <= 2e-16 * (1.0 + abs(x)) or hi - lo <= 4e-16 * (1.0 + abs(lo)):
            return xn
        x = xn
    return x


@nb.njit(cache=True)
def reversals(h, is_sin, U, grid):
    """Reversal angles in ``[0, 2 pi)`` (sorted) of ``u = phi U``: sign changes of ``u'`` on a
    grid of ``grid`` points, refined to machine precision."""
    work = np.empty(h.size)
    out = np.empty(grid)
    n = 0
    step = 2.0 * math.pi / grid
    v0 = _dot_phi(h, is_sin, U, 0.0, 1, work)
    for j in range(grid):
        v1 = _dot_phi(h, is_sin, U, (j + 1) * step, 1, work)
        if v0 == 0.0:
            out[n] = j * step
            n += 1
        elif v0 * v1 < 0.0:
            out[n] = _root(h, is_sin, U, 1, 0.0, j * step, (j + 1) * step, v0 < 0.0, work)
            n += 1
        v0 = v1
    return np.sort(out[:n] % (2.0 * math.pi))


@nb.njit(cache=True)
def jenkins_harmonics(h, is_sin, U, kt, fs, grid, gx, gw, F, J):
    """Harmonic force ``F`` (nc,) and ``dF/dU`` (nc, nc) of a Jenkins element (module doc),
    written into ``F`` and ``J``; returns False (``F``, ``J`` untouched) when the loop never
    slips or ``u`` has fewer than two reversals.  ``h``, ``is_sin`` from :func:`row_kinds`,
    ``gx``, ``gw`` from :func:`gauss_table`."""
    th = reversals(h, is_sin, U, grid)
    r = th.size
    if r < 2:
        return False
    nc = h.size
    work = np.empty(nc)
    ui = np.empty(r)
    for i in range(r):
        ui[i] = _dot_phi(h, is_sin, U, th[i], 0, work)
    s = np.argmax(ui)
    kmax = int(h.max())
    Ic, Is = np.empty(kmax + 1), np.empty(kmax + 1)
    C, C2 = np.empty(nc), np.empty(nc)
    phi_n, df = np.empty(nc), np.zeros(nc)
    Fa, Ja = np.zeros(nc), np.zeros((nc, nc))
    f = fs
    slipped = False
    for rec in range(2):
        for j in range(r):
            i, n = (s + j) % r, (s + j + 1) % r
            a, b = th[i], th[n] + (2.0 * math.pi if n <= i else 0.0)
            d = 1.0 if ui[n] > ui[i] else -1.0
            _phi_diff(h, is_sin, th[n], th[i], phi_n)
            step = 0.0
            for q in range(nc):
                step += U[q] * phi_n[q]
            end = f + kt * step
            cut = b
            if d * end > fs:
                cut = _root(h, is_sin, U, -1, (d * fs - f) / kt, a, b, d > 0.0, work, th[i])
            if rec == 1:
                _stick(h, is_sin, U, kt, f, a, cut, df, gx, gw, Fa, Ja, work, C)
                if cut < b:
                    _means(h, is_sin, cut, b, Ic, Is, C2)
                    for p in range(nc):
                        Fa[p] += d * fs * C2[p]
            if cut < b:
                f = d * fs
                df[:] = 0.0
                slipped = True
            else:
                f = end
                for q in range(nc):
                    df[q] += kt * phi_n[q]
        if not slipped:
            return False
    for p in range(nc):
        c = 1.0 / (2.0 * math.pi) if h[p] == 0 else 1.0 / math.pi
        F[p] = c * Fa[p]
        for q in range(nc):
            J[p, q] = c * Ja[p, q]
    return True
