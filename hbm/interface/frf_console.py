"""What ``hbm frf`` prints: the run in one line, then peaks, folds, jumps, warnings and notes.

Warnings (a gap, a stop hint, implausible stability, truncation) go to stderr; the rest to
stdout, so a log of stdout alone reads as the result.
"""
from __future__ import annotations

import sys

from hbm.interface.report import describe_folds


def print_frf(case, res, summary: dict, explicit_tol: bool) -> None:
    """Print the result of ``hbm frf``.

    Parameters
    ----------
    case : Case
    res : FRFResult
    summary : dict
        :func:`hbm.interface.report.summary_dict` of the run.
    explicit_tol : bool
        ``--tol`` was given (the harmonics' ladder is then always reported).
    """
    print(f"{case.name}: {summary['n_points']} points, {summary['newton_iterations']} Newton iterations, "
          f"{summary['solve_seconds']:.3f} s, H={res.settings['harmonics'][-1]}, N={res.settings['time_samples']}"
          + _defaults_note(res.settings))
    st = res.settings
    if st.get("adaptive"):
        _print_adaptive(st["adaptive"], explicit=explicit_tol)
    if st.get("solver") == "condensed":
        print(f"  condensed solver: {st['n_dof']} DOFs -> {st['contact_coordinates']} contact coordinates, "
              f"{st['modes']} modes (to {st['highest_kept_mode_hz']:.6g} Hz), reduction {st['reduction_seconds']:.3f} s"
              + (" (cached)" if st.get("reduction_cached") else ""))
        if st.get("modes_added"):
            from hbm.model.mode_cover import MARGIN
            print(f"  warning: {st['modes_requested']} modes stop below {MARGIN:g} x fmax: added {st['modes_added']} "
                  f"(the omitted modes would respond inside the window)", file=sys.stderr)
    for name, pk in summary["peaks"].items():
        for p in pk:
            print(f"  peak {name}: {p['amplitude']:.6g} at {p['freq_hz']:.6g} Hz")
    if summary["folds"]:
        print("  " + describe_folds(summary["folds"], (st["fmin_hz"], st["fmax_hz"])))
    for name, jumps in (summary["jumps"] or {}).items():
        for way in ("up", "down"):
            for j in jumps[way]:
                after = ("no stable branch (no stable point to land on in the traced path: "
                         "check with hbm timesim)" if j["amplitude_after"] is None else f"{j['amplitude_after']:.6g}")
                print(f"  jump {name} (sweep {way}) at {j['from_hz']:.6g} Hz: "
                      f"{j['amplitude_before']:.6g} -> {after}")
    for key in ("gap_warning", "contact_hint", "stability_warning", "closure_warning", "truncation_warning",
                "harmonics_note", "harmonics_hint"):
        if st.get(key):
            print(f"  warning: {st[key]}", file=sys.stderr)
    if summary["max_energy_error"] is not None:
        print(f"  max energy-balance error {summary['max_energy_error']:.2e}")
    _print_notes(st)
    if st.get("stuck_points"):
        print(f"  note: at {st['stuck_points']} points a contact sticks for the whole period: its slider offset, "
              f"hence the mean and max |y|, is one of a family of periodic solutions (column stuck_contacts)")
    for name, v in (st.get("error_estimate") or {}).get("max", {}).items():
        if v["error"] == 0.0:
            print(f"  estimated error of {name}_h1 0 at every point (the richer harmonics add nothing)")
        else:
            print(f"  largest estimated error of {name}_h1 {v['error']:.1e} at {v['freq_hz']:.6g} Hz "
                  f"(harmonic truncation)")


def _print_notes(st) -> None:
    """What the run did beside the trace: marches across gaps, the retries on events and on
    richer harmonics, the time fill, the Floquet checks."""
    if st.get("gaps_bridged"):
        b = st["gaps_bridged"]
        joined = sum(g["joined"] for g in b)
        print(f"  note: {len(b)} stop(s) of the continuation marched across at fixed frequencies "
              f"({sum(g['points'] for g in b)} points): {joined} joined the path again"
              + ("" if joined == len(b) else f", {len(b) - joined} narrowed"))
    if st.get("overhangs"):
        o = st["overhangs"]
        joined, folded = sum(g["joined"] for g in o), sum(g["sides_folded"] > 0 and not g["joined"] for g in o)
        print(f"  note: {len(o)} junction(s) of traced segments traced on from both sides "
              f"({sum(g['points'] for g in o)} points): {joined} joined, {folded} traced round a fold")
    if st.get("middle_gap_note"):
        print(f"  note: {st['middle_gap_note']}")
    for key in ("aft_retry", "harmonics_retry"):
        if st.get(key):
            print(f"  note: {st[key]['note']}")
    if st.get("time_fill"):
        print(f"  note: {st['time_fill']['note']}")
    elif st.get("time_fill_note"):
        print(f"  note: {st['time_fill_note']}")
    if st.get("floquet_overrides_hz"):
        fl = st["floquet_overrides_hz"]
        print(f"  note: {len(fl)} point(s) Hill called unstable are stable by the Floquet multipliers of the "
              f"time-domain period map (at {', '.join(f'{f:.6g}' for f in fl[:5])} Hz); the verdicts are Floquet's")
    if st.get("floquet_unstable_hz"):
        fl = st["floquet_unstable_hz"]
        print(f"  note: {len(fl)} point(s) Hill called stable between unstable ones are unstable by the Floquet "
              f"multipliers of the time-domain period map (at {', '.join(f'{f:.6g}' for f in fl[:5])} Hz); "
              f"the verdicts are Floquet's")
    if st.get("floquet_unchecked"):
        print(f"  note: {st['floquet_unchecked']} point(s) Hill calls unstable were not checked by Floquet "
              f"multipliers (the checks stop past 40 and 30 s per FRF, or a quarter of Hill's time if longer): "
              f"their verdicts are Hill's")


def _defaults_note(st) -> str:
    """`` (element defaults: H, N)`` for the settings that were not given, else empty."""
    d = [k for k, s in (("H", "harmonics_source"), ("N", "time_samples_source")) if st.get(s) == "default"]
    return f" (element defaults: {', '.join(d)})" if d else ""


def _print_adaptive(a: dict, explicit: bool) -> None:
    """What the harmonics' tolerance did: printed when asked for, or when it did anything."""
    pts = a["points"]
    if not explicit and len(a["tried"]) == 1 and not pts["levels"]:
        return
    if not a["checked"]:
        print(f"  harmonics for --tol {a['tol']:g}: not checked (no point's error could be estimated)")
        return
    steps = " -> ".join(f"H={t['H']} (largest estimate {t['max_error']:.1e}, {t['share_above']:.0%} of points "
                        f"above, {t['seconds']:.2f} s)" for t in a["tried"])
    ref = ", ".join(f"{v['points']} at H={v['H']}" for v in pts["levels"]) or "none"
    print(f"  harmonics for --tol {a['tol']:g}: path traced at {steps}; points refined: {ref} "
          f"({pts['seconds']:.2f} s)" + ("" if a["met"] else
                                         f": tolerance NOT met (largest estimate {a['max_error']:.1e}, "
                                         f"{pts['left_above']} points above, {pts['failed']} refinements failed)"))
    if a.get("budget_note"):
        print(f"  note: {a['budget_note']} (the estimates above are of the harmonics reached)", file=sys.stderr)
    if pts.get("failed_hz"):
        seen = list(dict.fromkeys(f"{f:.6g} Hz (H = {h})" for f, h in pts["failed_hz"]))
        where = ", ".join(seen[:5]) + (f" and {len(seen) - 5} more" if len(seen) > 5 else "")
        print(f"  note: the richer solve did not converge at {where}: those points keep their last "
              f"solution and estimate (near a fold, or a stiff contact's switch: see contact_hint or the "
              f"README's \"Stiff contacts\"; a larger --tol accepts them)", file=sys.stderr)
