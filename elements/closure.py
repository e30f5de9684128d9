r"""Periodic closure of a path-dependent law by Newton on the state at the start sample.

:func:`elements.kernels.march` closes a hysteresis loop by marching whole periods until the
state repeats.  That converges geometrically at the rate of the period map's contraction,
which for 2D friction loops near the stick/slip boundary (little slip per cycle, or slip in
a nearly fixed direction) is close to one: thousands of passes.  Here the period map
``s_end = Phi_T(s_begin)`` is differentiated along with the march, ``M = ds_end/ds_begin``
(``M_T = A_N ... A_1``, ns x ns), and the start state is updated by Newton,

.. math::

    s_{begin} \leftarrow s_{begin} + (I - M)^{-1} (s_{end} - s_{begin}),

which is exact in one step while the stick/slip pattern of the samples does not change.
The parameter seeds obey the same affine map, ``ds_end = M ds_begin + g``, so the same
update gives the seeds of the periodic solution, ``ds* = (I - M)^{-1} g``.

Rules (so that the physical transient from the rest state is kept where it decides):

- plain passes first; Newton only once plain passes contract slowly (residual ratio above
  0.3 after at least two passes).  A loop that shakes down to pure stick after one slipping
  pass keeps that stick state (the periodic state is not unique there: any stuck slider
  position repeats; Newton from the first pass would jump to another one);
- when the state has closed but the seeds have not (a direction that contracts slowly, e.g.
  the transverse force of a contact slipping along a line: the state is exactly periodic
  after one pass, its derivative is not), one Newton update of the seeds alone and a last
  pass give the derivative of the periodic solution rather than of a finite number of passes;
- when ``I - M`` is singular (1-norm condition number > 1e12 in the state's own scales, so
  that a force state beside a displacement state does not count as singular: a direction
  that never slips keeps its start value, the rest-state convention), plain passes are used;
- when a pass does not reduce the residual (a Newton step across a change of the stick/slip
  pattern), the next ``NEWTON_RETRY`` passes are plain, then Newton is tried again.  (It was
  turned off for good: a friction3d contact of an FE patch barely slipping in 2D, whose
  transverse force relaxes by 1.2e-4 per period, then marched its 1000 periods unclosed at
  15 % of the evaluations.)

The forces of the last pass, which starts from the closed state, are returned.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from .kernels import rest_start, sample_step

NEWTON_RETRY = 8          # plain passes after a pass that did not reduce the residual


@nb.njit(cache=True)
def _solve_small(K, R):
    """Solve ``K Y = R`` (K (n, n), R (n, m)) by Gauss-Jordan elimination with partial pivoting,
    and the 1-norm condition number ``||K||_1 ||K^{-1}||_1`` (inf if ``K`` is singular).

    The closure's systems have the state size (n <= 5): hand-written elimination instead of
    LAPACK, whose numba bindings (cond, solve) cost ~12 s of compile time.
    """
    n = K.shape[0]
    m = R.shape[1]
    W = np.zeros((n, n + m + n))
    for i in range(n):
        for j in range(n):
            W[i, j] = K[i, j]
        for j in range(m):
            W[i, n + j] = R[i, j]
        W[i, n + m + i] = 1.0
    for c in range(n):
        piv = c
        for r in range(c + 1, n):
            if abs(W[r, c]) > abs(W[piv, c]):
                piv = r
        if W[piv, c] == 0.0:
            return np.zeros((n, m)), np.inf
        if piv != c:
            for j in range(W.shape[1]):
                t = W[c, j]
                W[c, j] = W[piv, j]
                W[piv, j] = t
        d = 1.0 / W[c, c]
        for j in range(W.shape[1]):
            W[c, j] *= d
        for r in range(n):
            if r != c and W[r, c] != 0.0:
                f = W[r, c]
                for j in range(W.shape[1]):
                    W[r, j] -= f * W[c, j]
    norm_k = 0.0
    norm_inv = 0.0
    for j in range(n):
        ck = 0.0
        ci = 0.0
        for i in range(n):
            ck += abs(K[i, j])
            ci += abs(W[i, n + m + j])
        norm_k = max(norm_k, ck)
        norm_inv = max(norm_inv, ci)
    return W[:, n:n + m].copy(), norm_k * norm_inv


@nb.njit(cache=True)
def _close_or_update(s, s_begin, ds, ds_begin, Ms, tol, passes, last_res, newton_wait, seeds_fixed):
    """The closure rules (module doc) after a pass: closed, or ``s`` / ``ds`` updated in place.

    ``s`` (ns,), ``ds`` (ns, P) at the end of the pass, ``s_begin``, ``ds_begin`` at its start,
    ``Ms`` (ns, ns) the period map's derivative; ``newton_wait`` plain passes are left before
    Newton may be tried again.  Returns ``(closed, last_res, newton_wait, seeds_fixed)``.
    Law-independent, so compiled once (not inlined into every law's march).
    """
    ns, P = ds.shape
    scale = 0.0
    res = 0.0
    for i in range(ns):
        scale = max(scale, abs(s[i]), abs(s_begin[i]))
        res = max(res, abs(s[i] - s_begin[i]))
    dscale = 0.0
    dres = 0.0
    for i in range(ns):
        for c in range(P):
            dscale = max(dscale, abs(ds[i, c]), abs(ds_begin[i, c]))
            dres = max(dres, abs(ds[i, c] - ds_begin[i, c]))
    state_closed = res <= tol * scale or scale == 0.0
    seeds_closed = dres <= 1e3 * tol * dscale or dscale == 0.0
    if state_closed and (seeds_closed or seeds_fixed):
        return True, last_res, newton_wait, seeds_fixed
    slow = passes >= 2 and res > 0.3 * last_res
    if not state_closed:
        if res >= last_res and passes > 2:
            newton_wait = NEWTON_RETRY
        elif newton_wait > 0:
            newton_wait -= 1
        last_res = res
        if not (slow and newton_wait == 0):
            return False, last_res, newton_wait, seeds_fixed
    # (I - M) Y = R: R = ds - ds_begin (state closed, seeds not: the affine seed map solved once,
    # then re-recorded), or R = [s - s_begin, ds - ds_begin] (Newton on state and seeds);
    # explicit loops, not array expressions: they cost seconds of compile time
    # solved in the state's own scales, sigma_i = max(|s_i|, |s_begin_i|) (1 where both are 0):
    # D^-1 (I - M) D (D^-1 Y) = D^-1 R, so that the condition number does not mix units (a
    # force state beside a displacement state: kt = 1e6 N/m made I - M look singular, 1e14)
    o = 0 if state_closed else 1
    sig = np.empty(ns)
    for i in range(ns):
        sig[i] = max(abs(s[i]), abs(s_begin[i]))
        if sig[i] == 0.0:
            sig[i] = 1.0
    K = np.empty((ns, ns))
    R = np.empty((ns, P + o))
    for i in range(ns):
        for k in range(ns):
            K[i, k] = ((1.0 if i == k else 0.0) - Ms[i, k]) * sig[k] / sig[i]
        if o == 1:
            R[i, 0] = (s[i] - s_begin[i]) / sig[i]
        for c in range(P):
            R[i, o + c] = (ds[i, c] - ds_begin[i, c]) / sig[i]
    Y, cond = _solve_small(K, R)
    for i in range(ns):
        for c in range(P + o):
            Y[i, c] *= sig[i]
    if state_closed:
        if cond > 1e12:
            return True, last_res, newton_wait, seeds_fixed
        for i in range(ns):
            for c in range(P):
                ds[i, c] = ds_begin[i, c] + Y[i, c]
        return False, last_res, newton_wait, True
    if cond <= 1e12:
        for i in range(ns):
            s[i] = s_begin[i] + Y[i, 0]
            for c in range(P):
                ds[i, c] = ds_begin[i, c] + Y[i, 1 + c]
    return False, last_res, newton_wait, seeds_fixed


@nb.njit(inline="always")
def newton_body(kind, p, n_state, n_local, z, dz, start, max_passes, tol):
    """Body of :func:`march_newton`, inlined into its callers.

    The period map's derivative ``M`` is propagated like the seeds (``M_j = A_j M_{j-1}``), in
    two parity buffers; the state is copied back (no array swaps).
    """
    N, nz = z.shape
    P = dz.shape[2]
    ns = n_state
    s = np.zeros(ns)
    s_new = np.zeros(ns)
    s_begin = np.zeros(ns)
    D = np.zeros((2, ns, P))
    ds_begin = np.zeros((ns, P))
    MS = np.zeros((2, ns, ns))
    A = np.zeros((ns, ns))
    B = np.zeros((ns, nz))
    zj = np.empty(nz)
    rest_start(kind, p, z, dz, start, s, D, zj, B)
    cur = 0
    f = np.empty((N, n_local))
    df = np.empty((N, n_local, P))
    passes = 0
    closed = False
    last_res = np.inf
    newton_wait = 0
    seeds_fixed = False
    while passes < max_passes and not closed:
        passes += 1
        for i in range(ns):
            s_begin[i] = s[i]
            for c in range(P):
                ds_begin[i, c] = D[cur, i, c]
        mc = 0
        for i in range(ns):
            for c in range(ns):
                MS[0, i, c] = 1.0 if i == c else 0.0
        j = start
        for jj in range(N):
            j += 1
            if j >= N:
                j = 0
            cur = sample_step(kind, p, z, dz, j, zj, s, s_new, A, B, D, cur, f, df)
            # M <- A M (A is small and sparse)
            mn = 1 - mc
            for i in range(ns):
                for c in range(ns):
                    MS[mn, i, c] = 0.0
                for k in range(ns):
                    m = A[i, k]
                    if m != 0.0:
                        for c in range(ns):
                            MS[mn, i, c] += m * MS[mc, k, c]
            mc = mn
        closed, last_res, newton_wait, seeds_fixed = _close_or_update(
            s, s_begin, D[cur], ds_begin, MS[mc], tol, passes, last_res, newton_wait, seeds_fixed)
    if not closed:
        passes = -passes
    return f, df, passes


@nb.njit(cache=True)
def march_newton(kind, p, n_state, n_local, z, dz, start, max_passes, tol):
    """Same interface as :func:`elements.kernels.march`, with Newton closure (module doc).

    Generic in ``kind``; :func:`elements.law_march.march_of` gives it compiled for one law.
    """
    return newton_body(kind, p, n_state, n_local, z, dz, start, max_passes, tol)
