r"""A converged point whose energy balance or residual is loose: polished by Newton at fixed
frequency, or accepted when the balance's own resolution explains what is left.

The works over a period must balance, :math:`W_{exc} = W_{visc} + W_{nl}`
(:mod:`hbm.balance.energy`); a point's relative error
:math:`|W_{exc} - W_{visc} - W_{nl}| / W_{exc}` above ``POLISH_ENERGY`` is polished
(:func:`polish`), and one still above ``ENERGY_LIMIT`` plus twice the balance's resolution
there (:func:`refused`) is not reported.

The residual is checked beside it, relative to the load :math:`r_s = \|R(0)\|`:
:math:`\|R\|_\infty / r_s` above ``POLISH_FORCE`` is polished, and above ``FORCE_LIMIT``
after polishing the point is not reported.  The energy balance cannot see a residual that
does no work on the motion (in phase with the displacement), and the continuation's test,
relative to the Jacobian's row norm, lets a stiff contact's point through with
:math:`\|R\|/r_s` up to 1e-3: on the undamped Jenkins oscillator at kt/k = 1e5 (H = 15, aft
events) the last point before a stop was reported with :math:`\|R\|/r_s = 2 \cdot 10^{-3}`
and an energy error of 2e-10, a Newton update of 0.6 % of the unknowns away from the solution.
Both checks come from one evaluation of the nonlinear forces
(:meth:`hbm.balance.residual.HarmonicBalance.balance_check`).
"""
from __future__ import annotations

import numpy as np

from hbm.balance.newton import newton

POLISH_ENERGY = 1e-10
# a point whose energy balance stays looser than this after polishing (and than twice the
# balance's resolution there, CondensedLinear.work_resolution) is not a solution the FRF can
# report: the path ends before it (status failed, the point named)
ENERGY_LIMIT = 1e-8
POLISH_FORCE = 1e-8     # |R|_inf / r_scale above this is polished ...
FORCE_LIMIT = 1e-6      # ... and above this after polishing, not reported


def _badness(err: float, res: float) -> float:
    """How far a point is from being reported, on both checks (<= 1: within both limits)."""
    return max(err / ENERGY_LIMIT, res / FORCE_LIMIT)


def polish(problem, X, w, xscale, r_scale, eb, res, linear_solve=None, w_scale=1.0):
    """Newton at fixed ``w`` on a point whose energy balance ``eb`` is not closed, or whose
    residual ``res`` (``|R|_inf / r_scale``) exceeds ``POLISH_FORCE``.

    The continuation's tolerance is relative to the Jacobian's row norm, which a stiff
    contact (kt >> k) makes large against the excitation: such a point can be accepted with
    an energy error ~ 1e-6, or a residual ~ 1e-3 of the load.  Here the target is relative
    to ``|F|``.  Returns the better of the two points (:func:`_badness`): ``(X, relative
    energy error, the balance's resolution in the same measure (0 when not needed), res)``.

    The imbalance of the works is the work of the residual on the motion,
    ``pi R . (D X)`` (:mod:`hbm.balance.energy`), plus what the linear part's arithmetic leaves
    (:meth:`hbm.balance.residual.HarmonicBalance.energy_resolution`).  When the residual is
    within ``POLISH_FORCE`` and its work is below a tenth of the imbalance, no Newton update
    can close the balance (e.g. 1e-8 on a stuck FE contact patch next to a mode its contacts
    block, at |R| / |F| = 1e-13): the point is returned as it is with that resolution, at the
    cost of one evaluation.

    The update solves the continuation's bordered system with the frequency row fixed,
    ``[J, dR/dw; e_w^T] [dX; dw] = [-R; 0]`` (so ``dw = 0``), with ``linear_solve``: the
    path's own solver (:attr:`continuation.arclength.Arclength.linear_solve`), whose kept LU
    of ``[J, dR/dw; rho t^T]`` at the last point differs from it by one row, so that a
    large polish costs a few Krylov iterations instead of a factorisation (and a factorisation
    it does make becomes the path's kept LU, one row away from the path's matrices).
    ``w_scale`` is the path's scale of ``w`` (the same column scaling as the kept LU's).
    """
    nu = problem.n_unknowns
    err = eb.relative_error

    def bordered(u):
        Jb = np.empty((nu + 1, nu + 1))       # the residual writes its Jacobian in place
        Jb[nu, :nu] = 0.0
        Jb[nu, nu] = 1.0
        R = problem.jacobian_into(problem.expand(u[:-1]), w, Jb[:nu])
        return np.r_[R, 0.0], Jb

    x0 = np.r_[problem.unknowns(X), w]
    first = bordered(x0)
    explained = np.pi * abs(first[0][:-1] @ problem.unknowns(problem.basis.D @ X))
    if res <= POLISH_FORCE and explained < 0.1 * abs(eb.excitation - eb.viscous - eb.nonlinear):
        return X, err, balance_resolution(problem, X, w, eb), res
    calls = iter([first])                     # Newton's first call gets the evaluation at hand
    del first                                 # (its Jacobian is then not held past that call)
    out = newton(lambda u: next(calls, None) or bordered(u), x0, scale=np.r_[xscale, w_scale],
                 r_scale=r_scale, tol=1e-13, max_iter=4, linear_solve=linear_solve, overwrite_jacobian=True)
    if np.all(np.isfinite(out.x)):
        Xp = problem.expand(out.x[:-1])
        eb_p, r_p = problem.balance_check(Xp, w, residual=True)
        err_p, res_p = eb_p.relative_error, r_p / r_scale
        if _badness(err_p, res_p) < _badness(err, res):
            return Xp, err_p, 0.0, res_p
    return X, err, 0.0, res


def closed_balance(problem, X, w, xscale, r_scale, linear_solve=None, w_scale=1.0):
    """The converged point ``(X, w)`` with its energy balance and residual checked, polished
    (:func:`polish`) when looser than ``POLISH_ENERGY`` or ``POLISH_FORCE``:
    ``(X, relative_error, resolution, res)`` (``res = |R|_inf / r_scale``); :func:`refused` on
    the last three says whether the FRF may report it."""
    eb, r = problem.balance_check(X, w, residual=True)
    res = r / r_scale
    if eb.relative_error <= POLISH_ENERGY and res <= POLISH_FORCE:
        return X, eb.relative_error, 0.0, res
    return polish(problem, X, w, xscale, r_scale, eb, res, linear_solve, w_scale)


def balance_resolution(problem, X, w, eb) -> float:
    """The energy balance's resolution at ``(X, w)`` (the linear part's share of the
    imbalance, :meth:`hbm.balance.residual.HarmonicBalance.energy_resolution`) in the measure of
    ``eb.relative_error``."""
    imbalance = abs(eb.excitation - eb.viscous - eb.nonlinear)
    return eb.relative_error * problem.energy_resolution(X, w) / imbalance if imbalance else 0.0


def refused(err: float, floor: float, res: float = 0.0) -> bool:
    """A point the FRF does not report: its energy error above ``ENERGY_LIMIT`` plus twice the
    balance's resolution ``floor`` there (same measure), or its residual ``res`` (``|R|_inf /
    r_scale``) above ``FORCE_LIMIT``."""
    return err > ENERGY_LIMIT + 2 * floor or res > FORCE_LIMIT
