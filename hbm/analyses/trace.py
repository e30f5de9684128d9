r"""Tracing one FRF window: first point, continuation, restarts past stops, and the branches
that leave it.

:func:`trace_window` solves a first point at ``fmin`` (:func:`hbm.analyses.problem_setup._first_point`),
traces the branch upwards by :class:`continuation.Arclength` (:func:`_trace`: every point's
energy balance checked, loose ones polished), restarts past a stop the corrector cannot
pass (:func:`_restart_past_stops`, every skipped stretch stated; a fresh point from the
linear responses or, failing them, from a time integration's periodic response,
:mod:`hbm.analyses.td_start`; where no restart converges, the branch through ``fmax`` traced
down towards the stop, :func:`_top_down_past_stop`), and traces from ``fmax``
down what a branch folding back out at ``fmin`` leaves.  When no first point converges at
``fmin`` (a stiff contact in stick-slip there, where Newton, the force ramp and its
arclength version all fail), the window is traced from ``fmax`` down instead, and the
message says so.
"""
from __future__ import annotations

import numpy as np

from continuation import Arclength

from hbm.analyses.gaps import jump, state_gaps
from hbm.analyses.polish import ENERGY_LIMIT, FORCE_LIMIT, balance_resolution, closed_balance, refused
from hbm.analyses.problem_setup import _first_point, recover_outputs
from hbm.analyses.resonances import ResonanceStepLimit, linear_resonances
from hbm.balance.energy import energy_balance
from hbm.analyses.td_start import time_domain_start
from hbm.analyses.traced_points import TracedPoints

def _widened_scale(problem, xscale: np.ndarray, X0: np.ndarray) -> np.ndarray:
    """The unknowns' scale (n_unknowns,) raised, unknown DOF by unknown DOF, to the first
    point's largest harmonic coefficient ``max_{k: h > 0} |X0[k, j]|`` where that is larger.

    The scale from the linear limits (geometric mean of the stuck and free peaks) is far below
    the response when a stiff contact slips from the start: with ``kt / k = 1e6`` it is
    ``1e-3`` of the free peak, so every arclength step moved the frequency by ``3e-5 Hz`` and
    den Hartog's oscillator (kt = 1e6, a 0.08 Hz window) stopped at ``max_points``."""
    nc = X0.shape[0]
    vib = problem.basis.h_of_row > 0        # a static offset (an interference) is not a motion
    amp = np.abs(problem.unknowns(X0).reshape(nc, -1)[vib]).max(axis=0, initial=0.0)
    return np.maximum(xscale, np.tile(amp, nc))


def _step_limit(problem, case, window) -> ResonanceStepLimit:
    """The FRF's parameter-step limit at the linear resonances of the free and stuck limits
    (:mod:`hbm.analyses.resonances`) inside ``window`` (rad/s)."""
    d = np.ix_(problem.modal_rows(), problem.modal_rows())
    om, z = linear_resonances(problem.modal_data(), problem.stuck_stiffness()[d], problem.stuck_damping()[d])
    return ResonanceStepLimit(om, z, window)


def _trace(problem, case, pts, X0, it0, w0, bounds, direction, xscale, r_scale, opts, progress, offset=0,
           lam_step=None, stop=None):
    """One continuation from ``(X0, w0)`` in ``direction``; appends to ``pts``.

    Returns ``(status, message, folds_hz, n_rejected)``.  Points whose energy balance is
    looser than ``POLISH_ENERGY`` are polished by a fixed-frequency Newton solve; a point
    still looser than ``ENERGY_LIMIT`` ends the path (status ``failed``, not kept).
    ``stop(X, w) -> bool``, called on every point kept, ends the path there when True
    (status ``stopped``).
    """
    scale = np.r_[xscale, bounds[1] - bounds[0]]
    solver = Arclength(problem, np.r_[problem.unknowns(X0), w0], scale, lam_bounds=bounds,
                       direction=direction, options=opts, lam_step=lam_step, overwrite_jacobian=True,
                       fun_into=problem.call_into, blocks=problem.solver_structure(),
                       describe_lam=lambda lam: f"{lam / (2 * np.pi):.6g} Hz")
    for pt in solver:
        X = problem.expand(pt.x[:-1])
        w = float(pt.x[-1])
        X, err, floor, res = closed_balance(problem, X, w, xscale, r_scale, solver.linear_solve, scale[-1])
        if refused(err, floor, res):
            return ("failed", f"stopped at {w / (2 * np.pi):.6g} Hz: {_unclosed(err, floor, res)}; the "
                    f"{len(pts.w)} points before it are kept",
                    [f / (2 * np.pi) for f in solver.folds], solver.n_rejected)
        pts.append(X, w, recover_outputs(problem, case, X, w), pt.iterations if pts.w else it0 + pt.iterations,
                   err, problem.nl.last_unclosed)        # of the energy balance's force call at X
        if progress is not None:
            progress(offset + len(pts.w), w / (2 * np.pi))
        if stop is not None and stop(X, w):
            return "stopped", "", [f / (2 * np.pi) for f in solver.folds], solver.n_rejected
        if offset + len(pts.w) >= case.analysis.max_points:
            break
    return solver.status, solver.message, [f / (2 * np.pi) for f in solver.folds], solver.n_rejected


def _unclosed(err: float, floor: float, res: float) -> str:
    """Why a converged point is not reported (:func:`hbm.analyses.polish.refused`)."""
    if err > ENERGY_LIMIT + 2 * floor:
        return (f"the energy balance of the converged point does not close (relative error {err:.1e} > "
                f"{ENERGY_LIMIT:g} after polishing, resolution there {floor:.1e})")
    return (f"the residual of the converged point stays at {res:.1e} of the load after polishing "
            f"(> {FORCE_LIMIT:g})")


GAP_FIRST = 1e-3        # first restart this share of the window past a stop, doubled per try
GAP_TRIES = 8
TD_TRIES, TD_EVERY = 2, 3      # time-domain starts past a stop: at 1 and 8 times GAP_FIRST
MAX_GAPS = 10


def _restart_past_stops(problem, case, pts, segments, window, xscale, r_scale, opts, progress, lam_step,
                        outcome, settings):
    """Where the continuation stopped inside the window, solve a fresh point a little further
    (``GAP_FIRST`` of the window, doubled up to ``GAP_TRIES`` times), trace back from it
    towards the stop (what that reaches is not a gap) and on from it.

    A stop at a stick-slip discontinuity (static above kinetic friction) or a corner the
    corrector cannot turn leaves the rest of the window untraced; restarting past it gives the
    user the rest, and every skipped stretch is stated: ``settings["gaps"]`` (from, to, why)
    and a ``gap_warning``.  Returns the last segment's ``(status, message, folds, n_rejected)``.
    """
    status, message, folds, n_rej = outcome
    w_lo, w_hi = window
    gaps, restarts = [], 0
    while (status == "failed" and pts.w and pts.w[-1] < w_hi * (1 - 1e-9) and len(gaps) < MAX_GAPS
           and len(pts.w) < case.analysis.max_points):
        if restarts == MAX_GAPS:
            message += (f"; {MAX_GAPS} restarts past stops were made and the path still stops, so "
                        f"no more are tried")
            break
        restarts += 1
        w_from = pts.w[-1]
        restart = _fresh_point_past(problem, case, w_from, window, xscale, r_scale, pts)
        if isinstance(restart, str):
            w_end = min(w_from + GAP_FIRST * 2 ** (GAP_TRIES - 1) * (w_hi - w_lo), w_hi)
            message += (f"; no restart past it converged up to {w_end / (2 * np.pi):.6g} Hz ({restart}): "
                        f"there may be no periodic response (hbm timesim shows the motion)")
            break
        start = len(pts.w)
        # back from the restart towards the stop, so that only what neither side reaches is a gap
        back = TracedPoints()
        _trace(problem, case, back, restart[0], restart[1], restart[2], (w_from, w_hi), -1, xscale, r_scale,
               opts, progress, offset=len(pts.w), lam_step=lam_step)
        pts.extend(back, skip_first=True, reverse=True)
        w_reached = min(back.w) if back.w else restart[2]
        if w_reached > w_from * (1 + 1e-9):
            gaps.append({"from_hz": w_from / (2 * np.pi), "to_hz": w_reached / (2 * np.pi), "reason": message,
                         **jump(problem.basis, pts.Y[start - 1], back.Y[-1] if back.w else
                                 recover_outputs(problem, case, restart[0], restart[2]))})
        status, message, f2, r2 = _trace(problem, case, pts, restart[0], restart[1], restart[2], (w_lo, w_hi), +1,
                                         xscale, r_scale, opts, progress, offset=0, lam_step=lam_step)
        folds, n_rej = folds + f2, n_rej + r2
        segments.append([start, len(pts.w)])
    state_gaps(settings, gaps)
    return status, message, folds, n_rej


def _start_at(problem, case, w, xscale, r_scale):
    """``(X, iterations)`` at ``w``: Newton from the linear responses, failing them from a time
    integration (:mod:`hbm.analyses.td_start`); RuntimeError saying why neither converged."""
    try:
        return _first_point(problem, case, w, xscale, r_scale)
    except RuntimeError as exc:
        try:
            return time_domain_start(problem, case, w, xscale, r_scale)
        except RuntimeError as exc2:
            raise RuntimeError(f"{exc}; {exc2}") from exc2


def _top_down_past_stop(problem, case, pts, segments, window, xscale, r_scale, opts, progress, lam_step,
                        outcome, settings):
    """Where the path stopped and no restart past the stop converged: the branch through a
    point at ``fmax`` traced down towards the stop, restarted past its own stops as the upward
    path is (:func:`_down_past_stops`), so that only what neither side reaches is untraced
    (gaps, stated; the window's top is then covered and the run finishes past them).  The
    outcome unchanged, its message extended, when no point at ``fmax`` converges."""
    status, message, folds, n_rej = outcome
    w_stop, w_hi = pts.w[-1], window[1]
    try:
        X, it = _start_at(problem, case, w_hi, xscale, r_scale)
    except RuntimeError as exc:
        return status, f"{message}; from {w_hi / (2 * np.pi):.6g} Hz down neither: {exc}", folds, n_rej
    parts, ends, f2, r2 = _down_past_stops(problem, case, (X, it, w_hi), w_stop, len(pts.w), window, xscale,
                                           r_scale, opts, progress, lam_step)
    if not parts:
        return status, f"{message}; from {w_hi / (2 * np.pi):.6g} Hz down neither: {ends[w_hi]}", folds, n_rej
    ends[w_stop] = message
    gaps = list(settings.get("gaps", [])) + _merge_parts(pts, segments, parts, ends, problem.basis)
    state_gaps(settings, gaps)
    return "finished", f"traced from {w_hi / (2 * np.pi):.6g} Hz down", folds + f2, n_rej + r2


def _merge_parts(pts, segments, parts, ends, basis) -> list:
    """Append the ``parts`` of :func:`_down_past_stops` to ``pts`` (lowest frequency first, a
    segment each) above its last point, and return the gaps between them: where the upper
    end of one (its last point, or the restart a part traced up from starts at, which the
    part traced down from it holds) lies below the lower end of the next; ``ends`` give why."""
    spans = [(pts.w[-1], pts.w[-1], len(pts.w) - 1, len(pts.w) - 1)]     # (lo, hi, i_lo, i_hi)
    for part, down in sorted(parts, key=lambda pd: (min(pd[0].w), not pd[1])):
        start = len(pts.w)
        if down:
            pts.extend(part, reverse=True)
        else:                   # traced up from a restart, which the part down from it holds
            pts.extend(part, skip_first=True)
        if len(pts.w) > start:
            segments.append([start, len(pts.w)])
            lo = pts.w[start] if down else part.w[0]
            spans.append((lo, pts.w[-1], start, len(pts.w) - 1))
    gaps = []
    for (_, a, _, ia), (b, _, ib, _) in zip(spans[:-1], spans[1:]):
        if b > a * (1 + 1e-9):
            why = "; ".join(m for m in (ends.get(a), ends.get(b)) if m)
            gaps.append({"from_hz": a / (2 * np.pi), "to_hz": b / (2 * np.pi), "reason": why,
                         **jump(basis, pts.Y[ia], pts.Y[ib])})
    return gaps


def _down_past_stops(problem, case, first, w_stop, offset, window, xscale, r_scale, opts, progress, lam_step):
    """The branch through ``first = (X, iterations, w)`` traced down to ``w_stop``, restarted
    below each of its stops (:func:`_fresh_point_past` downwards, then traced up towards the
    stop and on down), at most ``MAX_GAPS`` times.

    Returns ``(parts, ends, folds_hz, n_rejected)``: ``(TracedPoints, down)`` per traced part
    (``down``: highest frequency first), and ``ends``, why a part ended, by the frequency
    (rad/s) where it did (a stop going down, a stop going up, or no point at ``first``)."""
    X, it, w_from = first
    parts, ends, folds, n_rej = [], {}, [], 0

    def run(X, it, w0, bounds, direction):
        """One part traced from ``(X, w0)`` (kept when it has points): ``(part, status, message)``."""
        nonlocal folds, n_rej
        part = TracedPoints()
        st, msg, f, r = _trace(problem, case, part, X, it, w0, bounds, direction, xscale, r_scale, opts, progress,
                               offset=offset + sum(len(p.w) for p, _ in parts), lam_step=lam_step)
        folds, n_rej = folds + f, n_rej + r
        if part.w:
            parts.append((part, direction < 0))
        return part, st, msg

    for _ in range(MAX_GAPS):
        if w_from <= w_stop:            # a restart on the stop itself: nothing left below it
            break
        part, st, msg = run(X, it, w_from, (w_stop, w_from), -1)
        if not part.w:
            ends[w_from] = msg
            break
        w_low = part.w[-1]                  # where it stopped
        if (st == "finished" or w_low <= w_stop * (1 + 1e-9)
                or offset + sum(len(p.w) for p, _ in parts) >= case.analysis.max_points):
            break
        restart = _fresh_point_past(problem, case, w_low, window, xscale, r_scale, part, direction=-1,
                                    limit=w_stop)
        ends[w_low] = f"from {w_from / (2 * np.pi):.6g} Hz down: {msg}"
        if isinstance(restart, str):
            ends[w_low] += f"; no restart below it converged ({restart})"
            break
        X, it, w_from = restart
        back, st, msg = run(X, it, w_from, (w_from, w_low), +1)
        if back.w and st != "finished":
            ends[back.w[-1]] = f"from {w_from / (2 * np.pi):.6g} Hz up: {msg}"
    return parts, ends, folds, n_rej


def _fresh_point_past(problem, case, w_from, window, xscale, r_scale, traced, direction=1, limit=None):
    """``(X, iterations, w)`` solved a little past a stop at ``w_from``: Newton from the linear
    responses at ``GAP_FIRST`` of the window past it, doubled up to ``GAP_TRIES`` times; failing
    all, from a time integration's periodic response at the first and every ``TD_EVERY``-th
    of those frequencies, ``TD_TRIES`` at most (:mod:`hbm.analyses.td_start`, small full
    models).  A solution on the path ``traced`` so far is not a restart: where the path
    stopped on a fold's middle branch, the linear starts land on the branch already traced
    (which the same fold would then send round again).  When nothing converges with a closed
    energy balance: why the time-domain start failed (str).  ``direction = -1``: below a stop
    of a path traced downwards, down to ``limit`` (default: the window's other end)."""
    w_lo, w_hi = window
    limit = (w_hi if direction > 0 else w_lo) if limit is None else limit
    ladder = sorted({min(max(w_from + direction * GAP_FIRST * 2 ** k * (w_hi - w_lo), min(limit, w_from)),
                         max(limit, w_from)) for k in range(GAP_TRIES)}, reverse=direction < 0)
    starts = [(w_r, lambda w_r: _first_point(problem, case, w_r, xscale, r_scale, arclength_ramp=False,
                                             avoid=lambda X, w_r=w_r: traced.passes(X, w_r)))
              for w_r in ladder]
    starts += [(w_r, lambda w_r: time_domain_start(problem, case, w_r, xscale, r_scale))
               for w_r in ladder[:TD_TRIES * TD_EVERY:TD_EVERY]]
    why = "no time-domain start (a condensed or large model)"
    for k, (w_r, solve) in enumerate(starts):
        try:
            Xr, itr = solve(w_r)
        except RuntimeError as exc:
            if k >= len(ladder):
                why = str(exc)
            continue
        if k >= len(ladder) and traced.passes(Xr, w_r):       # (the linear starts avoid it)
            why = "the time-domain start settled on the branch already traced"
            continue
        eb = energy_balance(problem, Xr, w_r)
        err = eb.relative_error
        if err <= ENERGY_LIMIT or not refused(err, balance_resolution(problem, Xr, w_r, eb)):
            return Xr, itr, w_r
        if k >= len(ladder):
            why = f"the time-domain start's energy balance did not close ({err:.1e})"
    return why


def trace_window(problem, case, window, xscale, r_scale, opts, progress, settings):
    """The points of the FRF over ``window`` (rad/s), lowest frequency first.

    Returns
    -------
    pts : TracedPoints
    segments : list of [start, stop]
        Index ranges of ``pts`` traced as one continuation each.
    outcome : tuple
        ``(status, message, folds_hz, n_rejected)`` of the run.
    xscale : ndarray, shape (n_unknowns,)
        The unknowns' scale, widened by the first point (:func:`_widened_scale`).
    """
    w_lo, w_hi = window
    lo, hi = w_lo / (2 * np.pi), w_hi / (2 * np.pi)
    pts, segments = TracedPoints(), []
    lam_step = _step_limit(problem, case, window)
    try:
        X0, it0 = _first_point(problem, case, w_lo, xscale, r_scale)
    except RuntimeError as exc:
        return _from_the_top(problem, case, window, xscale, r_scale, opts, progress, lam_step, str(exc))
    xscale = _widened_scale(problem, xscale, X0)
    outcome = _trace(problem, case, pts, X0, it0, w_lo, window, +1, xscale, r_scale, opts, progress,
                     lam_step=lam_step)
    segments.append([0, len(pts.w)])
    outcome = _restart_past_stops(problem, case, pts, segments, window, xscale, r_scale, opts, progress,
                                  lam_step, outcome, settings)
    if outcome[0] == "failed" and pts.w and pts.w[-1] < w_hi * (1 - 1e-9) and len(pts.w) < case.analysis.max_points:
        outcome = _top_down_past_stop(problem, case, pts, segments, window, xscale, r_scale, opts, progress,
                                      lam_step, outcome, settings)
    status, message, folds, n_rej = outcome
    if status == "finished" and pts.w and pts.w[-1] < w_hi * (1 - 1e-9):
        # the branch folded back out of the window at fmin (e.g. a softening upper branch):
        # the rest of the window lies on another branch, traced from fmax downwards
        first_msg = (f"the branch from {lo:.6g} Hz folded back to {pts.w[-1] / (2 * np.pi):.6g} Hz; "
                     f"traced the rest from {hi:.6g} Hz down")
        try:
            part, (st2, msg2, f2, r2), _, folded = _down_from_fmax(problem, case, window, xscale, r_scale, opts,
                                                                   progress, lam_step, offset=len(pts.w))
        except RuntimeError as exc:
            status, message = "failed", f"{first_msg}, but: {exc}"
        else:
            folds, n_rej = folds + f2, n_rej + r2
            if folded:
                st2 = "failed"
                msg2 = (f"the FRF between {part.w[-1] / (2 * np.pi):.6g} Hz and the first branch is not "
                        f"traced: the branch from {hi:.6g} Hz folded back too")
            status, message = st2, f"{first_msg}: {msg2}"
            segments.append([len(pts.w), len(pts.w) + len(part.w)])
            pts.extend(part, reverse=True)
    if len(pts.w) >= case.analysis.max_points and status not in ("finished", "failed"):
        status = "max_steps"
        message = f"stopped after max_points={case.analysis.max_points} points at {pts.w[-1] / (2 * np.pi):.6g} Hz"
    return pts, segments, (status, message, folds, n_rej), xscale


def _down_from_fmax(problem, case, window, xscale, r_scale, opts, progress, lam_step, offset=0, widen=False):
    """The branch through a first point at ``fmax`` (:func:`_start_at`), traced down (points
    highest frequency first); raises RuntimeError when that first point does not converge.

    Returns ``(part, outcome, xscale, folded)``: the points, ``(status, message, folds_hz,
    n_rejected)``, the scale (widened by the first point if ``widen``), and whether the
    branch left the window again at ``fmax`` (folded back) instead of reaching ``fmin``."""
    w_lo, w_hi = window
    Xh, ith = _start_at(problem, case, w_hi, xscale, r_scale)
    if widen:
        xscale = _widened_scale(problem, xscale, Xh)
    part = TracedPoints()
    outcome = _trace(problem, case, part, Xh, ith, w_hi, window, -1, xscale, r_scale, opts, progress,
                     offset=offset, lam_step=lam_step)
    folded = outcome[0] == "finished" and bool(part.w) and part.w[-1] > w_lo * (1 + 1e-9)
    return part, outcome, xscale, folded


def _from_the_top(problem, case, window, xscale, r_scale, opts, progress, lam_step, why):
    """:func:`trace_window` when ``fmin``'s first point did not converge (``why``): the window
    from ``fmax`` down, the points returned lowest frequency first."""
    hi = window[1] / (2 * np.pi)
    pts = TracedPoints()
    try:
        part, (status, message, folds, n_rej), xscale, folded = _down_from_fmax(
            problem, case, window, xscale, r_scale, opts, progress, lam_step, widen=True)
    except RuntimeError as exc:
        return pts, [], ("failed", f"{why}; from {hi:.6g} Hz neither: {exc}", [], 0), xscale
    pts.extend(part, reverse=True)
    if folded:
        status, message = "failed", f"the branch from {hi:.6g} Hz folded back out of the window at {hi:.6g} Hz"
    elif len(pts.w) >= case.analysis.max_points and status not in ("finished", "failed"):
        status = "max_steps"
        message = f"stopped after max_points={case.analysis.max_points} points at {pts.w[0] / (2 * np.pi):.6g} Hz"
    note = f"{why}; traced from {hi:.6g} Hz down instead"
    return pts, [[0, len(pts.w)]], (status, f"{note}: {message}", folds, n_rej), xscale
