r"""A run that stops where its harmonics are inadequate is traced again on richer ones.

The continuation can stop (or leave a gap) because the harmonic-balance path itself is not
smooth there: with too few harmonics for a stick-slip or contact-opening motion, the
solutions at neighbouring frequencies may differ by tens of percent (a 3-DOF chain of two
stiff Jenkins contacts at H = 5: 20-75 % between neighbours, estimated errors of 50-100 %
next to its stops; on odd harmonics up to 9 the same window is traced without a stop; a
separating point contact at H = 5 folds where the estimate is 89 %, and at H = 12 the fold
is traced).  A stop is blamed on
the harmonics when the truncation error estimate (:mod:`hbm.analyses.truncation`) at the
points that bound it, the last point before a stop and the first after it,

.. math::

    e_{stop} = \max_{p \in \text{bounds},\ o} \hat\varepsilon_o(p) > \text{ERR\_STOP}

(an estimate that could not be made counts as too large).  Then :func:`retry_with_harmonics`
traces the window again on the next richer set (:func:`hbm.analyses.adaptive.next_harmonics`,
``H -> ceil(1.5 H)``, odd only for a half-wave symmetric response), and again on the next
while the new run still stops where its estimate blames the harmonics, up to ``RUNGS`` sets;
the run that covers most of the window is kept, by the rule of the events retry
(:func:`hbm.analyses.aft_retry.better_run`).  ``settings["harmonics_retry"]`` says what was
tried and kept; every point's harmonics are those of the run kept.  Each rung is a whole
:func:`hbm.analyses.response.frf` trace (with its events retry); none starts once the runs so
far with its predicted time (the last run's, scaled by the cube of the unknowns' ratio) would
take more than ``RETRY_SECONDS`` of tracing (:func:`hbm.analyses.aft_retry.trace_seconds`:
the stability pass is not counted, so runs with and without it retry alike), and a stop that richer harmonics do not remove (a fold
whose branches the continuation cannot join at any of the sets tried) stays stated.
Harmonics given as an argument (``--harmonics``, or by :func:`hbm.analyses.adaptive` for its
richer traces) are kept as asked; the run's ``harmonics_hint`` then names the next set.
"""
from __future__ import annotations

import math
import time

import numpy as np

from hbm.analyses.aft_retry import RETRY_SECONDS, better_run, trace_seconds, untraced_hz
from hbm.balance.fourier import default_samples, min_samples

ERR_STOP = 0.1          # estimated error at a stop's bounding points above which H is blamed
RUNGS = 2               # richer harmonic sets tried at most


def stop_points(res) -> np.ndarray:
    """Indices of the points that bound a stop of ``res``: the ends of its traced segments
    that are not at the window's ends (int array, sorted)."""
    s = res.settings
    lo, hi = float(s["fmin_hz"]), float(s["fmax_hz"])
    f = res.freq_hz
    ends = {i for a, b in s.get("segments", [[0, f.size]]) if b > a for i in (a, b - 1)}
    inside = [i for i in sorted(ends) if not (math.isclose(f[i], lo, rel_tol=1e-9)
                                             or math.isclose(f[i], hi, rel_tol=1e-9))]
    return np.array(inside, dtype=int)


def stop_error(res) -> float:
    """Largest estimated error of the outputs' first harmonics at the points bounding a stop
    (:func:`stop_points`); ``inf`` where an estimate could not be made, ``nan`` when the run
    carries no estimates or has no such point."""
    idx = stop_points(res)
    errs = [o.err for o in res.outputs.values() if o.err is not None]
    if idx.size == 0 or not errs:
        return math.nan
    return float(max(np.nan_to_num(e[idx], nan=math.inf).max() for e in errs))


def _samples_for(samples, h, factor: int):
    """The samples to retry with: the given ones if they suffice for ``h``, else the default."""
    if samples is None or int(samples) >= min_samples(h):
        return samples
    return max(int(samples), default_samples(h, factor))


def predicted_seconds(seconds: float, h_old, h_new) -> float:
    """A run's time on ``h_new`` from ``seconds`` on ``h_old``: scaled by the cube of the ratio
    of their coefficient counts (the dense linear algebra of a large model; small models grow
    more slowly, so this errs on the safe side)."""
    n = [2 * int(np.count_nonzero(np.asarray(h) > 0)) + int(np.count_nonzero(np.asarray(h) == 0))
         for h in (h_old, h_new)]
    return float(seconds) * (n[1] / n[0]) ** 3


def _as_argument(h) -> str:
    """``h`` as ``--harmonics`` takes it: ``H`` for 1..H, else the comma list (the mean is
    added by the elements that need it)."""
    pos = [int(x) for x in h if x > 0]
    return str(max(pos)) if pos == list(range(1, max(pos) + 1)) else ",".join(map(str, pos))


def _stopped(res) -> bool:
    """The run stopped short of the window or left gaps in it."""
    return res.status != "finished" or bool(res.settings.get("gaps"))


def _blames_harmonics(res) -> bool:
    """``res`` stopped where its harmonics are inadequate (module doc), and may be repeated."""
    from hbm.analyses.adaptive import H_MAX
    return (_stopped(res) and trace_seconds(res) <= RETRY_SECONDS and int(max(res.basis.harmonics)) < H_MAX
            and stop_error(res) > ERR_STOP)


def retry_with_harmonics(case, res, trace, samples=None, given=None):
    """``res``, or a run of ``trace(harmonics, samples)`` on richer harmonics when ``res`` stopped
    where its harmonics are inadequate and that run covers more of the window (module doc).

    Up to ``RUNGS`` richer sets are tried, each the next after the last run's, while the last
    run still stops where its estimate blames the harmonics and the runs so far (the first's
    trace time and each rung's, its events retry included) with the next one's
    predicted time (:func:`predicted_seconds`) stay within ``RETRY_SECONDS``.  When even the
    first rung would not, ``settings["harmonics_hint"]`` names it with its predicted time.

    Parameters
    ----------
    case : Case
        The case (its elements' samples factor sets N where the given samples are too few).
    res : FRFResult
        The run on the asked harmonics (after its events retry).
    trace : callable
        ``trace(harmonics, samples) -> FRFResult`` with every other setting as ``res``.
    samples : int, optional
        The samples asked for (None: the case's or the default).
    given : int or list of int, optional
        Harmonics given as an argument (``--harmonics``): kept as asked; where the estimate
        blames them, ``settings["harmonics_hint"]`` names the next set instead.
    """
    from hbm.analyses.adaptive import carried_harmonics, next_harmonics
    if not _blames_harmonics(res):
        return res
    h = next_harmonics(carried_harmonics(res))
    guess = predicted_seconds(trace_seconds(res), res.basis.harmonics, h)
    if given is not None or trace_seconds(res) + guess > RETRY_SECONDS:
        why = ("with H left to the case, hbm frf tries them itself" if given is not None else
               f"not tried: about {guess:.0f} s predicted")
        res.settings["harmonics_hint"] = (
            f"the path stopped where the estimated error of the first harmonics is {stop_error(res):.2g}: richer "
            f"harmonics may pass it (--harmonics {_as_argument(h)}; {why})")
        return res
    best, last, runs, spent = res, res, [], trace_seconds(res)
    while True:                     # h: the next set, its time within the budget (checked above)
        err = stop_error(last)
        t0 = time.perf_counter()
        last = trace(h, _samples_for(samples, h, case.analysis.samples_factor))
        secs = time.perf_counter() - t0
        work = trace_seconds(last) + last.settings.get("aft_retry", {}).get("other_run_seconds", 0.0)
        spent += work
        runs.append({"H": int(max(h)), "harmonics": h, "after_stop_error": err, "status": last.status,
                     "untraced_hz": untraced_hz(last), "gaps": len(last.settings.get("gaps", ())),
                     "seconds": secs})
        if better_run(best, last):
            best = last
        if len(runs) == RUNGS or not _blames_harmonics(last):
            break
        h_last, h = h, next_harmonics(carried_harmonics(last))
        if spent + predicted_seconds(work, h_last, h) > RETRY_SECONDS:
            break
    H0, Hk = int(max(res.basis.harmonics)), int(max(best.basis.harmonics))
    why = "stopped" if res.status != "finished" else "left gaps"
    tried = "; ".join(f"H = {r['H']}: {r['gaps']} gap(s), {r['untraced_hz']:.3g} Hz untraced"
                      + ("" if r["status"] == "finished" else f", {r['status']}") for r in runs)
    first = f"{len(res.settings.get('gaps', ()))} gap(s), {untraced_hz(res):.3g} Hz untraced"
    best.settings["harmonics_retry"] = {
        "harmonics_asked": [int(x) for x in res.basis.harmonics], "untraced_hz_asked": untraced_hz(res),
        "runs": runs, "kept_H": Hk,
        "note": (f"at H = {H0} the path {why} ({first}) where the estimated error of the first harmonics "
                 f"is {runs[0]['after_stop_error']:.2g}; traced again ({tried}): the run at H = {Hk} is kept"),
    }
    if best is not res:
        best.settings["harmonics_source"] = "retry"
    return best
