r"""Harmonic balance on the contact coordinates only, with the linear part condensed exactly.

With the contact coordinates ``u_c = G_c q`` (a set of independent rows spanning every
element's gather rows, so each element reads ``u_e = A_e u_c``), the excitation
``f = G_e^T F_e`` and the receptance ``H`` of the reduced linear structure
(:mod:`hbm.model.reduction`: kept modes plus residual flexibility), the balance per harmonic is
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

Energy balance over a period (:mod:`hbm.balance.energy`), exact for the reduced model: with the
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

import numpy as np

from hbm.balance.aft import NonlinearForces
from hbm.balance.condensed_kernels import assemble
from hbm.balance.condensed_linear import LinearBuilder, LinearPart
from hbm.balance.contact_coordinates import contact_coordinates, regathered
from hbm.balance.fourier import FourierBasis
from hbm.balance.stuck_inverse import StuckInverse
from hbm.analyses.modal_hill import ModalData
from hbm.model.condensed_model import condense
from hbm.model.reduction import ReducedModel
from hbm.balance.residual import HarmonicBalance


def condensed_balance(reduced: ReducedModel, elements, basis: FourierBasis, force, transform,
                      output_rows=None, linear_strategy: str = "auto") -> HarmonicBalance:
    """The harmonic balance of ``reduced`` with ``elements`` on their contact coordinates
    (:class:`CondensedLinear`'s parameters)."""
    linear = CondensedLinear(reduced, elements, basis, force, output_rows, linear_strategy)
    return HarmonicBalance(linear, NonlinearForces(basis, linear.elements, linear.n_dof, transform))


class CondensedLinear:
    """``Z_c(w)``, ``F_eq(w)`` and what the analyses ask of a reduced model, on the contact
    coordinates (module docstring).

    The linear part at a frequency, ``Z_c`` and ``h dZ_c/dW`` per harmonic with the equivalent
    load, comes from :class:`hbm.balance.condensed_linear.LinearBuilder` (few contacts: one compiled
    call; many: the Woodbury form on quantities factored once); one compiled call then adds
    ``Z_c`` to the Jacobian beside the AFT's, so no ``n_u x n_u`` matrix of the linear part is
    ever formed.  :meth:`at` keeps the last frequency's parts (Newton at a fixed frequency
    asks for them again; the same numbers either way).

    Parameters
    ----------
    reduced : ReducedModel
        Must keep every DOF touched by the elements, the force and the outputs.
    elements : sequence of Element
        Gather matrices over the full model, (n_local, n_dof).
    basis : FourierBasis
        Must contain harmonic 1.
    force : ndarray, shape (n_dof,) or (2, n_dof)
        Cosine (and sine) excitation at the first harmonic (N per DOF).
    output_rows : ndarray, shape (n_o, n_dof), optional
        Output coordinates ``y = G_o q`` (default: the force's direction).
    linear_strategy : str
        How the linear part is formed (:class:`hbm.balance.condensed_linear.LinearBuilder`): ``auto``
        or one of ``compiled``, ``woodbury``, ``dense`` (the same numbers to round-off).

    Attributes
    ----------
    n_dof : int
        Number of contact coordinates ``n_c`` (the unknowns per coefficient).
    contact_rows : ndarray, shape (n_c, n_dof)
    elements : list of Element
        The elements reading the contact coordinates (gather ``A_e``).
    condensed : CondensedModel
    """

    def __init__(self, reduced: ReducedModel, elements, basis: FourierBasis, force,
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
            elems = [regathered(e, a) for e, a in zip(elements, A)]
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
        self.elements = elems
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
        self._last = (None, None)

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

    def to_complex(self, x: np.ndarray) -> np.ndarray:
        """Unknown vector (n_u,) -> complex amplitudes ``X_c - i X_s`` per harmonic (n_h, n_c)."""
        return self._complex(x.reshape(self.basis.n_coef, self.n_dof))

    def to_real(self, Y: np.ndarray) -> np.ndarray:
        """Complex amplitudes per harmonic (n_h, n_c) -> unknown vector (n_u,)."""
        return self._real(Y).reshape(-1)

    # ------------------------------------------------------------------ linear part
    @property
    def last_frequency(self) -> float | None:
        """The frequency of the linear part last built (:meth:`at`), or None."""
        return self._last[0]

    def stuck_inverse(self, Ks: np.ndarray) -> StuckInverse | None:
        """The approximate inverse of the balance's Jacobian with the elements' rest stiffness
        ``Ks`` (n_c, n_c) (:mod:`hbm.balance.stuck_inverse`); None unless the linear part is
        in the Woodbury form."""
        parts = self._builder.woodbury_parts()
        return None if parts is None else StuckInverse(*parts, Ks, self)

    def at(self, w: float) -> LinearPart:
        """The linear part at ``w`` (:class:`hbm.balance.condensed_linear.LinearPart`); the last
        frequency's is kept."""
        w = float(w)
        if self._last[0] != w:
            self._last = (w, self._builder(w))
        return self._last[1]

    def load(self, w: float) -> np.ndarray:
        """Equivalent contact load ``F_eq(w)`` (n_coef, n_c)."""
        return self.at(w).F.reshape(self.basis.n_coef, self.n_dof).copy()

    # ------------------------------------------------------------------ residual
    def assemble(self, X, w, Fn, dFw, J, R, dRw):
        """``R = Z_c U - F_eq + F_nl`` and ``dR/dw`` written, ``Z_c`` added to ``J`` (which
        holds ``dF_nl/dU`` on entry).

        Parameters
        ----------
        X, Fn, dFw : ndarray, shape (n_coef, n_c)
            Contact coefficients, nonlinear forces and their ``w``-derivative.
        w : float
        J : ndarray, shape (n_u, n_u)
        R, dRw : ndarray, shape (n_u,)
        """
        L = self.at(w)
        assemble(L.Z, self._h, self._rc, L.F, L.dF, np.ascontiguousarray(X.reshape(-1), dtype=float),
                 np.ascontiguousarray(Fn.reshape(-1)), np.ascontiguousarray(dFw.reshape(-1)), J, R, dRw)
        dZU = (L.hdZ @ self._complex(X.reshape(-1, self.n_dof))[:, :, None])[:, :, 0]
        dRw += self._real(dZU).reshape(-1)

    def residual_forces(self, X: np.ndarray, w: float, Fn: np.ndarray) -> np.ndarray:
        """``R = Z_c U - F_eq + F_nl`` (n_u,) without a Jacobian: the nonlinear forces ``Fn``
        (n_coef, n_c) less the contact forces the linear part implies."""
        return (Fn - self._real(self._implied_forces(X, self.at(w)))).reshape(-1)

    def modal_data(self, rows: np.ndarray) -> ModalData:
        """The kept modes and residual flexibility seen from the contact coordinates ``rows``
        (:mod:`hbm.analyses.modal_hill`)."""
        Rcc = self._R_all[self._sl["c"], self._sl["c"]]
        return ModalData(self.reduced.omega, self._phi["c"][rows], Rcc[np.ix_(rows, rows)], self.reduced.modal_c)

    def linear_solution(self, w: float, extra_stiffness=None) -> np.ndarray:
        """Solution of ``(Z_c(w) + K_extra) U = F_eq(w)`` (n_coef, n_c): the start of Newton.

        ``extra_stiffness`` (n_c, n_c) adds e.g. the stuck stiffness of the elements.
        Per harmonic in complex form (a real ``K_extra`` adds to the real part of ``Z_c``).
        """
        L = self.at(w)
        Z = L.Z if extra_stiffness is None else L.Z + np.asarray(extra_stiffness, dtype=float)
        f = self._complex(L.F.reshape(self.basis.n_coef, self.n_dof))
        u = np.zeros_like(f)
        for i in np.flatnonzero(np.any(f != 0.0, axis=1)):
            u[i] = np.linalg.solve(Z[i], f[i])
        return self._real(u)

    def linear_peak_amplitudes(self, ws, Ks, Cs=None, observed: bool = False):
        """Largest first-harmonic amplitudes over ``ws`` of the free and the stuck linear
        responses (stuck: ``Z_c + Ks``, (n_c, n_c)).

        ``Cs`` is not used (the stuck limit adds the stiffness only).  ``observed`` appends the
        excitation and output coordinates (their stuck response: ``y = H_ae F_e - H_ac Ks U``).

        Returns
        -------
        free, stuck : ndarray, shape (n_c,), or (n_c + n_e + n_o,) when ``observed``
        """
        ws = np.atleast_1d(np.asarray(ws, dtype=float))
        nc, ne = self.n_dof, self._Fe_c.shape[1]
        rows = np.arange(self._sl["o"].stop if observed else nc)
        free, stuck = np.zeros(rows.size), np.zeros(rows.size)
        for w in ws:               # one frequency at a time: n_c^2 memory, not n_w n_c^2
            H = self._builder.receptances(np.array([w]), rows, np.arange(nc + ne))[0]
            u = H[:, nc:] @ self._Fe_c[self._i1]               # response to F_e
            free = np.maximum(free, np.abs(u))
            try:
                uc = np.linalg.solve(np.eye(nc) + H[:nc, :nc] @ Ks, u[:nc])
            except np.linalg.LinAlgError:                      # skip a singular frequency
                continue
            stuck = np.maximum(stuck, np.abs(np.r_[uc, u[nc:] - H[nc:, :nc] @ (Ks @ uc)]))
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
        :meth:`hbm.model.condensed_model.CondensedModel.recover_outputs`."""
        L = self.at(w)
        return self._respond("o", self._implied_forces(X, L), L)

    def work_resolution(self, X: np.ndarray, w: float) -> float:
        """How well :meth:`work` can check a point (J per period): the work of the implied
        contact forces ``F'`` on ``X - (H_ce F_e - H_cc F')``, the gap between the contact motion
        and the one the receptances give for those forces.

        The residual's ``Z = H_cc^{-1}`` and the works' modal sums are the same model in exact
        arithmetic, but next to a mode the contacts block (the structure's own resonance with
        the contacts open) ``H_cc`` is nearly singular and they agree only to about
        ``eps cond(H_cc)``: on the 64-contact patch 3e-12 relative at 6370 Hz, where the exact
        stuck solution shows an energy imbalance of 1e-8 that no Newton update can close.
        """
        L = self.at(w)
        fp = self._implied_forces(X, L)
        nc = self.n_dof
        ne = self._Fe_c.shape[1]
        H = self._builder.receptances(self._h * w, np.arange(nc), np.arange(nc + ne))
        yc = (H[:, :, nc:] @ self._Fe_c[:, :, None] - H[:, :, :nc] @ fp[:, :, None])[:, :, 0]
        gap = self._complex(X) - yc
        return abs(np.pi * float(np.sum(self._h[:, None] * (np.conj(fp) * gap).imag)))

    def work(self, X: np.ndarray, w: float, Fn=None):
        """Excitation and viscous work per period and the bound ``S`` (module doc,
        :mod:`hbm.balance.energy`); the nonlinear forces ``Fn`` are not needed here.

        In complex form per harmonic (``X_h = Xc - i Xs``, velocity ``i h w X_h``), the work of
        ``F`` on the motion ``Y`` over a period is ``-pi sum_h h Im(conj(F_h) Y_h)``; for the unit
        cosine excitation at harmonic 1 that is ``-pi Im(y_e)`` with ``y_e`` the excitation
        coordinate's harmonic-1 amplitude (with a sine row, ``-pi Im(conj(F_e) . y_e)``).
        """
        r = self.reduced
        L = self.at(w)
        fp = self._implied_forces(X, L)
        i1, nc = self._i1, self.n_dof
        ne = self._Fe_c.shape[1]
        fe = self._Fe_c[i1]
        ye = L.Hx[i1, :ne, nc:] @ fe - L.Hx[i1, :ne, :nc] @ fp[i1]   # y_e = H_ee F_e - H_ec F'
        w_ex = -np.pi * float(np.vdot(fe, ye).imag)
        # modal amplitudes under F_e and -F' (the mean, W = 0, does no work)
        v = (1j * self._h * w)[:, None] * self._modal(fp, w)
        w_v = float(np.vdot(v, v @ r.modal_c.T).real)
        return w_ex, np.pi / w * w_v, np.pi * float(np.linalg.norm(fe) * np.linalg.norm(ye))

    def _modal(self, fp: np.ndarray, w: float) -> np.ndarray:
        """Modal amplitudes ``eta`` (n_h, m) complex under ``F_e`` and the contact forces
        ``-fp`` (n_h, n_c) complex: ``(Omega^2 - W^2 + i W C_m) eta = Phi_e^T F_e - Phi_c^T fp``."""
        r = self.reduced
        W = self._h * w
        iW = (1j * W)[:, None]
        g = self._ge - fp @ self._phi["c"]                           # (n_h, m)
        if r.proportional:
            return g / (self._om2 - (W * W)[:, None] + iW * self._cdiag)
        D = iW[:, :, None] * r.modal_c
        ar = np.arange(self._om2.size)
        D[:, ar, ar] += self._om2 - (W * W)[:, None]
        return np.linalg.solve(D, g[:, :, None])[:, :, 0]

    def modal_coefficients(self, X: np.ndarray, w: float) -> np.ndarray:
        """Coefficients (n_coef, m) of the kept modes' coordinates at the balance point ``X``
        (n_coef, n_c), under the excitation and the contact forces the balance implies."""
        return self._real(self._modal(self._implied_forces(X, self.at(w)), w))
