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
from .energy import EnergyBalance, work
from .fourier import FourierBasis
from .reduction import ReducedModel, apply_blocks, condense, real_block

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
                 output_rows=None):
        if 1 not in basis.harmonics:
            raise ValueError("the harmonic list must contain harmonic 1 (the excitation's)")
        n = reduced.n_dof
        force = np.asarray(force, dtype=float)
        if force.shape != (n,) or not np.any(force):
            raise ValueError(f"force must be a non-zero vector of {n} amplitudes")
        G_e = force[None, :]
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
        self.condensed = condense(reduced, G_c, G_o, G_e)
        nc = G_c.shape[0]
        self.n_dof = nc
        self.nl = NonlinearForces(basis, elems, nc, transform)
        F_e = np.zeros((basis.n_coef, 1))
        F_e[basis.row_of(1, "c"), 0] = 1.0
        self.F_e = F_e
        self._slices = []
        r = 0
        for h in basis.harmonics:
            nr = 1 if h == 0 else 2
            self._slices.append(slice(r * nc, (r + nr) * nc))
            r += nr
        self._nl_index = (np.arange(basis.n_coef)[:, None] * nc + self.nl.dofs[None, :]).ravel()
        cg = {"c": self.condensed.G_c, "e": self.condensed.G_e, "o": self.condensed.G_o}
        self._phi = {k: G @ reduced.phi for k, G in cg.items()}
        self._R = {a + b: cg[a] @ reduced.residual @ cg[b].T for a, b in ("cc", "ce", "ee", "ec", "oc", "oe")}
        self._outer = {}
        self._c = np.ascontiguousarray(np.diag(reduced.modal_c))
        self._h = np.asarray(basis.harmonics, dtype=float)
        self._i1 = int(np.flatnonzero(basis.harmonics == 1)[0])
        self._rows = [basis.row_of(int(h), "c") for h in basis.harmonics]
        self._memo_w = None
        self._memo = None

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

    # ------------------------------------------------------------------ linear part
    def _receptances(self, a: str, b: str, Ws: np.ndarray):
        """``H_ab(W)`` and ``dH_ab/dW`` for all ``Ws`` at once, (n_W, n_a, n_b) complex."""
        r = self.reduced
        pa, pb = self._phi[a], self._phi[b]
        Rab = self._R[a + b]
        om2 = r.omega ** 2
        if r.proportional:
            # H_ab(W) = sum_r P_r / d_r(W) + R_ab with P_r = phi_a[:, r] phi_b[:, r]^T: one product
            P = self._outer.get(a + b)
            if P is None:
                P = self._outer[a + b] = np.einsum("ir,jr->rij", pa, pb).reshape(om2.size, -1)
            c = self._c
            d = om2[None, :] - Ws[:, None] ** 2 + 1j * Ws[:, None] * c[None, :]
            inv = 1.0 / d
            dinv = (2.0 * Ws[:, None] - 1j * c[None, :]) * inv * inv
            shape = (Ws.size, pa.shape[0], pb.shape[0])
            H = (inv @ P).reshape(shape) + Rab
            dH = (dinv @ P).reshape(shape)
            return H, dH
        H = np.empty((Ws.size, pa.shape[0], pb.shape[0]), dtype=complex)
        dH = np.empty_like(H)
        for i, W in enumerate(Ws):
            H[i], dH[i] = self.condensed.receptance(a, b, W)
        return H, dH

    def _linear(self, w: float):
        """``Z_c``, ``dZ_c/dW`` per harmonic (n_h, n_c, n_c) complex, and ``F_eq``, ``dF_eq/dw``
        (n_coef, n_c).

        Memoised for the last ``w`` only (Newton at a fixed frequency re-uses it).
        """
        w = float(w)
        if self._memo_w == w:
            return self._memo
        Ws = self._h * w
        Hcc, dHcc = self._receptances("c", "c", Ws)
        try:
            Z = np.linalg.inv(Hcc)
        except np.linalg.LinAlgError:
            raise ValueError("contact receptance is singular (dependent contact coordinates?)") from None
        dZ = -Z @ dHcc @ Z
        F = np.zeros((self.basis.n_coef, self.n_dof))
        dF = np.zeros_like(F)
        i1 = self._i1
        Hce, dHce = self._receptances("c", "e", Ws[i1:i1 + 1])
        t = Z[i1] @ Hce[0, :, 0]                       # unit cosine force at harmonic 1
        dt = dZ[i1] @ Hce[0, :, 0] + Z[i1] @ dHce[0, :, 0]
        k = self.basis.row_of(1, "c")
        F[k], F[k + 1] = t.real, -t.imag               # Fc - i Fs = t
        dF[k], dF[k + 1] = dt.real, -dt.imag
        self._memo_w, self._memo = w, (Z, dZ, F, dF)
        return self._memo

    def _blocks(self, w: float):
        """Real blocks ``Z_h`` per harmonic, as :func:`hbm.linear.harmonic_blocks` lays them out."""
        Z = self._linear(w)[0]
        return [np.ascontiguousarray(z.real) if h == 0 else real_block(z)
                for h, z in zip(self.basis.harmonics, Z)]

    def load(self, w: float) -> np.ndarray:
        """Equivalent contact load ``F_eq(w)`` (n_coef, n_c)."""
        return self._linear(w)[2]

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
        Z, dZ, F, dF = self._linear(w)
        n = self.n_dof
        R = -F.copy()
        dRw = -dF.copy()
        J = np.zeros((X.size, X.size))
        Jv = J.reshape(self.basis.n_coef, n, self.basis.n_coef, n)
        for h, kc, z, dz in zip(self.basis.harmonics, self._rows, Z, dZ):
            if h == 0:
                R[kc] += z.real @ X[kc]
                Jv[kc, :, kc, :] = z.real
                continue
            ks = kc + 1
            u = X[kc] - 1j * X[ks]
            zu = z @ u
            dzu = h * (dz @ u)
            R[kc] += zu.real
            R[ks] -= zu.imag
            dRw[kc] += dzu.real
            dRw[ks] -= dzu.imag
            Jv[kc, :, kc, :] = z.real
            Jv[kc, :, ks, :] = z.imag
            Jv[ks, :, kc, :] = -z.imag
            Jv[ks, :, ks, :] = z.real
        if self.nl.n_nl:
            d = self.nl.dofs
            Fn, dFn, dFw = self.nl.evaluate(np.ascontiguousarray(X[:, d]), w)
            R[:, d] += Fn
            dRw[:, d] += dFw
            J[np.ix_(self._nl_index, self._nl_index)] += dFn
        return R.reshape(-1), J, dRw.reshape(-1)

    def __call__(self, x: np.ndarray):
        """Continuation form: ``x = [U.ravel(), w]`` -> ``R`` (n_u,), ``[dR/dU, dR/dw]`` (n_u, n_u + 1)."""
        X = x[:-1].reshape(self.basis.n_coef, self.n_dof)
        R, J, dw = self.residual(X, float(x[-1]))
        return R, np.hstack([J, dw[:, None]])

    def nonlinear_forces(self, X: np.ndarray, w: float) -> np.ndarray:
        """``F_nl`` on the contact coordinates, (n_coef, n_c)."""
        F = np.zeros_like(X)
        if self.nl.n_nl:
            F[:, self.nl.dofs] = self.nl.forces(np.ascontiguousarray(X[:, self.nl.dofs]), w)
        return F

    def linear_solution(self, w: float, extra_stiffness=None) -> np.ndarray:
        """Solution of ``(Z_c(w) + K_extra) U = F_eq(w)`` (n_coef, n_c): the start of Newton.

        ``extra_stiffness`` (n_c, n_c) adds e.g. the stuck stiffness of the elements.
        """
        blocks, F = self._blocks(w), self._linear(w)[2]
        X = np.zeros_like(F)
        f, x = F.reshape(-1), X.reshape(-1)
        n = self.n_dof
        for s, B in zip(self._slices, blocks):
            if not np.any(f[s]):
                continue
            if extra_stiffness is not None:
                B = B + np.kron(np.eye(B.shape[0] // n), extra_stiffness)
            x[s] = np.linalg.solve(B, f[s])
        return X

    def stuck_stiffness(self) -> np.ndarray:
        """Tangent stiffness of the elements at rest on the contact coordinates, (n_c, n_c)."""
        K = np.zeros((self.n_dof, self.n_dof))
        for e in self.nl.elements:
            K += e.gather.T @ e.linear_stiffness() @ e.gather
        return K

    def linear_peak_amplitudes(self, ws, stuck_stiffness=None):
        """Largest first-harmonic amplitudes over ``ws`` of the free and the stuck linear responses.

        Returns
        -------
        free, stuck : ndarray, shape (n_c,)
        """
        cm = self.condensed
        Ks = self.stuck_stiffness() if stuck_stiffness is None else stuck_stiffness
        free = np.zeros(self.n_dof)
        stuck = np.zeros(self.n_dof)
        for w in ws:
            Hcc, _ = cm.receptance("c", "c", w)
            Hce, _ = cm.receptance("c", "e", w)
            u = Hce[:, 0]
            np.maximum(free, np.abs(u), out=free)
            try:
                us = np.linalg.solve(np.eye(self.n_dof) + Hcc @ Ks, u)
            except np.linalg.LinAlgError:
                continue
            np.maximum(stuck, np.abs(us), out=stuck)
        return free, stuck

    # ------------------------------------------------------------------ outputs and energy
    def _implied_forces(self, X: np.ndarray, w: float) -> np.ndarray:
        """Contact forces implied by the linear part, ``F' = F_eq - Z_c U`` (n_coef, n_c)."""
        return self._linear(w)[2] - apply_blocks(self._blocks(w), self.basis, X)

    def _respond(self, a: str, X: np.ndarray, w: float) -> np.ndarray:
        """Response ``y_a = H_ae F_e - H_ac F'`` (n_coef, n_a) of coordinates ``a`` (``'e'``, ``'o'``)."""
        Fp = self._implied_forces(X, w)
        Ws = self._h * w
        Hae, _ = self._receptances(a, "e", Ws)
        Hac, _ = self._receptances(a, "c", Ws)
        Y = np.zeros((self.basis.n_coef, Hae.shape[1]))
        for i, (h, kc) in enumerate(zip(self.basis.harmonics, self._rows)):
            if h == 0:
                Y[kc] = Hae[i].real @ self.F_e[kc] - Hac[i].real @ Fp[kc]
                continue
            y = Hae[i] @ (self.F_e[kc] - 1j * self.F_e[kc + 1]) - Hac[i] @ (Fp[kc] - 1j * Fp[kc + 1])
            Y[kc], Y[kc + 1] = y.real, -y.imag
        return Y

    def recover_outputs(self, X: np.ndarray, w: float) -> np.ndarray:
        """Output coefficients ``Y = H_oe F_e - H_oc F'`` (n_coef, n_o) from the contact
        coefficients ``X`` (n_coef, n_c); equal to ``T_oc U + T_oe F_e`` of
        :meth:`hbm.reduction.CondensedModel.recover_outputs`."""
        return self._respond("o", X, w)

    def energy_balance(self, X: np.ndarray, w: float) -> EnergyBalance:
        """Work per period of the excitation, the viscous and the nonlinear forces (module doc)."""
        basis = self.basis
        r = self.reduced
        Fp = self._implied_forces(X, w)
        V = w * (basis.D @ X)
        w_nl = work(basis, self.nonlinear_forces(X, w), V, w)
        w_ex = work(basis, self.F_e, w * (basis.D @ self._respond("e", X, w)), w)
        w_v = 0.0
        Cm = r.modal_c
        om2 = r.omega ** 2
        for h, kc in zip(basis.harmonics, self._rows):
            if h == 0:
                continue
            W = h * w
            fc = Fp[kc] - 1j * Fp[kc + 1]
            fe = self.F_e[kc] - 1j * self.F_e[kc + 1]
            g = self._phi["e"].T @ fe - self._phi["c"].T @ fc
            if r.proportional:
                eta = g / (om2 - W * W + 1j * W * np.diag(Cm))
            else:
                eta = np.linalg.solve(np.diag(om2 - W * W) + 1j * W * Cm, g)
            v = 1j * W * eta
            w_v += float(np.real(np.vdot(v, Cm @ v)))
        return EnergyBalance(w_ex, np.pi / w * w_v, w_nl)
