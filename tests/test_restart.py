"""A stop inside the window is restarted past, and the skipped stretch is stated (issue 17:
the user gets the rest of the FRF, never a silent hole).  The stiff 3-DOF chain of the stress
matrix (kt/k = 1e4) stalls where its stick-slip corner is sharpest; the path goes on from a
fresh point past it."""
import pathlib
import sys

import hbm
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "stress"))
import cases  # noqa: E402


def test_a_stall_is_restarted_past_and_stated():
    case = hbm.case_from_dict(cases.jenkins_chain3(1.0, 1.0, 1e4, 5))
    res = hbm.frf(case, stability=False, error_estimate=False)
    gaps = res.settings["gaps"]
    lo, hi = res.settings["fmin_hz"], res.settings["fmax_hz"]
    assert res.ok and res.freq_hz[0] == lo and abs(res.freq_hz[-1] - hi) <= 1e-9 * hi
    assert len(gaps) >= 1 and "not traced" in res.settings["gap_warning"]
    for g in gaps:
        assert lo < g["from_hz"] < g["to_hz"] < hi and g["reason"]
        assert g["to_hz"] - g["from_hz"] <= 0.13 * (hi - lo)          # at most 2^7 x 0.1 % of the window
        inside = (res.freq_hz > g["from_hz"] * (1 + 1e-9)) & (res.freq_hz < g["to_hz"] * (1 - 1e-9))
        assert not inside.any()
    assert res.energy_error.max() < 1e-8
    assert len(res.settings["segments"]) == len(gaps) + 1
    assert sum(e - s for s, e in res.settings["segments"]) == res.freq_hz.size


def test_where_no_restart_converges_the_window_is_traced_from_its_top(monkeypatch):
    """The railcar rig's case (rigs/railcar_wedge.toml: no restart past its stop at 30.33 Hz
    converged, and 30.33-40 Hz were left untraced) on the stiff chain with restarts made to
    fail: the branch through fmax is traced down towards the stop, the stretch between stated."""
    import hbm.analyses.trace as trace
    monkeypatch.setattr(trace, "_fresh_point_past", lambda *a, **k: "no restart (test)")
    case = hbm.case_from_dict(cases.jenkins_chain3(1.0, 1.0, 1e4, 5))
    res = hbm.frf(case, stability=False, error_estimate=False)
    lo, hi = res.settings["fmin_hz"], res.settings["fmax_hz"]
    assert res.status == "finished" and res.freq_hz[0] == lo and abs(res.freq_hz[-1] - hi) <= 1e-9 * hi
    (g,) = res.settings["gaps"]
    assert "no restart (test)" in g["reason"] and "not traced" in res.settings["gap_warning"]
    a, b = res.settings["segments"]
    assert a[1] == b[0] and b[1] == res.freq_hz.size
    assert res.freq_hz[a[1] - 1] == g["from_hz"] and res.freq_hz[b[0]] == g["to_hz"]
    assert res.energy_error.max() < 1e-8


def test_the_branch_from_the_top_is_restarted_below_its_own_stops(monkeypatch):
    """With restarts above the upward stop (0.0608 Hz) made to fail, the branch from fmax
    stops on its way down at 0.0763 Hz, is restarted below that (down to the upward stop), and
    the gap between states both stops and why no restart converged."""
    import hbm.analyses.trace as trace
    fresh = trace._fresh_point_past

    def upward_fails(*a, direction=1, **k):
        return "no restart (test)" if direction > 0 else fresh(*a, direction=direction, **k)
    monkeypatch.setattr(trace, "_fresh_point_past", upward_fails)

    def no_time_domain(*a, **k):          # (600 periods from rest: 15 s, not periodic either)
        raise RuntimeError("no time-domain start (test)")
    monkeypatch.setattr(trace, "time_domain_start", no_time_domain)
    case = hbm.case_from_dict(cases.jenkins_chain3(1.0, 1.0, 1e4, 5))
    res = hbm.frf(case, stability=False, error_estimate=False)
    hi = res.settings["fmax_hz"]
    assert res.status == "finished" and abs(res.freq_hz[-1] - hi) <= 1e-9 * hi
    for g in res.settings["gaps"]:
        inside = (res.freq_hz > g["from_hz"] * (1 + 1e-9)) & (res.freq_hz < g["to_hz"] * (1 - 1e-9))
        assert not inside.any()
    why = " ".join(g["reason"] for g in res.settings["gaps"])
    assert "no restart (test)" in why and "Hz down: " in why and "no restart below it converged" in why
    assert sum(e - s for s, e in res.settings["segments"]) == res.freq_hz.size
    assert res.energy_error.max() < 1e-8


def test_a_restart_on_the_upward_stop_ends_the_descent(monkeypatch):
    """A restart below a stop of the branch from fmax may land on its limit, the upward path's
    stop: nothing is left to trace down from it.  The descent once asked the continuation for
    the window (w_stop, w_stop) there, which it refuses with a ValueError (seen on a stiff
    point contact).  Traces and restarts are stand-ins here."""
    import types

    import hbm.analyses.trace as trace
    w_stop, w_hi = 1.0, 2.0
    calls = []

    def fake_trace(problem, case, part, X, it, w0, bounds, direction, *a, **k):
        assert bounds[0] < bounds[1], f"a window of no width: {bounds}"
        calls.append((w0, direction))
        end = 1.5 if direction < 0 else bounds[1]          # down: a stop at 1.5; up: finished
        for w in (w0, end):
            part.append(X, w, None, 0, 0.0, 0)
        return ("failed" if direction < 0 else "finished"), "stop (test)", [], 0
    monkeypatch.setattr(trace, "_trace", fake_trace)
    monkeypatch.setattr(trace, "_fresh_point_past", lambda *a, limit=None, **k: ("X", 0, limit))
    case = types.SimpleNamespace(analysis=types.SimpleNamespace(max_points=1000))
    parts, ends, _, _ = trace._down_past_stops(None, case, ("X", 0, w_hi), w_stop, 0, (0.5, w_hi), None, 1.0,
                                                None, None, None)
    assert calls == [(w_hi, -1), (w_stop, +1)]     # down to the stop at 1.5, up from the restart at 1.0
    assert [p.w for p, _ in parts] == [[w_hi, 1.5], [w_stop, 1.5]]


# ------------------------------------------------------------------ restarts on a traced branch
def duffing_setup():
    """The hardening Duffing of tests/test_duffing.py (three solutions between its folds), its
    FRF, and the problem with its scales."""
    import numpy as np
    from hbm.analyses.problem_setup import _residual_scale, _unknown_scale, build_problem, resolve_settings
    from hbm.balance.fourier import FourierBasis
    from test_duffing import duffing_case
    case = duffing_case([1])
    res = hbm.frf(case, stability=False, error_estimate=False)
    h, N, lo, hi, tr = resolve_settings(case, None, None, None, None, None)
    problem, _ = build_problem(case, FourierBasis(h, N), tr)
    w_lo, w_hi = 2 * np.pi * lo, 2 * np.pi * hi
    return case, res, problem, _unknown_scale(problem, case, w_lo, w_hi), _residual_scale(problem, w_lo)


def branch_path(res, lo, hi):
    """A traced path of the FRF points ``lo:hi``."""
    import numpy as np
    from hbm.analyses.traced_points import TracedPoints
    p = TracedPoints()
    for k in range(lo, hi):
        p.X.append(np.asarray(res.X[k]))
        p.w.append(2 * np.pi * res.freq_hz[k])
    return p


def test_a_fresh_start_on_the_branch_already_traced_is_passed_over():
    """Cause of a restart loop on the UPD rig (rigs/upd_rig_flanks.toml at CF/Fexc = 100): the
    path stopped on a fold's middle branch, the linear start past the stop converged on the
    lower branch traced before, and the path went round to the same stop again and again
    until max_points.  A start on a traced branch is now passed over."""
    import numpy as np
    import pytest
    from hbm.analyses.problem_setup import _first_point
    case, res, problem, xscale, r_scale = duffing_setup()
    f1, f2 = sorted(res.folds_hz)
    k2 = int(np.argmin(np.abs(res.freq_hz - f2)))       # upper branch: the path up to its peak fold
    k1 = int(np.argmin(np.abs(res.freq_hz - f1)))       # lower branch: after the second fold
    upper, lower = branch_path(res, 0, k2 + 1), branch_path(res, k1, res.freq_hz.size)
    w = 2 * np.pi * 0.5 * (f1 + f2)
    X, _ = _first_point(problem, case, w, xscale, r_scale, arclength_ramp=False)
    assert lower.passes(X, w) and not upper.passes(X, w)          # the linear start finds the lower branch
    X2, _ = _first_point(problem, case, w, xscale, r_scale, arclength_ramp=False,
                         avoid=lambda X: upper.passes(X, w))
    assert np.abs(X2 - X).max() <= 1e-10 * np.abs(X).max()          # not avoided: the same point
    with pytest.raises(RuntimeError, match="already traced"):
        _first_point(problem, case, w, xscale, r_scale, arclength_ramp=False,
                     avoid=lambda X: lower.passes(X, w))
    # a point off every chord, and frequencies outside the traced span, are not on the path
    assert not lower.passes(1.05 * X, w)
    assert not lower.passes(X, 2 * np.pi * 10 * f2)


def test_a_gap_states_how_much_the_response_changes_across_it():
    """friction3d, force ratio 100, kt/k = 1e4, H = 5, the contact separating: where the contact
    opens the path stops; a restart further on and the marches at fixed frequencies from both
    ends narrow the gap to 5e-7 Hz, across which the first harmonics change by 99 % (the lower
    branch ends at a fold, the upper one goes on below it: the arclength from the gap's upper
    end traces it round its fold, the one from the lower end stalls short of its fold).  The gap
    states that change, and it is the FRF's own values at its two ends."""
    import numpy as np
    res = hbm.frf(hbm.case_from_dict(cases.friction3d_2dof(100.0, 1e4, 5, True)), stability=False,
                  error_estimate=False)
    (g,) = res.settings["gaps"]
    assert g["to_hz"] - g["from_hz"] < 1e-4 * g["from_hz"]
    assert g["h1_change"] > 0.5
    assert "first harmonics" in res.settings["gap_warning"]
    a, b = (int(np.flatnonzero(res.freq_hz == g[k])[0]) for k in ("from_hz", "to_hz"))
    h1 = max(abs(o.h1[a] - o.h1[b]) / max(o.h1[a], o.h1[b]) for o in res.outputs.values())
    assert abs(h1 - g["h1_change"]) < 1e-9
    assert "traced round its fold" in g["reason"]
    assert res.freq_hz[a + 1:b].min() < 0.99 * g["from_hz"]        # the upper branch goes on below


def test_a_gap_of_no_visible_width_is_named_a_corner():
    from hbm.analyses.gaps import gap_text
    corner = gap_text({"from_hz": 15.8365, "to_hz": 15.8365 * (1 + 3e-8), "h1_change": 6e-6, "change": 6e-3})
    assert "15.8365 Hz (a corner of the path, 3e-08 of the frequency wide)" in corner and "6.0e-06" in corner
    jump = gap_text({"from_hz": 0.13620796, "to_hz": 0.13620796 * (1 + 5e-8), "h1_change": 0.87, "change": 1.2})
    assert "0.13620796 Hz (a jump of the path, 5e-08 of the frequency wide)" in jump
    gap = gap_text({"from_hz": 0.2087, "to_hz": 0.2221, "h1_change": 1.0, "change": 1.5})
    assert gap.startswith("0.2087..0.2221 Hz (outputs across it") and "corner" not in gap


def _part(ws):
    import numpy as np
    from hbm.analyses.traced_points import TracedPoints
    p = TracedPoints()
    for w in ws:
        p.X.append(np.zeros((3, 1)))
        p.w.append(w)
        p.Y.append(np.full((3, 1), w))
        p.its.append(1)
        p.err.append(0.0)
        p.unclosed.append(0)
    return p


def test_parts_from_the_top_join_at_their_restarts_and_leave_only_real_gaps():
    """The railcar's case: a part down from fmax stops at 3.0, a restart at 2.9 is traced down
    to 2.0 (stopped) and up to 3.0 (or stalls at 2.95): the restart joins its two parts, so the
    gaps are 1.0-2.0 (and 2.95-3.0), never a sliver between the restart and the next point up
    (a 0.0002 Hz "corner" the railcar's first run reported)."""
    from hbm.analyses.trace import _merge_parts
    from hbm.balance.fourier import FourierBasis
    basis = FourierBasis([0, 1], 8)
    for back, expected in (([2.9, 2.95, 3.0], [(1.0, 2.0)]), ([2.9, 2.95], [(1.0, 2.0), (2.95, 3.0)])):
        pts, segments = _part([0.5, 1.0]), [[0, 2]]
        parts = [(_part([4.0, 3.5, 3.0]), True), (_part([2.9, 2.5, 2.0]), True), (_part(back), False)]
        ends = {1.0: "up stop", 3.0: "down stop", 2.0: "second down stop", 2.95: "up from 2.9"}
        gaps = _merge_parts(pts, segments, parts, ends, basis)
        assert [(g["from_hz"] * 2 * 3.141592653589793, g["to_hz"] * 2 * 3.141592653589793) for g in gaps] == \
            [pytest.approx(e) for e in expected]
        assert pts.w == sorted(pts.w) and len(pts.w) == 2 + 3 + 3 + len(back) - 1
        assert sum(e - s for s, e in segments) == len(pts.w)
        assert gaps[0]["reason"] == "up stop; second down stop"
