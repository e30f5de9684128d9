"""A run that stops short with stiff sampled contacts is traced again on their exact AFT.

A sampled AFT puts a contact's switches on the time grid: for a stiff contact (``kt`` at least
``STIFF_CONTACT`` times the structure's stiffness along its first coordinate,
:mod:`hbm.model.contact_stiffness`) that is an error Newton cannot average out, and the path
may stall there.  The elements that offer an event-based AFT (``events_available``: Jenkins,
friction3d on (t1, n)) compute the same law exactly from its events.  So when an FRF with such
contacts stops or leaves gaps, :func:`retry_with_events` traces the window again with
``aft = "events"`` on them and keeps the run that covers more of it: a finished run before a
stopped one, then the untraced width (gaps, the window's ends a stopped run did not reach, a
hole between a folded-back start and a trace from the top) if it is at most ``SHARE`` of the
first run's, or no more than it with fewer gaps (a gap whose frequencies another part of the
path covers leaves nothing untraced, yet it is a stop); else the first run.
``settings["aft_retry"]`` says what was tried, what each run left untraced and which was
kept.  A first run whose trace took longer than ``RETRY_SECONDS`` is not repeated (it would
double a long run, e.g. the railcar rig's 150 s for 0.005 Hz more): its ``contact_hint`` says
what to try.  The time judged is the trace's (:func:`trace_seconds`), without the stability
pass, so that a run with and one without stability make the same retries and draw the same
curve.
"""
from __future__ import annotations

import copy
import dataclasses


from hbm.analyses.time_fill import untraced_stretches
from hbm.model.contact_stiffness import stiff_contacts

RETRY_SECONDS = 60.0        # a first run longer than this is not repeated (its hint says how)
SHARE = 0.9                 # the events run is kept if it leaves at most this share untraced


def stiff_sampled_contacts(case) -> list:
    """:func:`stiff_contacts` that offer ``aft = "events"`` and are sampled (module doc)."""
    return [(i, r) for i, r in stiff_contacts(case)
            if case.elements[i].events_available and case.elements[i].aft == "sampled"]


def trace_seconds(res) -> float:
    """Seconds a run spent tracing its path (``settings["trace_seconds"]``: the continuation,
    its gap marches and added points, before the stability pass and the estimates)."""
    return float(res.settings.get("trace_seconds", res.solve_seconds))


def untraced_hz(res) -> float:
    """Width of the window (Hz) that no traced segment of a run covers
    (:func:`hbm.analyses.time_fill.untraced_stretches`)."""
    return sum(b - a for a, b in untraced_stretches(res))


def better_run(res, alt) -> bool:
    """True if ``alt`` covers more of the window than ``res`` (module doc): finished before
    stopped, then at most ``SHARE`` of the untraced width, or no more of it with fewer gaps."""
    first, second = untraced_hz(res), untraced_hz(alt)
    done, done_alt = res.status == "finished", alt.status == "finished"
    fewer = len(alt.settings.get("gaps", ())) < len(res.settings.get("gaps", ()))
    return done_alt > done or (done_alt == done and (second < SHARE * first or (second <= first and fewer)))


def _events_case(case, stiff):
    """A copy of ``case`` whose stiff sampled contacts ``stiff`` use ``aft = "events"``."""
    elements = list(case.elements)
    for i, _ in stiff:
        e = copy.copy(elements[i])
        e.aft = "events"
        elements[i] = e
    return dataclasses.replace(case, elements=tuple(elements))


def retry_with_events(case, res, trace):
    """``res``, or the run of ``trace(case')`` with ``case'`` on event-based AFTs when that one
    covers more of the window (module doc).

    Parameters
    ----------
    case : Case
    res : FRFResult
        The run on ``case``.
    trace : callable
        ``trace(case) -> FRFResult`` with the same settings.
    """
    if (res.status == "finished" and not res.settings.get("gaps")) or trace_seconds(res) > RETRY_SECONDS:
        return res
    stiff = stiff_sampled_contacts(case)
    if not stiff:
        return res
    names = ", ".join(case.elements[i].name for i, _ in stiff)
    alt = trace(_events_case(case, stiff))
    first, second = untraced_hz(res), untraced_hz(alt)
    better = better_run(res, alt)
    kept, other = (alt, res) if better else (res, alt)
    kept.settings["aft_retry"] = {
        "contacts": names, "untraced_hz_sampled": first, "untraced_hz_events": second,
        "kept": "events" if better else "sampled", "other_run_seconds": trace_seconds(other),
        "note": (f"the run with sampled contacts {'stopped' if res.status != 'finished' else 'left gaps'} "
                 f"({first:.3g} Hz untraced); traced again with aft = \"events\" on {names} "
                 f"({second:.3g} Hz untraced{'' if alt.status == 'finished' else ', ' + alt.status}): "
                 f"the {'events' if better else 'sampled'} run is kept"),
    }
    if not better:
        kept.settings.pop("contact_hint", None)        # events were tried: nothing left to suggest
    return kept
