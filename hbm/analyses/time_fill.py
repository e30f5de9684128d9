r"""Time-domain answers where the harmonic balance left the window untraced or is far off.

When the continuation stops short or restarts past a gap, the stretches of
:math:`[f_{min}, f_{max}]` that no traced segment covers have no HBM answer.  Where the
response there cannot be represented with the retained harmonics (a contact that sticks for
most of the period and slips in short bursts: the truncated displacement rings by more than
the contact's stick range :math:`2 F_s / k_t`, so the penalty law chatters and Newton stalls),
more continuation cannot help, but the time domain can: :func:`fill_untraced` finds the
periodic solutions at points spread over the untraced stretches, within a time budget, and
checks the traced points estimated more than ``UNRELIABLE`` off (up to a third of the points
when there are some; each check's record holds the HBM's first harmonics beside the time
domain's, and how far apart they are).  A condensed model is simulated on the model its
balance solves, the kept modes and residual flexibility (:mod:`hbm.timedomain.condensed_twin`).
The points are kept apart from the HBM path (``settings["time_fill"]``, ``frf_timedomain.csv``,
markers in ``frf.png``): they carry no harmonic coefficients.

Each point is found by shooting (:func:`hbm.timedomain.floquet_check.check_point`: Newton on
the period map, ``n`` and ``2 n`` steps per period for the error estimate), with its Floquet
verdict: a check from the traced point itself, else from the nearest solution another shot
found or the nearest traced point estimated within 5 %; a point of an untraced stretch from
the nearest solution known, a traced point or one its neighbours' shots found, walking into
the stretch from the traced path (a shot that fails is tried again after the walk from a
start that has become nearer, e.g. past a jump).  It converges in a few periods where a
lightly damped rig integrated from rest takes hundreds or thousands (the UPD flanks rig: not
periodic after 224 periods in 7.5 s; the undamped Jenkins oscillator at kt / k = 1e6: 5 of
12 points settled in 30 s from rest, 11 of 12 in 12.5 s by the walk), or settles on another
branch.  What no shot finds is integrated from rest after every shot
(:func:`hbm.timedomain.timesim.timesim`, Newmark with located switches and an ``n`` / ``2 n``
error estimate), for at most ``POINT_SHARE`` of the budget each (:mod:`hbm.analyses.time_points`).
A check found from another start than its own point (a neighbour's solution, or from rest)
that lands beyond the point's estimate may be on another branch: it is reported apart, not as
the HBM's error.

A stretch is ``[a, b]`` with ``a`` and ``b`` the ends of the traced spans around it (or the
window's ends); its points sit at the window's end when the stretch reaches it, else at
interior fractions ``k / (m + 1)``.  With budget left, up to ``REFINE_POINTS`` more are shot
one at a time between the two neighbouring answers (traced ends included) whose first
harmonics differ most, by over ``REFINE_CHANGE`` (5 %): a jump inside a stretch is located
instead of drawn across.  Stretches narrower than ``MIN_WIDTH`` of the window (a
corner of the path, e.g. a stuck slider's offset that jumps when it starts to slip) get none.
"""
from __future__ import annotations

import time

import numpy as np

from hbm.analyses.time_points import REFINE_CHANGE, FillRun

MIN_WIDTH = 1e-4        # stretches narrower than this share of the window get no point
BUDGET_SECONDS = 30.0   # time simulations stop being started after this
MAX_POINTS = 12         # simulations in all (stretches and checks) before the refinement
REFINE_POINTS = 24      # points added after them where neighbouring answers differ most
LARGE_ERROR = 0.1       # a traced point next to a stretch estimated this far off is named
UNRELIABLE = 0.2        # traced points estimated this far off are checked in the time domain
ROUND_OFF = 1e-12       # of fmax: a stretch this narrow is the round-off of a solved window end


def untraced_stretches(res) -> list:
    """``(a, b)`` (Hz) of the window that no traced segment of ``res`` covers: its gaps, the
    ends it did not reach, the hole a run leaves when it folds back and is traced from the top.

    Parameters
    ----------
    res : FRFResult

    Returns
    -------
    list of (float, float)
        Sorted, disjoint, inside ``[fmin_hz, fmax_hz]``.
    """
    s = res.settings
    lo, hi = float(s["fmin_hz"]), float(s["fmax_hz"])
    f = res.freq_hz
    spans = sorted((max(float(f[a:b].min()), lo), min(float(f[a:b].max()), hi))
                   for a, b in s.get("segments", [[0, f.size]]) if b > a)
    out, end = [], lo
    tiny = ROUND_OFF * hi            # a window end solved to round-off is reached
    for a, b in spans:
        if a > end + tiny:
            out.append((end, a))
        end = max(end, b)
    if hi > end + tiny:
        out.append((end, hi))
    return out


def fill_frequencies(stretches: list, window: tuple, max_points: int = MAX_POINTS) -> list:
    """Frequencies (Hz) to simulate in ``stretches``: shares of ``max_points`` in proportion to
    width (at least one each), at the window's end where a stretch reaches it, else inside.

    Parameters
    ----------
    stretches : list of (float, float)
    window : (float, float)
        ``(fmin, fmax)``, Hz.
    max_points : int

    Returns
    -------
    list of list of float
        One list per stretch (empty for a stretch narrower than ``MIN_WIDTH`` of the window).
    """
    lo, hi = window
    wide = [(a, b) for a, b in stretches if b - a > MIN_WIDTH * (hi - lo)]
    total = sum(b - a for a, b in wide)
    out = []
    for a, b in stretches:
        if (a, b) not in wide:
            out.append([])
            continue
        m = max(1, int(round(max_points * (b - a) / total)))
        if a <= lo:             # the window's start was not reached: simulate at it
            out.append([a + (b - a) * k / m for k in range(m)])
        elif b >= hi:
            out.append([b - (b - a) * k / m for k in range(m)][::-1])
        else:
            out.append([a + (b - a) * k / (m + 1) for k in range(1, m + 1)])
    return out


def _neighbour_errors(res, a: float, b: float) -> list:
    """Largest estimated first-harmonic error (over the outputs) of the traced points nearest
    to ``a`` and ``b``, for those above ``LARGE_ERROR``: ``[(freq_hz, error), ...]``."""
    worst = _worst_errors(res)
    if worst is None:
        return []
    out = []
    for f in {a, b}:
        i = int(np.argmin(np.abs(res.freq_hz - f)))
        if abs(res.freq_hz[i] - f) <= 1e-9 * max(abs(f), 1.0) and worst[i] > LARGE_ERROR:
            out.append((float(res.freq_hz[i]), float(worst[i])))
    return out


def spread_order(n: int) -> list:
    """Indices ``0 .. n-1`` in an order that covers the range early (bit-reversed), so that a
    budget that runs out leaves the simulated points spread out."""
    bits = max(1, (n - 1).bit_length())
    keys = [int(format(i, f"0{bits}b")[::-1], 2) for i in range(n)]
    return sorted(range(n), key=lambda i: keys[i])


def _worst_errors(res):
    """Largest estimated first-harmonic error over the outputs, per point (n_points,), or None."""
    errs = [o.err for o in res.outputs.values() if o.err is not None]
    return np.nan_to_num(np.array(errs), nan=0.0).max(axis=0) if errs and res.freq_hz.size else None


def check_points(res, k: int, worst=None) -> list:
    """Up to ``k`` path indices of points estimated more than ``UNRELIABLE`` off, spread over
    their frequencies (``worst``: :func:`_worst_errors` of ``res``, when at hand)."""
    worst = _worst_errors(res) if worst is None else worst
    if worst is None or k <= 0:
        return []
    idx = np.flatnonzero(worst > UNRELIABLE)
    idx = idx[np.argsort(res.freq_hz[idx], kind="stable")]
    if idx.size > k:
        idx = idx[np.unique(np.round(np.linspace(0, idx.size - 1, k)).astype(int))]
    return [int(i) for i in idx]


def wanted(res) -> bool:
    """Whether :func:`fill_untraced` has anything to do: a stop, a gap, or a point estimated
    more than ``UNRELIABLE`` off."""
    worst = _worst_errors(res)
    return (res.status != "finished" or bool(res.settings.get("gaps"))
            or (worst is not None and bool(np.nanmax(worst) > UNRELIABLE)))


def _condensed_problem(case, res):
    """The balance problem of a condensed FRF (the time model and the checks' shots come from
    it), None for the full solver (its checks need none)."""
    from hbm.analyses.problem_setup import build_problem, choose_solver
    if choose_solver(case) == "full":
        return None
    return build_problem(case, res.basis, res.settings["transform"], res.settings["fmax_hz"])[0]


def _time_model(case, res, problem=None):
    """What the time simulations step: ``case`` for the full solver; for the condensed one its
    kept modes and residual flexibility (:mod:`hbm.timedomain.condensed_twin`), the model its
    balance (``problem``, built here when None) solves; None (and
    ``settings["time_fill_note"]``) when it cannot be stepped."""
    from hbm.analyses.problem_setup import choose_solver, condensed_time_model
    from hbm.interface.case import CaseError
    if choose_solver(case) == "full":
        return case
    try:
        return condensed_time_model(case, res.basis, res.settings["transform"], res.settings["fmax_hz"],
                                    problem=problem)
    except CaseError as exc:
        res.settings["time_fill_note"] = (f"no time-domain points where the path stopped, left gaps or is far "
                                          f"off: {str(exc).split(': ', 1)[-1]}")
        return None


def fill_untraced(case, res, budget: float = BUDGET_SECONDS, max_points: int = MAX_POINTS,
                  progress=None, refine_points: int = REFINE_POINTS) -> dict | None:
    """Time-simulate the stretches of the window that ``res`` left untraced, and the traced
    points estimated more than ``UNRELIABLE`` off (module doc); record them in
    ``res.settings["time_fill"]``.

    Parameters
    ----------
    case : Case
    res : FRFResult
    budget : float
        No simulation is started once this many seconds have been spent.
    max_points : int
        Simulations in all before the refinement; a third of them go to the far-off points
        when there are some.
    progress : callable, optional
        ``progress(done, total)`` after each simulation.
    refine_points : int
        Points the refinement may add (module doc).

    Returns
    -------
    dict or None
        ``stretches`` (each ``a_hz``, ``b_hz``, ``neighbour_errors``), ``points`` (each
        ``freq_hz``, ``kind`` (``untraced`` / ``check``), ``ok``, per output ``h1`` and ``max``,
        ``error_estimate``, ``periods``, ``seconds``, ``message``; a check also ``hbm_h1``,
        ``hbm_estimate`` and ``hbm_off``, the HBM's largest relative deviation), ``skipped``
        (frequencies not simulated for the budget), ``checks`` (far-off points planned to be
        checked), ``refined`` (points added where
        neighbouring answers differ most, :meth:`FillRun.refine`), ``seconds``, ``budget``,
        ``note``; None when there is
        nothing to simulate or the model is not simulated here (a condensed model with a
        velocity-dependent law; ``settings["time_fill_note"]`` says so).
    """
    problem = _condensed_problem(case, res)
    model = _time_model(case, res, problem)
    if model is None:
        return None
    window = (float(res.settings["fmin_hz"]), float(res.settings["fmax_hz"]))
    stretches = untraced_stretches(res)
    worst = _worst_errors(res)
    n_checks = max_points // 3 if worst is not None and np.any(worst > UNRELIABLE) else 0
    freqs = fill_frequencies(stretches, window, max_points - n_checks)
    walk = [f for fs in freqs for f in fs]
    checks = check_points(res, max_points - len(walk), worst)
    if not walk and not checks:
        return None
    run = FillRun(case, res, problem, model, budget, progress, len(walk) + len(checks))
    lost = run.untraced(walk)
    run.from_rest(lost, run.checks([(checks[k], worst[checks[k]]) for k in spread_order(len(checks))]))
    refined = run.refine([s for s, fs in zip(stretches, freqs) if fs], refine_points)
    points, skipped = run.points, run.skipped
    points.sort(key=lambda p: p["freq_hz"])
    skipped.sort()
    record = {"stretches": [{"a_hz": a, "b_hz": b, "neighbour_errors": _neighbour_errors(res, a, b)}
                            for (a, b), fs in zip(stretches, freqs) if fs],
              "points": points, "skipped": skipped, "refined": refined, "checks": len(checks),
              "seconds": time.perf_counter() - run.t0, "budget": budget}
    record["note"] = fill_note(record, res.settings.get("harmonics", []))
    res.settings["time_fill"] = record
    return record


def _span(values) -> str:
    """``"a-b"`` (percent of the relative values), or ``"a"`` for one."""
    lo, hi = 100 * min(values), 100 * max(values)
    return f"{lo:.2g}" + ("" if len(values) == 1 else f"-{hi:.2g}")


def fill_note(record: dict, harmonics) -> str:
    """One line: what was simulated where, what the traced points next to it say, what the
    checks of far-off points found, what failed."""
    ok = [p for p in record["points"] if p["ok"]]
    parts = [f"{a['a_hz']:.6g}..{a['b_hz']:.6g} Hz" for a in record["stretches"]]
    checks = [p for p in record["points"] if p["kind"] == "check"]
    where = [f"untraced {', '.join(parts)}"] if parts else []
    n_checks = record.get("checks", len(checks))        # planned, simulated or not
    where += [f"{n_checks} traced point{'s' * (n_checks > 1)} estimated over {100 * UNRELIABLE:.0f} % "
              f"off"] if n_checks else []
    note = (f"{' and '.join(where)}: {len(ok)} of {len(record['points']) + len(record['skipped'])} "
            f"time-domain points ({record['seconds']:.1f} s) in frf_timedomain.csv")
    if ok:
        note += f", estimated error up to {max(p['error_estimate'] for p in ok):.1e}"
    walked = [p for p in ok if p["kind"] != "check" and p.get("method") == "shooting"]
    if walked:
        note += (f"; {len(walked)} of the untraced shot from the traced path or a periodic solution found "
                 f"next to them")
    if record.get("refined"):
        note += f" ({record['refined']} added where neighbouring answers differ by over {100 * REFINE_CHANGE:.0f} %)"
    shaky = [p for p in ok if p["kind"] != "check" and p.get("stable") is False]
    if shaky:
        at = ", ".join(f"{p['freq_hz']:.6g}" for p in shaky[:3])
        note += (f" ({len(shaky)} of them found by shooting and unstable by Floquet, at {at} Hz: periodic "
                 f"solutions a motion from rest leaves)")
    compared = [p for p in checks if p["ok"] and p["same_branch"]]
    if compared:
        own = sum(p["own_start"] for p in compared)
        unstable = sum(p.get("stable") is False for p in compared)
        note += (f"; there the HBM's first harmonic is off by {_span([p['hbm_off'] for p in compared])} % "
                 f"({own} shot from the traced point itself"
                 + (f", {len(compared) - own} found from another start within the point's estimate"
                    if own < len(compared) else "")
                 + (f", {unstable} of them unstable by Floquet" if unstable else "") + ")")
    apart = [p for p in checks if p["ok"] and not p["same_branch"]]
    if apart:
        note += (f"; {len(apart)} check{'s' * (len(apart) > 1)} found from another start (a neighbouring "
                 f"solution, or integrated from rest where no shot converged) lie "
                 f"{_span([p['hbm_off'] for p in apart])} % from the HBM's first harmonic, beyond the "
                 f"point's estimate: another branch, or the HBM farther off than estimated (not counted above)")
    bad = [p for p in record["points"] if not p["ok"]]
    if bad:
        note += f"; at {bad[0]['freq_hz']:.6g} Hz {bad[0]['message']}"
    if record["skipped"]:
        note += f"; {len(record['skipped'])} not simulated (budget {record['budget']:g} s)"
    near = [e for s in record["stretches"] for e in s["neighbour_errors"]]
    if near:
        f, e = max(near, key=lambda t: t[1])
        H = max(harmonics) if len(harmonics) else "?"
        note += (f". The traced point at {f:.6g} Hz next to it is estimated {100 * e:.0f} % off: the response "
                 f"there is beyond H = {H} harmonics, and the continuation stalls where it cannot be represented "
                 f"(e.g. a stiff contact that sticks for most of the period: its truncated motion rings by more "
                 f"than its stick range)")
    return note
