r"""An approximate inverse of the condensed balance's Jacobian, factored once per model: every contact stuck.

In complex form per harmonic (``y = X_c - i X_s``, :mod:`hbm.balance.condensed`) the Jacobian
of a balance whose contacts all stick is ``Z_h + K_s``, ``K_s`` the elements' stiffness at rest
(:meth:`hbm.balance.residual.HarmonicBalance.stuck_stiffness`).  With the Woodbury form of the
condensed stiffness, ``Z = R_cc^{-1} - B M_h^{-1} B^T``, ``M_h = D(h w) + S``
(:mod:`hbm.balance.condensed_linear`), and the real, constant ``Q = R_cc^{-1} + K_s``:

.. math::

    (Z_h + K_s)^{-1} = Q^{-1} + E\,(M_h - T)^{-1} E^T, \qquad E = Q^{-1} B, \quad T = B^T E .

``Q^{-1}``, ``E`` and ``T`` are formed once per model; a frequency costs ``n_h`` inverses of
``m x m``; an application ``2 n_h n_c^2 + 4 n_h n_c m``, with no factorisation of an
``n_c x n_c`` block per Newton iteration.  Exact when every contact sticks (GMRES then stops
after one iteration); each contact that slips or opens changes the Jacobian by a block of its
own, which GMRES makes up (:class:`continuation.linsolve.BlockPreconditioned`).
"""
from __future__ import annotations

import numpy as np


class StuckInverse:
    """``v -> (J_stuck(w))^{-1} v`` on the unknown vector, for the frequency last built.

    Parameters
    ----------
    Rinv, B : ndarray, shape (n_c, n_c), (n_c, m)
        ``R_cc^{-1}`` and ``R_cc^{-1} Phi_c`` of the Woodbury form.
    modal : callable
        ``w -> M_h = D(h w) + S`` per harmonic, (n_h, m, m) complex.
    Ks : ndarray, shape (n_c, n_c)
        Stiffness of the elements at rest.
    linear : hbm.balance.condensed.CondensedLinear
        For the frequency last built (``last_frequency``) and the complex form of the
        unknowns (``to_complex``, ``to_real``).
    """

    def __init__(self, Rinv: np.ndarray, B: np.ndarray, modal, Ks: np.ndarray, linear):
        self.Qinv = np.linalg.inv(Rinv + Ks)                   # (n_c, n_c)
        self.E = self.Qinv @ B                                  # (n_c, m)
        self.T = B.T @ self.E                                   # (m, m)
        self.modal, self.linear = modal, linear
        self._w, self._Minv = None, None

    def __call__(self):
        """The approximate inverse at the frequency of the linear part last built, as
        ``v (n_u,) -> y (n_u,)``; None before any was built."""
        w = self.linear.last_frequency
        if w is None:
            return None
        if w != self._w:
            self._Minv = np.linalg.inv(self.modal(w) - self.T)          # (n_h, m, m)
            self._w = w
        return self._apply

    def _apply(self, v: np.ndarray) -> np.ndarray:
        V = self.linear.to_complex(v)                                    # (n_h, n_c)
        nh = V.shape[0]
        QV = self.Qinv @ np.concatenate((V.real.T, V.imag.T), axis=1)   # (n_c, 2 n_h)
        W = (self._Minv @ (V @ self.E)[:, :, None])[:, :, 0]            # (n_h, m)
        Y = (QV[:, :nh] + 1j * QV[:, nh:]).T + W @ self.E.T
        return self.linear.to_real(Y)
