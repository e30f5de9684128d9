r"""Bridges across the gaps the arclength continuation leaves: marches at fixed frequencies.

Where the pseudo-arclength corrector stalls inside the window, the path is often still there.
A stiff contact whose truncated displacement rings through its stick phases makes the residual
a surface of thin facets, on which Newton cycles along the tilted hyperplane of the corrector,
yet at each fixed frequency Newton finds the solution from its neighbour's; where a stuck
contact starts to slip or to open, the path turns steeply at a kink that the corrector cannot
follow in one step.  A gap between the last point :math:`v_a = (u_a, \omega_a)` of one traced
segment and the first point :math:`v_b` of the next is therefore marched across in the
frequency (natural-parameter continuation):

.. math::

    R(u_{k+1}, \omega_{k+1}) = 0, \qquad \omega_{k+1} = \omega_k + h_k, \qquad
    u^{(0)}_{k+1} = u_k + \frac{h_k}{\omega_k - \omega_{k-1}} (u_k - u_{k-1}),

by Newton from the secant predictor (from :math:`u_k` on the first step).  A step is accepted
when Newton converges, the energy balance closes (polished as on the path) and the unknowns
moved continuously:

.. math::

    c_k = \frac{\|u_{k+1} - u_k\|}{\max(\|u_k\|, \|u_{k+1}\|)} \le c_{max}, \qquad
    c_k \le \max\big(f\, r_{k-1}\, |h_k|,\ \epsilon\big), \quad r_{k-1} = \frac{c_{k-1}}{|h_{k-1}|}

(``MAX_CHANGE``, ``RATE_FACTOR``, ``ROUND_OFF``; the first rate from the traced segment's last
step), or, at a kink, when halving the step halved its change too (the ratio within
``KINK``): the path goes on at a steeper slope.  A jump does not shrink with
the step, so it ends a march instead of being taken.  After an accepted step :math:`h` grows
by ``GROW``; after a refused one it is halved, down to ``MIN_SHARE`` of the gap, and then
leaps of 2-16 first steps are tried over frequencies where Newton fails.

The march up from :math:`v_a` aims at :math:`\omega_b` and joins the next segment when its
point there is :math:`v_b` (within ``MEET``); where it stops short, a march down from
:math:`v_b` aims at where the first one stopped and joins it in the same way.  A joined gap is
gone: its points and the two segments become one.  One not joined is narrowed to what neither
march reached and stated as before (:mod:`hbm.analyses.gaps`); a fold inside it (two
solutions at one frequency: the march arrives on another one) is such a gap.

What a bridge does not show: the path between two accepted points is taken as continuous, as
between two continuation steps, with each step's change bounded as above; a fold whose other
branch lies closer than that bound (the rate grows as a fold nears) could be stepped across
without its middle branch.  The points are harmonic-balance solutions at the case's
harmonics, with their own stability verdicts and truncation estimates (on the railcar rig the
marched stretch is unstable at every point; where the truncation is poor, the estimates say
so, :mod:`hbm.analyses.truncation`).
"""
from __future__ import annotations

import numpy as np

from hbm.analyses.gaps import jump, state_gaps
from hbm.analyses.curve_fill import solve_near
from hbm.analyses.polish import closed_balance, refused
from hbm.analyses.problem_setup import recover_outputs
from hbm.analyses.stuck import stuck_contacts
from hbm.analyses.traced_points import TracedPoints

FIRST_SHARE = 1.0 / 32.0    # first step, share of the span
MIN_SHARE = 1e-4            # smallest step, share of the span
GROW = 1.5
MAX_CHANGE = 0.1            # largest relative move of the unknowns in one step
RATE_FACTOR = 10.0          # a step may change the point this many times faster than the last
ROUND_OFF = 1e-9            # changes this small always continue
KINK = (0.35, 0.65)         # a halved step's change over the longer step's, on a continuous path
MEET = 1e-6                 # two solutions within this (relative) are one
MAX_SOLVES = 400            # Newton solves per gap, both marches together


def _rel(a, b) -> float:
    """Relative distance of two unknown vectors (the frequency, last entry, left out)."""
    a, b = a[:-1], b[:-1]
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(a), np.linalg.norm(b), 1e-300))


class _Marcher:
    """Newton solves at fixed frequency on the FRF's problem, on a budget."""

    def __init__(self, problem, xscale, r_scale, budget=MAX_SOLVES):
        self.problem, self.xscale, self.r_scale, self.budget = problem, xscale, r_scale, budget
        nc = problem.basis.n_coef
        vib = np.asarray(problem.basis.h_of_row) > 0
        self.vibrating = np.r_[np.repeat(vib[:, None], xscale.size // nc, axis=1).ravel(), True]
        self._stuck = (None, False)

    def change(self, new, old) -> float:
        """:func:`_rel` of ``new`` against ``old`` ([u, w]), over the harmonics above the mean
        alone when a contact sticks for the whole period at ``old``: its slider offset, hence
        the static part of the solution, is one of a family (:mod:`hbm.analyses.stuck`), and
        where the contact starts to open or slip the path's member of it jumps to the one the
        motion fixes, a change that is no jump of the response."""
        if self._stuck[0] is not old:
            X = self.problem.expand(old[:-1])
            n = stuck_contacts(self.problem, X[None], np.array([old[-1]]))
            self._stuck = (old, n is not None and n[0] > 0)
        if self._stuck[1]:
            return _rel(new[self.vibrating], old[self.vibrating])
        return _rel(new, old)

    def solve(self, guess):
        """Newton from ``guess = [u, w]`` (n_u + 1,) at its ``w``, the energy balance closed:
        ``(v, iterations, energy_error, unclosed)`` (``unclosed``: the balance's loops left
        open, :attr:`hbm.balance.aft.NonlinearForces.last_unclosed`) or None."""
        self.budget -= 1
        problem, w = self.problem, float(guess[-1])
        got = solve_near(problem, problem.expand(guess[:-1]), w, np.inf, self.xscale, self.r_scale)
        if got is None or not np.all(np.isfinite(got[0])):
            return None
        X, err, floor, res = closed_balance(problem, got[0], w, self.xscale, self.r_scale)
        if refused(err, floor, res):
            return None
        return np.r_[problem.unknowns(X), w], got[1], err, problem.nl.last_unclosed


def _steps(h, h_min, span, left):
    """The steps to try from one point: ``h`` halved down to ``h_min``, then leaps over what
    none of them passed, of 2, 4, 8 and 16 times the larger of ``h`` and the first step (signed
    like ``span``, none beyond ``left``)."""
    out, t = [], h
    while t >= h_min:
        out.append(t)
        t *= 0.5
    base = max(h, FIRST_SHARE * abs(span))
    out += [base * 2 ** j for j in range(1, 5) if base * 2 ** (j - 1) < left]
    return [np.sign(span) * min(t, left) for t in out]


def _kink(faster: list, change: float) -> bool:
    """Whether halving the step halved its change as well (``faster`` holds the changes of the
    longer steps refused before this one): the path goes on at a steeper slope (a kink, where
    a contact starts to slip or to open), not across a jump, whose change does not shrink with
    the step."""
    return bool(faster) and change <= MAX_CHANGE and KINK[0] <= change / faster[-1] <= KINK[1]


def _continues(change: float, rate: float | None, dw: float) -> bool:
    """Whether a step of ``dw`` (rad/s) that moved the unknowns by ``change`` (relative)
    continues the path: at most ``MAX_CHANGE``, and at most ``RATE_FACTOR`` times what the last
    step's rate of change ``rate`` (per rad/s; None: unknown) predicts, or round-off."""
    return change <= MAX_CHANGE and (rate is None or change <= max(RATE_FACTOR * rate * dw, ROUND_OFF))


def march(m: _Marcher, start, w_end: float, target=None, rate=None):
    """March from ``start`` to the frequency ``w_end`` (module doc).

    Parameters
    ----------
    m : _Marcher
    start : ndarray, shape (n_u + 1,)
        ``[unknowns, w]`` of a solution.
    w_end : float
        rad/s, above or below ``start``'s.
    target : ndarray, shape (n_u + 1,), optional
        The solution at ``w_end`` to join: the march's point there must be it (``MEET``).
    rate : float, optional
        The path's relative change of the unknowns per rad/s at ``start``.

    Returns
    -------
    points : list of (ndarray (n_u + 1,), iterations, energy_error, unclosed)
        Accepted points after ``start``, in marching order (a joined end not included).
    joined : bool
    """
    v, prev = start, None
    span = w_end - v[-1]
    h, h_min = FIRST_SHARE * abs(span), MIN_SHARE * abs(span)
    pts = []
    while m.budget > 0:
        faster = []                 # changes of the steps refused only for their rate, in order
        for step in _steps(h, h_min, span, abs(w_end - v[-1])):
            at = w_end if abs(w_end - v[-1] - step) <= 1e-12 * abs(span) else v[-1] + step
            guess = v.copy() if prev is None else v + (at - v[-1]) / (v[-1] - prev[-1]) * (v - prev)
            guess[-1] = at
            got = m.solve(guess)
            if got is not None and (at != w_end or target is None or _rel(got[0], target) <= MEET):
                c = m.change(got[0], v)
                if _continues(c, rate, abs(at - v[-1])) or _kink(faster, c):
                    break
                faster.append(c if c <= MAX_CHANGE else np.inf)
            if m.budget <= 0:
                return pts, False
        else:
            return pts, False
        if at == w_end and target is not None:
            return pts, True
        pts.append(got)
        if at == w_end:
            return pts, False
        rate = m.change(got[0], v) / abs(at - v[-1])
        prev, v = v, got[0]
        h = min(abs(step) * GROW, abs(w_end - v[-1]))
    return pts, False


def _as_points(problem, case, marched) -> TracedPoints:
    out = TracedPoints()
    for v, its, err, unclosed in marched:
        X, w = problem.expand(v[:-1]), float(v[-1])
        out.append(X, w, recover_outputs(problem, case, X, w), its, err, unclosed)
    return out


def _v(pts, problem, i):
    return np.r_[problem.unknowns(pts.X[i]), pts.w[i]]


def _rate(pts, problem, i, j, segment):
    """The path's relative change per rad/s between its points ``i`` and ``j`` of ``segment``
    (None when ``j`` lies outside it or at the same frequency)."""
    if not segment[0] <= j < segment[1] or pts.w[i] == pts.w[j]:
        return None
    return _rel(_v(pts, problem, i), _v(pts, problem, j)) / abs(pts.w[i] - pts.w[j])


def _segment_pair(pts, segments, gap):
    """``k`` such that ``gap`` starts at the last point of segment ``k`` (where the path
    stopped) and segment ``k + 1`` follows it, or None.  Segment ``k + 1`` begins where the trace
    back from the restart stopped, at the gap's end or, past a fold of that trace, just above
    it."""
    w_a = 2 * np.pi * gap["from_hz"]
    for k in range(len(segments) - 1):
        ia, ib = segments[k][1] - 1, segments[k + 1][0]
        if ia >= segments[k][0] and ib < segments[k + 1][1] and pts.w[ib] > pts.w[ia] and \
                np.isclose(pts.w[ia], w_a, rtol=1e-13, atol=0):
            return k
    return None


def _bridge(m, va, vb, rates):
    """The marches across one gap from ``va`` to ``vb`` (module doc): ``(up, down, joined)``,
    ``up`` from ``va`` and ``down`` from ``vb``, each in its marching order."""
    up, joined = march(m, va, vb[-1], vb, rates[0])
    down = []
    if not joined:
        lo = up[-1][0] if up else va
        down, joined = march(m, vb, lo[-1], lo, rates[1])
    return up, down, joined


def bridge_gaps(problem, case, pts, segments, settings, xscale, r_scale, progress=None) -> None:
    """March across every gap of ``settings["gaps"]`` (module doc): joined gaps are removed
    (their two segments merged), the others narrowed; ``settings["gaps_bridged"]`` records
    each attempt (``from_hz``, ``to_hz``, ``points`` added, ``joined``) and the gaps and their
    warning are stated again.  ``pts`` and ``segments`` change in place."""
    gaps = settings.get("gaps") or []
    if not gaps:
        return
    kept, record = [], []
    for gap in sorted(gaps, key=lambda g: -g["from_hz"]):      # the top first: lower indices stay
        k = _segment_pair(pts, segments, gap)
        if k is None or len(pts.w) >= case.analysis.max_points:
            kept.append(gap)
            continue
        ia, ib = segments[k][1] - 1, segments[k + 1][0]
        rates = (_rate(pts, problem, ia, ia - 1, segments[k]), _rate(pts, problem, ib, ib + 1, segments[k + 1]))
        budget = min(MAX_SOLVES, case.analysis.max_points - len(pts.w))     # a point costs a solve at least
        up, down, joined = _bridge(_Marcher(problem, xscale, r_scale, budget),
                                   _v(pts, problem, ia), _v(pts, problem, ib), rates)
        pts.insert(ib, segments, k + 1, _as_points(problem, case, down[::-1]), 0, len(down))
        pts.insert(ib, segments, k, _as_points(problem, case, up), 0, len(up))
        record.append({"from_hz": gap["from_hz"], "to_hz": gap["to_hz"], "points": len(up) + len(down),
                       "joined": joined})
        if progress is not None and (up or down):
            progress(len(pts.w), float((down or up)[-1][0][-1]) / (2 * np.pi))
        if joined:
            segments[k][1] = segments[k + 1][1]
            del segments[k + 1]
            continue
        ia, ib = segments[k][1] - 1, segments[k + 1][0]
        narrowed = {"from_hz": pts.w[ia] / (2 * np.pi), "to_hz": min(gap["to_hz"], pts.w[ib] / (2 * np.pi))}
        why = gap["reason"] if not (up or down) else (
            f"{gap['reason']}; marched at fixed frequencies from {gap['from_hz']:.6g}..{gap['to_hz']:.6g} Hz "
            f"to what neither march passed")
        kept.append({**gap, **narrowed, "reason": why, **jump(problem.basis, pts.Y[ia], pts.Y[ib])})
    settings["gaps_bridged"] = record[::-1]
    settings.pop("gaps", None)
    settings.pop("gap_warning", None)
    state_gaps(settings, sorted(kept, key=lambda g: g["from_hz"]))
