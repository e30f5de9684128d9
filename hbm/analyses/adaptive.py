r"""Harmonics chosen for a tolerance: ``hbm frf --tol``.

The FRF is traced at the case's harmonics and every point's truncation error estimated
(:mod:`hbm.analyses.truncation`).  When more than ``WHOLE_SHARE`` of the points exceed ``tol``
the path itself needs more harmonics: it is traced again on the next set
(:math:`H \to \lceil 1.5 H \rceil`, an odd-only pattern kept odd).  Once most points are within
``tol``, each point still above it is solved again, alone, on richer harmonics until within
(:mod:`hbm.analyses.point_harmonics`), so only the stretches that need harmonics pay for them.
Even harmonics that carry nothing at any traced point (a symmetric response) are left out of
the richer sets (:func:`carried_harmonics`): they follow the odd pattern, at half the unknowns.
``settings["adaptive"]`` lists every trace (its harmonics, largest estimate, share of points
above ``tol``, time) and the points refined per harmonic level.

Raising stops at a budget: the first trace's time plus the larger of ``ADAPT_SECONDS`` and
``ADAPT_SHARE`` times it.  No further trace is started when the time so far and its predicted
time (:func:`hbm.analyses.harmonics_retry.predicted_seconds`) exceed it, and no further
refinement level or point once it is spent; ``settings["adaptive"]["budget_note"]`` says
where.  An output whose estimate does not fall with H (a stiff stuck contact's needle
response, far above any affordable harmonics) once made the default ``hbm frf`` climb to
H = 53 and refine to 63 for over 20 minutes on a two-DOF case.
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

H_MAX = 63
ADAPT_SECONDS = 120.0  # raising harmonics may add this much time to the first trace's ...
ADAPT_SHARE = 1.0      # ... or this share of the first trace's time, whichever is more
DEFAULT_TOL = 1e-2    # ``hbm frf`` without --harmonics or --tol: points estimated worse are refined
WHOLE_SHARE = 0.5     # above this share of points over tol, the whole path is traced again


def next_harmonics(h) -> list:
    """The next, richer harmonic list after ``h`` (sorted ints): ``ceil(1.5 H)``, same pattern."""
    h = [int(x) for x in h]
    top = max(h)
    pos = [x for x in h if x > 0]
    odd = len(pos) > 1 and all(x % 2 == 1 for x in pos)
    new = max(top + (2 if odd else 1), math.ceil(1.5 * top))
    if odd and new % 2 == 0:
        new += 1
    step = 2 if odd else 1
    return sorted(set(h) | set(range(top + step, new + 1, step)))


def carried_harmonics(res, rel: float = 1e-10) -> list:
    """The harmonics of ``res`` without its even ones (not the mean) when they carry nothing at
    any point (every coefficient at most ``rel`` times the largest: a symmetric response), so
    richer sets follow the odd pattern at half the unknowns; else all of them."""
    h = [int(x) for x in res.basis.harmonics]
    even = [x for x in h if x > 0 and x % 2 == 0]
    if not even or res.X.size == 0:
        return h
    rows = np.isin(res.basis.h_of_row, even)
    top = float(np.abs(res.X).max())
    return [x for x in h if x not in even] if float(np.abs(res.X[:, rows]).max()) <= rel * top else h


def _worst(res) -> float:
    errs = [np.nanmax(o.err) for o in res.outputs.values() if o.err is not None and np.isfinite(o.err).any()]
    return float(max(errs)) if errs else math.inf


def frf_to_tolerance(case, tol: float, harmonics=None, **kwargs):
    """:func:`hbm.analyses.response.frf` with harmonics raised, for the path and then point by
    point, until every point's estimated error of the first harmonics is within ``tol``
    (module doc); returns the FRF."""
    from hbm.analyses.harmonics_retry import predicted_seconds
    from hbm.analyses.point_harmonics import over_tolerance, refine_points
    from hbm.analyses.problem_setup import resolve_settings
    from hbm.analyses.response import frf
    if not (tol > 0 and math.isfinite(tol)):
        raise ValueError(f"tol must be a positive number, got {tol!r}")
    h, _, lo, hi, _ = resolve_settings(case, harmonics, kwargs.get("samples"), kwargs.get("fmin"),
                                       kwargs.get("fmax"), kwargs.get("transform"))
    # the first trace takes the harmonics as given (None: the case's, with the case's samples),
    # the next ones their richer lists
    h, given, tried, t0, budget_note, deadline = list(h), harmonics, [], time.perf_counter(), None, None
    while True:
        t1 = time.perf_counter()
        res = frf(case, harmonics=given, error_estimate=True, **kwargs)
        h = [int(x) for x in res.basis.harmonics]      # richer than asked after a stop (harmonics_retry)
        share = float(np.mean(over_tolerance(res, tol))) if res.freq_hz.size else 0.0
        tried.append({"H": int(max(h)), "max_error": _worst(res), "share_above": round(share, 4),
                      "seconds": round(time.perf_counter() - t1, 4), "status": res.status})
        if deadline is None:
            first = tried[0]["seconds"]
            deadline = t0 + first + max(ADAPT_SECONDS, ADAPT_SHARE * first)
        if share <= WHOLE_SHARE or max(h) >= H_MAX or not res.ok or not math.isfinite(tried[-1]["max_error"]):
            break
        nxt = next_harmonics(carried_harmonics(res))
        ahead = time.perf_counter() + predicted_seconds(tried[-1]["seconds"], h, nxt)
        if ahead > deadline:
            budget_note = (f"the path was not traced again at H = {max(nxt)}: with the time so far that "
                           f"would take about {ahead - t0:.0f} s, past the budget of {deadline - t0:.0f} s")
            break
        h = given = nxt
    start = carried_harmonics(res)
    dropped = [int(x) for x in res.basis.harmonics if x not in start]
    res, refined = refine_points(case, res, tol, (lo, hi), kwargs.get("transform") or "auto",
                                 kwargs.get("stability_options"), start, kwargs.get("progress"),
                                 deadline=deadline)
    if refined.get("stopped_hz") is not None:
        budget_note = "; ".join(filter(None, [budget_note, (
            f"refinement stopped at the budget of {deadline - t0:.0f} s at H = {refined['stopped_hz'][1]} "
            f"({refined['left_above']} points left above tol)")]))
    res = _confirmed(case, res, base_harmonics=int(max(h)))
    worst = _worst(res)
    checked = math.isfinite(worst)      # False: no point's error could be estimated (too large)
    res.settings["adaptive"] = {"tol": tol, "tried": tried, "points": refined, "checked": checked,
                                "dropped": dropped,
                                "max_error": worst if checked else None, "met": bool(checked and worst <= tol),
                                "seconds": round(time.perf_counter() - t0, 4), "budget_note": budget_note}
    _restate_errors(res)
    return dataclasses.replace(res, solve_seconds=res.settings["adaptive"]["seconds"])


def _confirmed(case, res, base_harmonics: int):
    """``res`` with the refined points Hill calls unstable checked by Floquet multipliers, as
    the FRF checks its own (:func:`hbm.timedomain.floquet_check.confirm_unstable`; full models)."""
    from hbm.analyses.problem_setup import choose_solver
    from hbm.timedomain.floquet_check import confirm_unstable
    if res.stable is None or res.point_harmonics is None or choose_solver(case) != "full":
        return res
    refined = res.point_harmonics > base_harmonics
    st = {}
    checked = confirm_unstable(case, res.basis, res.X, res.freq_hz, res.stable | ~refined, st)
    turned = st.get("floquet_overrides_hz", [])
    if turned:
        res.settings["floquet_overrides_hz"] = sorted(res.settings.get("floquet_overrides_hz", []) + turned)
    res.settings["floquet_checked"] = res.settings.get("floquet_checked", 0) + st.get("floquet_checked", 0)
    stable = np.where(refined, checked, res.stable)
    lost = [round(float(f), 6) for f in res.freq_hz[res.stable & ~stable]]       # islands turned
    if lost:
        res.settings["floquet_unstable_hz"] = sorted(res.settings.get("floquet_unstable_hz", []) + lost)
    return dataclasses.replace(res, stable=stable)


def _restate_errors(res) -> None:
    """``settings["error_estimate"]["max"]`` and the truncation warning after refinement."""
    from hbm.analyses.truncation import largest_errors, truncation_warning
    est = res.settings.get("error_estimate") or {}
    if "max" not in est or res.point_harmonics is None:
        return
    est["max"] = largest_errors(res.outputs, res.freq_hz)
    warning = truncation_warning(est["max"], f"points refined up to H = {int(res.point_harmonics.max())}")
    if warning:
        res.settings["truncation_warning"] = warning
    else:
        res.settings.pop("truncation_warning", None)
