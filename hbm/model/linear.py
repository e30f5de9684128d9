r"""Linear model and its dynamic stiffness, stored per harmonic (never as a Kronecker product).

For ``M q'' + C q' + K q`` and the real Fourier layout of :mod:`hbm.balance.fourier`, harmonic ``h``
contributes the block

.. math::

    Z_0 = K, \qquad
    Z_h(w) = \begin{bmatrix} K - (h w)^2 M & h w C \\ -h w C & K - (h w)^2 M \end{bmatrix}

acting on ``[Xc_h, Xs_h]``, with ``dZ_h/dw = [[-2 h^2 w M, h C], [-h C, -2 h^2 w M]]``.
Damping is a viscous matrix, a Rayleigh pair ``C = a M + b K``, or modal damping ratios
``C = M Phi diag(2 zeta_r omega_r) Phi^T M`` (mass-normalised modes ``Phi``).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from hbm.balance.fourier import FourierBasis


def _square(name, A, n=None):
    A = np.asarray(A, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise ValueError(f"{name} must be {n}x{n} like the mass matrix, got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ValueError(f"{name} has non-finite entries")
    return A


def _symmetric(name, A):
    tol = 1e-10 * max(1.0, np.abs(A).max())
    if np.abs(A - A.T).max() > tol:
        raise ValueError(f"{name} must be symmetric")


def modal_damping_matrix(M, K, zeta) -> np.ndarray:
    """``C = M Phi diag(2 zeta_r omega_r) Phi^T M`` for ratios ``zeta`` (scalar or (n,))."""
    lam, Phi = sla.eigh(K, M)
    om = np.sqrt(np.clip(lam, 0.0, None))
    z = np.broadcast_to(np.asarray(zeta, dtype=float), om.shape)
    MPhi = M @ Phi
    return (MPhi * (2.0 * z * om)) @ MPhi.T


@dataclass(frozen=True)
class LinearModel:
    """Mass, damping and stiffness matrices of the linear structure, shape (n, n) each.

    Parameters
    ----------
    M, C, K : ndarray, shape (n, n)
        Symmetric; ``M`` positive definite, ``K`` positive semi-definite.
    dof_names : tuple of str, optional
        Names of the DOFs (for case files that name DOFs).
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    dof_names: tuple = ()
    _dof_index: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        M = _square("mass", self.M)
        n = M.shape[0]
        K = _square("stiffness", self.K, n)
        C = _square("damping", self.C, n)
        for name, A in (("mass", M), ("stiffness", K), ("damping", C)):
            _symmetric(name, A)
        try:
            np.linalg.cholesky(M)
        except np.linalg.LinAlgError:
            raise ValueError("mass matrix must be positive definite (non-positive mass?)") from None
        kmin = np.linalg.eigvalsh(K).min() if n else 0.0
        if kmin < -1e-9 * max(1.0, np.abs(K).max()):
            raise ValueError("stiffness matrix must be positive semi-definite (negative stiffness?)")
        cmin = np.linalg.eigvalsh(C).min() if n else 0.0
        if cmin < -1e-9 * max(1.0, np.abs(C).max()):
            raise ValueError("damping matrix must be positive semi-definite (negative damping?)")
        names = tuple(self.dof_names)
        if names and len(names) != n:
            raise ValueError(f"dof_names has {len(names)} names for {n} DOFs")
        for A in (M, C, K):
            A.setflags(write=False)
        object.__setattr__(self, "M", M)
        object.__setattr__(self, "C", C)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "dof_names", names)
        object.__setattr__(self, "_dof_index", {s: i for i, s in enumerate(names)})

    @classmethod
    def with_damping(cls, M, K, *, damping=None, rayleigh=None, modal_damping=None, dof_names=()):
        """Build from M, K and exactly one of a viscous matrix, a Rayleigh pair or modal ratios."""
        M = _square("mass", M)
        K = _square("stiffness", K, M.shape[0])
        given = [x is not None for x in (damping, rayleigh, modal_damping)]
        if sum(given) > 1:
            raise ValueError("give only one of damping, rayleigh, modal_damping")
        if damping is not None:
            C = _square("damping", damping, M.shape[0])
        elif rayleigh is not None:
            a = np.asarray(rayleigh, dtype=float)
            if a.shape != (2,):
                raise ValueError("rayleigh must be a pair [a, b] (C = a M + b K)")
            C = a[0] * M + a[1] * K
        elif modal_damping is not None:
            z = np.asarray(modal_damping, dtype=float)
            if np.any(z < 0):
                raise ValueError("modal_damping ratios must be >= 0")
            if z.ndim > 1 or (z.ndim == 1 and z.size != M.shape[0]):
                raise ValueError(f"modal_damping must be a number or a list of {M.shape[0]} ratios")
            _symmetric("mass", M)
            _symmetric("stiffness", K)
            C = modal_damping_matrix(M, K, z)
        else:
            C = np.zeros_like(M)
        return cls(M, C, K, tuple(dof_names))

    @property
    def n_dof(self) -> int:
        return self.M.shape[0]

    @property
    def dof_index(self) -> dict:
        return self._dof_index

    def with_internal_dofs(self, names, M_add, K_add) -> "LinearModel":
        """The model with extra DOFs appended (block diagonal, no damping on them).

        Used for the internal unknowns of elements (e.g. a damper body).  When this model has
        no DOF names, its DOFs are named ``dof0``, ``dof1``, ... so that every DOF has one.

        Parameters
        ----------
        names : sequence of str, length m
            Names of the new DOFs; must not clash with existing names.
        M_add, K_add : ndarray, shape (m, m)
            Mass and stiffness (to ground) of the new DOFs.
        """
        names = tuple(str(s) for s in names)
        m = len(names)
        M_add = _square("internal mass", M_add, m)
        K_add = _square("internal stiffness", K_add, m)
        old = self.dof_names or tuple(f"dof{i}" for i in range(self.n_dof))
        clash = sorted(set(old) & set(names)) or sorted({s for s in names if names.count(s) > 1})
        if clash:
            raise ValueError(f"DOF name {clash[0]!r} is used twice")
        return LinearModel(sla.block_diag(self.M, M_add), sla.block_diag(self.C, np.zeros((m, m))),
                           sla.block_diag(self.K, K_add), old + names)


def harmonic_blocks(model: LinearModel, basis: FourierBasis, w: float):
    """Per-harmonic dynamic stiffness blocks and their w-derivatives.

    Returns
    -------
    blocks : list of ndarray
        One block per harmonic of ``basis.harmonics``: (n, n) for h = 0, (2n, 2n) otherwise,
        acting on that harmonic's rows of the unknown vector.
    dblocks : list of ndarray
        ``dZ_h/dw``, same shapes.
    """
    M, C, K = model.M, model.C, model.K
    blocks, dblocks = [], []
    for h in basis.harmonics:
        if h == 0:
            blocks.append(K.copy())
            dblocks.append(np.zeros_like(K))
            continue
        hw = h * w
        A = K - hw * hw * M
        B = hw * C
        blocks.append(np.block([[A, B], [-B, A]]))
        dA = -2.0 * h * hw * M
        dB = h * C
        dblocks.append(np.block([[dA, dB], [-dB, dA]]))
    return blocks, dblocks


def fill_dynamic_stiffness(Z: np.ndarray, K, C, M, basis: FourierBasis, w: float, add: bool = False) -> np.ndarray:
    r"""Write (or with ``add``, add) the dense harmonic-balance dynamic stiffness ``Z(w)`` into ``Z``
    and return it.

    Per coefficient row ``r`` of harmonic ``h_r``: ``K - (h_r w)^2 M`` on the diagonal block and
    ``\pm h w C`` between the cosine and sine rows of ``h`` (the derivative operator), so that
    ``(Z X)_r = K X_r + w C (D X)_r - w^2 h_r^2 M X_r``.

    Parameters
    ----------
    Z : ndarray, shape (n_coef n, n_coef n)
        Zeroed on entry (or holding only entries outside the blocks written here); any
        strides (e.g. the first columns of a bordered matrix).
    K, C, M : ndarray, shape (n, n)
    basis : FourierBasis
    w : float

    Returns
    -------
    Z : ndarray, shape (n_coef n, n_coef n)
        The same array, filled block by block through a 4-D view (no loop over harmonics).
    """
    nc, n = basis.n_coef, K.shape[0]
    h = basis.h_of_row
    Z4 = Z.reshape(nc, n, nc, n)             # a view whatever Z's strides (axes only split)
    r = np.arange(nc)
    diag = K[None] - (w * w) * (h * h).astype(float)[:, None, None] * M[None]
    rc = np.flatnonzero(h > 0)[::2]
    wC = (w * h[rc]).astype(float)[:, None, None] * C[None]
    if add:
        Z4[r, :, r, :] += diag
        Z4[rc, :, rc + 1, :] += wC
        Z4[rc + 1, :, rc, :] -= wC
    else:
        Z4[r, :, r, :] = diag
        Z4[rc, :, rc + 1, :] = wC
        Z4[rc + 1, :, rc, :] = -wC
    return Z
