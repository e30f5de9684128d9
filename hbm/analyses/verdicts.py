r"""Stability verdicts of a traced FRF: Hill's test along each path segment, and the stable
solution a jump lands on.

Along a segment the verdicts come from :func:`hbm.analyses.stability_path.path_stability` (Hill
spectra where a change can hide); a jump that leaves the stable branch at ``f`` lands on the
solution Newton finds at ``f`` from the path interpolated between two points,

.. math::

    X_0 = X_{i_0} + t (X_{i_1} - X_{i_0}), \qquad t = (f - f_{i_0}) / (f_{i_1} - f_{i_0}),

kept only if Hill calls it stable.
"""
from __future__ import annotations

import numpy as np

from hbm.balance.newton import newton
from hbm.analyses.hill_system import HillSystem, point_is_stable
from hbm.analyses.stability import StabilityOptions
from hbm.analyses.stability_path import hill_margin, path_stability


def path_verdicts(problem, Xs, ws, segments, options):
    """Hill verdicts of every point, segment by segment (:func:`hbm.analyses.stability_path.path_stability`).

    At a point whose elements' Jacobian is exactly their stiffness at rest
    (:meth:`hbm.analyses.hill_system.HillSystem.at_rest`: every element sticks all period)
    the variational equation is the stuck linear system's, one time-invariant system: the
    first such point's spectrum gives the verdict and the largest real part of all of them
    (the margin ``max Re(lambda) - tol w`` follows ``w``).

    Returns
    -------
    stable : ndarray of bool, shape (n_points,)
    margin : ndarray, shape (n_points,)
        ``max Re(lambda) - tol w`` where a spectrum was computed or reused, NaN elsewhere.
    reused : int
        Points whose verdict came from another point's spectrum at rest.
    """
    opts = options or StabilityOptions()
    hill = HillSystem(problem)
    stable = np.ones(ws.size, dtype=bool)
    margin = np.full(ws.size, np.nan)
    rest = []                                  # (verdict, max Re) of the first point at rest
    reused = 0

    def test(i):
        nonlocal reused
        w = float(ws[i])
        J_nl = hill.jacobian(Xs[i], w)
        at_rest = hill.at_rest(J_nl)
        if at_rest and rest:
            reused += 1
            return rest[0][0], rest[0][1] - opts.rel_tol * w
        verdict, m = hill_margin(*hill.system(J_nl, w), hill.basis, w, opts)
        if at_rest:
            rest.append((verdict, m + opts.rel_tol * w))
        return verdict, m

    for a, b in segments:
        stable[a:b], margin[a:b] = path_stability(lambda k, a=a: test(a + k), ws[a:b], opts.max_skip)
    return stable, margin, reused


def landing_solver(problem, Xs, freq_hz, xscale, r_scale, stability_options):
    """``land(i0, i1, f_hz) -> X`` (n_coef, n) or ``None``: the stable solution at ``f_hz``
    by Newton from the path interpolated linearly between points ``i0`` and ``i1``.

    Results are cached (one solve per landing, shared by all outputs); ``None`` when Newton
    fails or lands on an unstable solution.
    """
    cache = {}

    def land(i0, i1, f_hz):
        key = (i0, i1, float(f_hz))
        if key not in cache:
            w = 2 * np.pi * f_hz
            df = freq_hz[i1] - freq_hz[i0]
            t = 0.0 if df == 0 else min(max((f_hz - freq_hz[i0]) / df, 0.0), 1.0)
            X0 = Xs[i0] + t * (Xs[i1] - Xs[i0])
            fun = lambda x: problem.residual(problem.expand(x), w)[:2]
            res = newton(fun, problem.unknowns(X0), scale=xscale, r_scale=r_scale,
                         blocks=problem.solver_structure())
            X = problem.expand(res.x) if res.converged else None
            if X is not None and not point_is_stable(problem, X, w, stability_options):
                X = None
            cache[key] = X
        return cache[key]

    return land


