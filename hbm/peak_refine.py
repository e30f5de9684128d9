r"""Points placed on the resonance peaks, not only where the continuation stepped.

The continuation's steps are sized for the corrector, so a smooth peak usually falls between
two points and the drawn curve (and the reported peak) is low by up to a few tenths of a per
cent.  For every resonance peak of every output (a local maximum of prominence at least 10 % of
its height along a stretch where the frequency is monotone) the parabola through the peak
point :math:`i` and its neighbours,

.. math::

    a(w) \approx a_i + \frac{(w - w_i)\,\big[(w - w_{i-1}) s_+ - (w - w_{i+1}) s_-\big]}{w_{i+1} - w_{i-1}},

with :math:`s_\pm` the one-sided slopes, has its vertex at :math:`w^*`; the balance is solved
there by Newton at fixed frequency from :math:`X_i` and the point is inserted in path order.
This repeats (at most ``ROUNDS`` times per peak) until the vertex moves the amplitude by less
than ``AMPLITUDE_TOL``.  A solve that fails, or lands off the branch (amplitude below both
neighbours), inserts nothing.
"""
from __future__ import annotations

import numpy as np

from .energy import energy_balance
from .newton import newton

ROUNDS = 3
AMPLITUDE_TOL = 1e-5
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


def _peak_indices(w, a):
    """Interior resonance peaks of ``a`` along the path where ``w`` is monotone around them."""
    from scipy.signal import find_peaks
    idx, _ = find_peaks(a, prominence=(PROMINENCE * np.abs(a), None))
    return [int(i) for i in idx if 0 < i < len(a) - 1 and (w[i] - w[i - 1]) * (w[i + 1] - w[i]) > 0]


def _segment_of(segments, i):
    for k, (s, e) in enumerate(segments):
        if s <= i - 1 and i + 1 < e:
            return k
    return None


def _insert(pts, segments, k, at, values) -> None:
    """Insert one point at path index ``at`` into segment ``k``; later segments shift."""
    for name, v in values.items():
        getattr(pts, name).insert(at, v)
    segments[k][1] += 1
    for seg in segments[k + 1:]:
        seg[0] += 1
        seg[1] += 1


def refine_peaks(problem, pts, segments, outputs_of, amplitudes, xscale, r_scale) -> int:
    """Insert points at the peaks of every output (module doc); returns how many.

    Parameters
    ----------
    problem
        The FRF's problem.
    pts : hbm.response._Path
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
                fun = lambda u, ws=ws: problem.residual(problem.expand(u), ws)[:2]
                res = newton(fun, problem.unknowns(pts.X[i]), scale=xscale, r_scale=r_scale, tol=1e-12)
                if not res.converged:
                    continue
                X = problem.expand(res.x)
                if np.linalg.norm(X - pts.X[i]) > np.linalg.norm(pts.X[i + 1] - pts.X[i - 1]):
                    continue                          # landed on another branch
                Y = outputs_of(X, ws)
                h1 = amplitudes(Y)[o]
                if h1 < max(a[i - 1], a[i + 1]) or abs(h1 - a[i]) <= AMPLITUDE_TOL * a[i]:
                    continue
                at = i if (ws - w[i]) * (w[i + 1] - w[i]) < 0 else i + 1
                err = energy_balance(problem, X, ws).relative_error
                _insert(pts, segments, k, at, {"X": X, "w": ws, "Y": Y, "its": res.iterations, "err": err,
                                               "unclosed": problem.nl.last_unclosed})
                added += 1
                moved = True
            if not moved:
                break
    return added
