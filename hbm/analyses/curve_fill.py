r"""Points between long continuation steps, so the drawn curve follows the true one.

On flat stretches the continuation takes long steps (the corrector converges easily there),
and the piecewise-linear curve cuts across what lies between: an anti-resonance between two
modes drawn as a V of two chords.  Wherever two consecutive points of one traced segment lie
more than ``MAX_SHARE`` of the window apart in frequency (and the frequency is monotone
between them), points are solved at evenly spaced frequencies in between by Newton at fixed
frequency, each started from the linear interpolation of its neighbours' coefficients, and
inserted in path order.  A solve that fails inserts nothing.  When one lands farther from its
guess than ``BRANCH_SHARE`` of the step, the path bulges away from the chord there (a
feature the step jumped over) or the solve found another branch coexisting at that
frequency: the chord is then traced again by continuation in ``n + 1`` steps
(:func:`hbm.analyses.curve_bends.retrace_chord`), whose points are kept only when the trace
arrives at the chord's end, i.e. lie on the same branch.
"""
from __future__ import annotations

import math

import numpy as np

from hbm.balance.energy import energy_balance
from hbm.balance.newton import newton
from hbm.analyses.curve_bends import retrace_chord
from hbm.analyses.traced_points import TracedPoints

MAX_SHARE = 1.0 / 60.0
BRANCH_SHARE = 0.5      # a solved point farther than this share of the step from its guess is refused


def solve_near(problem, guess, w, radius, xscale, r_scale, tol=1e-10):
    """Newton at fixed ``w`` from ``guess`` (n_coef, n): ``(X, iterations)``, or None when it
    fails or lands farther than ``radius`` from the guess (another branch coexisting at ``w``)."""
    fun = lambda u: problem.residual(problem.expand(u), w)[:2]
    res = newton(fun, problem.unknowns(guess), scale=xscale, r_scale=r_scale, tol=tol,
                 blocks=problem.solver_structure())
    if not res.converged:
        return None
    X = problem.expand(res.x)
    return (X, res.iterations) if np.linalg.norm(X - guess) <= radius else None


def insert_point(problem, pts, segments, k, at, X, w, its, Y) -> None:
    """Insert the solved point ``(X, w)`` with outputs ``Y`` at path index ``at`` of segment
    ``k`` (its energy error and loop closure taken here); later segments shift by one."""
    one = TracedPoints()
    one.append(X, w, Y, its, energy_balance(problem, X, w).relative_error, problem.nl.last_unclosed)
    pts.insert(at, segments, k, one, 0, 1)


def fill_long_steps(problem, case, pts, segments, outputs_of, window, xscale, r_scale, progress=None) -> int:
    """Insert points so that no step inside a segment spans more than ``MAX_SHARE`` of the
    window (module doc); returns how many were inserted.

    Parameters
    ----------
    problem, case
        The FRF's problem and case.
    pts : hbm.analyses.traced_points.TracedPoints
        Traced points, changed in place.
    segments : list of [int, int]
        ``[start, end)`` of each traced segment, shifted by every insertion.
    outputs_of : callable
        ``(X, w) -> Y``, the outputs of a point.
    window : (float, float)
        ``(w_lo, w_hi)``, rad/s.
    xscale : ndarray
    r_scale : float
    progress : callable, optional
        The FRF's, told of the points of a chord traced again.
    """
    limit = MAX_SHARE * (window[1] - window[0])
    added = 0
    for k in range(len(segments)):
        i = segments[k][0]
        while i < segments[k][1] - 1:
            w0, w1 = pts.w[i], pts.w[i + 1]
            n_new = math.ceil(abs(w1 - w0) / limit) - 1
            if n_new <= 0:
                i += 1
                continue
            new = _solved_between(problem, pts.X[i], pts.X[i + 1], w0, w1, n_new, xscale, r_scale)
            if new is None:         # the path bulges away from the chord: traced again
                n = retrace_chord(problem, case, pts, segments, k, i, n_new + 1, xscale, r_scale, progress)
            else:
                for off, (X, w, its) in enumerate(new, start=1):
                    insert_point(problem, pts, segments, k, i + off, X, w, its, outputs_of(X, w))
                n = len(new)
            added += n
            i += n + 1
    return added


def _solved_between(problem, X0, X1, w0, w1, n_new, xscale, r_scale):
    """``n_new`` points ``(X, w, iterations)`` solved at even frequencies strictly between
    ``w0`` and ``w1``, each from the chord's interpolation; None when one lands farther than
    ``BRANCH_SHARE`` of the chord from its guess.  A point whose Newton fails is left out."""
    radius = BRANCH_SHARE * np.linalg.norm(X1 - X0)
    new = []
    for j in range(1, n_new + 1):
        t = j / (n_new + 1)
        w = w0 + t * (w1 - w0)
        got = solve_near(problem, (1 - t) * X0 + t * X1, w, math.inf, xscale, r_scale)
        if got is None:
            continue
        if np.linalg.norm(got[0] - ((1 - t) * X0 + t * X1)) > radius:
            return None
        new.append((got[0], w, got[1]))
    return new
