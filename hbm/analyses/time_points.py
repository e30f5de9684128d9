r"""One time-domain point of the time fill (:mod:`hbm.analyses.time_fill`): a periodic solution
by shooting, or a steady state integrated from rest.

Shooting solves :math:`y_0 = \Phi_T(y_0)` for the state at the start of a period by Newton
on the period map :math:`\Phi_T` of the time integrator
(:func:`hbm.timedomain.floquet_check.check_point`), at ``n`` and ``2 n`` steps per period;
the relative difference of their first harmonics and peaks is the point's error estimate, the
monodromy matrix's multipliers its Floquet verdict.  :class:`FillRun` runs a fill's points
within its budget: the points of an untraced stretch walk into it from the traced path, each
shot from the nearest solution known (a traced point, or what a neighbour's shot found); the
checks of far-off traced points shoot from the points themselves, else from a solution found
nearby or a traced point estimated within ``REFINE_CHANGE``.  What no shot finds is
integrated from rest (:func:`hbm.timedomain.timesim.timesim`) after every shot, for at most
``POINT_SHARE`` of the budget each.  A check is read as the HBM's error when it is on the
traced branch: shot from its own point, or found elsewhere within the point's estimate
(:func:`compare`).  Then, with budget left, :meth:`FillRun.refine` adds points where
neighbouring answers of a stretch differ by more than ``REFINE_CHANGE``.
"""
from __future__ import annotations

import time

import numpy as np

POINT_SHARE = 0.25      # a point that has not settled after this share of the budget is abandoned
REFINE_CHANGE = 0.05    # neighbouring answers of a stretch whose first harmonics differ more get a point between
REFINE_WIDTH = 1e-3     # ... unless they are closer than this share of their stretch


class _OutOfTime(Exception):
    """Raised from a time simulation's progress callback past its deadline."""


def simulate(case, f: float, seconds: float, why: str) -> dict:
    """One steady-state time simulation at ``f`` Hz as a JSON-friendly record, abandoned
    (``ok`` False) after about ``seconds`` (``why``: what limited them)."""
    from hbm.interface.case import CaseError
    from hbm.timedomain.timesim import timesim
    t0 = time.perf_counter()

    def watch(periods, change):
        if time.perf_counter() - t0 > seconds:
            raise _OutOfTime(f"not periodic after {periods} periods in {seconds:.1f} s ({why})")
    try:
        r = timesim(case, f, progress=watch)
    except (RuntimeError, CaseError, _OutOfTime) as exc:      # a failed or refused integration
        return {"freq_hz": f, "ok": False, "message": str(exc), "seconds": time.perf_counter() - t0}
    rec = {"freq_hz": f, "ok": bool(r.converged), "h1": dict(r.h1), "max": dict(r.max),
           "error_estimate": float(r.error_estimate), "periods": int(r.periods),
           "seconds": time.perf_counter() - t0,
           "method": "rest",
           "message": (f"integrated from rest: periodic after {r.periods} periods" if r.converged
                       else f"not periodic to tolerance after {r.periods} periods")}
    if r.converged and r.shot_unstable is not None:       # a periodic solution, not a settled motion
        rec.update(stable=False, largest_multiplier=r.shot_unstable,
                   message=f"found by shooting, unstable by Floquet (largest |multiplier| {r.shot_unstable:.4g}): "
                           f"a motion from rest leaves it")
    return rec


def shoot_point(case, basis, X, f: float, problem, start: str):
    """A periodic solution at ``f`` Hz found by shooting from the balance coefficients ``X``
    (n_coef, n) (module doc), as a record like :func:`simulate`'s with ``method``, ``stable``
    and ``largest_multiplier``, and the solution's own coefficients (None for a condensed
    model); ``(None, None)`` when shooting cannot be used (a velocity law) or does not
    converge at two step counts in a row of ``n``, ``2 n``, ``4 n`` (``n`` the time
    integrator's default, at least ``FINE_STEPS`` with stiff contacts: a non-smooth period map
    that stalls Newton at 1024 steps may not at 2048).  ``start`` names where ``X`` comes from; ``problem``: the condensed balance
    (None for a full model)."""
    from hbm.model.contact_stiffness import stiff_contacts
    from hbm.timedomain.floquet_check import FINE_STEPS, check_point
    from hbm.timedomain.time_results import TimeSimOptions
    t0, n = time.perf_counter(), TimeSimOptions().steps
    if stiff_contacts(case):        # as the Floquet checks: at 512 steps Newton stalls on the
        n = max(n, FINE_STEPS)      # separating point contact kn = 1000 (4.5e-5), at 1024 it converges
    runs = []
    for steps in (n, 2 * n, 4 * n):     # the first two converged levels in a row
        try:
            c = check_point(case, basis, X, f, steps=steps, problem=problem)
        except ValueError:
            return None, None
        runs = runs + [c] if c.converged else []
        if len(runs) == 2 or (steps == 2 * n and not runs):
            break
    if len(runs) < 2:
        return None, None
    coarse, fine = runs
    est = max(abs(a[k] - b[k]) / abs(b[k]) for a, b in ((coarse.h1, fine.h1), (coarse.max, fine.max))
              for k in b if b[k] != 0.0)
    return ({"freq_hz": f, "ok": True, "h1": fine.h1, "max": fine.max, "error_estimate": float(est),
             "periods": coarse.periods + fine.periods, "seconds": time.perf_counter() - t0,
             "message": (f"shot from {start}; Floquet: {'stable' if fine.stable else 'unstable'} "
                         f"(largest |multiplier| {fine.largest:.4g})"),
             "method": "shooting", "stable": bool(fine.stable), "largest_multiplier": float(fine.largest)},
            fine.X)


def compare(p: dict, res, i: int, estimate: float, own_start: bool) -> dict:
    """A time-domain point at path point ``i`` (estimated ``estimate`` off), with the HBM's
    first harmonics beside it.  ``same_branch``: shot from the traced point itself (Newton
    stays by the orbit it starts from), or found from another start (a neighbouring
    solution, or from rest) within the point's own estimate; a solution found elsewhere and
    further off may be another branch, so it is not read as the HBM's error."""
    hbm = {n: float(o.h1[i]) for n, o in res.outputs.items()}
    p = {**p, "kind": "check", "hbm_h1": hbm, "hbm_estimate": float(estimate), "own_start": bool(own_start)}
    if p["ok"]:
        p["hbm_off"] = max((abs(hbm[n] / p["h1"][n] - 1.0) for n in hbm if p["h1"][n] != 0.0),
                           default=float("nan"))
        p["same_branch"] = bool(own_start or p["hbm_off"] <= estimate)
    return p


def distance(res, f: float) -> float:
    """Distance (Hz) from ``f`` to the nearest traced point of ``res`` (inf without any)."""
    return float(np.min(np.abs(res.freq_hz - f))) if res.freq_hz.size else np.inf


class FillRun:
    """The simulations of one fill within its budget: ``points`` and ``skipped`` (Hz) so far,
    and the periodic solutions its shots found (Hz -> coefficients), which later shots in the
    untraced stretches start from when they are nearer than the traced path (a walk into the
    stretch: a shot from a far start may not converge, e.g. 0.0796 Hz from 0.1265 Hz on the
    undamped Jenkins oscillator at kt / k = 1e6)."""

    def __init__(self, case, res, problem, model, budget, progress, total):
        self.case, self.res, self.problem, self.model = case, res, problem, model
        self.budget, self.progress, self.total = budget, progress, total
        self.t0, self.points, self.skipped, self.known = time.perf_counter(), [], [], {}

    def _left(self) -> float:
        return self.budget - (time.perf_counter() - self.t0)

    def _start(self, f: float):
        """``(X, description)`` of the nearest known solution to ``f``: a traced point or a
        converged shot; ``(None, "")`` when there is neither."""
        d_path = distance(self.res, f)
        g = self._nearest_known(f)
        if g is not None and abs(g - f) < d_path:
            return self.known[g], f"the periodic solution at {g:.6g} Hz"
        if not np.isfinite(d_path):
            return None, ""
        i = int(np.argmin(np.abs(self.res.freq_hz - f)))
        return self.res.X[i], f"the traced point at {self.res.freq_hz[i]:.6g} Hz"

    def untraced(self, freqs: list) -> list:
        """The points ``freqs`` (Hz) of the untraced stretches, nearest the traced path first:
        each shot from the nearest known solution; one whose shot fails is shot again after
        the others from a start that is now nearer (a solution found beyond it: the walk
        passes a jump).  Returns those that no shot found (for :meth:`from_rest`)."""
        deferred, failed = [], []
        for f in sorted(freqs, key=lambda f: distance(self.res, f)):
            if self._left() <= 0:
                self.skipped.append(f)
                continue
            X, start = self._start(f)
            if not self._shot(f, X, start):
                deferred.append((f, start))
        for f, tried in deferred:
            if self._left() <= 0:
                self.skipped.append(f)
                continue
            X, start = self._start(f)
            if start == tried or not self._shot(f, X, start):
                failed.append(f)
        return failed

    def _shot(self, f: float, X, start: str) -> bool:
        """Shoot at ``f`` from ``X`` (nothing without one); a converged shot is kept as a
        point and as a start.  Returns whether it converged."""
        shot, X_shot = (None, None) if X is None else shoot_point(self.case, self.res.basis, X, f, self.problem, start)
        if shot is None:
            return False
        if X_shot is not None:
            self.known[f] = X_shot
        self._add(f, shot)
        return True

    def refine(self, stretches: list, most: int) -> int:
        """Up to ``most`` more points in the untraced ``stretches`` ((a, b) Hz each), one at a
        time at the middle of the two neighbouring answers (a traced end or a converged point)
        whose first harmonics differ most, by more than ``REFINE_CHANGE`` (a traced end only
        if estimated within that); each shot from the nearest known solution, none integrated
        from rest.  Stops while a point's share of the budget is left.  Returns the points
        added."""
        added, failed = 0, set()
        while added < most and self._left() > POINT_SHARE * self.budget:
            pair = self._largest_change(stretches, failed)
            if pair is None:
                break
            f = 0.5 * (pair[0] + pair[1])
            self.total = max(self.total, len(self.points) + 1)
            X, start = self._start(f)
            if X is not None and self._shot(f, X, start):
                added += 1
            else:
                failed.add(pair)
        return added

    def _largest_change(self, stretches, failed):
        """``(f_a, f_b)``: the neighbouring answers of a stretch, not in ``failed``, whose first
        harmonics differ most (relative, largest over the outputs), if by more than
        ``REFINE_CHANGE``; None otherwise."""
        res, best, pair = self.res, REFINE_CHANGE, None
        for a, b in stretches:
            nodes = [(p["freq_hz"], p["h1"]) for p in self.points
                     if p["ok"] and p["kind"] == "untraced" and a <= p["freq_hz"] <= b]
            for end in (a, b):          # a traced end, unless estimated too far off to compare
                i = int(np.argmin(np.abs(res.freq_hz - end))) if res.freq_hz.size else -1
                if i >= 0 and distance(res, end) <= 1e-9 * end and self._reliable(i):
                    nodes.append((end, {n: float(o.h1[i]) for n, o in res.outputs.items()}))
            nodes.sort(key=lambda t: t[0])
            for (fa, ha), (fb, hb) in zip(nodes[:-1], nodes[1:]):
                if fb - fa <= REFINE_WIDTH * (b - a) or (fa, fb) in failed:
                    continue
                change = max((abs(ha[n] - hb[n]) / max(abs(ha[n]), abs(hb[n]), 1e-300) for n in ha), default=0.0)
                if change > best:
                    best, pair = change, (fa, fb)
        return pair

    def _nearest_known(self, f: float):
        """Frequency (Hz) of the solution the shots found nearest to ``f``, or None."""
        return min(self.known, key=lambda g: abs(g - f), default=None)

    def _to_known(self, f: float) -> float:
        """Distance (Hz) from ``f`` to the nearest solution the shots found (0 without any)."""
        g = self._nearest_known(f)
        return 0.0 if g is None else abs(g - f)

    def _nearest_reliable(self, f: float):
        """Index of the traced point nearest to ``f`` that is estimated within
        ``REFINE_CHANGE`` (a start closer to the true orbit than a far-off point), or None."""
        order = np.argsort(np.abs(self.res.freq_hz - f), kind="stable")
        return next((int(j) for j in order[:200] if self._reliable(int(j))), None)

    def _reliable(self, i: int) -> bool:
        """Traced point ``i`` is estimated within ``REFINE_CHANGE`` (or carries no estimate)."""
        errs = [o.err[i] for o in self.res.outputs.values() if getattr(o, "err", None) is not None]
        return not errs or bool(np.nan_to_num(max(errs), nan=np.inf) <= REFINE_CHANGE)

    def checks(self, items: list) -> list:
        """The checks of path points ``items`` ((i, estimate) each, in the order given): each
        shot from its traced point; those whose shots fail are shot again after the others,
        nearest first, from the nearest periodic solution found (a neighbouring check's or a
        stretch point's: a traced point estimated far off may be too far for Newton to start
        from), then from the nearest traced point estimated within ``REFINE_CHANGE``.  Returns
        the items that no shot found (for :meth:`from_rest`)."""
        deferred, failed = [], []
        for i, estimate in items:
            f = float(self.res.freq_hz[i])
            if self._left() <= 0:
                self.skipped.append(f)
                continue
            shot, X_shot = shoot_point(self.case, self.res.basis, self.res.X[i], f, self.problem, "the traced point")
            if shot is None:
                deferred.append((i, estimate))
                continue
            if X_shot is not None:
                self.known[f] = X_shot
            self._add(f, shot, i, estimate, own_start=True)
        while deferred:             # a walk: the one nearest a solution found first
            k = min(range(len(deferred)), key=lambda m: self._to_known(float(self.res.freq_hz[deferred[m][0]])))
            i, estimate = deferred.pop(k)
            f = float(self.res.freq_hz[i])
            if self._left() <= 0:
                self.skipped.append(f)
                continue
            g = self._nearest_known(f)
            shot, X_shot = (None, None) if g is None else shoot_point(
                self.case, self.res.basis, self.known[g], f, self.problem, f"the periodic solution at {g:.6g} Hz")
            j = self._nearest_reliable(f) if shot is None else None
            if j is not None:
                shot, X_shot = shoot_point(self.case, self.res.basis, self.res.X[j], f, self.problem,
                                           f"the traced point at {self.res.freq_hz[j]:.6g} Hz")
            if shot is None:
                failed.append((i, estimate))
                continue
            if X_shot is not None:
                self.known[f] = X_shot
            self._add(f, shot, i, estimate)
        return failed

    def from_rest(self, freqs: list, items: list) -> None:
        """Integrate from rest what no shot found, after every shot (each may take a quarter
        of the budget): the untraced points ``freqs`` (Hz) first (an answer where there is
        none), then the checks ``items`` ((i, estimate) each), which may settle on another
        branch than the traced one (``method`` "rest": reported apart)."""
        for f in freqs:
            self._add(f, None)
        for i, estimate in items:
            self._add(float(self.res.freq_hz[i]), None, i, estimate)

    def _add(self, f, shot, i=None, estimate=None, own_start=False) -> None:
        left = self._left()                  # a shot that did not converge took its time
        share = POINT_SHARE * self.budget
        why = "a point's share of the budget" if share < left else "the budget ran out"
        if shot is None and left <= 0:
            self.skipped.append(f)
            return
        p = {"kind": "untraced", **(shot or simulate(self.model, f, min(left, share), why))}
        self.points.append(p if i is None else compare(p, self.res, i, estimate, own_start and shot is not None))
        if self.progress is not None:
            self.progress(len(self.points), self.total)
