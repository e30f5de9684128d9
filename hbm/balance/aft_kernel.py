r"""AFT of one law on DFT matrices: inputs, march, analysis + gather, compiled per closure.

For a law acting on local coordinates ``u = G q`` (``G`` (n_l, n_nl) on the nonlinear DOFs)
with coefficients ``U = X G^T`` (n_coef, n_l):

.. math::

    u = E U,\ \dot u = w\, E' U, \qquad (f, \partial f) = \text{march}(u, \dot u), \qquad
    F \mathrel{+}= (P f)\, G, \qquad
    \frac{\partial F_{k i}}{\partial X_{m j}} \mathrel{+}=
        \sum_{a b} G_{a i}\, \frac{\partial (P f)_{k a}}{\partial U_{m b}}\, G_{b j},

with the march seeded by ``du_{j a}/dU_{m b} = E_{j m} \delta_{a b}`` (and, for velocity
laws, ``d\dot u/dU = w E'``, ``d\dot u/dw = E' U``).  When the law is linear over the whole
period (its own test, :func:`elements.kernels.law_linear_inline`: ``f = f_0 + K z``), the coefficients
follow without marching or transforming, ``P f = K U + f_0 e_0`` (``e_0`` the mean row) and
``\partial (P f)/\partial U = K \otimes I``, because ``P E = I`` on an alias-free grid.

This is the path :class:`hbm.balance.aft.NonlinearForces` takes for law elements when the
transform is the DFT matrix (few harmonics); it returns the same numbers as the generic path
(element ``march`` between transform calls), to round-off.  One compiled function per law
and closure (:func:`make_aft_law`), with the law's step inlined into the march: a single
function dispatching to both closures made numba link and re-optimise both (with their LAPACK
calls) into it, which multiplied the first run's compile time (measured: 16 s -> 59 s CPU for
the default rig), and a march generic in the law compiles every law and calls its step per
sample; the linear test is the law's own too (the dispatch over every law's test, compiled
into a kernel of its own, cost about 1 s of the first run).  The steps avoid BLAS/LAPACK
bindings where loops do.
"""
from __future__ import annotations

import functools

import numba as nb
import numpy as np

from elements.closure import newton_body
from elements.kernels import law_linear_inline, march_body
from elements.law_march import CLOSE_NEWTON, start_sample


@nb.njit(cache=True)
def aft_coords(velocity, G, cols, X, w, E, dE):
    """Coordinates of one law over the period.

    Parameters
    ----------
    velocity : bool
        The law reads velocities too.
    G : ndarray, shape (n_l, n_g)
        The law's gather on the nonlinear DOFs ``cols`` it touches.
    cols : ndarray of int, shape (n_g,)
        Those DOFs' columns in ``X`` (the gather's other columns are zero: a contact of a large
        patch reads 2 of its hundreds of DOFs, and loops over all of them made its cost grow
        with the patch).
    X : ndarray, shape (n_coef, n_nl)
        Coefficients of the nonlinear DOFs.
    w : float
    E, dE : ndarray, shape (N, n_coef)
        Synthesis matrix and its derivative in the phase.

    Returns
    -------
    U : ndarray, shape (n_coef, n_l)
    z : ndarray, shape (N, n_z)
        ``u`` (and ``w du/dphase`` for velocity laws).
    dth : ndarray, shape (N, n_l)
        ``du/dphase`` (zeros unless ``velocity``).
    """
    nc = X.shape[0]
    nl, nn = G.shape
    N = E.shape[0]
    U = np.zeros((nc, nl))
    for a in range(nl):
        for i in range(nn):
            g = G[a, i]
            if g != 0.0:
                c = cols[i]
                for k in range(nc):
                    U[k, a] += X[k, c] * g
    nz = 2 * nl if velocity else nl
    z = np.zeros((N, nz))
    dth = np.zeros((N, nl))
    for j in range(N):          # synthesis by loops: small, and no BLAS binding to compile
        for k in range(nc):
            e = E[j, k]
            de = dE[j, k]
            for a in range(nl):
                z[j, a] += e * U[k, a]
                if velocity:
                    dth[j, a] += de * U[k, a]
    if velocity:
        for j in range(N):
            for a in range(nl):
                z[j, nl + a] = w * dth[j, a]
    return U, z, dth


@nb.njit(cache=True)
def aft_seeds(start_rule, n_start, velocity, seeds, z, dth, w, E, dE):
    """The march's seeds ``dz`` (N, n_z, n_coef n_l + 1; with ``seeds`` False no seed
    columns) and its start sample by the law's rule (:func:`elements.law_march.start_sample`);
    arguments as :func:`aft_coords` and its results."""
    nc = E.shape[1]
    nl = dth.shape[1]
    Pc = nc * nl + 1 if seeds else 0
    dz = np.empty((z.shape[0], z.shape[1], Pc))
    if seeds:
        _seed(E, dE, w, dth, velocity, dz)
    return dz, start_sample(start_rule, n_start, z)


@nb.njit(cache=True)
def _seed(E, dE, w, dth, velocity, dz):
    """The march's seeds ``dz`` (N, n_z, n_coef n_l + 1), every entry written once (no zero
    fill first): ``du_{j a}/dU_{m b} = E_{j m} delta_{a b}``, for velocity laws also
    ``d(du)_{j a}/dU_{m b} = w E'_{j m} delta_{a b}`` and ``d(du)_{j a}/dw = dth_{j a}``
    (``dth`` (N, n_l) the phase derivative of ``u``), and 0 by ``w`` for the displacements."""
    N, nc = E.shape
    nl = dth.shape[1]
    Pc = dz.shape[2]
    for j in range(N):
        for a in range(nl):
            for m in range(nc):
                e = E[j, m]
                for b in range(nl):
                    dz[j, a, m * nl + b] = e if a == b else 0.0
            dz[j, a, Pc - 1] = 0.0
        if velocity:
            for a in range(nl):
                for m in range(nc):
                    de = w * dE[j, m]
                    for b in range(nl):
                        dz[j, nl + a, m * nl + b] = de if a == b else 0.0
                dz[j, nl + a, Pc - 1] = dth[j, a]


@nb.njit(cache=True)
def _gather(G, cols, Fe, dFe, F, J4, dFdw, seeds):
    """``F += Fe G``; with seeds also ``dFdw += dFe[..., -1] G`` and
    ``J4[k, :, m, :] += G^T dFe[k, :, m-block] G``, on the columns ``cols`` of ``G`` (loops
    skip its zeros)."""
    nc = Fe.shape[0]
    nl, nn = G.shape
    for a in range(nl):
        for i in range(nn):
            g = G[a, i]
            if g == 0.0:
                continue
            c = cols[i]
            for k in range(nc):
                F[k, c] += Fe[k, a] * g
                if seeds:
                    dFdw[k, c] += dFe[k, a, dFe.shape[2] - 1] * g
    if not seeds:
        return
    for k in range(nc):
        for a in range(nl):
            for m in range(nc):
                for b in range(nl):
                    d = dFe[k, a, m * nl + b]
                    if d == 0.0:
                        continue
                    for i in range(nn):
                        ga = G[a, i]
                        if ga == 0.0:
                            continue
                        for j in range(nn):
                            gb = G[b, j]
                            if gb != 0.0:
                                J4[k, cols[i], m, cols[j]] += ga * d * gb


@nb.njit(cache=True)
def aft_analyse(P, f, df, G, cols, F, J4, dFdw, seeds):
    """Analysis ``P f``, ``P df`` of a marched period and the gather onto the nonlinear DOFs.

    Parameters
    ----------
    P : ndarray, shape (n_coef, N)
    f : ndarray, shape (N, n_l)
    df : ndarray, shape (N, n_l, P_s)
    G, cols
        The gather on the DOFs it touches (:func:`aft_coords`).
    F, dFdw : ndarray, shape (n_coef, n_nl)
        Accumulated in place (``dFdw`` only with seeds).
    J4 : ndarray, shape (n_coef, n_nl, n_coef, n_nl)
        Accumulated in place (only with seeds).
    seeds : bool
    """
    nc, N = P.shape
    nl = f.shape[1]
    Fe = P @ f
    if seeds:
        Ps = df.shape[2]
        dFe = (P @ np.ascontiguousarray(df).reshape(N, nl * Ps)).reshape(nc, nl, Ps)
    else:
        dFe = np.zeros((nc, nl, 1))
    _gather(G, cols, Fe, dFe, F, J4, dFdw, seeds)


@nb.njit(cache=True)
def aft_linear(U, K, f0, row0, G, cols, F, J4, dFdw, seeds):
    """Gather of a linear period: ``P f = K U + f0 e_0``, ``d(P f)/dU = K (x) I`` (module doc).

    ``row0`` is the row of the mean (harmonic 0), -1 if absent; other arguments as
    :func:`aft_analyse`.
    """
    nc, nl = U.shape
    Pc = nc * nl + 1 if seeds else 1
    Fe = np.zeros((nc, nl))
    dFe = np.zeros((nc, nl, Pc))
    for a in range(nl):
        for b in range(nl):
            kab = K[a, b]
            if kab != 0.0:
                for k in range(nc):
                    Fe[k, a] += kab * U[k, b]
                    if seeds:
                        dFe[k, a, k * nl + b] = kab
        if row0 >= 0:
            Fe[row0, a] += f0[a]
    _gather(G, cols, Fe, dFe, F, J4, dFdw, seeds)


def make_aft_law(kind, closure):
    """The three steps (inputs, march, analysis + gather) compiled for one law and closure:
    ``run(p, n_state, start_rule, n_start, velocity, max_passes, tol, seeds, G, cols, X, w, E, dE,
    P, row0, F, J4, dFdw, f_out) -> passes`` (arguments as :func:`aft_law`; ``f_out`` (N, n_l)
    receives the sampled forces ``f``, or has no rows).

    ``kind`` and ``closure`` are constants of the compiled function (ints in its closure cells,
    which numba's cache keys by value): numba prunes the other laws and the other closure
    before typing, so only this law's march is compiled, its step inlined into the sample
    loop (:func:`elements.law_march.make_law_march`).  Use :func:`aft_of`.
    """
    kind = int(kind)
    newton = int(closure) == CLOSE_NEWTON

    @nb.njit(cache=True)
    def run(p, n_state, start_rule, n_start, velocity, max_passes, tol, seeds,
            G, cols, X, w, E, dE, P, row0, F, J4, dFdw, f_out):
        U, z, dth = aft_coords(velocity, G, cols, X, w, E, dE)
        K = np.zeros((G.shape[0], z.shape[1]))
        f0 = np.zeros(G.shape[0])
        if not velocity and law_linear_inline(kind, p, z, K, f0):
            aft_linear(U, K, f0, row0, G, cols, F, J4, dFdw, seeds)
            if f_out.shape[0]:
                for j in range(z.shape[0]):
                    for a in range(K.shape[0]):
                        f_out[j, a] = f0[a]
                        for b in range(K.shape[1]):
                            f_out[j, a] += K[a, b] * z[j, b]
            return 0
        dz, start = aft_seeds(start_rule, n_start, velocity, seeds, z, dth, w, E, dE)
        if newton:
            f, df, passes = newton_body(kind, p, n_state, G.shape[0], z, dz, start, max_passes, tol)
        else:
            f, df, passes = march_body(kind, p, n_state, G.shape[0], z, dz, start, max_passes, tol)
        aft_analyse(P, f, df, G, cols, F, J4, dFdw, seeds)
        if f_out.shape[0]:      # loops: a slice copy compiles numba's shape-error machinery
            for j in range(f.shape[0]):
                for a in range(f.shape[1]):
                    f_out[j, a] = f[j, a]
        return passes

    return run


# not touched without seeds; strided like a Jacobian inside a bordered matrix (as the seeded
# calls pass it), so that each law's kernel is compiled for one layout only
_NO_J4 = np.zeros((1, 1, 2, 2))[:, :, :, :1]
_NO_F = np.zeros((0, 0))


@functools.cache
def aft_of(kind, closure):
    """:func:`make_aft_law` of ``(kind, closure)``, built once per process (the cache holds
    compiled code only)."""
    return make_aft_law(kind, closure)


def touched(G: np.ndarray):
    """``(G_c, cols)``: the columns of ``G`` (n_l, n_nl) that are not all zero, and their
    indices, the form the kernels take (:func:`aft_coords`)."""
    cols = np.flatnonzero(np.any(G != 0.0, axis=0)).astype(np.int64)
    return np.ascontiguousarray(G[:, cols]), cols


def aft_law(spec, G, X, w, E, dE, P, row0, F, J4=None, dFdw=None, cols=None):
    """Add one law's harmonic forces (and, given ``J4`` and ``dFdw``, exact derivatives).

    Parameters
    ----------
    spec : elements.base.LawSpec
    G : ndarray, shape (n_l, n_nl), or (n_l, n_g) with ``cols``
        The law's gather on the nonlinear DOFs; with ``cols``, only its columns ``cols``
        (:func:`touched`, done once by the caller).
    X : ndarray, shape (n_coef, n_nl)
        Coefficients of the nonlinear DOFs (C-contiguous).
    w : float
    E, dE : ndarray, shape (N, n_coef)
    P : ndarray, shape (n_coef, N)
    row0 : int
        Row of the mean (harmonic 0), -1 if absent.
    F : ndarray, shape (n_coef, n_nl)
    J4 : ndarray, shape (n_coef, n_nl, n_coef, n_nl), optional
    dFdw : ndarray, shape (n_coef, n_nl), optional
        All accumulated in place.  Without them the march carries no seeds at all.
    cols : ndarray of int, shape (n_g,), optional

    Returns
    -------
    passes : int
        Periods marched (0: linear shortcut; negative: the loop did not close).
    """
    if cols is None:
        G, cols = touched(G)
    run = aft_of(spec.kind, spec.closure)
    if J4 is None:
        return run(spec.params, spec.n_state, spec.start_rule, spec.n_start, spec.velocity, spec.max_passes,
                   spec.tol, False, G, cols, X, w, E, dE, P, row0, F, _NO_J4, F, _NO_F)
    return run(spec.params, spec.n_state, spec.start_rule, spec.n_start, spec.velocity, spec.max_passes,
               spec.tol, True, G, cols, X, w, E, dE, P, row0, F, J4, dFdw, _NO_F)


def law_samples(spec, G, cols, X, w, E, dE, P, row0):
    """The sampled forces ``f`` (N, n_l) of one law over the period (arguments as
    :func:`aft_law`, ``cols`` given), from the same compiled function: the element outputs and
    the stuck-contact count need no march compiled apart (it doubled the first run's compile
    time)."""
    f = np.zeros((E.shape[0], G.shape[0]))
    F = np.zeros((E.shape[1], X.shape[1]))
    aft_of(spec.kind, spec.closure)(
        spec.params, spec.n_state, spec.start_rule, spec.n_start, spec.velocity, spec.max_passes,
        spec.tol, False, G, cols, X, w, E, dE, P, row0, F, _NO_J4, F, f)
    return f
