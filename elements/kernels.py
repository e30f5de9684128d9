r"""Law dispatch and the generic AFT march with forward-mode seeds.

Every law is an incremental update ``s_new = Phi(s, z)`` of a state ``s`` (ns,) whose first
``n_local`` entries are the element forces, driven by inputs ``z`` (displacements, and
velocities for rate-dependent laws).  A law kernel returns the local Jacobians
``A = dPhi/ds`` (ns, ns) and ``B = dPhi/dz`` (ns, nz).

The march over one sampled period propagates derivative seeds with respect to any ``P``
parameters (for the AFT: the harmonic coefficients of the element coordinates and ``w``):

.. math::

    \frac{ds_j}{dp} = A_j \frac{ds_{j-1}}{dp} + B_j \frac{dz_j}{dp},

so force and exact Jacobian come from one pass.  Path-dependent laws start at a sample chosen
by the element (a reversal point), from the rest state reached there from ``q = 0``, and march
whole periods until the state at the end of a period equals the state at its start (the
closing pass); the forces of the last period are returned.  The element knows nothing of
harmonics: ``dz`` is just a tangent seed.
"""
from __future__ import annotations

import numba as nb
import numpy as np
from numba.core import types
from numba.extending import overload

from .laws.registry import INITS, LINEARS, STEPS, _law_init, _law_linear, _law_step


# One dispatch text, two compilations: a called kernel for the time integrator
# (hbm.timedomain.timesim, ``kind`` varies per element), and an inlined one for the marches, where a
# constant ``kind`` (elements.law_march.march_of) selects the law's own step at typing time, so
# that only the marched law is compiled, inlined into the sample loop.
law_step = nb.njit(cache=True)(_law_step)
law_init = nb.njit(cache=True)(_law_init)


def law_step_inline(kind, p, s, z, s_new, A, B):
    """:func:`law_step` inlined into compiled callers (no Python implementation)."""
    raise NotImplementedError("called from compiled code only")


def law_init_inline(kind, p, z0, s0, C0):
    """:func:`law_init` inlined into compiled callers (no Python implementation)."""
    raise NotImplementedError("called from compiled code only")


@overload(law_step_inline, inline="always", prefer_literal=True)
def _law_step_of(kind, p, s, z, s_new, A, B):
    """A constant ``kind`` (a literal type) inlines that law's step alone; otherwise the
    dispatch on ``kind``.  Selecting here, at typing, copies one law's code into the march:
    inlining the dispatch copied every law's (pruned only afterwards), which was a third of
    the first run's compile time."""
    if isinstance(kind, types.IntegerLiteral):
        step = STEPS[kind.literal_value]

        def one(kind, p, s, z, s_new, A, B):
            step(p, s, z, s_new, A, B)
        return one
    return _law_step


@overload(law_init_inline, inline="always", prefer_literal=True)
def _law_init_of(kind, p, z0, s0, C0):
    """As :func:`_law_step_of`, for the rest state."""
    if isinstance(kind, types.IntegerLiteral):
        init = INITS[kind.literal_value]

        def one(kind, p, z0, s0, C0):
            init(p, z0, s0, C0)
        return one
    return _law_init


def law_linear_inline(kind, p, z, K, f0):
    """:func:`elements.law_march.linear_shortcut` inlined into compiled callers (no Python
    implementation)."""
    raise NotImplementedError("called from compiled code only")


@overload(law_linear_inline, inline="always", prefer_literal=True)
def _law_linear_of(kind, p, z, K, f0):
    """As :func:`_law_step_of`, for the linear test (a law without one is never linear)."""
    if isinstance(kind, types.IntegerLiteral):
        test = LINEARS[kind.literal_value]
        if test is None:
            def never(kind, p, z, K, f0):
                return False
            return never

        def one(kind, p, z, K, f0):
            return test(p, z, K, f0)
        return one
    return _law_linear


@nb.njit(cache=True)
def _accumulate(M, X, out):
    """``out += M @ X`` skipping zero entries of the small matrix ``M``."""
    for i in range(M.shape[0]):
        for k in range(M.shape[1]):
            m = M[i, k]
            if m != 0.0:
                for c in range(X.shape[1]):
                    out[i, c] += m * X[k, c]


@nb.njit(inline="always")
def propagate(A, B, D, cur, dz, j):
    """``D[1 - cur] = A @ D[cur] + B @ dz[j]`` for the seed buffers ``D`` (2, ns, P), skipping
    zero entries of the small matrices ``A``, ``B`` (all indexed in place: no views)."""
    nxt = 1 - cur
    P = D.shape[2]
    for i in range(A.shape[0]):
        first = True
        for k in range(A.shape[1]):
            m = A[i, k]
            if m != 0.0:
                if first:
                    for c in range(P):
                        D[nxt, i, c] = m * D[cur, k, c]
                    first = False
                else:
                    for c in range(P):
                        D[nxt, i, c] += m * D[cur, k, c]
        for k in range(B.shape[1]):
            m = B[i, k]
            if m != 0.0:
                if first:
                    for c in range(P):
                        D[nxt, i, c] = m * dz[j, k, c]
                    first = False
                else:
                    for c in range(P):
                        D[nxt, i, c] += m * dz[j, k, c]
        if first:
            for c in range(P):
                D[nxt, i, c] = 0.0


@nb.njit(inline="always")
def sample_step(kind, p, z, dz, j, zj, s, s_new, A, B, D, cur, f, df):
    """Advance the state ``s`` (ns,) and the seed buffers ``D`` (2, ns, P) over sample ``j``
    and record forces ``f[j]`` and seeds ``df[j]``; returns the seeds' new buffer index.
    ``A``, ``B`` keep the step's local Jacobians (the Newton closure also uses ``A``);
    ``zj``, ``s_new`` are work arrays."""
    for k in range(zj.shape[0]):
        zj[k] = z[j, k]
    law_step_inline(kind, p, s, zj, s_new, A, B)
    for i in range(s.shape[0]):
        s[i] = s_new[i]
    n_local = f.shape[1]
    for a in range(n_local):
        f[j, a] = s[a]
    P = D.shape[2]
    if P == 0:
        return cur
    propagate(A, B, D, cur, dz, j)
    cur = 1 - cur
    for a in range(n_local):
        for c in range(P):
            df[j, a, c] = D[cur, a, c]
    return cur


@nb.njit(inline="always")
def rest_start(kind, p, z, dz, start, s, D, zj, B):
    """Rest state ``s`` at sample ``start`` and its seeds ``D[0] = C0 dz[start]``
    (``zj`` (nz,) and ``B`` (ns, nz) are work arrays; ``D`` (2, ns, P) is overwritten)."""
    for k in range(zj.shape[0]):
        zj[k] = z[start, k]
    law_init_inline(kind, p, zj, s, B)
    D[:, :, :] = 0.0
    for i in range(B.shape[0]):
        for k in range(B.shape[1]):
            m = B[i, k]
            if m != 0.0:
                for c in range(D.shape[2]):
                    D[0, i, c] += m * dz[start, k, c]


@nb.njit(inline="always")
def march_body(kind, p, n_state, n_local, z, dz, start, max_passes, tol):
    """Body of :func:`march`, inlined into its callers (see :func:`march`).

    The sample loop copies the small state back (no array swaps: each costs reference-count
    updates) and keeps the seeds in two buffers selected by parity; with ``P = 0`` seeds no
    seed work is done at all.
    """
    N, nz = z.shape
    P = dz.shape[2]
    ns = n_state
    s = np.zeros(ns)
    s_new = np.zeros(ns)
    s_begin = np.zeros(ns)
    D = np.zeros((2, ns, P))
    A = np.zeros((ns, ns))
    B = np.zeros((ns, nz))
    zj = np.empty(nz)
    rest_start(kind, p, z, dz, start, s, D, zj, B)
    cur = 0
    f = np.empty((N, n_local))
    df = np.empty((N, n_local, P))
    passes = 0
    closed = False
    while passes < max_passes and not closed:
        passes += 1
        for i in range(ns):
            s_begin[i] = s[i]
        j = start
        for jj in range(N):
            j += 1
            if j >= N:
                j = 0
            cur = sample_step(kind, p, z, dz, j, zj, s, s_new, A, B, D, cur, f, df)
        scale = 0.0
        diff = 0.0
        for i in range(ns):
            scale = max(scale, abs(s[i]), abs(s_begin[i]))
            diff = max(diff, abs(s[i] - s_begin[i]))
        closed = diff <= tol * scale or scale == 0.0
    if not closed:
        passes = -passes
    return f, df, passes


@nb.njit(cache=True)
def march(kind, p, n_state, n_local, z, dz, start, max_passes, tol):
    """March a law over one sampled period with forward-mode derivative seeds.

    Generic in ``kind`` (all laws compiled in); :func:`elements.law_march.march_of` gives the
    same march compiled for one law.

    Parameters
    ----------
    kind : int
        Law id (:mod:`elements.laws.registry`).
    p : ndarray, shape (n_p,)
        Law parameters.
    n_state, n_local : int
        State size and number of force components (the first ``n_local`` state entries).
    z : ndarray, shape (N, nz)
        Inputs at the N samples of one period.
    dz : ndarray, shape (N, nz, P)
        Derivative seeds of the inputs (``P = 0``: forces only).
    start : int
        Sample at which the march starts from the rest state.
    max_passes : int
        Maximum number of periods marched to close the loop.
    tol : float
        Relative closure tolerance on the state after a period.

    Returns
    -------
    f : ndarray, shape (N, n_local)
    df : ndarray, shape (N, n_local, P)
    passes : int
        Periods marched (the last one recorded); ``-passes`` if the loop did not close.
    """
    return march_body(kind, p, n_state, n_local, z, dz, start, max_passes, tol)
