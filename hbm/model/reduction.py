r"""Modal reduction with residual flexibility and the receptance at the kept DOFs.

Modal reduction
---------------
For ``M q'' + C q' + K q = f`` with ``K`` non-singular (a clamped structure: free-free
structures with rigid-body modes are not handled), the mass-normalised modes
``K phi_r = omega_r^2 M phi_r``, ``phi_r^T M phi_r = 1`` of the ``m`` kept modes give the
receptance at the kept DOFs (contact, excitation and output DOFs)

.. math::

    H(W) = \Phi_k\, D(W)^{-1} \Phi_k^T + R, \qquad
    D(W) = \Omega^2 - W^2 I + i W C_m, \qquad C_m = \Phi^T C \Phi,

    R = K^{-1}\big|_{kept} - \Phi_k \Omega^{-2} \Phi_k^T
    \quad(\text{residual, i.e. static, flexibility of the truncated modes}),

with ``Phi_k`` the kept rows of the kept modes.  For proportional damping ``C_m`` is
diagonal, ``C_m = diag(2 zeta_r omega_r)`` (modal ratios ``zeta_r``; a Rayleigh pair
``C = a M + b K`` gives ``2 zeta_r omega_r = a + b omega_r^2``), and
``H = sum_r phi_r phi_r^T / (omega_r^2 - W^2 + i 2 zeta_r omega_r W) + R``.
For a general (non-proportional) viscous ``C`` the kept modes stay coupled through the full
``m x m`` matrix ``C_m`` (one complex ``m x m`` solve per frequency).  With all modes kept
this *is* the exact direct solve, because ``K - W^2 M + i W C = Phi^{-T} D(W) Phi^{-1}``, so
``(K - W^2 M + i W C)^{-1} = Phi D^{-1} Phi^T``; we use this form rather than factorising
the full dynamic stiffness at every frequency so that the cost stays independent of the
full model size.  With truncation, the damping of the truncated modes is neglected (the
residual term is static).  ``dH/dW = -Phi_k D^{-1} (-2 W I + i C_m) D^{-1} Phi_k^T``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from hbm.balance.fourier import FourierBasis
from hbm.model.real_blocks import real_blocks_of

# ----------------------------------------------------------------------------------------
# reduced model
# ----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ReducedModel:
    """Kept modes (mass-normalised) at the kept DOFs, their damping, and the residual term.

    Attributes
    ----------
    keep_dofs : ndarray of int, shape (n_keep,)
        Indices of the kept DOFs in the full model.
    omega : ndarray, shape (m,)
        Natural angular frequencies of the kept modes, rad/s, ascending.
    phi : ndarray, shape (n_keep, m)
        Mode shapes at the kept DOFs.
    modal_c : ndarray, shape (m, m)
        Modal damping matrix ``Phi^T C Phi`` (diagonal ``2 zeta omega`` if proportional).
    residual : ndarray, shape (n_keep, n_keep)
        Residual flexibility ``R`` (zeros when not requested).
    n_dof : int
        Size of the full model.
    dof_names : tuple of str
        Names of the kept DOFs (empty if the full model had none).
    """

    keep_dofs: np.ndarray
    omega: np.ndarray
    phi: np.ndarray
    modal_c: np.ndarray
    residual: np.ndarray
    n_dof: int
    dof_names: tuple = ()
    proportional: bool = field(init=False)

    def __post_init__(self):
        c = np.asarray(self.modal_c, dtype=float)
        off = c - np.diag(np.diag(c))
        prop = bool(np.abs(off).max(initial=0.0) <= 1e-10 * max(np.abs(c).max(initial=0.0), 1e-300))
        object.__setattr__(self, "proportional", prop)
        for name in ("keep_dofs", "omega", "phi", "modal_c", "residual"):
            getattr(self, name).setflags(write=False)

    @property
    def n_keep(self) -> int:
        return int(self.keep_dofs.size)

    @property
    def n_modes(self) -> int:
        return int(self.omega.size)

    def receptance(self, W: float, derivative: bool = False):
        """Complex receptance ``H(W)`` at the kept DOFs, shape (n_keep, n_keep).

        With ``derivative=True`` returns ``(H, dH/dW)``.
        """
        H, dH = _receptance(self.phi, self.phi, self.omega, self.modal_c, self.proportional,
                            self.residual, float(W))
        return (H, dH) if derivative else H

    def receptance_blocks(self, basis: FourierBasis, w: float):
        """Per-harmonic real receptance blocks (inverses of :func:`hbm.model.linear.harmonic_blocks`).

        Returns
        -------
        blocks : list of ndarray
            (n_keep, n_keep) static flexibility for h = 0, (2 n_keep, 2 n_keep)
            ``real_block(H(h w))`` otherwise.
        dblocks : list of ndarray
            Their derivatives with respect to ``w``.
        """
        return real_blocks_of(lambda W: self.receptance(W, derivative=True), basis, w)


def _receptance(phi_a, phi_b, omega, modal_c, proportional, R_ab, W):
    """``H_ab(W) = phi_a D(W)^{-1} phi_b^T + R_ab`` and its W-derivative (complex)."""
    om2 = omega * omega
    if proportional:
        c = np.diag(modal_c)
        d = om2 - W * W + 1j * W * c
        inv = 1.0 / d
        H = (phi_a * inv) @ phi_b.T + R_ab
        dinv = -(-2.0 * W + 1j * c) * inv * inv
        dH = (phi_a * dinv) @ phi_b.T
    else:
        D = np.diag(om2 - W * W) + 1j * W * modal_c
        lu = sla.lu_factor(D)
        Y = sla.lu_solve(lu, phi_b.T.astype(complex))          # D^-1 phi_b^T
        H = phi_a @ Y + R_ab
        dD = -2.0 * W * np.eye(omega.size) + 1j * modal_c
        Za = sla.lu_solve(lu, phi_a.T.astype(complex), trans=1)  # D^-T phi_a^T
        dH = -(Za.T @ (dD @ Y))
    return H, dH


def receptance_stack(phi, omega, modal_c, proportional, R, Ws):
    """``H(W) = phi D(W)^{-1} phi^T + R`` and ``dH/dW`` for many ``W`` at once (complex).

    Parameters
    ----------
    phi : ndarray, shape (p, m)
        Mode shapes at the ``p`` coordinates of interest (e.g. ``G phi`` for gather rows ``G``).
    omega : ndarray, shape (m,)
    modal_c : ndarray, shape (m, m)
    proportional : bool
        ``modal_c`` is diagonal: ``H = sum_r phi_r phi_r^T / d_r(W) + R``, one product for all ``W``.
    R : ndarray, shape (p, p)
        Residual flexibility at the coordinates.
    Ws : ndarray, shape (n_W,)
        Angular frequencies, rad/s.

    Returns
    -------
    H, dH : ndarray, complex, shape (n_W, p, p)
    """
    Ws = np.asarray(Ws, dtype=float)
    p, m = phi.shape
    om2 = omega * omega
    k = Ws.size
    if proportional:
        outer = np.einsum("ir,jr->rij", phi, phi).reshape(m, p * p)
        c = np.diag(modal_c)
        inv = 1.0 / (om2[None, :] - Ws[:, None] ** 2 + 1j * Ws[:, None] * c[None, :])
        dinv = (2.0 * Ws[:, None] - 1j * c[None, :]) * inv * inv
        HdH = np.concatenate([inv, dinv]) @ outer            # (2 n_W, p * p), one product
        H = HdH[:k].reshape(k, p, p) + R
        return H, HdH[k:].reshape(k, p, p)
    D = 1j * Ws[:, None, None] * modal_c[None, :, :]
    ar = np.arange(m)
    D[:, ar, ar] += om2[None, :] - Ws[:, None] ** 2
    phiT = np.broadcast_to(phi.T.astype(complex), (k, m, p))
    Y = np.linalg.solve(D, phiT)                               # D^-1 phi^T
    Za = np.linalg.solve(D.transpose(0, 2, 1), phiT)           # D^-T phi^T
    dD = np.empty((k, m, m), dtype=complex)
    dD[:] = 1j * modal_c
    dD[:, ar, ar] -= 2.0 * Ws[:, None]
    H = phi @ Y + R
    dH = -(Za.transpose(0, 2, 1) @ (dD @ Y))
    return H, dH


def _as_index(dofs, n, what):
    idx = np.asarray(dofs)
    if idx.ndim != 1 or (idx.size and idx.dtype.kind not in "iu"):
        raise ValueError(f"{what} must be a 1-D list of integer DOF indices")
    idx = idx.astype(np.int64)
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ValueError(f"{what} has an index outside 0..{n - 1}")
    if np.unique(idx).size != idx.size:
        raise ValueError(f"{what} has repeated DOF indices")
    return idx


def _check_square(name, A, n=None):
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"{name} must be a square matrix, got shape {A.shape}")
    if n is not None and A.shape[0] != n:
        raise ValueError(f"{name} must be {n}x{n} like the mass matrix, got {A.shape}")


def reduce_model(M, K, *, n_modes=None, residual_flexibility=True, modal_damping=None,
                 rayleigh=None, damping=None, keep_dofs=None, sigma=0.0, dof_names=()):
    """Reduce ``(M, K, damping)`` to kept modes at kept DOFs, with residual flexibility.

    Parameters
    ----------
    M, K : ndarray or scipy.sparse matrix, shape (n, n)
        Symmetric; ``K`` must be non-singular (clamped structure; free-free is not handled).
        Dense input uses ``scipy.linalg.eigh``; sparse input uses ``eigsh`` in shift-invert
        mode about ``sigma`` (then ``n_modes`` is required and must be < n).
    n_modes : int, optional
        Number of lowest modes kept (default: all, dense input only).
    residual_flexibility : bool
        Add the static flexibility of the truncated modes at the kept DOFs.
    modal_damping : float or array_like (n_modes,), optional
        Modal damping ratios ``zeta_r``.
    rayleigh : pair (a, b), optional
        ``C = a M + b K``.
    damping : ndarray or sparse (n, n), optional
        Viscous matrix ``C`` (projected on the kept modes; may be non-proportional).
    keep_dofs : array_like of int, optional
        Full-model DOF indices kept (contact + excitation + output DOFs); default all.
    sigma : float
        Shift (rad/s squared) for the shift-invert eigen-solve of sparse input.
    dof_names : sequence of str, optional
        Names of the full model's DOFs.

    Returns
    -------
    ReducedModel
    """
    sparse = sp.issparse(M) or sp.issparse(K)
    if not sparse:
        M = np.asarray(M, dtype=float)
        K = np.asarray(K, dtype=float)
    else:
        M = sp.csr_matrix(M, dtype=float)
        K = sp.csr_matrix(K, dtype=float)
    _check_square("mass", M)
    n = M.shape[0]
    _check_square("stiffness", K, n)
    if sum(x is not None for x in (modal_damping, rayleigh, damping)) > 1:
        raise ValueError("give only one of modal_damping, rayleigh, damping")
    if n_modes is None:
        if sparse:
            raise ValueError("n_modes is required for sparse mass and stiffness matrices")
        n_modes = n
    n_modes = int(n_modes)
    if n_modes < 1 or n_modes > n or (sparse and n_modes >= n):
        raise ValueError(f"n_modes must be between 1 and {n - 1 if sparse else n}, got {n_modes}")
    keep = np.arange(n) if keep_dofs is None else _as_index(keep_dofs, n, "keep_dofs")
    if keep.size == 0:
        raise ValueError("keep_dofs is empty")
    names = tuple(dof_names)
    if names and len(names) != n:
        raise ValueError(f"dof_names has {len(names)} names for {n} DOFs")

    lam, Phi = _modes(M, K, n_modes, sparse, sigma)
    Cm = _modal_damping(Phi, lam, n, modal_damping, rayleigh, damping)

    phi_k = np.ascontiguousarray(Phi[keep])
    R = (_residual_flexibility(K, keep, phi_k, lam, sparse) if residual_flexibility
         else np.zeros((keep.size, keep.size)))
    kept_names = tuple(names[i] for i in keep) if names else ()
    return ReducedModel(keep, np.sqrt(lam), phi_k, np.ascontiguousarray(Cm), R, n, kept_names)


def _modes(M, K, n_modes: int, sparse: bool, sigma: float):
    """The ``n_modes`` lowest eigenpairs ``(lam (m,), Phi (n, m))`` of ``K phi = lam M phi``,
    mass-normalised; ValueError for a negative or singular stiffness."""
    n = M.shape[0]
    if sparse:
        # a fixed start vector: ARPACK's random one made two runs of one case differ at
        # round-off, enough to change a continuation's steps (and its points) between runs
        v0 = np.random.default_rng(0).standard_normal(n)
        lam, Phi = spla.eigsh(K.tocsc(), k=n_modes, M=M.tocsc(), sigma=float(sigma), which="LM", v0=v0)
        order = np.argsort(lam)
        lam, Phi = lam[order], Phi[:, order]
    else:
        try:
            lam, Phi = sla.eigh(K, M, subset_by_index=[0, n_modes - 1])
        except np.linalg.LinAlgError:
            raise ValueError("mass matrix must be symmetric positive definite") from None
    if lam.min() < -1e-9 * max(abs(lam.max()), 1e-300):
        raise ValueError(f"stiffness matrix must be positive semi-definite (negative stiffness?): "
                         f"eigenvalue {lam.min():.3g} (rad/s)^2")
    if lam.min() <= 1e-12 * max(abs(lam.max()), 1e-300):
        raise ValueError("stiffness matrix is singular (free-free structure?): clamp it first")
    return lam, Phi / np.sqrt(np.einsum("ir,ir->r", Phi, M @ Phi))


def _modal_damping(Phi, lam, n: int, modal_damping, rayleigh, damping) -> np.ndarray:
    """Modal damping matrix (m, m) from ratios, Rayleigh coefficients or a viscous matrix
    (zero without any); ValueError when it would be negative."""
    n_modes = lam.size
    if modal_damping is not None:
        z = np.asarray(modal_damping, dtype=float)
        if z.ndim > 1 or (z.ndim == 1 and z.size != n_modes):
            raise ValueError(f"modal_damping must be a number or a list of {n_modes} ratios")
        if np.any(z < 0):
            raise ValueError("modal_damping ratios must be >= 0")
        omega = np.sqrt(lam)
        Cm = np.diag(2.0 * np.broadcast_to(z, omega.shape) * omega)
    elif rayleigh is not None:
        a = np.asarray(rayleigh, dtype=float)
        if a.shape != (2,):
            raise ValueError("rayleigh must be a pair [a, b] (C = a M + b K)")
        Cm = np.diag(a[0] + a[1] * lam)
        if np.any(np.diag(Cm) < 0):
            raise ValueError(f"rayleigh = [{a[0]:g}, {a[1]:g}] gives negative damping (a + b w^2 < 0 for a "
                             f"kept mode): damping must be positive semi-definite")
    elif damping is not None:
        C = damping if sp.issparse(damping) else np.asarray(damping, dtype=float)
        _check_square("damping", C, n)
        Cm = Phi.T @ (C @ Phi)
        Cm = 0.5 * (Cm + Cm.T)
        cm = np.linalg.eigvalsh(Cm)
        if cm[0] < -1e-9 * max(abs(cm).max(), 1e-300):
            raise ValueError("damping matrix must be positive semi-definite (negative damping?): "
                             f"its modal projection has eigenvalue {cm[0]:.3g}")
    else:
        Cm = np.zeros((n_modes, n_modes))
    return Cm


def _residual_flexibility(K, keep, phi_k, lam, sparse: bool) -> np.ndarray:
    """Static flexibility of the truncated modes at the kept DOFs, ``K^-1 - Phi_k Lam^-1
    Phi_k^T`` (k, k), symmetrised.

    ``K^-1`` is taken as ``S (S K S)^-1 S`` with ``S = diag(K)^-1/2``: stiffnesses of very
    different scales (a beam's rotations, a damper held only by its anchor spring) no longer
    make the solve look singular (the UPD rig with platform rotations: condition number
    9e15 -> 2e6, the same flexibility to 2e-11, and no ill-conditioning warning)."""
    n = K.shape[0]
    d = np.asarray(K.diagonal(), dtype=float)
    s = np.where(d > 0, 1.0 / np.sqrt(np.where(d > 0, d, 1.0)), 1.0)
    E = np.zeros((n, keep.size))
    E[keep, np.arange(keep.size)] = s[keep]
    if sparse:
        Ks = sp.diags(s) @ K.tocsc() @ sp.diags(s)
        Kinv = s[keep, None] * spla.splu(sp.csc_matrix(Ks)).solve(E)[keep]
    else:
        Kinv = s[keep, None] * sla.solve(s[:, None] * np.asarray(K) * s[None, :], E, assume_a="sym")[keep]
    R = Kinv - (phi_k / lam) @ phi_k.T
    return 0.5 * (R + R.T)


def reduce_linear_model(model, *, n_modes=None, residual_flexibility=True, keep_dofs=None):
    """:func:`reduce_model` of a :class:`hbm.model.linear.LinearModel` (its ``C`` is projected)."""
    return reduce_model(model.M, model.K, damping=model.C, n_modes=n_modes,
                        residual_flexibility=residual_flexibility, keep_dofs=keep_dofs,
                        dof_names=model.dof_names)


# ----------------------------------------------------------------------------------------
# condensation on contact coordinates
# ----------------------------------------------------------------------------------------
