r"""The linear part of a dense (lumped or full FE) model for :class:`hbm.balance.residual.HarmonicBalance`.

Per coefficient row ``r`` of harmonic ``h_r`` (:func:`hbm.model.linear.fill_dynamic_stiffness`)

.. math::

    (Z X)_r = K X_r + w\, C (D X)_r - w^2 h_r^2 M X_r, \qquad
    (Z' X)_r = C (D X)_r - 2 w h_r^2 M X_r, \qquad F = F_{ex}

with ``F_ex`` a cosine (and sine) force at harmonic 1.  Supports with imposed motion
(base excitation) have prescribed coefficients ``X_b`` and are not unknowns: their rows are
dropped and their coupling ``Z_fb(w) X_b`` moves to the load, ``F(w) = F_ex,f - Z_fb(w) X_b``.

Small models keep ``Z = Z_0 + w Z_1 - w^2 Z_2`` on the unknowns as three matrices built once
(and the support load as three vectors) and assemble in one compiled call
(:mod:`hbm.balance.dense_kernels`).

Energy over a period (:mod:`hbm.balance.energy`): the excitation does ``W[F_ex]`` on the free DOFs and
the support reactions ``R_b`` (the support rows of ``Z X + F_nl - F_ex``) do ``W[R_b]`` on the
supports' velocities; the viscous forces dissipate ``(T/2) sum_r V_r^T C V_r``.
"""
from __future__ import annotations

import numpy as np

from hbm.balance.aft import NonlinearForces
from hbm.balance.dense_kernels import dense_residual
from hbm.balance.energy import work
from hbm.balance.fourier import FourierBasis
from hbm.model.linear import LinearModel, fill_dynamic_stiffness, harmonic_blocks
from hbm.analyses.modal_hill import ModalData, modal_data_of
from hbm.balance.residual import HarmonicBalance

TEMPLATE_MAX = 600     # largest n_coef * n_dof for which Z0, Z1, Z2 are kept (3 n_u^2 floats)


def dense_balance(model: LinearModel, elements, basis: FourierBasis, force, transform,
                  base=None, output_rows=None) -> HarmonicBalance:
    """The harmonic balance of ``model`` with ``elements`` (:class:`DenseLinear`'s parameters)."""
    linear = DenseLinear(model, basis, force, base, output_rows)
    return HarmonicBalance(linear, NonlinearForces(basis, elements, model.n_dof, transform))


def _dense(A) -> np.ndarray:
    return A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float)


class DenseLinear:
    """``Z(w)``, ``F(w)`` and what the analyses ask of a dense model (module docstring).

    Parameters
    ----------
    model : LinearModel
    basis : FourierBasis
        Must contain harmonic 1 (the excitation's).
    force : ndarray, shape (n,) or (2, n)
        Excitation at the first harmonic per DOF: cosine amplitudes, or rows ``[cosine, sine]``.
    base : tuple (dofs, amplitude), optional
        Support DOFs (k,) and the amplitudes (k,) of their imposed motion ``A cos(w t)``.
    output_rows : ndarray, shape (n_o, n), optional
        Output coordinates ``y = G_o q`` (default every DOF).
    """

    def __init__(self, model: LinearModel, basis: FourierBasis, force, base=None, output_rows=None):
        if 1 not in basis.harmonics:
            raise ValueError("the harmonic list must contain harmonic 1 (the excitation's)")
        self.model, self.basis = model, basis
        n = self.n_dof = model.n_dof
        self.output_rows = np.eye(n) if output_rows is None else np.atleast_2d(np.asarray(output_rows, dtype=float))
        nco = basis.n_coef
        Fex = np.zeros((nco, n))
        f = np.atleast_2d(np.asarray(force, dtype=float))
        Fex[basis.row_of(1, "c")] = f[0]
        if f.shape[0] > 1:
            Fex[basis.row_of(1, "s")] = f[1]
        self.Fex = Fex
        fixed = np.zeros(n, dtype=bool)
        Xfix = np.zeros((nco, n))
        if base is not None:
            bd = np.asarray(base[0], dtype=int)
            fixed[bd] = True
            Xfix[basis.row_of(1, "c"), bd] = np.asarray(base[1], dtype=float)
        self.fixed, self.free = np.flatnonzero(fixed), np.flatnonzero(~fixed)
        self.X_fixed = Xfix
        self._all_free = self.fixed.size == 0
        self._fi = (np.arange(nco)[:, None] * n + self.free[None, :]).ravel()
        self._h2 = (basis.h_of_row ** 2).astype(float)
        self._templates = None
        if nco * n <= TEMPLATE_MAX and all(isinstance(m, np.ndarray) for m in (model.K, model.C, model.M)):
            self._templates = self._build_templates()

    def _build_templates(self):
        """``Z_0, Z_1, Z_2`` on the unknowns and the support load's three vectors."""
        n, nco = self.n_dof, self.basis.n_coef
        zero = np.zeros((n, n))
        m = self.model
        fi, xb = self._fi, self.X_fixed.reshape(-1)
        Zs, bs = [], []
        for K, C, M in ((m.K, zero, zero), (zero, m.C, zero), (zero, zero, -m.M)):
            Z = fill_dynamic_stiffness(np.zeros((nco * n, nco * n)), K, C, M, self.basis, 1.0)
            Zs.append(np.ascontiguousarray(Z[np.ix_(fi, fi)]))
            bs.append(Z[fi] @ xb)                    # Z_fb X_b (X_b is zero on the free DOFs)
        return tuple(Zs), (self.Fex.reshape(-1)[fi], *bs)

    @property
    def n_unknowns(self) -> int:
        return self.basis.n_coef * self.free.size

    def expand(self, x: np.ndarray) -> np.ndarray:
        """Unknown vector (n_coef * n_free,) -> full coefficients (n_coef, n) with supports."""
        if self._all_free:
            return x.reshape(self.basis.n_coef, self.n_dof)
        X = self.X_fixed.copy()
        X[:, self.free] = x.reshape(self.basis.n_coef, self.free.size)
        return X

    def unknowns(self, X: np.ndarray) -> np.ndarray:
        """Full coefficients (n_coef, n) -> unknown vector (n_coef * n_free,)."""
        return X.reshape(-1).copy() if self._all_free else X[:, self.free].reshape(-1)

    def load(self, w: float) -> np.ndarray:
        """The excitation ``F_ex`` (n_coef, n) (the supports' load is part of ``Z X``)."""
        return self.Fex.copy()

    def _products(self, X: np.ndarray, w: float):
        """``Z(w) X`` and ``Z'(w) X``, (n_coef, n) each, on every DOF."""
        M, C, K = self.model.M, self.model.C, self.model.K
        h2X = self._h2[:, None] * X
        DX = self.basis.D @ X
        return X @ K + w * (DX @ C) - (w * w) * (h2X @ M), DX @ C - (2.0 * w) * (h2X @ M)

    def assemble(self, X, w, Fn, dFw, J, R, dRw):
        """``R = Z X - F + F_nl`` and ``dR/dw`` written, ``Z`` added to ``J`` (which holds
        ``dF_nl/dX`` on entry), all on the unknowns.

        Parameters
        ----------
        X, Fn, dFw : ndarray, shape (n_coef, n)
            Coefficients, nonlinear forces and their ``w``-derivative on every DOF.
        w : float
        J : ndarray, shape (n_u, n_u)
        R, dRw : ndarray, shape (n_u,)
        """
        fi = None if self._all_free else self._fi
        if self._templates is not None:
            (Z0, Z1, Z2), (fex, b0, b1, b2) = self._templates
            F = fex - (b0 + w * b1 - (w * w) * b2)
            dF = -(b1 - (2.0 * w) * b2)
            x = np.ascontiguousarray(X.reshape(-1) if fi is None else X.reshape(-1)[fi])
            fn, fw = Fn.reshape(-1), dFw.reshape(-1)
            if fi is not None:
                fn, fw = fn[fi], fw[fi]
            dense_residual(Z0, Z1, Z2, w, x, F, dF, np.ascontiguousarray(fn), np.ascontiguousarray(fw), J, R, dRw)
            return
        ZX, dZX = self._products(X, w)
        nco, n = X.shape
        m = self.model
        if fi is None:
            fill_dynamic_stiffness(J, m.K, m.C, m.M, self.basis, w, add=True)
            R[:] = (ZX - self.Fex + Fn).reshape(-1)
            dRw[:] = (dZX + dFw).reshape(-1)
            return
        Z = fill_dynamic_stiffness(np.zeros((nco * n, nco * n)), m.K, m.C, m.M, self.basis, w)
        J += Z[np.ix_(fi, fi)]
        R[:] = (ZX - self.Fex + Fn).reshape(-1)[fi]
        dRw[:] = (dZX + dFw).reshape(-1)[fi]

    def residual_forces(self, X: np.ndarray, w: float, Fn: np.ndarray) -> np.ndarray:
        """``R = Z X - F + F_nl`` (n_u,) on the unknowns, without a Jacobian; ``Fn``
        (n_coef, n) the nonlinear forces on every DOF."""
        ZX, _ = self._products(X, w)
        R = (ZX - self.Fex + Fn).reshape(-1)
        return R if self._all_free else R[self._fi]

    def stuck_inverse(self, Ks: np.ndarray) -> None:
        """No approximate inverse is offered (the dense solves factor the whole Jacobian)."""
        return None

    def work_resolution(self, X: np.ndarray, w: float) -> float:
        """0: :meth:`work` uses the residual's own matrices, so only round-off separates them
        (compare :meth:`hbm.balance.condensed.CondensedLinear.work_resolution`)."""
        return 0.0

    def work(self, X: np.ndarray, w: float, Fn: np.ndarray):
        """Excitation and viscous work per period and the bound ``S`` (:mod:`hbm.balance.energy`).

        ``Fn`` (n_coef, n): the nonlinear forces (the support reactions include them).
        """
        basis = self.basis
        s = 1 if basis.has_zero else 0          # the mean does no work
        V = w * (basis.D @ X)
        Vp = V[s:]
        w_ex = work(basis, self.Fex, V, w)
        bound = np.pi / w * float(np.linalg.norm(self.Fex[s:]) * np.linalg.norm(Vp))
        if self.fixed.size:
            ZX, _ = self._products(X, w)
            Rb = (ZX - self.Fex + Fn)[:, self.fixed]
            w_ex += work(basis, Rb, V[:, self.fixed], w)
            bound += np.pi / w * float(np.linalg.norm(Rb[s:]) * np.linalg.norm(V[s:, self.fixed]))
        return w_ex, work(basis, V @ _dense(self.model.C), V, w), bound

    def modal_data(self, rows: np.ndarray) -> ModalData:
        """Every mode of the free DOFs seen from the DOFs ``rows`` (free ones; indices into
        ``n``); supports with imposed motion are not perturbed (:mod:`hbm.analyses.modal_hill`)."""
        fr = np.ix_(self.free, self.free)
        M, K, C = (_dense(A)[fr] for A in (self.model.M, self.model.K, self.model.C))
        return modal_data_of(M, K, C, np.searchsorted(self.free, rows))

    def recover_outputs(self, X: np.ndarray, w: float) -> np.ndarray:
        """Output coefficients ``X G_o^T`` (n_coef, n_o) of a point ``X`` (n_coef, n)."""
        return X @ self.output_rows.T

    def linear_peak_amplitudes(self, ws, Ks, Cs=None, observed: bool = False):
        """Largest first-harmonic amplitudes over ``ws`` of the free and the stuck linear
        responses (stuck: ``K + Ks``, ``C + Cs``), supports' imposed motion included.
        ``observed`` adds nothing: the excitation and the outputs are combinations of the DOFs.

        Returns
        -------
        free, stuck : ndarray, shape (n_free,)
        """
        fr, fx = self.free, self.fixed
        amp_free, amp_stuck = np.zeros(fr.size), np.zeros(fr.size)
        M, C, K = (_dense(A) for A in (self.model.M, self.model.C, self.model.K))
        Cx = C if Cs is None else C + Cs
        f = self.Fex[self.basis.row_of(1, "c"), fr]
        yb = self.X_fixed[self.basis.row_of(1, "c"), fx]
        for w in np.atleast_1d(ws):
            for Kw, Cw, amp in ((K, C, amp_free), (K + Ks, Cx, amp_stuck)):
                Zc = Kw - w * w * M + 1j * w * Cw
                try:
                    x = np.linalg.solve(Zc[np.ix_(fr, fr)], f - Zc[np.ix_(fr, fx)] @ yb)
                except np.linalg.LinAlgError:
                    continue
                np.maximum(amp, np.abs(x), out=amp)
        return amp_free, amp_stuck

    def linear_solution(self, w: float, extra_stiffness=None) -> np.ndarray:
        """Solution of ``(Z(w) + K_extra) X = F_ex`` (n_coef, n) with the supports' motion
        imposed, harmonic by harmonic.  ``extra_stiffness`` (n, n) adds e.g. the stuck
        stiffness of the elements."""
        blocks, _ = harmonic_blocks(self.model, self.basis, w)
        X = self.X_fixed.copy()
        n, fr = self.n_dof, self.free
        r0 = 0
        for B in blocks:
            nr = B.shape[0] // n
            if extra_stiffness is not None:
                B = B.copy()
                for k in range(nr):
                    B[k * n:(k + 1) * n, k * n:(k + 1) * n] += extra_stiffness
            rows = slice(r0, r0 + nr)
            r0 += nr
            Xr = X[rows]
            f_full = (self.Fex[rows].reshape(-1) - B @ Xr.reshape(-1)).reshape(nr, n)
            if not np.any(f_full[:, fr]):
                continue
            Bb = B.reshape(nr, n, nr, n)[:, fr][:, :, :, fr].reshape(nr * fr.size, nr * fr.size)
            Xr[:, fr] = np.linalg.solve(Bb, f_full[:, fr].reshape(-1)).reshape(nr, fr.size)
        return X
