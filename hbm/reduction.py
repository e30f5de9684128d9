r"""Modal reduction with residual flexibility, receptances, and condensation on contact DOFs.

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

Real block form (the conventions of :mod:`hbm.fourier` and :mod:`hbm.linear`)
--------------------------------------------------------------------------------
With ``x(t) = Xc cos(h w t) + Xs sin(h w t) = Re[(Xc - i Xs) e^{i h w t}]`` and likewise for
the force, the harmonic-``h`` balance ``Z_h [Xc; Xs] = [Fc; Fs]`` with
``Z_h = [[A, B], [-B, A]]``, ``A = K - (hw)^2 M``, ``B = hw C`` is the complex equation
``(A + i B)(Xc - i Xs) = Fc - i Fs``.  Hence ``Xc - i Xs = H(hw) (Fc - i Fs)`` and

.. math::

    Z_h^{-1} = \begin{bmatrix} \mathrm{Re}\,H & \mathrm{Im}\,H \\ -\mathrm{Im}\,H & \mathrm{Re}\,H
    \end{bmatrix}_{W = h w}, \qquad
    \frac{d Z_h^{-1}}{dw} = h \begin{bmatrix} \mathrm{Re}\,H' & \mathrm{Im}\,H' \\
    -\mathrm{Im}\,H' & \mathrm{Re}\,H' \end{bmatrix}, \qquad H' = dH/dW,

acting on ``[Xc_h, Xs_h]`` (:func:`real_block`).  The map ``a + i b -> [[a, b], [-b, a]]``
is a ring homomorphism, so products and inverses may be done in complex arithmetic and
converted at the end.  For ``h = 0`` the block is the static flexibility ``H(0)`` (real).

Condensation on the contact coordinates
---------------------------------------
Let the contact coordinates be ``u_c = G_c q`` (DOF indices or gather rows, e.g. rigid
offsets or relative displacements), the excitation act as ``f = G_e^T f_e``, and the outputs
be ``y = G_o q``.  The nonlinear forces act on the contact coordinates, ``f = -G_c^T f_nl``.
Per harmonic (complex form; ``H_ab = G_a H G_b^T``):

.. math::

    U_c = H_{ce} F_e - H_{cc} F_{nl}(U_c)
    \;\Longleftrightarrow\;
    Z_c U_c + F_{nl}(U_c) - Z_c H_{ce} F_e = 0, \qquad Z_c = H_{cc}^{-1},

so the Newton residual is ``R_c = Z_c U_c + F_nl(U_c) - F_eq`` with the exact condensed
dynamic stiffness ``Z_c`` (``n_c x n_c`` per harmonic) and the equivalent contact load
``F_eq = T_ce F_e``, ``T_ce = Z_c H_ce``.  The outputs follow from ``U_c`` alone, using
``F_nl = F_eq - Z_c U_c``:

.. math::

    Y = H_{oe} F_e - H_{oc} F_{nl} = T_{oc} U_c + T_{oe} F_e, \qquad
    T_{oc} = H_{oc} Z_c, \quad T_{oe} = H_{oe} - H_{oc} Z_c H_{ce}.

Derivatives: ``dZ_c/dW = -Z_c H_cc' Z_c``.  Every projection ``G_a Phi_k`` and
``G_a R G_b^T`` is formed once, so a residual evaluation costs ``O(n_c^2 m)`` per harmonic,
independent of the full model size.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .fourier import FourierBasis


def real_block(Hc: np.ndarray) -> np.ndarray:
    """Real form ``[[Re H, Im H], [-Im H, Re H]]`` of a complex matrix, acting on ``[Xc, Xs]``.

    Parameters
    ----------
    Hc : ndarray, complex, shape (p, q)

    Returns
    -------
    ndarray, shape (2p, 2q)
    """
    a, b = Hc.real, Hc.imag
    p, q = a.shape
    out = np.empty((2 * p, 2 * q))
    out[:p, :q] = a
    out[:p, q:] = b
    out[p:, :q] = -b
    out[p:, q:] = a
    return out


def apply_blocks(blocks, basis: FourierBasis, X: np.ndarray) -> np.ndarray:
    """Apply per-harmonic blocks to coefficients ``X`` (n_coef, q) -> (n_coef, p).

    Parameters
    ----------
    blocks : list of ndarray
        One per harmonic of ``basis``: (p, q) for h = 0, (2p, 2q) otherwise.
    basis : FourierBasis
    X : ndarray, shape (n_coef, q)
    """
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[0] != basis.n_coef:
        raise ValueError(f"coefficients must have shape (n_coef={basis.n_coef}, q), got {X.shape}")
    out, k = [], 0
    for h, B in zip(basis.harmonics, blocks):
        if h == 0:
            out.append((B @ X[k])[None, :])
            k += 1
        else:
            p = B.shape[0] // 2
            y = B @ X[k:k + 2].reshape(-1)
            out.append(y.reshape(2, p))
            k += 2
    return np.vstack(out)


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
        """Per-harmonic real receptance blocks (inverses of :func:`hbm.linear.harmonic_blocks`).

        Returns
        -------
        blocks : list of ndarray
            (n_keep, n_keep) static flexibility for h = 0, (2 n_keep, 2 n_keep)
            ``real_block(H(h w))`` otherwise.
        dblocks : list of ndarray
            Their derivatives with respect to ``w``.
        """
        return _blocks(lambda W: self.receptance(W, derivative=True), basis, w)


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


def _blocks(fun, basis: FourierBasis, w: float):
    """Real blocks of ``fun(W) -> (H, dH/dW)`` for each harmonic, and their w-derivatives."""
    blocks, dblocks = [], []
    for h in basis.harmonics:
        H, dH = fun(h * w)
        if h == 0:
            blocks.append(np.ascontiguousarray(H.real))
            dblocks.append(np.zeros(H.shape))
        else:
            blocks.append(real_block(H))
            dblocks.append(h * real_block(dH))
    return blocks, dblocks


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

    if sparse:
        lam, Phi = spla.eigsh(K.tocsc(), k=n_modes, M=M.tocsc(), sigma=float(sigma), which="LM")
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
    Phi = Phi / np.sqrt(np.einsum("ir,ir->r", Phi, M @ Phi))
    omega = np.sqrt(lam)

    if modal_damping is not None:
        z = np.asarray(modal_damping, dtype=float)
        if z.ndim > 1 or (z.ndim == 1 and z.size != n_modes):
            raise ValueError(f"modal_damping must be a number or a list of {n_modes} ratios")
        if np.any(z < 0):
            raise ValueError("modal_damping ratios must be >= 0")
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

    phi_k = np.ascontiguousarray(Phi[keep])
    if residual_flexibility:
        E = np.zeros((n, keep.size))
        E[keep, np.arange(keep.size)] = 1.0
        if sparse:
            Kinv = spla.splu(K.tocsc()).solve(E)[keep]
        else:
            Kinv = sla.solve(K, E, assume_a="sym")[keep]
        R = Kinv - (phi_k / lam) @ phi_k.T
        R = 0.5 * (R + R.T)
    else:
        R = np.zeros((keep.size, keep.size))
    kept_names = tuple(names[i] for i in keep) if names else ()
    return ReducedModel(keep, omega, phi_k, np.ascontiguousarray(Cm), R, n, kept_names)


def reduce_linear_model(model, *, n_modes=None, residual_flexibility=True, keep_dofs=None):
    """:func:`reduce_model` of a :class:`hbm.linear.LinearModel` (its ``C`` is projected)."""
    return reduce_model(model.M, model.K, damping=model.C, n_modes=n_modes,
                        residual_flexibility=residual_flexibility, keep_dofs=keep_dofs,
                        dof_names=model.dof_names)


# ----------------------------------------------------------------------------------------
# condensation on contact coordinates
# ----------------------------------------------------------------------------------------

def _gather(spec, reduced: ReducedModel, what: str) -> np.ndarray:
    """Gather rows over the kept DOFs from DOF indices (full model) or rows (k, n_dof)."""
    pos = np.full(reduced.n_dof, -1, dtype=np.int64)
    pos[reduced.keep_dofs] = np.arange(reduced.n_keep)
    if sp.issparse(spec):
        spec = spec.toarray()
    arr = np.asarray(spec)
    if arr.ndim == 1:
        idx = _as_index(arr, reduced.n_dof, what)
        if np.any(pos[idx] < 0):
            bad = idx[pos[idx] < 0][0]
            raise ValueError(f"{what} DOF {bad} is not among the kept DOFs of the reduced model")
        G = np.zeros((idx.size, reduced.n_keep))
        G[np.arange(idx.size), pos[idx]] = 1.0
        return G
    if arr.ndim == 2 and arr.shape[1] == reduced.n_dof:
        arr = arr.astype(float)
        outside = np.ones(reduced.n_dof, dtype=bool)
        outside[reduced.keep_dofs] = False
        if np.any(arr[:, outside] != 0.0):
            raise ValueError(f"{what} rows touch DOFs that are not kept in the reduced model")
        return np.ascontiguousarray(arr[:, reduced.keep_dofs])
    raise ValueError(f"{what} must be DOF indices or gather rows of shape (k, {reduced.n_dof})")


@dataclass(frozen=True)
class CondensedModel:
    """Linear part condensed on the contact coordinates (see the module docstring).

    Attributes
    ----------
    reduced : ReducedModel
    n_contact, n_excitation, n_output : int
        Numbers of contact coordinates, excitation forces and outputs.
    """

    reduced: ReducedModel
    G_c: np.ndarray
    G_e: np.ndarray
    G_o: np.ndarray
    _proj: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        r = self.reduced
        if self.G_c.shape[0] == 0:
            raise ValueError("contact DOFs are empty")
        phi = {k: G @ r.phi for k, G in (("c", self.G_c), ("e", self.G_e), ("o", self.G_o))}
        G = {"c": self.G_c, "e": self.G_e, "o": self.G_o}
        res = {a + b: G[a] @ r.residual @ G[b].T for a, b in ("cc", "ce", "oc", "oe")}
        object.__setattr__(self, "_proj", {"phi": phi, "R": res, "G": G})

    @property
    def n_contact(self) -> int:
        return int(self.G_c.shape[0])

    @property
    def n_excitation(self) -> int:
        return int(self.G_e.shape[0])

    @property
    def n_output(self) -> int:
        return int(self.G_o.shape[0])

    def receptance(self, a: str, b: str, W: float):
        """Complex ``H_ab(W) = G_a H G_b^T`` and its W-derivative for ``a, b`` in 'c', 'e', 'o'."""
        r = self.reduced
        phi = self._proj["phi"]
        R = self._proj["R"].get(a + b)
        if R is None:
            G = self._proj["G"]
            R = G[a] @ r.residual @ G[b].T
        return _receptance(phi[a], phi[b], r.omega, r.modal_c, r.proportional, R, float(W))

    def _zc(self, W):
        Hcc, dHcc = self.receptance("c", "c", W)
        try:
            Z = np.linalg.inv(Hcc)
        except np.linalg.LinAlgError:
            raise ValueError("contact receptance is singular (dependent contact coordinates?)") from None
        return Z, -Z @ dHcc @ Z

    def stiffness_blocks(self, basis: FourierBasis, w: float):
        """Condensed dynamic stiffness ``Z_c(h w) = H_cc^{-1}`` per harmonic and its w-derivative.

        Returns
        -------
        blocks, dblocks : list of ndarray
            (n_c, n_c) for h = 0, (2 n_c, 2 n_c) otherwise, like
            :func:`hbm.linear.harmonic_blocks`.
        """
        return _blocks(self._zc, basis, w)

    def _tce(self, W):
        Z, dZ = self._zc(W)
        Hce, dHce = self.receptance("c", "e", W)
        return Z @ Hce, dZ @ Hce + Z @ dHce

    def excitation_blocks(self, basis: FourierBasis, w: float):
        """``T_ce = Z_c H_ce`` per harmonic (equivalent contact load ``F_eq = T_ce F_e``).

        Returns
        -------
        blocks, dblocks : list of ndarray
            (n_c, n_e) for h = 0, (2 n_c, 2 n_e) otherwise, and their w-derivatives.
        """
        return _blocks(self._tce, basis, w)

    def equivalent_force(self, basis: FourierBasis, w: float, F_e: np.ndarray):
        """Equivalent contact load ``F_eq`` (n_coef, n_c) and ``dF_eq/dw`` for excitation ``F_e``.

        Parameters
        ----------
        F_e : ndarray, shape (n_coef, n_e)
            Harmonic coefficients of the excitation forces (fixed amplitudes).
        """
        T, dT = self.excitation_blocks(basis, w)
        return apply_blocks(T, basis, F_e), apply_blocks(dT, basis, F_e)

    def output_blocks(self, basis: FourierBasis, w: float):
        """Output recovery blocks ``Y = T_oc U_c + T_oe F_e`` per harmonic.

        Returns
        -------
        T_oc : list of ndarray
            ``H_oc Z_c``: (n_o, n_c) for h = 0, (2 n_o, 2 n_c) otherwise.
        T_oe : list of ndarray
            ``H_oe - H_oc Z_c H_ce``: (n_o, n_e) or (2 n_o, 2 n_e).
        """
        T_oc, T_oe = [], []
        for h in basis.harmonics:
            W = h * w
            Z, _ = self._zc(W)
            Hoc, _ = self.receptance("o", "c", W)
            Hce, _ = self.receptance("c", "e", W)
            Hoe, _ = self.receptance("o", "e", W)
            A = Hoc @ Z
            B = Hoe - A @ Hce
            if h == 0:
                T_oc.append(A.real.copy())
                T_oe.append(B.real.copy())
            else:
                T_oc.append(real_block(A))
                T_oe.append(real_block(B))
        return T_oc, T_oe

    def recover_outputs(self, basis: FourierBasis, w: float, U_c: np.ndarray,
                        F_e: np.ndarray) -> np.ndarray:
        """Output coefficients ``Y`` (n_coef, n_o) from contact coefficients ``U_c`` (n_coef, n_c)."""
        T_oc, T_oe = self.output_blocks(basis, w)
        return apply_blocks(T_oc, basis, U_c) + apply_blocks(T_oe, basis, F_e)


def condense(reduced: ReducedModel, contact_dofs, output_dofs, excitation_dofs) -> CondensedModel:
    """Condense the reduced linear part on the contact coordinates.

    Parameters
    ----------
    reduced : ReducedModel
    contact_dofs, output_dofs, excitation_dofs : array_like
        Full-model DOF indices (k,) or gather rows (k, n_dof) touching kept DOFs only:
        contact coordinates ``u_c = G_c q``, outputs ``y = G_o q``, forces ``f = G_e^T f_e``.

    Returns
    -------
    CondensedModel
    """
    return CondensedModel(reduced, _gather(contact_dofs, reduced, "contact_dofs"),
                          _gather(excitation_dofs, reduced, "excitation_dofs"),
                          _gather(output_dofs, reduced, "output_dofs"))
