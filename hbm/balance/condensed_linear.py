r"""The linear part of the condensed balance (:mod:`hbm.balance.condensed`) at one frequency, exact three ways.

With the kept modes ``Phi`` (mass-normalised), modal dynamic stiffness
``D(W) = Omega^2 - W^2 I + i W C_m`` and residual flexibility ``R``, the receptance between
the kept coordinates is ``H(W) = Phi D^{-1} Phi^T + R`` and the condensed stiffness on the
``n_c`` contact coordinates is ``Z(W) = H_cc(W)^{-1}``, with ``dZ/dW = -Z H_cc' Z``.

*compiled* (few contacts): every ``H`` in one compiled product over the modes, ``Z`` by
Gauss-Jordan per harmonic (:mod:`hbm.balance.condensed_kernels`).

*woodbury* (many contacts, ``R_cc`` positive definite): with ``B = R_cc^{-1} Phi_c`` and
``S = Phi_c^T R_cc^{-1} Phi_c`` formed once,

.. math::

    Z = R_{cc}^{-1} - B M^{-1} B^T, \qquad M(W) = D(W) + S, \qquad
    \frac{dZ}{dW} = B M^{-1} D'(W) M^{-1} B^T, \quad D' = -2W I + i C_m ,

so a frequency costs ``O(m^3 + n_c^2 m)`` per harmonic instead of ``O(n_c^3)``, and
``D^{-1}`` (singular at an undamped resonance) never appears in ``Z``.  ``B`` being real, ``Z``
takes two real products of ``n_c^2 m`` (not one complex one), and ``h dZ/dW`` is kept as its
factors ``G = B M^{-1}`` and ``h D'`` (:class:`Congruence`): the balance only multiplies it
by the displacements, ``O(n_c m)`` per harmonic.

*dense* (many contacts, ``R_cc`` singular, e.g. all modes kept): ``H_cc`` formed and
inverted by LAPACK per harmonic.

All three return the same :class:`LinearPart`: ``Z`` and ``h dZ/dW`` per harmonic, the
equivalent load of the unit cosine excitation at harmonic 1, ``F_eq = Z H_ce F_e`` with
``dF_eq/dw = Z' H_ce + Z H_ce'``, and the receptances the outputs and the energy balance
need (rows: excitation then outputs; columns: contacts then excitation).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from hbm.balance.condensed_kernels import condensed_linear, proportional_linear
from hbm.model.reduction import receptance_stack

WOODBURY_MIN_CONTACTS = 12     # below this the compiled per-harmonic inverse is faster
_RCOND_MIN = 1e-10             # smallest eigenvalue ratio of R_cc for the Woodbury form
STRATEGIES = ("auto", "compiled", "woodbury", "dense")


class Congruence(NamedTuple):
    """``G D G^T`` kept as its factors; ``@`` multiplies without forming it.

    Attributes
    ----------
    G : ndarray, complex, shape (..., n_c, m)
    D : ndarray, complex, shape (..., m, m)
    """

    G: np.ndarray
    D: np.ndarray

    def __matmul__(self, U: np.ndarray) -> np.ndarray:
        """``G D G^T U`` for ``U`` of shape (..., n_c, k) (or (n_c,) on one harmonic)."""
        return self.G @ (self.D @ (np.swapaxes(self.G, -1, -2) @ U))

    def __getitem__(self, k) -> "Congruence":
        return Congruence(self.G[k], self.D[k])


class LinearPart(NamedTuple):
    """The linear part at one fundamental frequency ``w``.

    Attributes
    ----------
    Z : ndarray, complex, shape (n_h, n_c, n_c)
        ``Z_c(h w)`` per harmonic.
    hdZ : ndarray, complex, shape (n_h, n_c, n_c), or Congruence
        ``h dZ_c/dW`` per harmonic (``dR/dw`` of ``Z_c U``); only ever multiplied (``@``).
    F, dF : ndarray, shape (n_u,)
        Equivalent contact load ``F_eq`` and ``dF_eq/dw``, flattened like the unknowns.
    Hx : ndarray, complex, shape (n_h, n_e + n_o, n_c + n_e)
        Receptances from the contacts and the excitation (columns) to the excitation and
        the outputs (rows) at ``W = h w``.
    """

    Z: np.ndarray
    hdZ: np.ndarray | Congruence
    F: np.ndarray
    dF: np.ndarray
    Hx: np.ndarray


class LinearBuilder:
    """Builds :class:`LinearPart` for any ``w`` (module docstring).

    Parameters
    ----------
    reduced : ReducedModel
    phi_all : ndarray, shape (p, m)
        Modes at the kept coordinates: ``n_c`` contacts, ``n_e`` excitation, ``n_o`` outputs.
    R_all : ndarray, shape (p, p)
        Residual flexibility between them.
    n_c, n_e : int
    hs : ndarray, shape (n_h,)
        Harmonic numbers (float); ``i1`` the position of harmonic 1.
    rows : ndarray of int, shape (n_h,)
        Coefficient row of each harmonic's cosine (or mean); the sine row follows it.
    strategy : str
        ``auto`` (compiled below :data:`WOODBURY_MIN_CONTACTS`, then woodbury when ``R_cc`` is
        positive definite, else dense) or one of ``compiled``, ``woodbury``, ``dense``.
    """

    def __init__(self, reduced, phi_all, R_all, n_c, n_e, hs, rows, i1, strategy="auto", fe=None):
        if strategy not in STRATEGIES:
            raise ValueError(f"strategy must be one of {STRATEGIES}, got {strategy!r}")
        self.reduced, self.phi, self.R = reduced, phi_all, R_all
        self.nc, self.ne, self.hs, self.rows, self.i1 = n_c, n_e, hs, rows, i1
        # complex harmonic-1 amplitudes of the excitation coordinates: [1] (cosine), or
        # [1, -i] for a cosine row and a sine row
        self.fe = np.ones(1, dtype=complex) if fe is None else np.asarray(fe, dtype=complex)
        self.om2 = np.ascontiguousarray(reduced.omega ** 2)
        self.Cm = reduced.modal_c
        self.cdiag = np.ascontiguousarray(np.diag(reduced.modal_c))
        self.n_u = (2 * int(np.count_nonzero(hs)) + int(np.count_nonzero(hs == 0))) * n_c
        self._x = np.r_[n_c:phi_all.shape[0]]                     # excitation and output rows
        self._y = np.r_[0:n_c + n_e]                              # contact and excitation columns
        if strategy == "auto":
            strategy = "compiled" if n_c < WOODBURY_MIN_CONTACTS else (
                "woodbury" if self._woodbury_ready() else "dense")
        elif strategy == "woodbury" and not self._woodbury_ready():
            raise ValueError("the Woodbury form needs a positive definite residual flexibility on the contacts")
        if strategy == "compiled":
            ia, ib = np.triu_indices(phi_all.shape[0])
            self._tri = (ia.astype(np.int64), ib.astype(np.int64))
            self._Pu = np.ascontiguousarray(phi_all[ia].T * phi_all[ib].T)   # (m, n_t)
            self._Ru = np.ascontiguousarray(R_all[ia, ib])
        self.strategy = strategy

    def _woodbury_ready(self) -> bool:
        """Factor ``R_cc`` once (``B``, ``S``, ``R_cc^{-1}``); False when it is not positive definite."""
        if hasattr(self, "_B"):
            return True
        Rcc = self.R[:self.nc, :self.nc]
        lam, V = np.linalg.eigh(0.5 * (Rcc + Rcc.T))
        if lam.size == 0 or lam[0] <= _RCOND_MIN * max(lam[-1], 1e-300):
            return False
        self._Rinv = (V / lam) @ V.T
        self._B = self._Rinv @ self.phi[:self.nc]                   # (n_c, m)
        self._S = self.phi[:self.nc].T @ self._B                     # (m, m)
        return True

    def woodbury_parts(self):
        """``(R_cc^{-1}, B, w -> D(h w) + S)`` of the Woodbury form (:mod:`hbm.balance.stuck_inverse`);
        None in the other strategies."""
        if self.strategy != "woodbury":
            return None
        return self._Rinv, self._B, lambda w: self._modal(self.hs * w)[0] + self._S

    # ------------------------------------------------------------------ pieces
    def _modal(self, Ws):
        """``D(W)`` and ``D'(W)`` per ``W``, (n_W, m, m) complex."""
        m = self.om2.size
        ar = np.arange(m)
        D = 1j * Ws[:, None, None] * self.Cm[None]
        D[:, ar, ar] += self.om2 - (Ws ** 2)[:, None]
        dD = np.broadcast_to(1j * self.Cm, (Ws.size, m, m)).copy()
        dD[:, ar, ar] -= 2.0 * Ws[:, None]
        return D, dD

    def _receptance_rows(self, Dinv, xr, yc, dD=None):
        """``H`` (and ``dH/dW`` when ``dD`` is given, else None) between rows ``xr`` and
        columns ``yc`` of the kept coordinates, (n_W, len(xr), len(yc)) complex, from
        ``D^{-1}`` and ``D'`` (n_W, m, m)."""
        px, py = self.phi[xr], self.phi[yc]
        A = px @ Dinv                                                # (n_W, len(xr), m)
        H = A @ py.T + self.R[np.ix_(xr, yc)]
        return H, (None if dD is None else -(A @ dD) @ (Dinv @ py.T))

    def _load(self, Z, hdZ, Hce, dHce):
        """``F_eq`` and ``dF_eq/dw`` (n_u,) from harmonic 1's ``Z``, ``Z'`` and ``H_ce`` (n_c,)."""
        i1, nc = self.i1, self.nc
        t = Z[i1] @ Hce
        dt = hdZ[i1] @ Hce + Z[i1] @ dHce
        F, dF = np.zeros(self.n_u), np.zeros(self.n_u)
        c0 = self.rows[i1] * nc
        F[c0:c0 + nc], F[c0 + nc:c0 + 2 * nc] = t.real, -t.imag
        dF[c0:c0 + nc], dF[c0 + nc:c0 + 2 * nc] = dt.real, -dt.imag
        return F, dF

    # ------------------------------------------------------------------ strategies
    def __call__(self, w: float) -> LinearPart:
        """The linear part at ``w`` (rad/s); ValueError when ``H_cc`` is singular."""
        return getattr(self, "_" + self.strategy)(float(w))

    def _compiled(self, w):
        nc = self.nc
        ok, H, dH, Z, hdZ, FF = proportional_linear(
            self._Pu, *self._tri, self.phi.shape[0], self.om2, self.cdiag, self._Ru, self.hs, w,
            self.rows, nc, nc, self.i1) if self.reduced.proportional else self._general(w)
        if not ok:
            raise ValueError("contact receptance is singular (dependent contact coordinates?)")
        F, dF = FF[0], FF[1]
        if self.ne > 1:     # the kernels load the cosine column only: add the sine row's share
            e = slice(nc, nc + self.ne)
            F, dF = self._load(Z, hdZ, H[self.i1][:nc, e] @ self.fe, dH[self.i1][:nc, e] @ self.fe)
        return LinearPart(Z, hdZ, F, dF, np.ascontiguousarray(H[:, nc:, :nc + self.ne]))

    def _general(self, w):
        H, dH = receptance_stack(self.phi, self.reduced.omega, self.Cm, False, self.R, self.hs * w)
        H, dH = np.ascontiguousarray(H), np.ascontiguousarray(dH)
        ok, Z, hdZ, FF = condensed_linear(H, dH, self.hs, self.rows, self.nc, self.nc, self.i1)
        return ok, H, dH, Z, hdZ, FF

    def _woodbury(self, w):
        Ws = self.hs * w
        D, dD = self._modal(Ws)
        G = self._B @ np.linalg.inv(D + self._S)                     # B M^{-1}, (n_h, n_c, m)
        nc = self.nc
        GB = np.concatenate((G.real, G.imag), axis=1) @ self._B.T     # (n_h, 2 n_c, n_c) real
        Z = np.empty((Ws.size, nc, nc), dtype=complex)
        Z.real, Z.imag = self._Rinv - GB[:, :nc], -GB[:, nc:]
        hdZ = Congruence(G, self.hs[:, None, None] * dD)
        return self._finish(w, Z, hdZ, np.linalg.inv(D), dD)

    def _dense(self, w):
        Ws = self.hs * w
        D, dD = self._modal(Ws)
        c = np.r_[0:self.nc]
        try:
            Dinv = np.linalg.inv(D)
            Hcc, dHcc = self._receptance_rows(Dinv, c, c, dD)
            Z = np.linalg.inv(Hcc)
        except np.linalg.LinAlgError:
            raise ValueError("contact receptance is singular (dependent contact coordinates?)") from None
        hdZ = -self.hs[:, None, None] * (Z @ dHcc @ Z)
        return self._finish(w, Z, hdZ, Dinv, dD)

    def _finish(self, w, Z, hdZ, Dinv, dD):
        """The load and the output receptances shared by the numpy strategies."""
        Hx, _ = self._receptance_rows(Dinv, self._x, self._y)
        i1, nc = self.i1, self.nc
        Hce, dHce = self._receptance_rows(Dinv[i1:i1 + 1], np.r_[0:nc], np.r_[nc:nc + self.ne], dD[i1:i1 + 1])
        F, dF = self._load(Z, hdZ, Hce[0] @ self.fe, dHce[0] @ self.fe)
        return LinearPart(Z, hdZ, F, dF, Hx)

    def receptances(self, Ws, rows, cols):
        """``H`` between kept coordinates ``rows`` and ``cols`` at ``Ws``, (n_W, len(rows), len(cols))."""
        Ws = np.ascontiguousarray(Ws, dtype=float)
        D, _ = self._modal(Ws)
        return self._receptance_rows(np.linalg.inv(D), np.asarray(rows), np.asarray(cols))[0]

