r"""One seeded march of a law over a period: start sample, linear shortcut and loop closure.

A law element (:class:`elements.base.LawSpec`) is marched from the rest state at a start
sample ``j0`` chosen by a rule on the sampled coordinates ``u`` (N, n):

- ``START_FIRST``: ``j0 = 0`` (memoryless laws);
- ``START_ARGMAX``: ``j0 = argmax_j u_{j,0}`` (a reversal of a 1D motion);
- ``START_PRINCIPAL``: the reversal along the principal direction ``v`` of the centred
  tangential samples ``c_j = u_j - \bar u`` (first ``n_start`` columns),
  ``j0 = argmax_j c_j \cdot v`` with ``v`` the leading eigenvector of ``C = \sum_j c_j c_j^T``
  (closed form for 2 x 2; sign fixed so that its largest component is positive).

Before marching, a law may recognise a period on which it is linear at every sample:

.. math::

    f_j = f_0 + K z_j \quad (j = 1 \dots N)

(a Jenkins slider or a closed friction contact that never slips: ``K = k_t``, ``f_0 = 0``;
an open contact: ``K = 0``, ``f_0 = [0, -N_0]``).  The march from the rest state gives exactly
that (to round-off), so the caller may skip marching and transforming.
"""
from __future__ import annotations

import functools
import math

import numba as nb
import numpy as np

from .kernels import march_body
from .closure import newton_body
from .laws.record import CLOSE_NEWTON, CLOSE_PLAIN, START_ARGMAX, START_FIRST, START_PRINCIPAL  # noqa: F401
from .laws.registry import _law_linear


@nb.njit(cache=True)
def principal_reversal_index(u, n):
    """Reversal sample of the first ``n`` (1 or 2) columns of ``u`` (N, >= n)."""
    N = u.shape[0]
    if n == 1:
        return int(np.argmax(u[:, 0]))
    mean = np.zeros(n)
    for j in range(N):
        for a in range(n):
            mean[a] += u[j, a]
    mean /= N
    v = np.zeros(n)
    if n == 2:
        a11 = 0.0
        a12 = 0.0
        a22 = 0.0
        for j in range(N):
            c0 = u[j, 0] - mean[0]
            c1 = u[j, 1] - mean[1]
            a11 += c0 * c0
            a12 += c0 * c1
            a22 += c1 * c1
        half = 0.5 * (a11 - a22)
        r = math.sqrt(half * half + a12 * a12)
        if half >= 0.0:
            v[0] = half + r
            v[1] = a12
        else:
            v[0] = a12
            v[1] = r - half
        if v[0] == 0.0 and v[1] == 0.0:
            v[0] = 1.0
    else:
        # tangential motions have at most two components; no LAPACK eigensolver compiled in
        raise ValueError("principal reversal needs 1 or 2 columns")
    big = 0
    for a in range(n):
        if abs(v[a]) > abs(v[big]):
            big = a
    sign = 1.0 if v[big] >= 0.0 else -1.0
    best = -np.inf
    j0 = 0
    for j in range(N):
        proj = 0.0
        for a in range(n):
            proj += (u[j, a] - mean[a]) * v[a]
        proj *= sign
        if proj > best:
            best = proj
            j0 = j
    return j0


@nb.njit(cache=True)
def start_sample(rule, n_start, u):
    """Start sample of the march by ``rule`` (module doc) on ``u`` (N, >= n_start)."""
    if rule == START_ARGMAX:
        return int(np.argmax(u[:, 0]))
    if rule == START_PRINCIPAL:
        return principal_reversal_index(u, n_start)
    return 0


linear_shortcut = nb.njit(cache=True)(_law_linear)
linear_shortcut.__doc__ = """True if the law is linear, ``f = f0 + K z``, at every sample of ``z`` (N, nz);
writes ``K`` (n_local, nz) and ``f0`` (n_local,) when it returns True
(:func:`elements.laws.registry._law_linear`)."""


def make_law_march(kind, closure):
    """A march compiled for one law and closure: ``m(p, n_state, n_local, z, dz, start,
    max_passes, tol) -> (f, df, passes)``, the interface of :func:`elements.kernels.march`.

    ``kind`` and ``closure`` are constants of the compiled function (closure cells holding
    plain ints, which numba's cache keys by value), so numba prunes the other laws' branches
    of the inlined dispatch before typing: only this law is compiled, with its step inlined
    into the sample loop.  Use :func:`march_of`, which builds each one once per process.
    """
    kind = int(kind)
    newton = int(closure) == CLOSE_NEWTON

    @nb.njit(cache=True)
    def law_march(p, n_state, n_local, z, dz, start, max_passes, tol):
        if newton:
            return newton_body(kind, p, n_state, n_local, z, dz, start, max_passes, tol)
        return march_body(kind, p, n_state, n_local, z, dz, start, max_passes, tol)

    return law_march


@functools.cache
def march_of(kind, closure):
    """The march of law ``kind`` with closure ``closure`` (:func:`make_law_march`), built once
    per process (the cache holds compiled code only)."""
    return make_law_march(kind, closure)
