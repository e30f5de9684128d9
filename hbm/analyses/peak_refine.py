r"""Points placed on the resonance peaks, not only where the continuation stepped.

The continuation's steps are sized for the corrector, so a smooth peak usually falls between
two points and the drawn curve (and the reported peak) is low by up to a few tenths of a per
cent.  For every resonance peak of every output (a local maximum of prominence at least 10 % of
its height along a stretch where the frequency is monotone) the parabola through the peak
point :math:`i` and its neighbours, in Newton form

.. math::

    a(w) = a_{i-1} + d_1 (w - w_{i-1}) + c\,(w - w_{i-1})(w - w_i),

with :math:`d_1` the first and :math:`c < 0` the second divided difference, has its vertex at
:math:`w^* = (w_{i-1} + w_i)/2 - d_1 / (2c)`; the balance is solved
there by Newton at fixed frequency from :math:`X_i` and the point is inserted in path order
(also when it is lower than point :math:`i`, as on a skewed peak: it narrows the bracket for
the next parabola).  This repeats (at most ``ROUNDS`` times per peak) until the vertex moves
the amplitude by less than ``AMPLITUDE_TOL`` and the frequency by less than
``FREQUENCY_TOL``, relative.  A solve that fails, or lands off the branch (amplitude below
the neighbour on its side), inserts nothing.
"""
from __future__ import annotations

import numpy as np

from hbm.analyses.curve_fill import insert_point, solve_near

ROUNDS = 3
AMPLITUDE_TOL = 1e-5
FREQUENCY_TOL = 1e-6
PROMINENCE = 0.1


def _vertex(w3, a3):
    """Frequency of the vertex of the parabola through three points (None unless a maximum).

    Newton form ``a = a0 + d1 (w - w0) + c (w - w0)(w - w1)``: the vertex is at
    ``(w0 + w1) / 2 - d1 / (2 c)``, a maximum when ``c < 0``."""
    (w0, w1, w2), (a0, a1, a2) = w3, a3
    d1, d2 = (a1 - a0) / (w1 - w0), (a2 - a1) / (w2 - w1)
    c = (d2 - d1) / (w2 - w0)
    if not c < 0:
        return None
    return 0.5 * (w0 + w1) - d1 / (2 * c)


def prominent_maxima(a, prominence: float = PROMINENCE) -> np.ndarray:
    """Indices of the local maxima of ``a`` (n,) whose prominence
    (:func:`scipy.signal.find_peaks`) is at least ``prominence`` times their own height."""
    from scipy.signal import find_peaks
    a = np.asarray(a, dtype=float)
    return find_peaks(a, prominence=(prominence * np.abs(a), None))[0]


def _peak_indices(w, a):
    """Interior resonance peaks of ``a`` along the path where ``w`` is monotone around them."""
    return [int(i) for i in prominent_maxima(a) if 0 < i < len(a) - 1 and (w[i] - w[i - 1]) * (w[i + 1] - w[i]) > 0]


def _segment_of(segments, i):
    for k, (s, e) in enumerate(segments):
        if s <= i - 1 and i + 1 < e:
            return k
    return None


def refine_peaks(problem, pts, segments, outputs_of, amplitudes, xscale, r_scale) -> int:
    """Insert points at the peaks of every output (module doc); returns how many.

    Parameters
    ----------
    problem
        The FRF's problem.
    pts : hbm.analyses.traced_points.TracedPoints
        The traced points (lists ``X, w, Y, its, err, unclosed``), changed in place.
    segments : list of [int, int]
        Index ranges ``[start, end)`` of the traced segments, shifted by every insertion.
    outputs_of : callable
        ``(X, w) -> Y`` (n_coef, n_o), the outputs of a point.
    amplitudes : callable
        ``Y -> h1`` (n_o,), first-harmonic amplitudes.
    xscale : ndarray
        Newton's unknown scale.
    r_scale : float
        Newton's residual scale.
    """
    added = 0
    n_out = len(amplitudes(pts.Y[0])) if pts.Y else 0
    for o in range(n_out):
        for _ in range(ROUNDS):
            a = np.array([amplitudes(Y)[o] for Y in pts.Y])
            w = np.array(pts.w)
            moved = False
            for i in reversed(_peak_indices(w, a)):
                k = _segment_of(segments, i)
                ws = _vertex(w[i - 1:i + 2], a[i - 1:i + 2])
                if k is None or ws is None or not min(w[i - 1], w[i + 1]) < ws < max(w[i - 1], w[i + 1]):
                    continue
                got = solve_near(problem, pts.X[i], ws, np.linalg.norm(pts.X[i + 1] - pts.X[i - 1]),
                                 xscale, r_scale, tol=1e-12)
                if got is None:
                    continue
                X, its = got
                Y = outputs_of(X, ws)
                h1 = amplitudes(Y)[o]
                after = (ws - w[i]) * (w[i + 1] - w[i]) > 0     # between points i and i + 1
                if h1 < a[i + 1 if after else i - 1] or abs(ws - w[i]) <= 1e-12 * abs(w[i]):
                    continue                                    # off the branch, or no new point
                insert_point(problem, pts, segments, k, i + 1 if after else i, X, ws, its, Y)
                added += 1
                moved = moved or abs(h1 - a[i]) > AMPLITUDE_TOL * a[i] or abs(ws - w[i]) > FREQUENCY_TOL * w[i]
            if not moved:
                break
    return added
