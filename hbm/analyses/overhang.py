r"""Branches that overhang a jump: arclength traces from both sides of where two traced
segments meet without being one solution.

Where the path stops and is restarted further on, and the marches at fixed frequency
(:mod:`hbm.analyses.gap_bridge`) narrow the gap to little or nothing without joining its
sides, the two segments usually meet across a fold's jump: below it the path is on one
branch, above it on another.  A march cannot turn a fold, so the branch that overhangs the
jump is missing, and no gap says so when the sides meet at one frequency.  On a separating
contact's softening resonance (the stress matrix's friction3d ``R = 100``, ``kt / k = 1e4``,
``H = 15``, 0.15-0.3 Hz) that was the whole upper branch below the jump at 0.2093 Hz, with the
peak: 41.2 at 0.1915 Hz, drawn as 11.1 at the jump.

At every such junction the pseudo-arclength continuation is run on from each side, away
from the junction (the last point below it upwards, the first point above it downwards):

* a trace that arrives on the other side's path (within ``MEET`` of one of its chords,
  :meth:`hbm.analyses.traced_points.TracedPoints.chord_through`, travelling the way the
  other side's points continue it) joins the two segments;
* a trace that turns a fold keeps its points: the overhanging branch is traced round its
  fold (it may then stop on the middle branch, where the unknowns a stuck contact leaves
  nearly free make Newton stall).  A turn counts as a fold only when the trace's last point
  lies on another branch than the one it came along and Newton at a fixed frequency just
  past the turn finds no solution near it (:func:`_beyond`);
* a trace that creeps to a stop in ever shorter steps on a branch that goes on (that
  fixed-frequency solve lands next to it: on the separating contact, where the tangential
  slider's offset is nearly free) hops: the branch is marched at fixed frequencies from the
  solution past the stop until it nears its fold, and traced on from there (:func:`_hop`);
* a trace that turns no fold within its budget (``MAX_POINTS``, and all traces together no
  more points than the path has) runs beside the other side's path on a distinct solution:
  it keeps only its points short of the other side's end, which narrow a gap.

When both sides turn a fold and do not join, every frequency of the window lies on a traced
branch and only a stretch of the middle branch between the folds is missing: it is stated as
such (``settings["middle_gaps"]``, a note), not as a gap of the window.  A stated gap that
is not joined stays one; where its two sides now overlap in frequency its reason says that
one branch goes on untraced past its end (a peak there may be missing).  A junction that no
gap stated and the traces do not resolve stays as it was (``settings["overhangs"]`` records
it): on stiff stuck contacts the trace from one side often runs beside the other side's path
on the same motion with another slider offset, which is no missing branch.
"""
from __future__ import annotations

import numpy as np

from hbm.analyses.gap_bridge import _Marcher, _rel, march
from hbm.analyses.problem_setup import recover_outputs
from hbm.analyses.gaps import jump, state_gaps
from hbm.analyses.trace import _trace
from hbm.analyses.traced_points import TracedPoints

MEET = 1e-4         # a trace within this (relative) of the other side's chord has arrived on it
MAX_POINTS = 600    # points of one trace: at most this many, and all together no more than the path has
MIN_POINTS = 50     # ... unless it has fewer than this
BACK = 3            # a trace that neither joins nor folds is tried again this many points back
PROBE = 1e-4        # a fold is checked by a solve this share of its frequency past it ...
GOES_ON = 0.1       # ... which must not land within this (relative) of the fold's point (a march's largest step)
ON_BRANCH = 1e-3    # a trace whose last point is this close to its path before the turn came back
HOPS = 50           # a trace that creeps to a stop is traced on past it this many times at most


class _Watch:
    """The stop test of one trace (module doc): ``(X, w) -> bool``; afterwards ``chord``
    (index into ``target`` of the chord arrived on, or None), ``folds`` (turns seen) and
    ``folds_hz`` (the folds the traces reported, filled in by :func:`_run`).
    ``along = 1``: the trace must arrive travelling the way ``target``'s points run (they
    continue it), ``-1``: against it (it is spliced in reversed)."""

    def __init__(self, target, direction: int, budget: int, along: int):
        self.target, self.direction, self.budget = target, direction, budget
        self.along, self.chord, self.seen = along, None, 0
        self.restart()

    def restart(self) -> None:
        """Forget the turns seen (``folds``, and ``folds_hz`` the traces reported): the trace
        goes on past a creep from a point where it heads in ``direction`` again."""
        self.folds, self.folds_hz, self.last, self.way = 0, [], None, self.direction

    def __call__(self, X, w) -> bool:
        self.seen += 1
        if self.last is not None and w != self.last:
            way = 1 if w > self.last else -1
            self.folds += way != self.way
            self.way = way
        self.last = w
        if self.seen == 1:
            return False                         # the start, on its own side
        i = self.target.chord_through(X, w, MEET)
        if i is not None and (self.target.w[i + 1] - self.target.w[i]) * self.way * self.along > 0:
            self.chord = i
            return True
        return self.seen > self.budget


def _run(ctx, X, w, direction, target, w_other, along):
    """One trace from ``(X, w)`` (:class:`_Watch`): ``(points kept, watch)``: all points
    after the start when it joins ``target`` or turns a fold, else those short of
    ``w_other`` (they narrow the gap).  Where the trace creeps to a stop on a branch that goes
    on (:func:`_beyond`), it hops: its points up to the farthest one are kept, the branch is
    marched on from the solution past it (:func:`_hop`) and traced on from the march's end,
    ``HOPS`` times at most."""
    problem, case, window, xscale, r_scale, opts, lam_step, n_budget = ctx
    watch = _Watch(target, direction, n_budget, along)
    kept, skip = TracedPoints(), 1          # the first trace's start is not new
    for _ in range(HOPS + 1):
        got = TracedPoints()
        watch.folds_hz += _trace(problem, case, got, X, 0, w, window, direction, xscale, r_scale, opts, None,
                                 lam_step=lam_step, stop=watch)[2]
        if watch.chord is not None or len(got.w) < 2:
            break
        turned, past = _beyond(ctx, got, direction)
        if turned or past is None or watch.seen > watch.budget:
            watch.folds = watch.folds if turned else 0
            break
        kept = kept + got.part(skip, int(np.argmax(direction * np.asarray(got.w))) + 1)
        watch.restart()
        hop = _hop(ctx, watch, past, direction)
        kept, got, skip = kept + hop, TracedPoints(), 1   # the next trace starts on the hop's end
        if watch.chord is not None:
            break
        X, w = hop.X[-1], hop.w[-1]
    kept = kept + got.part(skip, len(got.w))
    n = len(kept.w)
    if watch.chord is None and not watch.folds:
        beyond = np.flatnonzero((np.asarray(kept.w) - w_other) * direction > 0)
        n = int(beyond[0]) if beyond.size else n
    return kept.part(0, n), watch


def _hop(ctx, watch, past, direction) -> TracedPoints:
    """Past a spot where a trace crept to a stop: the solution ``past`` there (from
    :func:`_beyond`) and a march at fixed frequencies on from it
    (:func:`hbm.analyses.gap_bridge.march`, towards the window's end in ``direction``, within
    the trace's budget), which stops where the branch nears its fold or jumps; every point is
    shown to ``watch`` (a join ends the hop there)."""
    problem, case, window, xscale, r_scale = ctx[:5]
    m = _Marcher(problem, xscale, r_scale, budget=max(watch.budget - watch.seen, 1))
    marched, _ = march(m, past[0], window[1] if direction > 0 else window[0])
    out = TracedPoints()
    for v, its, err, unclosed in [past] + marched:
        X, w = problem.expand(v[:-1]), float(v[-1])
        out.append(X, w, recover_outputs(problem, case, X, w), its, err, unclosed)
        if watch(X, w):
            break
    return out


def _beyond(ctx, got, direction):
    """Whether the trace ``got`` (its start first) turned at a fold at the farthest frequency
    it reached in ``direction``, and the solution past that point where its branch goes on:
    ``(turned, past)``, ``past`` (``([u, w], iterations, energy_error, unclosed)``,
    :meth:`_Marcher.solve`) or None.  A fold: the trace's last point lies on another branch
    than the one it came along (not within ``ON_BRANCH`` of its path up to the farthest
    point) and Newton at a fixed frequency ``PROBE`` past the farthest point finds no solution
    near it (none within ``GOES_ON``).  A trace that creeps in ever shorter steps and zigzags
    where Newton is ill-conditioned (a stuck contact's nearly free slider offset) turns back
    in frequency too, but along its own path, and past that spot the solve lands next to it.
    A trace that stops at the farthest point is no evidence of a fold: in a field of thin
    facets of a poorly truncated solution Newton fails there as well."""
    problem, case, window, xscale, r_scale = ctx[:5]
    k = int(np.argmax(direction * np.asarray(got.w)))
    away = k < len(got.w) - 1 and not got.part(0, k + 1).passes(got.X[-1], got.w[-1], ON_BRANCH)
    w = got.w[k] * (1 + direction * PROBE)
    if not window[0] <= w <= window[1]:
        return away, None
    m = _Marcher(problem, xscale, r_scale)
    v = np.r_[problem.unknowns(got.X[k]), got.w[k]]
    probe = m.solve(np.r_[v[:-1], w])
    if probe is not None and m.change(probe[0], v) <= GOES_ON:
        return False, probe
    return away, None


def _side(ctx, seg, up: bool, target, along):
    """The trace away from one end of ``seg`` (its last point ``up``, else its first):
    ``(seg', points, watch, spent)``.  When it neither joins nor folds and keeps fewer than
    ``BACK`` points, once more from ``BACK`` points before that end (``seg'`` then ends or
    starts there): the arclength's start at a point on a fold's very turn can fail where one a
    few steps before goes round it."""
    w_other = target.w[0] if up else target.w[-1]
    i = -1 if up else 0
    got, watch = _run(ctx, seg.X[i], seg.w[i], 1 if up else -1, target, w_other, along)
    spent = watch.seen
    if watch.chord is None and not watch.folds and len(got.w) < BACK and len(seg.w) > 2 * BACK:
        base = seg.part(0, len(seg.w) - BACK) if up else seg.part(BACK, len(seg.w))
        got2, watch2 = _run(ctx, base.X[i], base.w[i], 1 if up else -1, target, w_other, along)
        spent += watch2.seen
        if watch2.chord is not None or watch2.folds:
            return base, got2, watch2, spent
    return seg, got, watch, spent


def _overhang(ctx, low, high):
    """Traces across one gap between the segments ``low`` and ``high`` (TracedPoints, path
    order): ``(joined, low', high', watches, spent)`` with ``low'`` the lower segment
    extended (the whole path when joined, ``high'`` then None), the :class:`_Watch` of each
    side's trace kept and the points all traces solved."""
    low, up, wa, spent = _side(ctx, low, True, high, 1)
    if wa.chord is not None:
        return True, low + up + high.part(wa.chord + 1, len(high.w)), None, [wa], spent
    lower = low + up
    high, down, wb, spent_b = _side(ctx, high, False, lower, -1)
    spent += spent_b
    if wb.chord is not None:
        path = lower.part(0, wb.chord + 1) + down.part(0, len(down.w), reverse=True) + high
        return True, path, None, [wa, wb], spent
    return False, lower, down.part(0, len(down.w), reverse=True) + high, [wa, wb], spent


def trace_overhangs(problem, case, pts, segments, settings, window, xscale, r_scale, opts, lam_step) -> list:
    """Trace from both sides of every junction of two segments that are not one solution
    (module doc), a stated gap (``settings["gaps"]``) or not; ``pts`` and ``segments`` are
    rebuilt in place, the gaps stated again, a stretch of a middle branch in
    ``settings["middle_gaps"]`` with ``settings["middle_gap_note"]``, and each attempt in
    ``settings["overhangs"]``.  Returns the folds turned (Hz)."""
    segs = [pts.part(a, b) for a, b in segments]
    gaps = list(settings.get("gaps") or [])
    folds_hz, middle, record = [], [], []
    budget = max(len(pts.w), MIN_POINTS)        # points of all traces together
    for k in range(len(segs) - 2, -1, -1):      # the top first: lower indices stay
        low, high = segs[k], segs[k + 1]
        n_have = sum(len(s.w) for s in segs)
        if _rel(low.X[-1], high.X[0]) <= MEET or n_have >= case.analysis.max_points or budget <= 0:
            continue
        gap = next((g for g in gaps if np.isclose(g["from_hz"], low.w[-1] / (2 * np.pi), rtol=1e-12, atol=0)), None)
        ctx = (problem, case, window, xscale, r_scale, opts, lam_step,
               min(MAX_POINTS, budget, case.analysis.max_points - n_have))
        ends = (low.Y[-1], high.Y[0])          # where the traces start
        joined, low, high, watches, spent = _overhang(ctx, low, high)
        budget -= spent
        sides = [w.folds > 0 for w in watches]
        folds_hz += [f for w in watches for f in w.folds_hz]
        added = sum(len(s.w) for s in ([low] if joined else [low, high])) - len(segs[k].w) - len(segs[k + 1].w)
        segs[k:k + 2] = [low] if joined else [low, high]
        record.append({"at_hz": segs[k].w[-1] / (2 * np.pi) if joined else low.w[-1] / (2 * np.pi),
                       "gap": gap is not None, "joined": joined, "sides_folded": sum(sides), "points": added})
        if joined or all(sides):
            if gap is not None:
                gaps.remove(gap)
            if not joined:
                fs = sorted((low.w[-1] / (2 * np.pi), high.w[0] / (2 * np.pi)))
                middle.append({"from_hz": fs[0], "to_hz": fs[1], "reason": gap["reason"] if gap else ""})
        elif gap is not None:
            gaps[gaps.index(gap)] = _narrowed(problem.basis, gap, low, high, ends, *sides)
    _rebuild(pts, segs)
    segments[:] = _ranges(segs)
    if record:
        settings["overhangs"] = record[::-1]
    settings.pop("gaps", None)
    settings.pop("gap_warning", None)
    state_gaps(settings, sorted(gaps, key=lambda g: g["from_hz"]))
    if middle:
        settings["middle_gaps"] = sorted(middle, key=lambda g: g["from_hz"])
        where = ", ".join(f"{g['from_hz']:.6g}..{g['to_hz']:.6g} Hz" for g in settings["middle_gaps"])
        settings["middle_gap_note"] = (
            f"the branches on both sides of a jump were traced round their folds, so every frequency of the "
            f"window lies on a traced branch; the middle branch between the folds is not traced over {where} "
            + (f"(where the first trace stopped: {middle[0]['reason']})" if middle[0]["reason"] else
               "(the two traces from its ends stopped on it)"))
    return folds_hz


def _narrowed(basis, gap: dict, low, high, ends, fold_low: bool, fold_high: bool) -> dict:
    """``gap`` between the segments ``low`` and ``high`` after the traces: the ends that moved
    towards each other (a side traced round a fold keeps its end ``ends[0]`` or ``ends[1]``,
    outputs (n_coef, n_out): its branch went on past the other side's), the change across it
    measured again, and the reason extended."""
    a = gap["from_hz"] if fold_low else low.w[-1] / (2 * np.pi)
    b = gap["to_hz"] if fold_high else high.w[0] / (2 * np.pi)
    out = {**gap, "from_hz": min(a, b), "to_hz": max(a, b)}
    out.update(jump(basis, ends[0] if fold_low else low.Y[-1], ends[1] if fold_high else high.Y[0]))
    if fold_low or fold_high:
        out["reason"] += "; the branch on one side of it was traced round its fold, the other side's not"
    if b <= a:
        out["reason"] += (f"; the branches on its two sides overlap in frequency and one of them goes on "
                          f"untraced past its end at {(b if not fold_high else a):.6g} Hz (a peak there "
                          f"may be missing)")
    return out


def _ranges(segs) -> list:
    """``[start, end)`` index ranges of consecutive segments."""
    ends = np.cumsum([len(s.w) for s in segs]).tolist()
    return [[e - len(s.w), e] for s, e in zip(segs, ends)]


def _rebuild(pts, segs) -> None:
    """``pts`` made the concatenation of ``segs``, in place."""
    for name in pts.FIELDS:
        getattr(pts, name)[:] = [v for s in segs for v in getattr(s, name)]
