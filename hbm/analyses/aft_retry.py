"""A run that stops short with stiff sampled contacts is traced again on their exact AFT.

A sampled AFT puts a contact's switches on the time grid: for a stiff contact (``kt`` at
least ``STIFF_CONTACT`` times the structure's stiffness ``g K g^T / g g^T`` along its first
coordinate) that is an error Newton cannot average out, and the path may stall there.  The
elements that offer an event-based AFT (``events_available``: Jenkins, friction3d on (t1, n))
compute the same law exactly from its events.  So when an FRF with such contacts stops or
leaves gaps, :func:`retry_with_events` traces the window again with ``aft = "events"`` on
them and keeps the run that covers more of it: a finished run before a stopped one, then the
smaller untraced width (gaps, and the window's ends a stopped run did not reach), the first
run on a tie.  ``settings["aft_retry"]`` says what was tried, what each run left untraced
and which was kept.
"""
from __future__ import annotations

import copy
import dataclasses

STIFF_CONTACT = 100.0       # kt over the structure's stiffness at the contact


def stiff_sampled_contacts(case) -> list:
    """``(index, kt / k_structure)`` of the elements that offer ``aft = "events"``, are sampled
    and are stiff (module doc); empty unless the model is dense (a condensed model's
    stiffness along a contact is not at hand)."""
    from hbm.analyses.problem_setup import choose_solver
    if choose_solver(case) != "full":
        return []
    K = case.model.K
    out = []
    for i, e in enumerate(case.elements):
        if not e.events_available or e.aft != "sampled":
            continue
        g = e.gather[0]
        ks = float(g @ K @ g) / float(g @ g)
        if ks > 0 and e.kt >= STIFF_CONTACT * ks:
            out.append((i, e.kt / ks))
    return out


def untraced_hz(res) -> float:
    """Width of the window a run did not trace: its gaps, and the ends it did not reach."""
    s = res.settings
    width = sum(g["to_hz"] - g["from_hz"] for g in s.get("gaps", []))
    if res.freq_hz.size == 0:
        return float(s["fmax_hz"] - s["fmin_hz"])
    return float(width + (s["fmax_hz"] - res.freq_hz.max()) + (res.freq_hz.min() - s["fmin_hz"]))


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
    if res.status == "finished" and not res.settings.get("gaps"):
        return res
    stiff = stiff_sampled_contacts(case)
    if not stiff:
        return res
    names = ", ".join(case.elements[i].name for i, _ in stiff)
    alt = trace(_events_case(case, stiff))
    first, second = untraced_hz(res), untraced_hz(alt)
    better = (alt.status == "finished", -second) > (res.status == "finished", -first)
    kept, other = (alt, res) if better else (res, alt)
    kept.settings["aft_retry"] = {
        "contacts": names, "untraced_hz_sampled": first, "untraced_hz_events": second,
        "kept": "events" if better else "sampled", "other_run_seconds": float(other.solve_seconds),
        "note": (f"the run with sampled contacts {'stopped' if res.status != 'finished' else 'left gaps'} "
                 f"({first:.3g} Hz untraced); traced again with aft = \"events\" on {names} "
                 f"({second:.3g} Hz untraced{'' if alt.status == 'finished' else ', ' + alt.status}): "
                 f"the {'events' if better else 'sampled'} run is kept"),
    }
    if not better:
        kept.settings.pop("contact_hint", None)        # events were tried: nothing left to suggest
    return kept
