r"""Points where the drawn curve bends, so that its chords stay within ``CURVE_TOL`` of the path.

The FRF is drawn as straight chords between points in the plane of log frequency and log
amplitude, :math:`P = (\ln f, \ln a)`, where a distance of :math:`10^{-3}` is a 0.1 % error in
frequency or amplitude.  On a path of curvature :math:`\kappa` a chord of length :math:`h` lies
at most

.. math::

    s = \kappa h^2 / 8

from the arc it cuts across (its sag).  The curvature at an interior point :math:`j` is
estimated from the turning angle :math:`\theta_j` between its two chords,
:math:`\kappa_j = 2\theta_j / (h_{j-1} + h_j)`, and the sag of chord :math:`j` from the larger of
its two ends, for every output's first harmonic.  A chord whose estimate exceeds
``FLAG_SHARE * CURVE_TOL`` is traced again by continuation (:func:`retrace_chord`) in
:math:`n = \lceil 2\sqrt{s / CURVE_TOL}\rceil` steps (2 to ``MAX_SPLIT``), which divides its
sag by :math:`n^2`; this repeats for ``ROUNDS`` rounds.  A corner (a stick-slip switch between
two points) has no curvature to estimate from, but it turns the chords at both ends, so it is
flagged the same way and resolved by the rounds.

A re-traced chord is kept only when the continuation from its first point arrives at its
second (the same point, to ``ARRIVAL`` in the scaled unknowns): the points in between then lie
on the same branch, never on another that coexists at those frequencies.  Its points are
inserted with their energy balance checked like every traced point
(:func:`hbm.analyses.trace._trace`).
"""
from __future__ import annotations

import math

import numpy as np

from continuation import ArclengthOptions

from hbm.analyses.trace import _trace
from hbm.analyses.traced_points import TracedPoints

CURVE_TOL = 5e-3        # largest distance of a chord from the path, in (ln f, ln a): 0.5 %
FLAG_SHARE = 0.25       # a chord is re-traced when its estimated sag exceeds this share of it
MAX_SPLIT = 8           # most steps one re-trace divides a chord into
ROUNDS = 3
ARRIVAL = 1e-6          # a re-trace ends on the chord's second point to this (scaled, inf-norm)
FLOOR = 1e-9            # amplitudes below this share of an output's largest are floored (ln 0)


def chord_sags(w: np.ndarray, amps: np.ndarray) -> np.ndarray:
    """Estimated sag of every chord of one traced segment (module doc).

    Parameters
    ----------
    w : ndarray, shape (m,)
        Frequencies of the segment's points (any unit).
    amps : ndarray, shape (m, n_o)
        First-harmonic amplitude of every output.

    Returns
    -------
    ndarray, shape (m - 1,)
        Largest estimated sag over the outputs; zero for a segment of fewer than 3 points.
    """
    m = w.size
    if m < 3:
        return np.zeros(max(m - 1, 0))
    a = np.maximum(np.abs(amps), FLOOR * np.abs(amps).max(axis=0, initial=0.0) + 1e-300)
    P = np.stack([np.broadcast_to(np.log(np.abs(w))[:, None], a.shape), np.log(a)], axis=-1)
    C = np.diff(P, axis=0)                                  # (m-1, n_o, 2)
    h = np.hypot(C[..., 0], C[..., 1])
    cross = C[:-1, :, 0] * C[1:, :, 1] - C[:-1, :, 1] * C[1:, :, 0]
    dot = (C[:-1] * C[1:]).sum(axis=-1)
    theta = np.abs(np.arctan2(cross, dot))                  # (m-2, n_o) turning angles
    kappa = 2.0 * theta / np.maximum(h[:-1] + h[1:], 1e-300)
    k_end = np.zeros((m, a.shape[1]))
    k_end[1:-1] = kappa                                     # curvature at every point
    sag = h * h / 8.0 * np.maximum(k_end[:-1], k_end[1:])
    return sag.max(axis=1)


def retrace_chord(problem, case, pts, segments, k: int, i: int, n_steps: int, xscale, r_scale,
                  progress=None) -> int:
    """Trace chord ``(i, i + 1)`` of segment ``k`` again by continuation in steps of at most
    ``1 / n_steps`` of its scaled length; insert the points in between when the trace arrives
    at point ``i + 1`` (module doc).  Returns how many were inserted (0: it did not arrive).

    Parameters
    ----------
    problem, case
        The FRF's problem and case.
    pts : hbm.analyses.traced_points.TracedPoints
        Traced points, changed in place.
    segments : list of [int, int]
        ``[start, end)`` of each segment, shifted by the insertion.
    xscale : ndarray, shape (n_unknowns,)
    r_scale : float
    progress : callable, optional
        The FRF's ``progress(n_points, freq_hz)``, told of every point of the trace (counted
        after the path's points).
    """
    w0, w1 = pts.w[i], pts.w[i + 1]
    if w1 == w0:
        return 0
    u1 = problem.unknowns(pts.X[i + 1])
    d = (u1 - problem.unknowns(pts.X[i])) / xscale
    ds = math.sqrt(float(d @ d) + 1.0) / n_steps
    opts = ArclengthOptions(ds0=ds, ds_max=ds, max_steps=4 * n_steps)
    sub = TracedPoints()
    _trace(problem, case, sub, pts.X[i], 0, w0, (min(w0, w1), max(w0, w1)), 1 if w1 > w0 else -1,
           xscale, r_scale, opts, progress, offset=len(pts.w) - 1)
    if len(sub.w) < 3 or abs(sub.w[-1] - w1) > 1e-12 * abs(w1) \
            or np.max(np.abs(problem.unknowns(sub.X[-1]) - u1) / xscale) > ARRIVAL:
        return 0
    return pts.insert(i + 1, segments, k, sub, 1, len(sub.w) - 1)


def fill_bends(problem, case, pts, segments, amplitudes, xscale, r_scale, budget: int, progress=None) -> int:
    """Re-trace the chords whose estimated sag exceeds ``FLAG_SHARE * CURVE_TOL`` (module doc),
    at most ``budget`` points in all; returns how many were inserted.

    Parameters
    ----------
    amplitudes : callable
        ``Y -> h1`` (n_o,), the first-harmonic amplitudes of a point's outputs.
    progress : callable, optional
        As :func:`retrace_chord`'s.
    """
    added = 0
    for _ in range(ROUNDS):
        flagged = []
        for k, (s, e) in enumerate(segments):
            if e - s < 3:
                continue
            sag = chord_sags(np.array(pts.w[s:e]), np.array([amplitudes(Y) for Y in pts.Y[s:e]]))
            flagged += [(k, s + j, sg) for j, sg in enumerate(sag) if sg > FLAG_SHARE * CURVE_TOL]
        if not flagged:
            break
        round_added = 0
        for k, i, sg in reversed(flagged):       # back to front: earlier indices stay valid
            if added + round_added >= budget:
                break
            n = min(MAX_SPLIT, max(2, math.ceil(2.0 * math.sqrt(sg / CURVE_TOL))))
            round_added += retrace_chord(problem, case, pts, segments, k, i, n, xscale, r_scale, progress)
        added += round_added
        if round_added == 0 or added >= budget:
            break
    return added
