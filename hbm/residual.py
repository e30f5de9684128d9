r"""Harmonic-balance residual and its exact Jacobian, composed from its parts.

.. math::

    R(X, w) = Z(w) X + F_{nl}(X, w) - F_{ex}, \qquad
    \frac{\partial R}{\partial X} = Z(w) + \frac{\partial F_{nl}}{\partial X}, \qquad
    \frac{\partial R}{\partial w} = Z'(w) X + \frac{\partial F_{nl}}{\partial w}

``X`` has shape (n_coef, n) (harmonic-major, :mod:`hbm.fourier`); ``Z`` is applied block by
block per harmonic (:func:`hbm.linear.harmonic_blocks`); ``F_ex`` is a cosine force at the
first harmonic.  The continuation works on ``x = [X[:, free].ravel(), w]``.

Base (support) excitation: DOFs listed as supports have prescribed coefficients
``X_b`` (a cosine motion at the first harmonic) and are not unknowns; their rows of the
residual are dropped.  Their motion drives the free DOFs through the coupling terms of
``Z`` (stiffness, damping and mass that connect to the support) and through any element
attached to them, exactly as in the full equations.
"""
from __future__ import annotations

import numpy as np

from .aft import NonlinearForces
from .dense_kernels import dense_residual
from .fourier import FourierBasis
from .linear import LinearModel, fill_dynamic_stiffness, harmonic_blocks
from .modal_hill import ModalData, modal_data_of


class HarmonicBalance:
    """Residual ``R(X, w)`` of a linear model with nonlinear elements and a harmonic force.

    Parameters
    ----------
    model : LinearModel
    elements : sequence of Element
    basis : FourierBasis
        Must contain harmonic 1 (the excitation's).
    force : ndarray, shape (n,) or (2, n)
        Excitation at the first harmonic per DOF: cosine amplitudes, or rows ``[cosine, sine]``
        (``F_c cos(w t) + F_s sin(w t)``).
    transform : object
        AFT transform built on ``basis``.
    base : tuple (dofs, amplitude), optional
        Support DOFs (k,) and the amplitudes (k,) of their imposed motion ``A cos(w t)``.
    output_rows : ndarray, shape (n_o, n), optional
        Output coordinates ``y = G_o q`` (:meth:`recover_outputs`; default every DOF).
    """

    def __init__(self, model: LinearModel, elements, basis: FourierBasis, force, transform,
                 base=None, output_rows=None):
        if 1 not in basis.harmonics:
            raise ValueError("the harmonic list must contain harmonic 1 (the excitation's)")
        self.model = model
        self.basis = basis
        n = model.n_dof
        self.output_rows = np.eye(n) if output_rows is None else np.atleast_2d(np.asarray(output_rows, dtype=float))
        self.n_dof = n
        self.nl = NonlinearForces(basis, elements, n, transform)
        Fex = np.zeros((basis.n_coef, n))
        f = np.atleast_2d(np.asarray(force, dtype=float))
        Fex[basis.row_of(1, "c")] = f[0]
        if f.shape[0] > 1:
            Fex[basis.row_of(1, "s")] = f[1]
        self.Fex = Fex
        fixed = np.zeros(n, dtype=bool)
        Xfix = np.zeros((basis.n_coef, n))
        if base is not None:
            bd, ba = base
            fixed[np.asarray(bd, dtype=int)] = True
            Xfix[basis.row_of(1, "c"), np.asarray(bd, dtype=int)] = np.asarray(ba, dtype=float)
        self.fixed = np.flatnonzero(fixed)
        self.free = np.flatnonzero(~fixed)
        self.X_fixed = Xfix
        self._all_free = self.fixed.size == 0
        self._free_index = (np.arange(basis.n_coef)[:, None] * n + self.free[None, :]).ravel()
        self._nl_all = self.nl.n_nl == n
        # row slices of each harmonic's block in the flat unknown vector
        self._slices = []
        r = 0
        for h in basis.harmonics:
            nr = 1 if h == 0 else 2
            self._slices.append(slice(r * n, (r + nr) * n))
            r += nr
        idx = (np.arange(basis.n_coef)[:, None] * n + self.nl.dofs[None, :]).ravel()
        self._nl_index = idx
        self._nl_free = ~np.isin(self.nl.dofs, self.fixed)
        self._modal = None
        h = basis.h_of_row
        self._h2 = (h * h).astype(float)
        # small dense models: Z(w) = Z0 + w Z1 - w^2 Z2 from three matrices built once
        self._templates = None
        mats = (model.K, model.C, model.M)
        if basis.n_coef * n <= self.TEMPLATE_MAX and all(isinstance(m, np.ndarray) for m in mats):
            nu_all, zero = basis.n_coef * n, np.zeros((n, n))
            parts = ((model.K, zero, zero), (zero, model.C, zero), (zero, zero, -model.M))
            self._templates = tuple(fill_dynamic_stiffness(np.zeros((nu_all, nu_all)), K, C, M, basis, 1.0)
                                    for K, C, M in parts)
        self._fex_flat = np.ascontiguousarray(self.Fex.reshape(-1))
        nu_all = basis.n_coef * n
        self._zero_forces = (np.zeros(nu_all), np.zeros((nu_all, nu_all)), np.zeros(nu_all))

    TEMPLATE_MAX = 600     # largest n_coef * n_dof for which Z0, Z1, Z2 are kept (3 n^2 floats)

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

    def linear_part(self, X: np.ndarray, w: float, out=None):
        """``Z(w) X`` (n_coef, n), ``Z(w)`` dense (n_u, n_u) and ``Z'(w) X`` (n_coef, n).

        ``out``, if given, is a zeroed (n_u, n_u) array (or view) that receives ``Z``.

        Per coefficient row ``r`` of harmonic ``h_r``: ``(Z X)_r = K X_r + w C (D X)_r
        - w^2 h_r^2 M X_r`` (``D`` the derivative operator), evaluated for all rows at
        once; ``Z`` is filled harmonic block by harmonic block through a 4-D view.
        """
        if self._templates is not None:
            Z0, Z1, Z2 = self._templates
            nc, n = X.shape
            Zw = Z0 + w * Z1 - (w * w) * Z2
            if out is None:
                Z = Zw
            else:
                Z = out
                Z[...] = Zw
            x = X.reshape(-1)
            z1, z2 = Z1 @ x, Z2 @ x
            dZX = (z1 - (2.0 * w) * z2).reshape(nc, n)
            return (Zw @ x).reshape(nc, n), Z, dZX
        M, C, K = self.model.M, self.model.C, self.model.K
        h2X = self._h2[:, None] * X
        DX = self.basis.D @ X
        ZX = X @ K + w * (DX @ C) - (w * w) * (h2X @ M)
        dZX = DX @ C - (2.0 * w) * (h2X @ M)
        nc, n = X.shape
        Z = fill_dynamic_stiffness(np.zeros((nc * n, nc * n)) if out is None else out, K, C, M, self.basis, w)
        return ZX, Z, dZX

    def residual(self, X: np.ndarray, w: float):
        """Residual and Jacobians.

        Parameters
        ----------
        X : ndarray, shape (n_coef, n)
        w : float

        Returns
        -------
        R : ndarray, shape (n_u,)
            On the free DOFs (harmonic-major).
        dRdX : ndarray, shape (n_u, n_u)
            With respect to the unknowns (free DOFs).
        dRdw : ndarray, shape (n_u,)
        """
        R, J, dRdw = self._full_residual(X, w)
        if self._all_free:
            return R.reshape(-1), J, dRdw.reshape(-1)
        fi = self._free_index
        return R.reshape(-1)[fi], J[np.ix_(fi, fi)], dRdw.reshape(-1)[fi]

    def _full_residual(self, X, w, out=None):
        """Residual (n_coef, n), Jacobian (n_c n, n_c n) and dR/dw (n_coef, n) on all DOFs."""
        ZX, J, dZX = self.linear_part(X, w, out)
        R = ZX - self.Fex
        dRdw = dZX
        if self.nl.n_nl:
            dofs = self.nl.dofs
            if self._nl_all:
                F, dF, dFw = self.nl.evaluate(X, w)
                R += F
                dRdw += dFw
                J += dF
            else:
                F, dF, dFw = self.nl.evaluate(np.ascontiguousarray(X[:, dofs]), w)
                R[:, dofs] += F
                dRdw[:, dofs] += dFw
                J[np.ix_(self._nl_index, self._nl_index)] += dF
        return R, J, dRdw

    def support_reactions(self, X: np.ndarray, w: float) -> np.ndarray:
        """Force the structure needs from its supports to move them, (n_coef, n_fixed):
        the support DOFs' rows of ``Z X + F_nl - F_ex``."""
        ZX, _, _ = self.linear_part(X, w)
        R = ZX - self.Fex + self.nonlinear_forces(X, w)
        return R[:, self.fixed]

    def __call__(self, x: np.ndarray):
        """Continuation form: ``x = [unknowns, w]`` -> ``R`` (n_u,), ``[dR/dX, dR/dw]``
        (n_u, n_u + 1), new arrays on every call."""
        X = self.expand(x[:-1])
        w = float(x[-1])
        if self._all_free and self._templates is not None and (self._nl_all or not self.nl.n_nl):
            return self._dense_call(x, X, w)
        if self._all_free:
            nu = X.size
            Jw = np.zeros((nu, nu + 1))
            R, _, dw = self._full_residual(X, w, Jw[:, :nu])
            Jw[:, nu] = dw.reshape(-1)
            return R.reshape(-1), Jw
        R, J, dw = self.residual(X, w)
        return R, np.hstack([J, dw[:, None]])

    def _dense_call(self, x, X, w):
        """:meth:`__call__` of a small dense model whose DOFs are all free and all touched
        by elements (or none): one compiled assembly (:mod:`hbm.dense_kernels`)."""
        nu = X.size
        if self.nl.n_nl:
            F, dF, dFw = self.nl.evaluate(X, w)
        else:
            F, dF, dFw = self._zero_forces
        A = np.empty((nu, nu + 1))
        R = np.empty(nu)
        Z0, Z1, Z2 = self._templates
        dense_residual(Z0, Z1, Z2, w, np.ascontiguousarray(x[:-1]), self._fex_flat, F.reshape(-1),
                       dF, dFw.reshape(-1), A[:, :nu], R, A[:, nu])
        return R, A

    def modal_data(self) -> ModalData:
        """Every mode of the free DOFs seen from the free nonlinear DOFs (:mod:`hbm.modal_hill`);
        supports with imposed motion are not perturbed.  Computed once."""
        if self._modal is None:
            dense = lambda A: A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=float)
            fr = np.ix_(self.free, self.free)
            M, K, C = (dense(A)[fr] for A in (self.model.M, self.model.K, self.model.C))
            rows = np.searchsorted(self.free, self.nl.dofs[self._nl_free])
            self._modal = modal_data_of(M, K, C, rows)
        return self._modal

    def nonlinear_jacobian(self, X: np.ndarray, w: float, nl=None):
        """``dF_nl/dX`` on the free nonlinear DOFs, (n_coef n_c, n_coef n_c), or ``None``.

        ``nl`` : the elements' :class:`~hbm.aft.NonlinearForces` on another basis (``X`` then
        has that basis' rows); default the problem's own."""
        nl = self.nl if nl is None else nl
        if not nl.n_nl or not self._nl_free.any():
            return None
        _, dF, _ = nl.evaluate(np.ascontiguousarray(X[:, nl.dofs]), w)
        if self._nl_free.all():
            return dF
        k = (np.arange(nl.basis.n_coef)[:, None] * nl.n_nl + np.flatnonzero(self._nl_free)[None, :]).ravel()
        return dF[np.ix_(k, k)]

    def recover_outputs(self, X: np.ndarray, w: float) -> np.ndarray:
        """Output coefficients ``X G_o^T`` (n_coef, n_o) of a point ``X`` (n_coef, n)."""
        return X @ self.output_rows.T

    def modal_rows(self) -> np.ndarray:
        """The DOFs (indices into ``n``) that :meth:`modal_data`'s ``phi_c`` rows stand for."""
        return self.nl.dofs[self._nl_free]

    def linear_peak_amplitudes(self, ws, Ks, Cs=None):
        """Largest first-harmonic amplitudes over ``ws`` of the free and the stuck linear
        responses (stuck: ``K + Ks``, ``C + Cs``), supports' imposed motion included.

        Returns
        -------
        free, stuck : ndarray, shape (n_free,)
        """
        fr, fx = self.free, self.fixed
        amp_free, amp_stuck = np.zeros(fr.size), np.zeros(fr.size)
        M, C, K = self.model.M, self.model.C, self.model.K
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

    def nonlinear_forces(self, X: np.ndarray, w: float) -> np.ndarray:
        """``F_nl`` on all DOFs, (n_coef, n)."""
        if self._nl_all:
            return self.nl.forces(X, w)
        F = np.zeros_like(X)
        if self.nl.n_nl:
            F[:, self.nl.dofs] = self.nl.forces(np.ascontiguousarray(X[:, self.nl.dofs]), w)
        return F

    def linear_solution(self, w: float, extra_stiffness=None) -> np.ndarray:
        """Solution of ``(Z(w) + K_extra) X = F_ex`` (n_coef, n) with the supports' motion
        imposed: the start of Newton.

        ``extra_stiffness`` (n, n) adds e.g. the stuck stiffness of the elements.
        """
        blocks, _ = harmonic_blocks(self.model, self.basis, w)
        X = self.X_fixed.copy()
        n = self.n_dof
        fr = self.free
        for h, s, B in zip(self.basis.harmonics, self._slices, blocks):
            if extra_stiffness is not None:
                B = B.copy()
                for k in range(B.shape[0] // n):
                    B[k * n:(k + 1) * n, k * n:(k + 1) * n] += extra_stiffness
            nr = B.shape[0] // n
            rows = slice(s.start // n, s.start // n + nr)
            Xr = X[rows]
            f_full = (self.Fex[rows].reshape(-1) - B @ Xr.reshape(-1)).reshape(nr, n)
            if not np.any(f_full[:, fr]):
                continue
            Bb = B.reshape(nr, n, nr, n)[:, fr][:, :, :, fr].reshape(nr * fr.size, nr * fr.size)
            Xr[:, fr] = np.linalg.solve(Bb, f_full[:, fr].reshape(-1)).reshape(nr, fr.size)
        return X
