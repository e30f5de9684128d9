r"""Condensation on the contact coordinates in per-harmonic block form (the reference for
:mod:`hbm.balance.condensed`, which forms the same numbers without blocks).

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
import scipy.sparse as sp

from hbm.balance.fourier import FourierBasis
from hbm.model.real_blocks import apply_blocks, real_block, real_blocks_of
from hbm.model.reduction import ReducedModel, _as_index, _receptance


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
            :func:`hbm.model.linear.harmonic_blocks`.
        """
        return real_blocks_of(self._zc, basis, w)

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
        return real_blocks_of(self._tce, basis, w)

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
