r"""Harmonic balance on the contact coordinates only, with the linear part condensed exactly.

With the contact coordinates ``u_c = G_c q`` (a set of independent rows spanning every
element's gather rows, so each element reads ``u_e = A_e u_c``), the excitation
``f = G_e^T F_e`` and the receptance ``H`` of the reduced linear structure
(:mod:`hbm.reduction`: kept modes plus residual flexibility), the balance per harmonic is
(Petrov 2011)

.. math::

    R(U, w) = Z_c(w) U + F_{nl}(U, w) - F_{eq}(w) = 0, \qquad
    Z_c(h w) = H_{cc}(h w)^{-1}, \qquad F_{eq} = Z_c H_{ce} F_e ,

    \frac{\partial R}{\partial U} = Z_c + \frac{\partial F_{nl}}{\partial U}, \qquad
    \frac{\partial R}{\partial w} = Z_c' U + \frac{\partial F_{nl}}{\partial w} - F_{eq}', \qquad
    Z_c' = -h\, Z_c H_{cc}' Z_c ,\quad F_{eq}' = Z_c' H_{ce} F_e + h\, Z_c H_{ce}' F_e ,

with ``H' = dH/dW`` at ``W = h w`` and ``F_nl`` the AFT forces of the elements on
``u_e = A_e u_c`` (acting as ``A_e^T f_e`` on the contact coordinates).  The unknowns are
``n_coef x n_c`` numbers whatever the size of the finite-element model; one evaluation
costs ``O(n_c^2 m)`` per harmonic for ``m`` kept modes.  Outputs ``y = G_o q`` follow from
``U`` (:meth:`CondensedModel.recover_outputs`): ``Y = H_oc Z_c U + (H_oe - H_oc Z_c H_ce) F_e``.

Energy balance over a period (:mod:`hbm.energy`), exact for the reduced model: with the
contact forces implied by the linear part, ``F' = F_eq - Z_c U`` (equal to ``F_nl`` at a
solution), the structure carries ``f = G_e^T F_e - G_c^T F'``, the modal amplitudes are
``eta = D(W)^{-1} Phi^T f`` and the excitation coordinate moves by
``y_e = H_ee F_e - H_ec F'``.  The residual-flexibility part ``R f`` does no work over a
period, so

.. math::

    W[F_e, \dot y_e] = \underbrace{\tfrac{T}{2}\sum_h (h w)^2\, \eta_h^H C_m \eta_h}_{\text{viscous}}
    + W[F', \dot U], \qquad
    W[F_e, \dot y_e] - W_{visc} - W[F_{nl}, \dot U] = -W[R, \dot U],

the same check as the full model's (there ``-W[R, \dot X]``).
"""
from __future__ import annotations

import copy

import numpy as np

from .aft import NonlinearForces
from .energy import EnergyBalance
from .fourier import FourierBasis
from .modal_hill import ModalData
from .condensed_kernels import assemble
from .condensed_linear import LinearBuilder, LinearPart
from .reduction import ReducedModel, condense

_RANK_TOL = 1e-10


def contact_coordinates(elements, n_dof: int):
    """Independent contact rows ``G_c`` and each element's rows on them, ``A_e``.

    Rows are taken from the elements' gather matrices in order, skipping any row in the span
    of those already taken, so the coordinates are the elements' own (relative) coordinates
    when these are independent.

    Parameters
    ----------
    elements : sequence of Element
        Gather matrices of shape (n_local, n_dof).
    n_dof : int

    Returns
    -------
    G_c : ndarray, shape (n_c, n_dof)
    A : list of ndarray
        ``A_e`` (n_local, n_c) with ``gather_e = A_e G_c``.
    """
    rows = np.vstack([e.gather for e in elements])
    if rows.shape[1] != n_dof:
        raise ValueError(f"element gather has {rows.shape[1]} columns, the model has {n_dof} DOFs")
    cols = np.flatnonzero(np.any(rows != 0.0, axis=0))
    S = rows[:, cols]
    chosen, Q = [], np.zeros((0, cols.size))
    for i, s in enumerate(S):
        v = s - Q.T @ (Q @ s)
        v = v - Q.T @ (Q @ v)
        nv = np.linalg.norm(v)
        if nv > _RANK_TOL * max(np.linalg.norm(s), 1e-300):
            chosen.append(i)
            Q = np.vstack([Q, v / nv])
    G_c = rows[chosen]
    P = np.linalg.pinv(G_c[:, cols])
    A = []
    for e in elements:
        Ae = e.gather[:, cols] @ P
        err = np.abs(Ae @ G_c[:, cols] - e.gather[:, cols]).max(initial=0.0)
        if err > 1e-9 * max(np.abs(e.gather).max(), 1e-300):
            raise ValueError(f"element {e.name}: its coordinates are not spanned by the contact rows")
        A.append(Ae)
    return G_c, A


def _regathered(element, A):
    """A copy of ``element`` reading its coordinates from the contact coordinates: gather ``A``."""
    e = copy.copy(element)
    G = np.array(A, dtype=float)
    G[np.abs(G) < 1e-14 * max(np.abs(G).max(initial=0.0), 1e-300)] = 0.0
    G.setflags(write=False)
    e.gather = G
    return e


class CondensedHarmonicBalance:
    """Residual ``R(U, w)`` on the contact coordinates (module docstring); the interface of
    :class:`hbm.residual.HarmonicBalance` used by :mod:`hbm.response` and :mod:`hbm.energy`.

    The linear part at a frequency, ``Z_c`` and ``h dZ_c/dW`` per harmonic with the equivalent
    load, comes from :class:`hbm.condensed_linear.LinearBuilder` (few contacts: one compiled
    call; many: the Woodbury form on quantities factored once); one compiled call then writes
    ``Z_c`` into the Jacobian beside the AFT's, so no ``n_u x n_u`` matrix of the linear part
    is ever formed.  The linear part is memoised
    for the last ``w`` and the nonlinear forces for the last residual evaluation (exact ``X``
    and ``w`` only: re-used, they are the same numbers).

    Parameters
    ----------
    reduced : ReducedModel
        Must keep every DOF touched by the elements, the force and the outputs.
    elements : sequence of Element
        Gather matrices over the full model, (n_local, n_dof).
    basis : FourierBasis
        Must contain harmonic 1.
    force : ndarray, shape (n_dof,)
        Cosine excitation at the first harmonic (N per DOF).
    transform : object
        AFT transform built on ``basis``.
    output_rows : ndarray, shape (n_o, n_dof), optional
        Output coordinates ``y = G_o q`` (default: the force's direction).
    linear_strategy : str
        How the linear part is formed (:class:`hbm.condensed_linear.LinearBuilder`): ``auto``
        or one of ``compiled``, ``woodbury``, ``dense`` (the same numbers to round-off).

    Attributes
    ----------
    n_dof : int
        Number of contact coordinates ``n_c`` (the unknowns per coefficient).
    contact_rows : ndarray, shape (n_c, n_dof)
    condensed : CondensedModel
    nl : NonlinearForces
        On the contact coordinates.
    """

    def __init__(self, reduced: ReducedModel, elements, basis: FourierBasis, force, transform,
                 output_rows=None, linear_strategy: str = "auto"):
        if 1 not in basis.harmonics:
            raise ValueError("the harmonic list must contain harmonic 1 (the excitation's)")
        n = reduced.n_dof
        force = np.atleast_2d(np.asarray(force, dtype=float))
        if force.shape not in ((1, n), (2, n)) or not np.any(force):
            raise ValueError(f"force must be a non-zero vector of {n} amplitudes (or cosine and sine rows)")
        G_e = force[:1] if force.shape[0] == 1 or not np.any(force[1]) else force
        if elements:
            G_c, A = contact_coordinates(elements, n)
            elems = [_regathered(e, a) for e, a in zip(elements, A)]
        else:   # linear structure: any coordinate will do, take the excitation's
            G_c, elems = G_e, []
        G_o = G_e if output_rows is None else np.atleast_2d(np.asarray(output_rows, dtype=float))
        self.basis = basis
        self.reduced = reduced
        self.contact_rows = G_c
        self.output_rows = G_o
        self.condensed = cm = condense(reduced, G_c, G_o, G_e)
        nc = G_c.shape[0]
        self.n_dof = nc
        self.nl = NonlinearForces(basis, elems, nc, transform)
        nco = basis.n_coef
        F_e = np.zeros((nco, G_e.shape[0]))      # unit cosine on the first row, unit sine on the second
        F_e[basis.row_of(1, "c"), 0] = 1.0
        if G_e.shape[0] == 2:
            F_e[basis.row_of(1, "s"), 1] = 1.0
        self.F_e = F_e
        # all kept coordinates stacked: contact, excitation, output
        G_all = np.vstack([cm.G_c, cm.G_e, cm.G_o])
        ne, no = cm.G_e.shape[0], cm.G_o.shape[0]
        self._sl = {"c": slice(0, nc), "e": slice(nc, nc + ne), "o": slice(nc + ne, nc + ne + no)}
        self._phi_all = G_all @ reduced.phi
        self._R_all = G_all @ reduced.residual @ G_all.T
        self._om2 = np.ascontiguousarray(reduced.omega ** 2)
        self._cdiag = np.ascontiguousarray(np.diag(reduced.modal_c))
        self._phi = {k: self._phi_all[s] for k, s in self._sl.items()}
        # harmonic rows: cosine (or mean) row of every harmonic, sine rows of h > 0
        h = np.asarray(basis.harmonics)
        self._h = h.astype(float)
        self._i1 = int(np.flatnonzero(h == 1)[0])
        self._rc = np.array([basis.row_of(int(k), "c") for k in h])
        self._pos = np.flatnonzero(h > 0)
        self._zero = np.flatnonzero(h == 0)
        self._rs = self._rc[self._pos] + 1
        # complex amplitudes Xc - i Xs per harmonic from real coefficients and back, as products
        to_c = np.zeros((h.size, nco), dtype=complex)
        to_c[np.arange(h.size), self._rc] = 1.0
        to_c[self._pos, self._rs] = -1j
        to_r = np.zeros((nco, h.size), dtype=complex)
        to_r[self._rc, np.arange(h.size)] = 1.0
        to_r[self._rs, self._pos] = 1j
        self._to_c, self._to_r = to_c, to_r
        self._Fe_c = self._complex(F_e)
        self._builder = LinearBuilder(reduced, self._phi_all, self._R_all, nc, ne, self._h, self._rc, self._i1,
                                      linear_strategy, self._Fe_c[self._i1])
        self._ge = self._Fe_c @ self._phi["e"]          # Phi^T G_e^T F_e per harmonic, (n_h, m)
        d = self.nl.dofs
        self._nl_all = d.size == nc
        idx = (np.arange(nco)[:, None] * nc + d[None, :]).ravel()
        self._nl_ix = np.ix_(idx, idx)
        self._memo_w = None
        self._memo = None
        self._last_nl = None

    @property
    def n_unknowns(self) -> int:
        return self.basis.n_coef * self.n_dof

    # no supports with imposed motion here: every contact coordinate is an unknown
    @property
    def free(self) -> np.ndarray:
        return np.arange(self.n_dof)

    @property
    def fixed(self) -> np.ndarray:
        return np.zeros(0, dtype=int)

    def expand(self, x: np.ndarray) -> np.ndarray:
        """Unknown vector (n_coef * n_c,) -> coefficients (n_coef, n_c)."""
        return x.reshape(self.basis.n_coef, self.n_dof)

    def unknowns(self, X: np.ndarray) -> np.ndarray:
        """Coefficients (n_coef, n_c) -> unknown vector (n_coef * n_c,)."""
        return X.reshape(-1).copy()

    # ------------------------------------------------------------------ complex form
    def _complex(self, X: np.ndarray) -> np.ndarray:
        """Real coefficients (n_coef, q) -> complex amplitudes ``Xc - i Xs`` per harmonic (n_h, q)."""
        return self._to_c @ X

    def _real(self, Y: np.ndarray) -> np.ndarray:
        """Complex amplitudes per harmonic (n_h, q) -> real coefficients (n_coef, q):
        ``Xc = Re Y``, ``Xs = Re(i Y) = -Im Y``."""
        return (self._to_r @ Y).real

    # ------------------------------------------------------------------ linear part
    def _linear(self, w: float) -> LinearPart:
        """The linear part at ``w`` (:class:`hbm.condensed_linear.LinearPart`).

        Memoised for the last ``w`` only (Newton at a fixed frequency re-uses it).
        """
        w = float(w)
        if self._memo_w != w:
            self._memo = self._builder(w)
            self._memo_w = w
        return self._memo

    def load(self, w: float) -> np.ndarray:
        """Equivalent contact load ``F_eq(w)`` (n_coef, n_c)."""
        return self._linear(w).F.reshape(self.basis.n_coef, self.n_dof).copy()

    # ------------------------------------------------------------------ residual
    def residual(self, X: np.ndarray, w: float):
        """Residual and Jacobians.

        Parameters
        ----------
        X : ndarray, shape (n_coef, n_c)
        w : float

        Returns
        -------
        R : ndarray, shape (n_u,)
        dRdX : ndarray, shape (n_u, n_u)
        dRdw : ndarray, shape (n_u,)
        """
        nu = self.n_unknowns
        J, dRw = np.empty((nu, nu)), np.empty(nu)
        R = self._evaluate(X, w, J, dRw)
        return R, J, dRw

    def __call__(self, x: np.ndarray):
        """Continuation form: ``x = [U.ravel(), w]`` -> ``R`` (n_u,), ``[dR/dU, dR/dw]``
        (n_u, n_u + 1), new arrays on every call."""
        nu = self.n_unknowns
        A = np.empty((nu, nu + 1))
        R = self._evaluate(x[:-1].reshape(self.basis.n_coef, self.n_dof), float(x[-1]), A[:, :nu], A[:, nu])
        return R, A

    def _evaluate(self, X: np.ndarray, w: float, J: np.ndarray, dRw: np.ndarray) -> np.ndarray:
        """``R`` (n_u,) returned; ``dR/dU`` written into ``J`` (n_u, n_u), ``dR/dw`` into ``dRw`` (n_u,)."""
        L = self._linear(w)
        x = np.ascontiguousarray(X.reshape(-1), dtype=float)
        nu = x.size
        if not self.nl.n_nl:
            z = np.zeros(nu)
            J[...] = 0.0
            R = np.empty(nu)
            assemble(L.Z, L.hdZ, self._h, self._rc, L.F, L.dF, x, z, z, J, R, dRw)
            return R
        d = self.nl.dofs
        Xn = np.ascontiguousarray(X if self._nl_all else X[:, d], dtype=float)
        if self._nl_all:                             # the AFT writes dF/dU straight into J
            Fn, _, dFw = self.nl.evaluate(Xn, w, J_out=J)
        else:
            Fn, dFn, dFw = self.nl.evaluate(Xn, w)
            if self._nl_all:
                J[...] = dFn
            else:                                    # scatter onto every contact coordinate
                J[...] = 0.0
                J[self._nl_ix] = dFn
        self._last_nl = (float(w), np.array(X, dtype=float), Fn)
        if not self._nl_all:
            nco, n = X.shape
            Fa, dFa = np.zeros((nco, n)), np.zeros((nco, n))
            Fa[:, d], dFa[:, d] = Fn, dFw
            Fn, dFw = Fa, dFa
        R = np.empty(nu)
        assemble(L.Z, L.hdZ, self._h, self._rc, L.F, L.dF, x, np.ascontiguousarray(Fn.reshape(-1)),
                 np.ascontiguousarray(dFw.reshape(-1)), J, R, dRw)
        return R

    def nonlinear_forces(self, X: np.ndarray, w: float) -> np.ndarray:
        """``F_nl`` on the contact coordinates, (n_coef, n_c).

        Re-uses the forces of the last residual evaluation when ``X`` and ``w`` are exactly
        its own (then they are the same numbers); otherwise runs the AFT (forces only).
        """
        if not self.nl.n_nl:
            return np.zeros_like(X, dtype=float)
        d = self.nl.dofs
        last = self._last_nl
        if last is not None and last[0] == float(w) and last[1].shape == X.shape and bool((last[1] == X).all()):
            Fn = last[2].copy()
        else:
            Fn = self.nl.forces(np.ascontiguousarray(X if self._nl_all else X[:, d], dtype=float), w)
        if self._nl_all:
            return Fn
        F = np.zeros_like(X, dtype=float)
        F[:, d] = Fn
        return F

    def nonlinear_jacobian(self, X: np.ndarray, w: float, nl=None):
        """``dF_nl/dU`` on every contact coordinate, (n_coef n_c, n_coef n_c), or ``None``
        without elements.

        ``nl`` : the elements' :class:`~hbm.aft.NonlinearForces` on another basis (``X`` then
        has that basis' rows); default the problem's own."""
        nl = self.nl if nl is None else nl
        if not nl.n_nl:
            return None
        d = nl.dofs
        _, dFn, _ = nl.evaluate(np.ascontiguousarray(X if self._nl_all else X[:, d], dtype=float), w)
        if self._nl_all:
            return dFn
        nco, nc = nl.basis.n_coef, self.n_dof
        idx = (np.arange(nco)[:, None] * nc + d[None, :]).ravel()
        Ja = np.zeros((nco * nc, nco * nc))
        Ja[np.ix_(idx, idx)] = dFn
        return Ja

    def modal_data(self) -> ModalData:
        """The kept modes and residual flexibility on the contact coordinates (:mod:`hbm.modal_hill`)."""
        c = self._sl["c"]
        return ModalData(self.reduced.omega, self._phi["c"], self._R_all[c, c], self.reduced.modal_c)

    def linear_solution(self, w: float, extra_stiffness=None) -> np.ndarray:
        """Solution of ``(Z_c(w) + K_extra) U = F_eq(w)`` (n_coef, n_c): the start of Newton.

        ``extra_stiffness`` (n_c, n_c) adds e.g. the stuck stiffness of the elements.
        Per harmonic in complex form (a real ``K_extra`` adds to the real part of ``Z_c``).
        """
        L = self._linear(w)
        Z = L.Z if extra_stiffness is None else L.Z + np.asarray(extra_stiffness, dtype=float)
        f = self._complex(L.F.reshape(self.basis.n_coef, self.n_dof))
        u = np.zeros_like(f)
        for i in np.flatnonzero(np.any(f != 0.0, axis=1)):
            u[i] = np.linalg.solve(Z[i], f[i])
        return self._real(u)

    def stuck_stiffness(self) -> np.ndarray:
        """Tangent stiffness of the elements at rest on the contact coordinates, (n_c, n_c)."""
        K = np.zeros((self.n_dof, self.n_dof))
        for e in self.nl.elements:
            K += e.gather.T @ e.linear_stiffness() @ e.gather
        return K

    def modal_rows(self) -> np.ndarray:
        """The contact coordinates that :meth:`modal_data`'s ``phi_c`` rows stand for: all."""
        return np.arange(self.n_dof)

    def linear_peak_amplitudes(self, ws, stuck_stiffness=None, stuck_damping=None):
        """Largest first-harmonic amplitudes over ``ws`` of the free and the stuck linear responses.

        ``stuck_damping`` is not used (the stuck limit adds the stiffness only).

        Returns
        -------
        free, stuck : ndarray, shape (n_c,)
        """
        Ks = self.stuck_stiffness() if stuck_stiffness is None else stuck_stiffness
        ws = np.atleast_1d(np.asarray(ws, dtype=float))
        nc = self.n_dof
        free, stuck = np.zeros(nc), np.zeros(nc)
        for w in ws:               # one frequency at a time: n_c^2 memory, not n_w n_c^2
            ne = self._Fe_c.shape[1]
            H = self._builder.receptances(np.array([w]), np.arange(nc), np.arange(nc + ne))[0]
            u = H[:, nc:] @ self._Fe_c[self._i1]               # (n_c,) contact response to F_e
            free = np.maximum(free, np.abs(u))
            try:
                stuck = np.maximum(stuck, np.abs(np.linalg.solve(np.eye(nc) + H[:, :nc] @ Ks, u)))
            except np.linalg.LinAlgError:                      # skip a singular frequency
                pass
        return free, stuck

    # ------------------------------------------------------------------ outputs and energy
    def _implied_forces(self, X: np.ndarray, L: LinearPart) -> np.ndarray:
        """Contact forces implied by the linear part, ``F' = F_eq - Z_c U``, per harmonic (n_h, n_c) complex."""
        f = self._complex(L.F.reshape(X.shape))
        return f - (L.Z @ self._complex(X)[:, :, None])[:, :, 0]

    def _respond(self, a: str, fp: np.ndarray, L: LinearPart) -> np.ndarray:
        """Response ``y_a = H_ae F_e - H_ac F'`` (n_coef, n_a) of coordinates ``a`` (``'e'``, ``'o'``)
        to the implied contact forces ``fp`` (n_h, n_c) complex."""
        nc, ne = self.n_dof, self._sl["e"].stop - self.n_dof
        ra = slice(0, ne) if a == "e" else slice(ne, None)
        Hx = L.Hx[:, ra]
        y = (Hx[:, :, nc:] @ self._Fe_c[:, :, None] - Hx[:, :, :nc] @ fp[:, :, None])[:, :, 0]
        return self._real(y)

    def recover_outputs(self, X: np.ndarray, w: float) -> np.ndarray:
        """Output coefficients ``Y = H_oe F_e - H_oc F'`` (n_coef, n_o) from the contact
        coefficients ``X`` (n_coef, n_c); equal to ``T_oc U + T_oe F_e`` of
        :meth:`hbm.reduction.CondensedModel.recover_outputs`."""
        L = self._linear(w)
        return self._respond("o", self._implied_forces(X, L), L)

    def energy_balance(self, X: np.ndarray, w: float) -> EnergyBalance:
        """Work per period of the excitation, the viscous and the nonlinear forces (module doc).

        In complex form per harmonic (``X_h = Xc - i Xs``, velocity ``i h w X_h``), the work of
        ``F`` on the motion ``Y`` over a period is ``-pi sum_h h Im(conj(F_h) Y_h)``; for the unit
        cosine excitation at harmonic 1 that is ``-pi Im(y_e)`` with ``y_e`` the excitation
        coordinate's harmonic-1 amplitude (with a sine row, ``-pi Im(conj(F_e) . y_e)``).
        """
        r = self.reduced
        L = self._linear(w)
        fp = self._implied_forces(X, L)
        w_nl = np.pi * float(np.vdot(self.nonlinear_forces(X, w), self.basis.D @ X))
        i1, nc = self._i1, self.n_dof
        ne = self._Fe_c.shape[1]
        fe = self._Fe_c[i1]
        ye = L.Hx[i1, :ne, nc:] @ fe - L.Hx[i1, :ne, :nc] @ fp[i1]   # y_e = H_ee F_e - H_ec F'
        w_ex = -np.pi * float(np.vdot(fe, ye).imag)
        # modal amplitudes under F_e and -F' (the mean, W = 0, does no work)
        W = self._h * w
        iW = (1j * W)[:, None]
        g = self._ge - fp @ self._phi["c"]                           # (n_h, m)
        Cm = r.modal_c
        if r.proportional:
            eta = g / (self._om2 - (W * W)[:, None] + iW * self._cdiag)
        else:
            D = iW[:, :, None] * Cm
            ar = np.arange(self._om2.size)
            D[:, ar, ar] += self._om2 - (W * W)[:, None]
            eta = np.linalg.solve(D, g[:, :, None])[:, :, 0]
        v = iW * eta
        w_v = float(np.vdot(v, v @ Cm.T).real)
        return EnergyBalance(w_ex, np.pi / w * w_v, w_nl, np.pi * float(np.linalg.norm(fe) * np.linalg.norm(ye)))
