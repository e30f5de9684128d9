r"""Newton corrector for ``R(x) = 0`` closed by one linear constraint, in scaled variables.

With :math:`x = s \odot x_s` and :math:`J_s = J\,\mathrm{diag}(s)`, the corrector solves

.. math::

    R(s \odot x_s) = 0, \qquad g(x_s) = 0,

with the linear constraint :math:`g = a^T x_s - b` (pseudo-arclength: :math:`a = t`,
:math:`b = t^T x_{s,pred}`; fixed parameter: :math:`a = e_\lambda`,
:math:`b = \lambda / s_\lambda`) or the sphere :math:`g = (\|x_s - c\|^2 - r^2) / (2r)`.
Newton update with :math:`a = \nabla g`, the constraint row weighted by :math:`\rho` to
balance the rows:

.. math::

    \begin{bmatrix} J_s \\ \rho\, a^T \end{bmatrix} \delta
        = -\begin{bmatrix} R \\ \rho\, g \end{bmatrix}, \qquad x_s \leftarrow x_s + \theta\delta,

with :math:`\theta = 1, 1/2, 1/4, \dots` while the merit
:math:`\max(\|R\|_\infty/\rho, |g|)` does not decrease (backtracking).

Convergence test (scaled residual): the residual scale is

.. math::

    \rho = \max\big(\rho_0, \|J_s(x)\|_\infty\big),

the largest change of a residual entry produced by unit changes of the scaled unknowns
(:math:`\rho_0` is the value at the converged starting point; the starting point itself
is solved with the current :math:`\|J_s\|_\infty` alone), so
:math:`\|R\|_\infty / \rho` estimates the error in the scaled unknowns.  Converged when
:math:`\|R\|_\infty \le tol\,\rho` and :math:`|g| \le tol\,(1 + \|x_s\|_\infty)`, or when the
Newton update has fallen to round-off, :math:`\|\delta\|_\infty \le 16\,\epsilon\,(1 +
\|x_s\|_\infty)`, with the residual already below :math:`\sqrt{tol}\,\rho`.

Non-smooth residuals (a stick-slip switch between two time samples) can make Newton cycle
between iterates whose residual stays a few times above ``tol``; the best iterate is then
accepted when its residual is within ``stall_factor * tol`` (default 10).

Polishing: at convergence the Newton matrix at the last evaluation is already at hand, so one
more update :math:`\delta` is solved and applied without calling the function again; by
quadratic convergence the returned point is then accurate to about :math:`tol^2`, i.e. to
round-off (the reported residual is the one before this update).  The same solve, with the
second right-hand side :math:`[0; \rho]`, gives the null vector of :math:`J_s` that fixes the
tangent when :math:`a` is the previous tangent.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from .kernels import border_rows, bordered_system, inf_norm, scale_jacobian
from .linsolve import direct_solve

_EPS = np.finfo(float).eps


class Evaluation:
    """The caller's function at one scaled point.

    Parameters
    ----------
    xs : ndarray, shape (n+1,)
        Scaled point.
    R : ndarray, shape (n,)
        Residual.
    Js : ndarray, shape (n, n+1)
        Scaled Jacobian ``J * scale``.

    Attributes
    ----------
    r_max : float
        ``||R||_inf``.
    x_max : float
        ``||xs||_inf``.
    """

    __slots__ = ("xs", "R", "Js", "r_max", "x_max", "_row_norm", "_finite")

    def __init__(self, xs: np.ndarray, R: np.ndarray, Js: np.ndarray):
        Js = np.ascontiguousarray(Js, dtype=float)
        R = np.ascontiguousarray(R, dtype=float)
        self._set(xs, R, Js, scale_jacobian(R, Js, np.ones(Js.shape[1]), np.empty_like(Js)))

    @classmethod
    def scaled(cls, xs: np.ndarray, R: np.ndarray, J: np.ndarray, scale: np.ndarray,
               out: np.ndarray | None = None) -> "Evaluation":
        """From the unscaled Jacobian ``J`` (n, n+1): ``Js = J * scale`` and the norms in one
        compiled pass (:func:`continuation.kernels.scale_jacobian`); ``out`` receives ``Js``
        (may be ``J`` itself)."""
        ev = cls.__new__(cls)
        Js = np.empty(J.shape) if out is None else out
        ev._set(xs, R, Js, scale_jacobian(R, J, scale, Js))
        return ev

    def _set(self, xs, R, Js, stats):
        norm, r_max, finite = stats
        self.xs = xs
        self.R = R
        self.Js = Js
        self._finite = finite
        self._row_norm = norm if finite else 0.0
        self.r_max = r_max
        self.x_max = inf_norm(xs)

    @property
    def finite(self) -> bool:
        """Residual and Jacobian are free of NaN and inf."""
        return self._finite

    def row_norm(self) -> float:
        """``||Js||_inf`` (largest absolute row sum); 0 when not finite."""
        return self._row_norm


@dataclass
class Correction:
    """Result of :func:`correct`.

    Parameters
    ----------
    converged : bool
        The convergence test passed.
    ev : Evaluation
        Last accepted evaluation (the solution when converged; its Jacobian gives the tangent).
    iterations : int
        Newton updates applied.
    residual : float
        ``||R||_inf / rho`` of ``ev``.
    reason : str
        Why it failed ('' when converged).
    xs : ndarray, shape (n+1,) or None
        The solution: ``ev.xs`` plus one last Newton update computed from ``ev`` without a
        further call of the function (module doc); ``None`` means ``ev.xs``.
    null : ndarray, shape (n+1,) or None
        When converged with a last update: ``v`` solving ``[Js; rho a^T] v = [0; rho]`` at
        ``ev`` (``a`` the constraint gradient there), a null vector of ``Js`` normalised by
        ``a @ v = 1``; for the arclength hyperplane (``a`` = the previous tangent) this is
        the new tangent's direction (:func:`continuation.tangent.null_tangent`'s system).
    matrix : ndarray, shape (n+1, n+1), or None
        The C-ordered Newton matrix whose first ``n`` rows are ``ev.Js`` (the Jacobian was
        evaluated into it), a work array for one more bordered solve at ``ev``
        (:func:`continuation.tangent.null_tangent`); ``None`` when ``ev.Js`` is its own array.
    """

    converged: bool
    ev: Evaluation
    iterations: int
    residual: float
    reason: str = ""
    xs: np.ndarray | None = None
    null: np.ndarray | None = None
    matrix: np.ndarray | None = None

    def __post_init__(self):
        if self.xs is None:
            self.xs = self.ev.xs


Constraint = Callable[[np.ndarray], tuple[float, np.ndarray]]


def linear_constraint(a: np.ndarray, b: float) -> Constraint:
    """``g = a @ xs - b`` with gradient ``a``; ``a`` shape (n+1,)."""
    a = np.asarray(a, dtype=float)
    return lambda xs: (float(a @ xs - b), a)


def sphere_constraint(center: np.ndarray, radius: float) -> Constraint:
    """``g = (|xs - center|^2 - radius^2) / (2 radius)``, gradient ``(xs - center) / radius``."""
    def g(xs):
        d = xs - center
        return float((d @ d - radius * radius) / (2.0 * radius)), d / radius
    return g


def correct(evaluate: Callable[[np.ndarray], Evaluation], xs0: np.ndarray,
            constraint: Constraint, rho0: float | None, tol: float, max_iter: int, max_backtrack: int,
            stall_factor: float = 10.0, stall_window: int = 3, linear_solve=direct_solve,
            evaluate_into=None) -> Correction:
    """Newton with backtracking on ``[R(s*xs); g(xs)] = 0`` (module doc).

    Parameters
    ----------
    evaluate : callable
        ``xs (n+1,) -> Evaluation``; one call of the caller's function.
    xs0 : ndarray, shape (n+1,)
        Scaled starting guess (the predictor).
    constraint : callable
        ``xs -> (g, dg/dxs)``: :func:`linear_constraint` or :func:`sphere_constraint`.
    rho0 : float or None
        Lower bound of the residual scale; ``None``: the current ``||Js||_inf`` alone.
    tol, max_iter, max_backtrack :
        Tolerance on the scaled residual; Newton updates; halvings of an update.
    stall_factor, stall_window :
        Unconverged, the best iterate is accepted within ``stall_factor * tol``; Newton stops
        early (stalled) when the last ``stall_window`` iterates have not halved the smallest
        merit before them (0: never): cycling at a stick-slip kink, which a shorter step cures.
    linear_solve : callable
        ``(A (n+1, n+1), B (n+1, k)) -> A^{-1} B`` or None when singular, ``A`` in the order of
        its ``order`` attribute (default ``"F"``) (:mod:`continuation.linsolve`).
    evaluate_into : callable, optional
        ``(xs, out (n, n+1)) -> Evaluation`` writing ``Js`` in ``out``: with a C-order
        ``linear_solve`` the Jacobian then lives in the Newton matrix (:class:`_NewtonMatrices`).

    Returns
    -------
    Correction
    """
    mats = _NewtonMatrices(evaluate, evaluate_into, xs0.size, getattr(linear_solve, "order", "F"))
    ev = mats.evaluate(xs0)
    if not ev.finite:
        return Correction(False, ev, 0, np.inf, "residual is not finite at the predictor")
    if rho0 is None:
        rho0 = 1e-300
    B2 = np.empty((xs0.size, 2), order="F")
    best = (np.inf, ev, 0)
    sqrt_tol = math.sqrt(tol)
    backtrack_below = max(1e3 * tol, sqrt_tol)
    history = []
    stalled = False
    for it in range(max_iter + 1):
        rho = max(rho0, ev.row_norm())
        res = ev.r_max / rho
        g, a = constraint(ev.xs)
        size = 1.0 + ev.x_max
        converged = res <= tol and abs(g) <= tol * size
        if res < best[0] and abs(g) <= tol * size:
            best = (res, ev, it)
        history.append(max(res, abs(g) / size))
        if not converged and stall_window and len(history) > 2 * stall_window \
                and min(history[-stall_window:]) > 0.5 * min(history[:-stall_window]):
            stalled = True      # cycling at a kink: a shorter step will do better
            break
        if it == max_iter and not converged:
            break
        # when converged, the same matrix also gives the null vector of Js (the tangent,
        # module doc) from a second right-hand side
        # (both right-hand sides are always written: one layout of B, one compiled kernel)
        sol = linear_solve(mats.matrix(ev, a, rho, g, B2), B2 if converged else B2[:, :1])
        done = _solved(sol, converged, ev, it, res, res <= sqrt_tol, size, mats)
        if done is not None:
            return done
        # near the solution (merit below sqrt(tol)) a full step is taken whatever it gives:
        # there the merit grows only when a stick-slip switch moves between samples, which a
        # shorter step does not cure (it would cost up to max_backtrack more evaluations)
        trial = _line_search(mats, constraint, ev.xs, sol[:, 0], max(res, abs(g)), rho0, max_backtrack,
                             backtrack_below)
        if not trial.finite:
            return Correction(False, ev, it + 1, res,
                              f"residual not finite along the Newton update (residual {res:.1e})")
        ev = trial
    return _unconverged(ev, it, ev.r_max / max(rho0, ev.row_norm()), stalled, min(history), best,
                        stall_factor * tol, mats)


def _unconverged(ev: Evaluation, it: int, res: float, stalled: bool, lowest: float, best,
                 accept: float, mats) -> Correction:
    """The end of a correction that did not pass the test: the best iterate ``best = (res,
    ev, it)`` if its residual is within ``accept`` and Newton did not stall, else a failure."""
    if stalled:
        # no acceptance of the best iterate here: a shorter step converges properly
        # (the best of a few cycling iterates can be off by far more than its residual says)
        return Correction(False, ev, it, res, f"Newton stalled after {it} iterations "
                          f"(residual {res:.1e}, best {lowest:.1e})")
    if best[0] <= accept:
        ev = mats.fresh(best[1])
        return Correction(True, ev, best[2], best[0], matrix=mats.holding(ev))
    return Correction(False, ev, it, res, f"no convergence in {it} iterations (residual {res:.1e})")


def _solved(sol, converged: bool, ev: Evaluation, it: int, res: float, near: bool, size: float,
            mats) -> Correction | None:
    """The correction that the Newton solve ``sol`` (n+1, 1 or 2) at ``ev`` ends with, or None
    to go on: converged (with the free polishing update and the null vector), a singular
    matrix, or an update at round-off (``near``: the residual is below ``sqrt(tol)``)."""
    d_max = math.nan if sol is None else inf_norm(sol[:, 0])
    if not math.isfinite(d_max):
        if converged:
            return Correction(True, ev, it, res, matrix=mats.holding(ev))
        return Correction(False, ev, it, res, f"singular Newton matrix (residual {res:.1e})")
    if converged:
        null = sol[:, 1]
        if not math.isfinite(inf_norm(null)):
            null = None
        # free polishing update: error ~ |delta|^2, no further call of the function
        return Correction(True, ev, it, res, xs=ev.xs + sol[:, 0], null=null, matrix=mats.holding(ev))
    if near and d_max <= 16 * _EPS * size:
        return Correction(True, ev, it, res, matrix=mats.holding(ev))
    return None


def _line_search(mats, constraint, xs, delta, merit, rho0, max_backtrack, backtrack_below):
    """The evaluation at ``xs + theta delta``, ``theta = 1, 1/2, ...`` until the merit falls
    below ``merit`` (any ``theta = 1`` when ``merit <= backtrack_below``); the last trial
    when none does (not finite only if every trial was)."""
    theta = 1.0
    for _ in range(max_backtrack + 1):
        trial = mats.evaluate(xs + theta * delta)
        if trial.finite:
            merit_t = max(trial.r_max / max(rho0, trial.row_norm()), abs(constraint(trial.xs)[0]))
            if merit_t < merit or merit <= backtrack_below:
                return trial
        theta *= 0.5
    return trial


class _NewtonMatrices:
    """The corrector's Newton matrix (n+1, n+1) and where its evaluations keep ``Js``.

    Without ``evaluate_into`` (or for a solver that wants Fortran order and overwrites the
    matrix) the matrix is refilled from each evaluation's own ``Js``.  With it, every
    evaluation writes ``Js`` into the matrix's first ``n`` rows, so the Newton matrix needs
    only its constraint row and a large system holds one ``n x n`` array (plus the solver's
    kept LU) however many evaluations the corrector makes.  The current iterate's ``Js`` is
    needed only up to its solve: a trial point overwrites it, and becomes the current iterate
    (a correction that fails on a non-finite trial returns an iterate whose ``Js`` is gone).
    """

    def __init__(self, evaluate, evaluate_into, n1: int, order: str):
        self._evaluate = evaluate
        self._into = evaluate_into if order == "C" else None
        self._A = np.empty((n1, n1), order=order)
        self._last = None

    def evaluate(self, xs: np.ndarray) -> Evaluation:
        """The function at ``xs`` (the first point or a trial)."""
        if self._into is None:
            return self._evaluate(xs)
        self._last = self._into(xs, self._A[:-1])
        return self._last

    def matrix(self, ev: Evaluation, a, rho: float, g: float, B: np.ndarray) -> np.ndarray:
        """The Newton matrix of the current iterate ``ev``; right-hand sides written in ``B``."""
        if self._into is None:
            bordered_system(ev.Js, ev.R, a, rho, g, self._A, B)
        else:
            border_rows(ev.R, a, rho, g, self._A, B)
        return self._A

    def holding(self, ev: Evaluation) -> np.ndarray | None:
        """The Newton matrix if its first rows are ``ev.Js``, else None."""
        return self._A if self._into is not None and ev is self._last else None

    def fresh(self, ev: Evaluation) -> Evaluation:
        """``ev`` (an earlier iterate) with its ``Js`` as evaluated: re-evaluated when a later
        evaluation has overwritten it."""
        if self._into is None or ev is self._last:
            return ev
        return self.evaluate(ev.xs)
