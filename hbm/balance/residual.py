r"""Harmonic-balance residual and its exact Jacobian: one formula, one AFT call, any linear part.

.. math::

    R(X, w) = Z(w) X + F_{nl}(X, w) - F(w), \qquad
    \frac{\partial R}{\partial X} = Z(w) + \frac{\partial F_{nl}}{\partial X}, \qquad
    \frac{\partial R}{\partial w} = Z'(w) X + \frac{\partial F_{nl}}{\partial w} - F'(w)

on the coordinates ``X`` (n_coef, n) (harmonic-major, :mod:`hbm.balance.fourier`) that the elements
read.  ``F_nl`` is the AFT of the elements (:class:`hbm.balance.aft.NonlinearForces`); everything else
is the *linear part*, of which there are two, with the same interface:

- :class:`hbm.balance.dense_part.DenseLinear`: the coordinates are the model's DOFs, ``Z`` is built
  per harmonic from ``M, C, K`` and ``F = F_ex`` (supports with imposed motion add a load and
  drop their rows);
- :class:`hbm.balance.condensed.CondensedLinear`: the coordinates are the contact coordinates of a
  reduced model, ``Z = H_cc^{-1}`` from kept modes and residual flexibility and
  ``F = Z H_ce F_e`` (exact condensation).

A linear part offers ``basis``, ``n_dof``, ``free``, ``fixed``, ``n_unknowns``, ``expand``,
``unknowns``, ``assemble`` (adds ``Z``, writes ``R`` and ``dR/dw`` given the nonlinear forces),
``load``, ``work`` (excitation and viscous work per period), ``residual_forces`` (``R`` without
a Jacobian, for the checks of :mod:`hbm.analyses.polish`), ``recover_outputs``,
``linear_solution``, ``linear_peak_amplitudes`` and ``modal_data`` (Hill's matrices).  The
continuation works on ``x = [unknowns, w]``.

The elements' Jacobian goes straight into the continuation's matrix when they read every
unknown, or when every element is a compiled law and the model has no supports (the laws then
write on the unknowns' own columns, :meth:`hbm.balance.aft.NonlinearForces.evaluate_laws_on`);
otherwise it is formed on the DOFs the elements read and scattered (on the 3-DOF chain with
contacts on DOFs 0 and 2, the scatter was a third of an evaluation: 71 -> 46 us).
"""
from __future__ import annotations

import numpy as np

from continuation.linsolve import Structure
from elements.base import rest_tangents

from hbm.balance.aft import NonlinearForces
from hbm.balance.energy import EnergyBalance, work
from hbm.analyses.modal_hill import ModalData


class HarmonicBalance:
    """Residual ``R(X, w)`` of a linear part with nonlinear elements (module docstring).

    Parameters
    ----------
    linear : DenseLinear or CondensedLinear
        The linear part on ``n`` coordinates.
    nl : NonlinearForces
        The elements on the same coordinates and basis.
    """

    def __init__(self, linear, nl: NonlinearForces):
        if nl.basis is not linear.basis and list(nl.basis.harmonics) != list(linear.basis.harmonics):
            raise ValueError("the elements' basis differs from the linear part's")
        self.linear = linear
        self.nl = nl
        self.basis = linear.basis
        self.n_dof = linear.n_dof
        free = linear.free
        d = nl.dofs
        self._nl_free = np.isin(d, free)
        # the AFT writes dF/dX straight into the Jacobian when the elements read every unknown,
        # or (compiled laws, no supports) on the unknowns' own columns
        self._direct = d.size == free.size == self.n_dof and bool(np.all(d == np.arange(self.n_dof)))
        self._laws_on = (nl.laws_columns(d) if nl.n_nl and not self._direct and free.size == self.n_dof
                         else None)
        nco, nn = self.basis.n_coef, d.size
        k = (np.arange(nco)[:, None] * nn + np.flatnonzero(self._nl_free)[None, :]).ravel()
        u = (np.arange(nco)[:, None] * free.size + np.searchsorted(free, d[self._nl_free])[None, :]).ravel()
        # nonlinear Jacobian entries on free coordinates -> unknowns, as index grids made once
        self._kk, self._uu = np.ix_(k, k), np.ix_(u, u)
        # the Newton solves' approximate inverse (every contact stuck), when the linear part offers one
        self._stuck_inverse = linear.stuck_inverse(self.stuck_stiffness()) if nl.n_nl else None

    # ------------------------------------------------------------------ unknowns
    @property
    def free(self) -> np.ndarray:
        return self.linear.free

    @property
    def fixed(self) -> np.ndarray:
        return self.linear.fixed

    @property
    def n_unknowns(self) -> int:
        return self.linear.n_unknowns

    def expand(self, x: np.ndarray) -> np.ndarray:
        """Unknown vector (n_u,) -> coefficients of every coordinate (n_coef, n)."""
        return self.linear.expand(x)

    def unknowns(self, X: np.ndarray) -> np.ndarray:
        """Coefficients (n_coef, n) -> unknown vector (n_u,)."""
        return self.linear.unknowns(X)

    def harmonic_blocks(self) -> list:
        """``[(start, stop, paired), ...]``: the unknowns of each harmonic in order, its cosine
        rows then its sine rows (``paired``: a harmonic above 0, whose linear part acts on
        ``X_c - i X_s`` as one complex matrix).  ``Z`` couples nothing across harmonics; only
        the nonlinear Jacobian does, through contacts whose stiffness varies over the period
        (slip, separation), so the blocks precondition the Newton solves
        (:class:`continuation.linsolve.BlockPreconditioned`)."""
        nf = self.n_unknowns // self.basis.n_coef
        h = self.basis.h_of_row
        edges = np.flatnonzero(np.r_[True, h[1:] != h[:-1], True])
        return [(int(a) * nf, int(b) * nf, bool(h[a] > 0)) for a, b in zip(edges[:-1], edges[1:])]

    def solver_structure(self) -> Structure:
        """:meth:`harmonic_blocks` and, on a condensed model in the Woodbury form, the inverse
        of the Jacobian with every contact stuck (:mod:`hbm.balance.stuck_inverse`), for the
        Newton solves (:func:`continuation.linsolve.make_solver`)."""
        return Structure(self.harmonic_blocks(), self._stuck_inverse)

    # ------------------------------------------------------------------ residual
    def residual(self, X: np.ndarray, w: float):
        """Residual and Jacobians.

        Parameters
        ----------
        X : ndarray, shape (n_coef, n)
        w : float

        Returns
        -------
        R : ndarray, shape (n_u,)
        dRdX : ndarray, shape (n_u, n_u)
            With respect to the unknowns.
        dRdw : ndarray, shape (n_u,)
        """
        nu = self.n_unknowns
        A = np.empty((nu, nu + 1))         # the layout of __call__'s: one compiled variant of each kernel
        R = self.jacobian_into(X, w, A)
        return R, A[:, :nu], A[:, nu]

    def jacobian_into(self, X: np.ndarray, w: float, out: np.ndarray) -> np.ndarray:
        """``R`` (n_u,) returned; ``[dR/dX, dR/dw]`` written into ``out`` (n_u, n_u + 1), a
        caller's array or a view of one (a bordered system's first rows: no copy of an
        ``n_u x n_u`` matrix)."""
        nu = self.n_unknowns
        return self._evaluate(X, float(w), out[:, :nu], out[:, nu])

    def __call__(self, x: np.ndarray):
        """Continuation form: ``x = [unknowns, w]`` -> ``R`` (n_u,), ``[dR/dX, dR/dw]``
        (n_u, n_u + 1), new arrays on every call."""
        A = np.empty((self.n_unknowns, self.n_unknowns + 1))
        return self.jacobian_into(self.expand(x[:-1]), x[-1], A), A

    def call_into(self, x: np.ndarray, out: np.ndarray) -> np.ndarray:
        """:meth:`__call__` with ``[dR/dX, dR/dw]`` written into ``out`` (n_u, n_u + 1), e.g.
        the rows of the continuation's Newton matrix; returns ``R`` (n_u,)."""
        return self.jacobian_into(self.expand(x[:-1]), x[-1], out)

    def _evaluate(self, X: np.ndarray, w: float, J: np.ndarray, dRw: np.ndarray) -> np.ndarray:
        """``R`` (n_u,) returned; ``dR/dX`` written into ``J`` (n_u, n_u), ``dR/dw`` into ``dRw``."""
        nl = self.nl
        if not nl.n_nl:
            J[...] = 0.0
            Fn = dFw = np.zeros_like(X)
        elif self._direct:
            Fn, _, dFw = nl.evaluate(X, w, J_out=J)
        elif self._laws_on is not None:
            Fn, dFw = nl.evaluate_laws_on(np.ascontiguousarray(X, dtype=float), w, self._laws_on, J)
        else:
            Fd, dFd, dFwd = nl.evaluate(np.ascontiguousarray(X[:, nl.dofs]), w)
            J[...] = 0.0
            J[self._uu] = dFd[self._kk]
            Fn, dFw = np.zeros_like(X), np.zeros_like(X)
            Fn[:, nl.dofs], dFw[:, nl.dofs] = Fd, dFwd
        R = np.empty(J.shape[0])
        self.linear.assemble(X, w, Fn, dFw, J, R, dRw)
        return R

    # ------------------------------------------------------------------ nonlinear part
    def nonlinear_forces(self, X: np.ndarray, w: float) -> np.ndarray:
        """``F_nl`` on every coordinate, (n_coef, n) (forces only: one AFT without seeds)."""
        F = np.zeros_like(X, dtype=float)
        if self.nl.n_nl:
            d = self.nl.dofs
            F[:, d] = self.nl.forces(np.ascontiguousarray(X[:, d], dtype=float), w)
        return F

    def nonlinear_jacobian(self, X: np.ndarray, w: float, nl=None):
        """``dF_nl/dX`` on the free coordinates the elements read, (n_coef n_k, n_coef n_k),
        ordered like :meth:`modal_rows`; ``None`` without such coordinates.

        ``nl`` : the elements' :class:`~hbm.balance.aft.NonlinearForces` on another basis (``X`` then
        has that basis' rows); default the problem's own.
        """
        nl = self.nl if nl is None else nl
        if not nl.n_nl or not self._nl_free.any():
            return None
        _, dF, _ = nl.evaluate(np.ascontiguousarray(X[:, nl.dofs]), w)
        if self._nl_free.all():
            return dF
        k = (np.arange(nl.basis.n_coef)[:, None] * nl.n_nl + np.flatnonzero(self._nl_free)[None, :]).ravel()
        return dF[np.ix_(k, k)]

    def stuck_stiffness(self) -> np.ndarray:
        """Tangent stiffness of the elements at rest on the coordinates, (n, n)."""
        return rest_tangents(self.nl.elements, self.n_dof)[0]

    def stuck_damping(self) -> np.ndarray:
        """Viscous tangent at rest of velocity-dependent elements (``linear_damping``), (n, n)."""
        return rest_tangents(self.nl.elements, self.n_dof)[1]

    # ------------------------------------------------------------------ what the analyses ask
    def modal_rows(self) -> np.ndarray:
        """The coordinates (indices into ``n``) that :meth:`modal_data`'s ``phi_c`` rows stand
        for: the free ones the elements read."""
        return self.nl.dofs[self._nl_free]

    def modal_data(self) -> ModalData:
        """Modes of the linear part seen from :meth:`modal_rows`, with the elements' stiffness
        at rest there (:mod:`hbm.analyses.modal_hill`)."""
        rows = self.modal_rows()
        return self.linear.modal_data(rows)._replace(K_ref=self.stuck_stiffness()[np.ix_(rows, rows)])

    def energy_balance(self, X: np.ndarray, w: float) -> EnergyBalance:
        """Work per period of the excitation, the viscous and the nonlinear forces (:mod:`hbm.balance.energy`)."""
        return self.balance_check(X, w)[0]

    def balance_check(self, X: np.ndarray, w: float, residual: bool = False):
        """:meth:`energy_balance` and, with ``residual``, ``max |R|`` at ``(X, w)`` from the
        same nonlinear forces (no Jacobian): ``(EnergyBalance, float or None)``."""
        Fn = self.nonlinear_forces(X, w)
        w_ex, w_visc, bound = self.linear.work(X, w, Fn)
        eb = EnergyBalance(w_ex, w_visc, work(self.basis, Fn, w * (self.basis.D @ X), w), bound)
        if not residual:
            return eb, None
        R = self.linear.residual_forces(X, w, Fn)
        return eb, float(np.abs(R).max(initial=0.0))

    def energy_resolution(self, X: np.ndarray, w: float) -> float:
        """Energy imbalance (J per period) the linear part's own arithmetic can leave at an
        exact solution (``linear.work_resolution``): below it the balance cannot tell a
        solution from a non-solution."""
        return self.linear.work_resolution(X, w)

    def recover_outputs(self, X: np.ndarray, w: float) -> np.ndarray:
        """Output coefficients (n_coef, n_o) of a point ``X`` (n_coef, n)."""
        return self.linear.recover_outputs(X, w)

    def linear_solution(self, w: float, extra_stiffness=None) -> np.ndarray:
        """Solution of ``(Z(w) + K_extra) X = F(w)`` (n_coef, n): the start of Newton."""
        return self.linear.linear_solution(w, extra_stiffness)

    def linear_peak_amplitudes(self, ws, stuck_stiffness, stuck_damping=None, observed=False):
        """Largest first-harmonic amplitudes over ``ws`` of the free and the stuck linear
        responses, (n_free,) each (:meth:`stuck_stiffness`, :meth:`stuck_damping`); with
        ``observed``, followed by those of coordinates the unknowns do not hold (a condensed
        model's excitation and outputs)."""
        return self.linear.linear_peak_amplitudes(ws, stuck_stiffness, stuck_damping, observed)

    def load(self, w: float) -> np.ndarray:
        """The load ``F(w)`` (n_coef, n) the linear part balances."""
        return self.linear.load(w)
