r"""Jumps of a slow frequency sweep predicted from a traced FRF with stability.

The path (points :math:`i = 0 \dots n-1` with frequency :math:`f_i`, amplitude :math:`a_i`,
stability :math:`s_i`) is cut into *stable monotone pieces*: maximal runs of consecutive
stable points along which :math:`f` moves in one direction.  On a piece the amplitude is a
function of the frequency, :math:`a(f)` for :math:`f \in [f_{lo}, f_{hi}]`.

A slow upward sweep starts on the piece holding the lowest stable frequency and follows it
to :math:`f_{hi}`.  Unless that is the end of the traced range, the response jumps there:
the jump frequency is :math:`f_{hi}`, refined to the continuation's fold frequency when a
fold lies beyond it by at most twice the adjacent frequency step (for a quadratic turning
point between the last stable point and the next point it lies within one step); it lands on
another piece that goes on upwards, :math:`f_{lo} \le f_{jump} < f_{hi}'`, at the amplitude
:math:`a'(f_{jump})` (the nearest in amplitude when several qualify), and the sweep goes on
from there.  The landing amplitude is interpolated linearly between the two path points
that bracket :math:`f_{jump}` unless a ``refine`` callable solves it there exactly (the
continuation's steps are long on flat branches, where linear interpolation is poor).
The amplitude before the jump is that of the last stable point.  A downward sweep mirrors this.  A jump with no stable
landing piece (e.g. a loss of stability without a fold) ends the sweep with
``amplitude_after = None``.  A landing within ``min_size`` (relative) of the amplitude before
is no jump: the sweep goes on along the landing piece without recording one (a few points
flagged unstable inside a branch that does not fold, such as a stability verdict that
flickers at a stick-slip transition, leave the response where it was).
"""
from __future__ import annotations

import numpy as np


def stable_pieces(freq: np.ndarray, stable: np.ndarray) -> list:
    """Stable monotone pieces of the path as index pairs ``(a, b)``, ``a <= b`` inclusive.

    Parameters
    ----------
    freq : ndarray, shape (n,)
    stable : ndarray of bool, shape (n,)

    Returns
    -------
    list of (int, int)
        Consecutive stable points with a monotone frequency; a reversal point belongs to
        both pieces it joins.  Single isolated stable points are pieces too.
    """
    pieces = []
    n = freq.size
    i = 0
    while i < n:
        if not stable[i]:
            i += 1
            continue
        a = i
        direction = 0
        while i + 1 < n and stable[i + 1]:
            d = np.sign(freq[i + 1] - freq[i])
            if direction and d and d != direction:
                break
            direction = direction or d
            i += 1
        pieces.append((a, i))
        if i + 1 < n and stable[i + 1]:
            continue            # reversal: the next piece starts at this same point
        i += 1
    return pieces


def _bracket(freq, a, b, f):
    """Consecutive path indices ``(i, i+1)`` in ``[a, b]`` whose frequencies bracket ``f``."""
    if a == b:
        return a, a
    for i in range(a, b):
        lo, hi = sorted((freq[i], freq[i + 1]))
        if lo <= f <= hi:
            return i, i + 1
    i = a if abs(freq[a] - f) <= abs(freq[b] - f) else b - 1
    return i, i + 1


def _amp_at(freq, amp, a, b, f):
    i, j = _bracket(freq, a, b, f)
    if freq[j] == freq[i]:
        return float(amp[i])
    t = min(max((f - freq[i]) / (freq[j] - freq[i]), 0.0), 1.0)
    return float(amp[i] + t * (amp[j] - amp[i]))


def _jump_frequency(freq, i_end, f_end, folds, direction, tol):
    """The nearest fold beyond ``f_end`` within twice the adjacent steps, else ``f_end``.

    For a quadratic turning point between the end point and the next point, the fold lies
    beyond ``f_end`` by less than the frequency step into the end point (equal steps).
    """
    steps = [abs(freq[j] - f_end) for j in (i_end - 1, i_end + 1) if 0 <= j < freq.size]
    reach = 2.0 * max(steps, default=0.0) + tol
    best = None
    for f in folds:
        beyond = (f - f_end) * direction
        if -tol <= beyond <= reach and (best is None or abs(f - f_end) < abs(best - f_end)):
            best = float(f)
    return f_end if best is None else best


def _sweep(freq, amp, stable, folds, direction, tol, refine, min_size):
    pieces = stable_pieces(freq, stable)
    if not pieces:
        return []
    lo_all, hi_all = float(freq.min()), float(freq.max())
    ends = [(float(freq[a:b + 1].min()), float(freq[a:b + 1].max())) for a, b in pieces]
    # the start: the piece holding the extreme stable frequency (the sweep's beginning)
    key = [e[0] if direction > 0 else -e[1] for e in ends]
    k = int(np.argmin(key))
    jumps = []
    visited = set()
    while k not in visited:
        visited.add(k)
        a, b = pieces[k]
        f_lo, f_hi = ends[k]
        f_end = f_hi if direction > 0 else f_lo
        if abs(f_end - (hi_all if direction > 0 else lo_all)) <= tol:
            break
        i_end = a + int(np.argmax(freq[a:b + 1] * direction))
        f_jump = _jump_frequency(freq, i_end, f_end, folds, direction, tol)
        before = float(amp[i_end])
        cand = []
        for m, ((ca, cb), (c_lo, c_hi)) in enumerate(zip(pieces, ends)):
            if m == k:
                continue
            if (direction > 0 and c_lo - tol <= f_jump < c_hi) or (direction < 0 and c_lo < f_jump <= c_hi + tol):
                cand.append((abs(_amp_at(freq, amp, ca, cb, f_jump) - before), m))
        if not cand:
            jumps.append({"from_hz": f_jump, "amplitude_before": before, "amplitude_after": None})
            break
        _, m = min(cand)
        after = _amp_at(freq, amp, *pieces[m], f_jump)
        if refine is not None:
            exact = refine(*_bracket(freq, *pieces[m], f_jump), f_jump)
            after = after if exact is None else float(exact)
        k = m
        if abs(after - before) <= min_size * max(abs(after), abs(before)):
            continue                        # no change of amplitude: not a jump
        jumps.append({"from_hz": f_jump, "amplitude_before": before, "amplitude_after": after})
    return jumps


def predict_jumps(freq_hz, amplitude, stable, folds_hz=(), rel_tol: float = 1e-9, refine=None,
                  min_size: float = 0.01) -> dict:
    """Jumps of slow upward and downward sweeps (module doc).

    Parameters
    ----------
    freq_hz : array_like, shape (n,)
        Frequencies along the continuation path.
    amplitude : array_like, shape (n,)
        An output's amplitude along the path.
    stable : array_like of bool, shape (n,)
    folds_hz : sequence of float
        Fold frequencies located by the continuation (refine the jump frequencies).
    rel_tol : float
        Frequencies closer than ``rel_tol * (max - min)`` count as equal.
    refine : callable, optional
        ``refine(i0, i1, f_hz) -> amplitude or None``: the amplitude at ``f_hz`` on the path
        between points ``i0`` and ``i1`` solved exactly (``None``: keep the interpolation).
    min_size : float
        A landing whose amplitude differs from the one before by at most ``min_size`` times
        the larger of the two is not a jump (module doc).

    Returns
    -------
    dict
        ``{"up": [jump, ...], "down": [jump, ...]}`` with every jump a dict
        ``{"from_hz", "amplitude_before", "amplitude_after"}`` (``amplitude_after`` is
        ``None`` when no stable branch is there to land on), in sweep order.
    """
    f = np.asarray(freq_hz, dtype=float)
    amp = np.asarray(amplitude, dtype=float)
    s = np.asarray(stable, dtype=bool)
    if not (f.shape == amp.shape == s.shape) or f.ndim != 1:
        raise ValueError("freq_hz, amplitude and stable must be 1-D arrays of one length")
    if f.size == 0:
        return {"up": [], "down": []}
    tol = rel_tol * max(float(f.max() - f.min()), 1e-300)
    folds = [float(x) for x in folds_hz]
    return {"up": _sweep(f, amp, s, folds, +1, tol, refine, min_size),
            "down": _sweep(f, amp, s, folds, -1, tol, refine, min_size)}
