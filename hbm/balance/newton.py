r"""Damped Newton solver with the exact Jacobian, unknown scaling and a backtracking line search.

Solves ``R(x) = 0`` for a square system.  With the diagonal scaling ``x = S y`` the step is

.. math::

    \Delta y = -(J S)^{-1} R, \qquad x \leftarrow x + \alpha S \Delta y,

with ``alpha`` halved until ``||R||`` decreases (Armijo-like), and convergence when
``||R|| <= tol * r_scale``, or when the residual has reached its round-off floor: the step
``||Delta y||_inf <= 16 eps (1 + ||y||_inf)`` with ``||R|| <= sqrt(tol) r_scale`` (a stiff
contact's forces ``k_t u`` carry round-off ``k_t |u| eps`` that can exceed ``tol * r_scale``;
the same rule as the continuation's corrector).  An iterative linear solve leaves the step
above that bound at the floor, so a residual that has not halved in ``STALL`` iterations also
counts as converged when it lies within ``FLOOR_FACTOR`` of the target (a 64-contact patch's
peak solved to ``tol = 1e-12`` stalls at 2.9 times its target: 30 iterations of a line search
that cannot descend, then a refusal, before this rule).  The
converged point gets one more update with the Jacobian at
hand (polish; the reported residual is the one before it).  The result always carries a status
and a message: it never fails silently.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from continuation.linsolve import make_solver

_EPS = np.finfo(float).eps
STALL = 4            # iterations without halving the residual that end the iteration
FLOOR_FACTOR = 10.0  # a stalled residual within this factor of the target is converged


@dataclass(frozen=True)
class NewtonResult:
    """Outcome of :func:`newton`: ``x``, ``converged``, ``iterations``, ``residual``, ``message``."""

    x: np.ndarray
    converged: bool
    iterations: int
    residual: float
    message: str


def _scaled(J, S, overwrite):
    """``J diag(S)``, in place when ``overwrite``."""
    if overwrite:
        J *= S
        return J
    return J * S


def _polished(x, R, J, S, linear_solve, overwrite=False):
    """One more Newton update with the Jacobian at hand (no further evaluation): by quadratic
    convergence the point is then accurate to about the square of the accepted error, so that
    round-off (e.g. a BLAS's thread count) no longer shows in the answer."""
    dy = linear_solve(_scaled(J, S, overwrite), -R[:, None])
    if dy is None or not np.all(np.isfinite(dy)):
        return x
    return x + S * dy[:, 0]


def newton(fun, x0, *, scale=None, r_scale=1.0, tol=1e-10, max_iter=30, linear_solve=None,
           overwrite_jacobian=False, blocks=None) -> NewtonResult:
    """Solve ``fun(x) = (R, J) -> R = 0``.

    Parameters
    ----------
    fun : callable
        ``x (n,) -> (R (n,), J (n, n))``.
    x0 : ndarray, shape (n,)
        Initial guess.
    scale : ndarray, shape (n,), optional
        Typical magnitude of each unknown (default 1).
    r_scale : float
        Typical magnitude of the residual (e.g. the force amplitude).
    tol : float
        Relative residual tolerance.
    max_iter : int
    linear_solve : callable, optional
        ``(A (n, n), B (n, 1)) -> A^{-1} B`` or None when singular (:mod:`continuation.linsolve`;
        pass one :class:`~continuation.linsolve.ReusedLU` to many calls to keep its LU);
        default: :func:`continuation.linsolve.make_solver` of ``n`` and ``blocks`` (a direct LU
        on small systems, else GMRES on the diagonal ``blocks`` or a kept LU).
    overwrite_jacobian : bool
        ``fun`` returns a new ``J`` on every call, which may be scaled in place (no copy of an
        ``n x n`` matrix per update).
    blocks : sequence of (int, int[, bool]), optional
        Ranges of unknowns coupled mainly among themselves (e.g.
        :meth:`hbm.balance.residual.HarmonicBalance.harmonic_blocks`).

    Returns
    -------
    NewtonResult
    """
    x = np.array(x0, dtype=float)
    S = np.ones_like(x) if scale is None else np.asarray(scale, dtype=float)
    if linear_solve is None:
        linear_solve = make_solver(x.size, blocks, scale=S)
    R, J = fun(x)
    r = float(np.linalg.norm(R))
    target = tol * max(r_scale, 1e-300)
    floor_ok = np.sqrt(tol) * max(r_scale, 1e-300)
    ref, stalled = r, 0          # the residual to halve, and iterations since it was
    for it in range(1, max_iter + 1):
        if not np.all(np.isfinite(R)):
            return NewtonResult(x, False, it - 1, np.inf, "residual is not finite")
        if r <= target:
            return NewtonResult(_polished(x, R, J, S, linear_solve, overwrite_jacobian), True, it - 1, r, "converged")
        dy = linear_solve(_scaled(J, S, overwrite_jacobian), -R[:, None])
        if dy is None or not np.all(np.isfinite(dy)):
            return NewtonResult(x, False, it - 1, r, "singular Jacobian")
        dy = dy[:, 0]
        if r <= floor_ok and np.max(np.abs(dy)) <= 16 * _EPS * (1.0 + np.max(np.abs(x / S))):
            return NewtonResult(x + S * dy, True, it - 1, r, "converged (residual at its round-off floor)")
        J = None                # not needed past its solve: one n x n array less held
        alpha = 1.0
        while True:
            xt = x + alpha * S * dy
            Rt, Jt = fun(xt)
            rt = float(np.linalg.norm(Rt))
            if np.isfinite(rt) and (rt < r or alpha < 1.0 / 64):
                break
            alpha *= 0.5
        x, R, J, r = xt, Rt, Jt, rt
        ref, stalled = (r, 0) if r <= 0.5 * ref else (ref, stalled + 1)
        if stalled >= STALL and target < r <= FLOOR_FACTOR * target:
            return NewtonResult(_polished(x, R, J, S, linear_solve, overwrite_jacobian), True, it, r,
                                f"converged (residual {r:.3g} stalled at its round-off floor, "
                                f"within {FLOOR_FACTOR:g} x the target {target:.3g})")
    if r <= target:
        return NewtonResult(_polished(x, R, J, S, linear_solve, overwrite_jacobian), True, max_iter, r, "converged")
    return NewtonResult(x, False, max_iter, r,
                        f"no convergence in {max_iter} iterations (residual {r:.3g}, target {target:.3g})")
