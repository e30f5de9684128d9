r"""A converged point whose energy balance is loose: polished by Newton at fixed frequency,
or accepted when the balance's own resolution explains what is left.

The works over a period must balance, :math:`W_{exc} = W_{visc} + W_{nl}`
(:mod:`hbm.balance.energy`); a point's relative error
:math:`|W_{exc} - W_{visc} - W_{nl}| / W_{exc}` above ``POLISH_ENERGY`` is polished
(:func:`polish`), and one still above ``ENERGY_LIMIT`` plus twice the balance's resolution
there (:func:`refused`) is not reported.
"""
from __future__ import annotations

import numpy as np

from hbm.balance.energy import energy_balance
from hbm.balance.newton import newton

POLISH_ENERGY = 1e-10
# a point whose energy balance stays looser than this after polishing (and than twice the
# balance's resolution there, CondensedLinear.work_resolution) is not a solution the FRF can
# report: the path ends before it (status failed, the point named)
ENERGY_LIMIT = 1e-8


def polish(problem, X, w, xscale, r_scale, eb, linear_solve=None, w_scale=1.0):
    """Newton at fixed ``w`` on a point whose energy balance ``eb`` is not closed.

    The continuation's tolerance is relative to the Jacobian's row norm, which a stiff
    contact (kt >> k) makes large against the excitation: such a point can be accepted with
    ``|R| / |F|`` ~ 1e-9 and an energy error ~ 1e-6.  Here the target is relative to ``|F|``.
    Returns the better of the two points, its relative energy error and the balance's
    resolution at it in the same measure (0 when not needed).

    The imbalance of the works is the work of the residual on the motion,
    ``pi R . (D X)`` (:mod:`hbm.balance.energy`), plus what the linear part's arithmetic leaves
    (:meth:`hbm.balance.residual.HarmonicBalance.energy_resolution`).  When the residual's work
    is below a tenth of the imbalance, no Newton update can close the balance (e.g. 1e-8 on a
    stuck FE contact patch next to a mode its contacts block, at |R| / |F| = 1e-13): the point
    is returned as it is with that resolution, at the cost of one evaluation.

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
    if explained < 0.1 * abs(eb.excitation - eb.viscous - eb.nonlinear):
        return X, err, balance_resolution(problem, X, w, eb)
    calls = iter([first])                     # Newton's first call gets the evaluation at hand
    del first                                 # (its Jacobian is then not held past that call)
    res = newton(lambda u: next(calls, None) or bordered(u), x0, scale=np.r_[xscale, w_scale],
                 r_scale=r_scale, tol=1e-13, max_iter=4, linear_solve=linear_solve, overwrite_jacobian=True)
    if np.all(np.isfinite(res.x)):
        Xp = problem.expand(res.x[:-1])
        err_p = energy_balance(problem, Xp, w).relative_error
        if err_p < err:
            return Xp, err_p, 0.0
    return X, err, 0.0


def closed_balance(problem, X, w, xscale, r_scale, linear_solve=None, w_scale=1.0):
    """The converged point ``(X, w)`` with its energy balance checked, polished
    (:func:`polish`) when looser than ``POLISH_ENERGY``: ``(X, relative_error, resolution)``;
    :func:`refused` on the last two says whether the FRF may report it."""
    eb = energy_balance(problem, X, w)
    if eb.relative_error <= POLISH_ENERGY:
        return X, eb.relative_error, 0.0
    return polish(problem, X, w, xscale, r_scale, eb, linear_solve, w_scale)


def balance_resolution(problem, X, w, eb) -> float:
    """The energy balance's resolution at ``(X, w)`` (the linear part's share of the
    imbalance, :meth:`hbm.balance.residual.HarmonicBalance.energy_resolution`) in the measure of
    ``eb.relative_error``."""
    imbalance = abs(eb.excitation - eb.viscous - eb.nonlinear)
    return eb.relative_error * problem.energy_resolution(X, w) / imbalance if imbalance else 0.0


def refused(err: float, floor: float) -> bool:
    """A point's energy error above what the FRF reports: ``ENERGY_LIMIT`` plus twice the
    balance's resolution ``floor`` there (same measure)."""
    return err > ENERGY_LIMIT + 2 * floor
