"""Hill's stability problem of a harmonic-balance point: its matrices from the problem, and the
verdict (:mod:`hbm.analyses.stability`).

The problem's linear part gives its modes seen from the coordinates the elements read
(``problem.modal_data()``, :mod:`hbm.analyses.modal_hill`); the elements give their Jacobian on every
harmonic ``0 .. H`` (:class:`HillSystem`); the matrices ``(J, M, C)`` of Hill's problem in
modal coordinates then go to :func:`hbm.analyses.stability.hill_stability` (eigenvalues, Floquet
exponents and the verdict) or :func:`hbm.analyses.stability.hill_is_stable` (the verdict alone).
"""
from __future__ import annotations

import numpy as np

from hbm.balance.aft import NonlinearForces
from hbm.balance.fourier import FourierBasis
from hbm.analyses.modal_hill import modal_hill_system, rest_departures
from hbm.analyses.stability import HillResult, StabilityOptions, hill_is_stable, hill_stability
from hbm.balance.transforms import make_transform


class HillSystem:
    """Hill's problem of the points of one harmonic-balance problem, in its modal coordinates
    (:func:`hbm.analyses.modal_hill.modal_hill_system`), on every harmonic ``0 .. H``.

    A perturbation ``e^{lambda t} p(t)`` has a periodic ``p`` with every harmonic, whatever
    the harmonics the solution keeps: a solution on odd harmonics only (a symmetric system)
    still has perturbations with even ones and a mean.  Restricting ``p`` to the solution's
    harmonics drops those Floquet exponents, and the filter then keeps spurious ones in
    their place: on ``rigs/blade_couple.toml`` (harmonics 1, 3, ..., 9) 33 of 168 points came
    out unstable, 1 on harmonics 0 .. 9 for the same solutions (identical to 1e-15).  So the
    element Jacobian is evaluated by an AFT on ``0 .. H`` with the solution's coefficients
    placed in their rows (the others zero: the same periodic solution).

    Parameters
    ----------
    problem : HarmonicBalance
        On any linear part: offers ``basis``, ``nl``, ``modal_data()`` and
        ``nonlinear_jacobian(X, w, nl)``.
    """

    def __init__(self, problem):
        self.problem = problem
        self.modal = problem.modal_data()          # the linear part's modes: the same at every point
        b = problem.basis
        full = list(range(0, int(max(b.harmonics)) + 1))
        if list(b.harmonics) == full:
            self.basis, self._rows, self._nl = b, None, None
        else:
            self.basis = FourierBasis(full, b.n_samples)
            self._rows = np.array([self.basis.row_of(int(h), p) for h, p in _row_parts(b)])
            nl = problem.nl
            self._nl = NonlinearForces(self.basis, nl.elements, problem.n_dof,
                                       make_transform(self.basis, nl.transform.name))

    def __call__(self, X: np.ndarray, w: float):
        """``(J, M, C)`` of the point ``X`` (n_coef, n) at ``w``: shapes (n_coef' m, n_coef' m),
        (m, m), (m, m) with ``n_coef' = 2 H + 1``."""
        return self.system(self.jacobian(X, w), w)

    def jacobian(self, X: np.ndarray, w: float):
        """The elements' Jacobian on every harmonic ``0 .. H`` at the point ``X`` (n_coef, n),
        (n_coef' n_k, n_coef' n_k), or None without elements."""
        if self._rows is not None:
            Xf = np.zeros((self.basis.n_coef, X.shape[1]))
            Xf[self._rows] = X
            X = Xf
        return self.problem.nonlinear_jacobian(X, w, self._nl)

    def system(self, J_nl, w: float):
        """``(J, M, C)`` from the elements' Jacobian ``J_nl`` (:meth:`jacobian`)."""
        return modal_hill_system(self.modal, J_nl, self.basis, w)

    def at_rest(self, J_nl) -> bool:
        """True when ``J_nl`` is exactly the elements' stiffness at rest on every harmonic
        (every element sticks, closed, for the whole period, evaluated as linear): the
        variational equation is then the stuck linear system's, the same at every such point."""
        if J_nl is None:
            return True
        Ks = self.modal.K_ref
        return Ks is not None and rest_departures(J_nl, Ks, self.basis.n_coef).size == 0


def _row_parts(basis: FourierBasis):
    """``(h, 'c' or 's')`` of every coefficient row of ``basis``."""
    h = basis.h_of_row
    return [(int(h[r]), "s" if r > 0 and h[r - 1] == h[r] else "c") for r in range(h.size)]


def point_is_stable(problem, X: np.ndarray, w: float, options: StabilityOptions | None = None) -> bool:
    """``point_stability(problem, X, w, options).stable`` by :func:`hill_is_stable`."""
    hs = HillSystem(problem)
    return hill_is_stable(*hs(X, w), hs.basis, w, options)


def point_stability(problem, X: np.ndarray, w: float, options: StabilityOptions | None = None) -> HillResult:
    """:func:`hill_stability` of the point ``X`` (n_coef, n) of a harmonic-balance problem, on
    its modal Hill system (:class:`HillSystem`): the modes at or below ``max(H + 1/2, 5/2) w`` of the
    free DOFs (supports with imposed motion are not perturbed) or of a condensed model."""
    hs = HillSystem(problem)
    return hill_stability(*hs(X, w), hs.basis, w, options)
