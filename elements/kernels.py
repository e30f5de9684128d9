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

from .kinds import JENKINS, CUBIC, FRICTION3D, COULOMB_STATIC_KINETIC, COULOMB_REGULARISED
from .laws.jenkins import jenkins_step, jenkins_init
from .laws.cubic import cubic_step, cubic_init
from .laws.friction3d import friction3d_step, friction3d_init
from .laws.coulomb import coulomb_sk_step, coulomb_sk_init, coulomb_reg_step, coulomb_reg_init


@nb.njit(cache=True)
def law_step(kind, p, s, z, s_new, A, B):
    """Dispatch one incremental update to the law ``kind`` (see module docstring)."""
    if kind == JENKINS:
        jenkins_step(p, s, z, s_new, A, B)
    elif kind == CUBIC:
        cubic_step(p, s, z, s_new, A, B)
    elif kind == FRICTION3D:
        friction3d_step(p, s, z, s_new, A, B)
    elif kind == COULOMB_STATIC_KINETIC:
        coulomb_sk_step(p, s, z, s_new, A, B)
    elif kind == COULOMB_REGULARISED:
        coulomb_reg_step(p, s, z, s_new, A, B)
    else:
        raise ValueError("unknown law kind")


@nb.njit(cache=True)
def law_init(kind, p, z0, s0, C0):
    """Rest state ``s0`` at input ``z0`` reached from ``q = 0``, and ``C0 = ds0/dz0``."""
    if kind == JENKINS:
        jenkins_init(p, z0, s0, C0)
    elif kind == CUBIC:
        cubic_init(p, z0, s0, C0)
    elif kind == FRICTION3D:
        friction3d_init(p, z0, s0, C0)
    elif kind == COULOMB_STATIC_KINETIC:
        coulomb_sk_init(p, z0, s0, C0)
    elif kind == COULOMB_REGULARISED:
        coulomb_reg_init(p, z0, s0, C0)
    else:
        raise ValueError("unknown law kind")


@nb.njit(cache=True)
def _accumulate(M, X, out):
    """``out += M @ X`` skipping zero entries of the small matrix ``M``."""
    for i in range(M.shape[0]):
        for k in range(M.shape[1]):
            m = M[i, k]
            if m != 0.0:
                for c in range(X.shape[1]):
                    out[i, c] += m * X[k, c]


@nb.njit(cache=True)
def _propagate(A, B, ds, dz, j, out):
    """``out = A @ ds + B @ dz[j]`` skipping zero entries of the small matrices ``A``, ``B``
    (``dz`` indexed in place: no per-sample view)."""
    P = ds.shape[1]
    for i in range(A.shape[0]):
        for c in range(P):
            out[i, c] = 0.0
        for k in range(A.shape[1]):
            m = A[i, k]
            if m != 0.0:
                for c in range(P):
                    out[i, c] += m * ds[k, c]
        for k in range(B.shape[1]):
            m = B[i, k]
            if m != 0.0:
                for c in range(P):
                    out[i, c] += m * dz[j, k, c]


@nb.njit(cache=True)
def rest_start(kind, p, z, dz, start, s, ds, zj, B):
    """Rest state ``s`` at sample ``start`` and its seeds ``ds = C0 dz[start]``
    (``zj`` (nz,) and ``B`` (ns, nz) are work arrays; ``ds`` is overwritten)."""
    zj[:] = z[start]
    law_init(kind, p, zj, s, B)
    ds[:, :] = 0.0
    _accumulate(B, dz[start], ds)


@nb.njit(cache=True)
def march(kind, p, n_state, n_local, z, dz, start, max_passes, tol):
    """March a law over one sampled period with forward-mode derivative seeds.

    Parameters
    ----------
    kind : int
        Law id (``elements.kinds``).
    p : ndarray, shape (n_p,)
        Law parameters.
    n_state, n_local : int
        State size and number of force components (the first ``n_local`` state entries).
    z : ndarray, shape (N, nz)
        Inputs at the N samples of one period.
    dz : ndarray, shape (N, nz, P)
        Derivative seeds of the inputs.
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
    N, nz = z.shape
    P = dz.shape[2]
    s = np.zeros(n_state)
    s_new = np.zeros(n_state)
    s_begin = np.zeros(n_state)
    ds = np.zeros((n_state, P))
    ds_new = np.zeros((n_state, P))
    A = np.zeros((n_state, n_state))
    B = np.zeros((n_state, nz))
    zj = np.empty(nz)
    rest_start(kind, p, z, dz, start, s, ds, zj, B)
    f = np.empty((N, n_local))
    df = np.empty((N, n_local, P))
    passes = 0
    closed = False
    while passes < max_passes and not closed:
        passes += 1
        s_begin[:] = s
        for jj in range(1, N + 1):
            j = start + jj
            if j >= N:
                j -= N
            for k in range(nz):
                zj[k] = z[j, k]
            law_step(kind, p, s, zj, s_new, A, B)
            _propagate(A, B, ds, dz, j, ds_new)
            s, s_new = s_new, s
            ds, ds_new = ds_new, ds
            for a in range(n_local):
                f[j, a] = s[a]
                for c in range(P):
                    df[j, a, c] = ds[a, c]
        scale = 0.0
        diff = 0.0
        for i in range(n_state):
            scale = max(scale, abs(s[i]), abs(s_begin[i]))
            diff = max(diff, abs(s[i] - s_begin[i]))
        closed = diff <= tol * scale or scale == 0.0
    if not closed:
        passes = -passes
    return f, df, passes
