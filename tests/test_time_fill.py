"""Time-domain points where the continuation left the window untraced (hbm/analyses/time_fill.py).

The case: the undamped Jenkins oscillator at kt/k = 1e5, H = 15 (issue 17's den Hartog case).
Below 0.1015 Hz its mass sticks for most of the period and slips in short bursts: the
truncated series rings by far more than the contact's stick range (1.8e-5), so no
continuation reaches the window's start at that H (given as an argument, it is kept: with H
left to the case the FRF is traced again at H = 23 and 35, and at 35 it finishes), and the
traced point next to the stop is estimated 55 % off.  The time integration answers there.
"""
from __future__ import annotations

import csv
from types import SimpleNamespace

import numpy as np
import pytest

import hbm
from hbm.analyses.time_fill import (MIN_WIDTH, check_points, fill_frequencies, fill_note, fill_untraced,
                                    spread_order, untraced_stretches, wanted)
from hbm.interface.case import case_from_dict
from hbm.interface.report import write_frf


def _run(freq, segments, lo=0.0, hi=10.0):
    return SimpleNamespace(freq_hz=np.array(freq, float),
                           settings={"fmin_hz": lo, "fmax_hz": hi, "segments": segments})


def test_untraced_stretches_are_the_window_minus_the_traced_spans():
    # traced 2..4 (down, after failing at the start), then 6..9 past a gap: 0..2, 4..6, 9..10 untraced
    res = _run([4.0, 3.0, 2.0, 6.0, 7.5, 9.0], [[0, 3], [3, 6]])
    assert untraced_stretches(res) == [(0.0, 2.0), (4.0, 6.0), (9.0, 10.0)]
    # a fold-back start (0..3 and back to 1) and a trace from the top (10 down to 5): hole 3..5
    res = _run([0.0, 3.0, 1.0, 10.0, 5.0], [[0, 3], [3, 5]])
    assert untraced_stretches(res) == [(3.0, 5.0)]
    assert untraced_stretches(_run([0.0, 10.0], [[0, 2]])) == []
    assert untraced_stretches(_run([1e-14, 10.0 - 1e-14], [[0, 2]])) == []        # ends solved to round-off


def test_fill_frequencies_share_the_points_by_width_and_reach_the_window_ends():
    f = fill_frequencies([(0.0, 2.0), (4.0, 6.0), (9.0, 10.0), (7.0, 7.0 + 1e-9)], (0.0, 10.0), max_points=5)
    assert f[0] == [0.0, 1.0]                        # the start was not reached: it is simulated
    assert f[1] == pytest.approx([4.0 + 2 / 3, 4.0 + 4 / 3])      # inside a gap
    assert f[2] == [10.0]                            # the end was not reached
    assert f[3] == []                                # narrower than MIN_WIDTH of the window: a corner
    assert 1e-9 < MIN_WIDTH * 10.0


def test_spread_order_covers_the_range_early():
    order = spread_order(8)
    assert sorted(order) == list(range(8))
    assert order[:2] == [0, 4] and set(order[:4]) == {0, 2, 4, 6}
    assert spread_order(1) == [0]


def _stiff_oscillator(**model):
    return case_from_dict({
        "name": "undamped Jenkins, kt/k = 1e5",
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.0]], **model},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 1e5, "slip_force": 0.9}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 15, "frequency_hz": [0.086, 0.2], "outputs": {"x": 0}},
    })


@pytest.fixture(scope="module")
def stopped():
    case = _stiff_oscillator()
    return case, hbm.frf(case, harmonics=15, stability=False)     # as asked: no richer retry


def test_a_stop_short_of_the_window_is_answered_by_time_simulations(stopped, tmp_path):
    case, res = stopped
    assert res.status == "failed"                    # the window's start is not reached (module doc)
    (a, b), = untraced_stretches(res)
    assert a == 0.086 and 0.09 < b < 0.11
    # 3 points: 2 in the stretch (0.086 Hz from rest settles in 39 periods), 1 check of the
    # traced point next to the stop (estimated 62 % off; from rest it settles in 77 periods)
    rec = fill_untraced(case, res, budget=20.0, max_points=3, refine_points=0)
    assert res.settings["time_fill"] is rec and rec["skipped"] == []
    untraced = [p for p in rec["points"] if p["kind"] == "untraced"]
    check, = [p for p in rec["points"] if p["kind"] == "check"]
    assert [p["freq_hz"] for p in untraced] == pytest.approx([a, (a + b) / 2])
    first, middle = untraced
    assert first["ok"] and first["error_estimate"] < 1e-3
    # walked into the stretch by shooting: the middle point from the traced point at the stop,
    # the window's start from the middle point's solution; the motion from rest settles on the
    # same periodic solution (1.5e-6 apart: two methods, each with its estimate)
    assert middle["method"] == first["method"] == "shooting" and first["stable"]
    assert f"the traced point at {b:.6g} Hz" in middle["message"]
    assert f"the periodic solution at {(a + b) / 2:.6g} Hz" in first["message"]
    from_rest = hbm.timesim(case, a)
    assert first["periods"] < from_rest.periods / 2
    assert first["h1"]["x"] == pytest.approx(from_rest.h1["x"], rel=max(first["error_estimate"],
                                                                        from_rest.error_estimate))
    assert "2 of the untraced shot from the traced path" in rec["note"]
    assert first["h1"]["x"] > 0.85                   # the HBM point next to the stop has 0.80
    # the check: the HBM's point against the time domain at its frequency
    i = int(np.argmin(np.abs(res.freq_hz - b)))
    assert check["freq_hz"] == pytest.approx(b) and check["hbm_estimate"] > 0.3
    assert check["hbm_h1"]["x"] == res.outputs["x"].h1[i]
    assert check["ok"] and check["hbm_off"] == pytest.approx(abs(res.outputs["x"].h1[i] / check["h1"]["x"] - 1))
    assert 0.05 < check["hbm_off"] < check["hbm_estimate"]     # off indeed, within its estimate
    # shot from the traced point: the periodic solution a simulation from rest settles on
    # (1.8e-7 apart at the same steps per period: 1024 and 2048, those of a stiff contact's
    # shots), in 8 periods instead of 77, with its Floquet verdict
    from hbm.timedomain.floquet_check import FINE_STEPS
    from hbm.timedomain.time_results import TimeSimOptions
    rest = hbm.timesim(case, check["freq_hz"], TimeSimOptions(steps=FINE_STEPS))
    assert check["method"] == "shooting" and check["stable"] and check["periods"] < rest.periods / 4
    assert check["h1"]["x"] == pytest.approx(rest.h1["x"], rel=1e-5)
    assert check["error_estimate"] == pytest.approx(rest.error_estimate, rel=0.05)
    (f_near, e_near), = rec["stretches"][0]["neighbour_errors"]
    assert f_near == pytest.approx(b) and e_near > 0.3
    assert "estimated" in rec["note"] and "H = 15" in rec["note"] and "1 traced point estimated" in rec["note"]
    assert "1 shot from the traced point" in rec["note"]
    write_frf(case, res, tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "frf_timedomain.csv")))
    assert [float(r["freq_hz"]) for r in rows] == pytest.approx([q["freq_hz"] for q in rec["points"]])
    assert all((r["x_h1"] != "") == bool(int(r["periodic"])) for r in rows)
    assert [r["kind"] for r in rows] == [q["kind"] for q in rec["points"]]
    assert float(rows[-1]["x_hbm_h1"]) == pytest.approx(check["hbm_h1"]["x"])
    assert (tmp_path / "frf.png").stat().st_size > 0
    del res.settings["time_fill"]                    # the same folder again: no stale points
    write_frf(case, res, tmp_path)
    assert not (tmp_path / "frf_timedomain.csv").exists()


def test_no_budget_simulates_nothing_and_says_so(stopped):
    from hbm.interface.cli import _time_fill
    case, res = stopped
    assert not _time_fill(case, res, SimpleNamespace(time_fill=0.0, quiet=True))     # --time-fill 0
    assert hbm.time_fill(case, res, budget=0.0)["skipped"]                            # the API's entry
    rec = fill_untraced(case, res, budget=0.0, max_points=4)
    assert rec["points"] == [] and len(rec["skipped"]) == 4
    assert "0 of 4" in rec["note"] and "4 not simulated (budget 0 s)" in rec["note"]
    # what was to be checked is said though nothing was simulated (it read ": 0 of 5 ...")
    assert rec["checks"] == 1 and "1 traced point estimated over 20 % off: 0 of 4" in rec["note"]


def test_only_points_estimated_far_off_are_checked():
    res = SimpleNamespace(freq_hz=np.array([1.0, 2.0, 3.0, 4.0, 5.0]), status="finished", settings={},
                          outputs={"x": SimpleNamespace(err=np.array([0.01, 0.5, np.nan, 0.3, 0.25])),
                                   "y": SimpleNamespace(err=np.array([0.3, 0.0, 0.0, 0.0, 0.0]))})
    assert check_points(res, 10) == [0, 1, 3, 4]
    assert check_points(res, 2) == [0, 4]            # spread over their frequencies
    assert wanted(res)
    res.outputs = {"x": SimpleNamespace(err=np.full(5, 0.1))}
    assert not wanted(res) and check_points(res, 3) == []


def test_hbm_frf_writes_the_time_domain_points_and_says_where(tmp_path):
    import subprocess
    import sys
    toml = tmp_path / "stiff.toml"
    toml.write_text('name = "stiff"\n[model]\nmass = [[1.0]]\nstiffness = [[1.0]]\ndamping = [[0.0]]\n'
                    '[[element]]\ntype = "jenkins"\ndofs = [0]\nkt = 1e5\nslip_force = 0.9\n'
                    '[excitation]\ndofs = [0]\namplitude = [1.0]\n'
                    '[analysis]\nharmonics = 15\nfrequency_hz = [0.086, 0.2]\noutputs = { x = 0 }\n')
    run = lambda out, *extra: subprocess.run(   # noqa: E731
        [sys.executable, "-m", "hbm", "frf", str(toml), "-o", str(tmp_path / out), "--harmonics", "15",
         "--no-stability", "-q", *extra], capture_output=True, text=True)
    r = run("fill", "--time-fill", "3")
    assert r.returncode == 1, r.stderr              # the HBM run still stopped: said, not hidden
    assert "untraced 0.086..0.0978965 Hz" in r.stdout and "frf_timedomain.csv" in r.stdout
    assert (tmp_path / "fill" / "frf_timedomain.csv").exists()


def test_a_refused_or_failed_integration_is_recorded_not_raised(monkeypatch):
    import hbm.timedomain.timesim as ts
    from hbm.analyses import time_points
    from hbm.interface.case import CaseError

    def refuse(case, f, progress=None):
        raise CaseError("the time history needs 40 GB") if f < 1 else RuntimeError("Newton did not converge")
    monkeypatch.setattr(ts, "timesim", refuse)
    p, q = time_points.simulate(None, 0.5, 1.0, "x"), time_points.simulate(None, 2.0, 1.0, "x")
    assert not p["ok"] and "40 GB" in p["message"] and not q["ok"] and "Newton" in q["message"]


def test_a_condensed_model_is_filled_on_the_model_its_balance_solves(stopped):
    """The condensed solver's run of the same oscillator (its one mode kept) is the full one's
    and stops as well; it is simulated on its kept modes (:mod:`hbm.timedomain.condensed_twin`): the point at the
    window's start equals the full model's."""
    case, res = stopped
    cond = _stiff_oscillator(solver="condensed", modes=1)
    rc = hbm.frf(cond, harmonics=15, stability=False)
    assert rc.settings["solver"] == "condensed" and rc.status == "failed"
    # the same run as the full solver's, retried with aft = "events" like it (a stiff contact)
    assert "aft_retry" in rc.settings and rc.freq_hz.size == res.freq_hz.size
    assert np.allclose(rc.outputs["x"].h1, res.outputs["x"].h1, rtol=1e-6)
    a = fill_untraced(case, res, budget=10.0, max_points=1, refine_points=0)
    b = fill_untraced(cond, rc, budget=10.0, max_points=1, refine_points=0)
    (pa,), (pb,) = a["points"], b["points"]
    assert pa["freq_hz"] == pb["freq_hz"] == 0.086 and pa["ok"] and pb["ok"]
    assert abs(pb["h1"]["x"] / pa["h1"]["x"] - 1) < 1e-8 and "time_fill_note" not in rc.settings


def test_a_condensed_model_with_a_velocity_law_is_not_filled_and_that_is_said():
    # the twin's static coordinates have no velocity a law could read
    from hbm.analyses import time_fill
    cond = case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.01]], "solver": "condensed", "modes": 1},
        "element": [{"type": "coulomb_regularised", "dofs": [0], "slip_force": 0.2, "v_r": 0.01}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 3, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}},
    })
    res = hbm.frf(cond, stability=False)
    assert time_fill._time_model(cond, res) is None
    assert "velocity-dependent law is not integrated in time" in res.settings["time_fill_note"]


def test_a_walk_shoots_again_a_point_that_failed_once_a_nearer_start_is_found(monkeypatch):
    """Points 0.9, 0.7, 0.55 Hz of a stretch below a path traced at 1 Hz: each is shot from the
    nearest solution known; 0.7 fails from 0.9's (a jump between them), 0.55 converges from
    0.9's, and 0.7 is then shot again from 0.55's, the nearer start, instead of integrated from
    rest; a point that fails from every start is integrated from rest."""
    from types import SimpleNamespace
    from hbm.analyses import time_points
    calls = []

    def shoot(case, basis, X, f, problem, start):
        calls.append((f, start))
        if f == 0.3 or (f == 0.7 and "0.55" not in start):
            return None, None
        return {"freq_hz": f, "ok": True, "method": "shooting", "message": start}, np.full((3, 1), f)

    def from_rest(model, f, seconds, why):
        calls.append((f, "rest"))
        return {"freq_hz": f, "ok": False, "message": "not periodic"}
    monkeypatch.setattr(time_points, "shoot_point", shoot)
    monkeypatch.setattr(time_points, "simulate", from_rest)
    res = SimpleNamespace(freq_hz=np.array([1.0]), X=np.zeros((1, 3, 1)), basis=None)
    run = time_points.FillRun(None, res, None, None, 30.0, None, 3)
    assert run.untraced([0.55, 0.7, 0.9]) == []
    assert calls == [(0.9, "the traced point at 1 Hz"), (0.7, "the periodic solution at 0.9 Hz"),
                     (0.55, "the periodic solution at 0.9 Hz"), (0.7, "the periodic solution at 0.55 Hz")]
    assert sorted(p["freq_hz"] for p in run.points) == [0.55, 0.7, 0.9] and all(p["ok"] for p in run.points)
    calls.clear()
    lost = run.untraced([0.3])              # nearest start 0.55: fails, and no other is nearer
    assert lost == [0.3] and calls == [(0.3, "the periodic solution at 0.55 Hz")]
    run.from_rest(lost, [])                 # after every shot, checks' included
    assert calls[-1] == (0.3, "rest") and run.points[-1]["freq_hz"] == 0.3


def test_the_refinement_brackets_a_jump_inside_a_stretch(monkeypatch):
    """A stretch 0.5..1 Hz below a path traced from 1 Hz (h1 0.19 there, estimated 1 % off),
    answered at 0.5 (h1 1) and 0.9 Hz (0.2), with a jump at 0.62 Hz: four more points halve
    the interval across the jump each time (0.7, 0.6, 0.65, 0.625 Hz); the smooth end
    (0.9 -> 1 Hz, 5 % apart) gets none; a traced end estimated far off is not compared."""
    from types import SimpleNamespace
    from hbm.analyses import time_points

    def shoot(case, basis, X, f, problem, start):
        return {"freq_hz": f, "ok": True, "kind": "untraced", "h1": {"x": 1.0 if f < 0.62 else 0.2},
                "method": "shooting"}, np.zeros((3, 1))
    monkeypatch.setattr(time_points, "shoot_point", shoot)
    out = SimpleNamespace(h1=np.array([0.19]), err=np.array([0.01]))
    res = SimpleNamespace(freq_hz=np.array([1.0]), X=np.zeros((1, 3, 1)), basis=None, outputs={"x": out})
    run = time_points.FillRun(None, res, None, None, 30.0, None, 2)
    run.untraced([0.5, 0.9])
    assert run.refine([(0.5, 1.0)], 4) == 4
    assert [p["freq_hz"] for p in run.points[2:]] == pytest.approx([0.7, 0.6, 0.65, 0.625])
    out.h1[0], out.err[0] = 0.1, 0.5        # the traced end 50 % off: its 0.1 against 0.2 is not a jump
    run = time_points.FillRun(None, res, None, None, 30.0, None, 2)
    run.untraced([0.9, 0.95])
    assert run.refine([(0.5, 1.0)], 4) == 0


def test_a_check_that_cannot_start_from_its_point_starts_from_a_reliable_neighbour(monkeypatch):
    """Path points at 1.0 (estimated 1 % off) and 1.1 Hz (50 % off, checked): the shot from the
    far-off point itself fails, no other solution is known, so the check is shot from the
    reliable point at 1.0 Hz, not integrated from rest; it lands beyond the point's estimate,
    and the note does not count it as the HBM's error."""
    from types import SimpleNamespace
    from hbm.analyses import time_points
    starts = []

    def shoot(case, basis, X, f, problem, start):
        starts.append(start)
        if start == "the traced point":
            return None, None
        return {"freq_hz": f, "ok": True, "h1": {"x": 1.0}, "max": {"x": 1.0}, "method": "shooting",
                "stable": True, "error_estimate": 1e-4}, np.zeros((3, 1))
    monkeypatch.setattr(time_points, "shoot_point", shoot)
    out = SimpleNamespace(h1=np.array([1.0, 2.0]), err=np.array([0.01, 0.5]))
    res = SimpleNamespace(freq_hz=np.array([1.0, 1.1]), X=np.zeros((2, 3, 1)), basis=None, outputs={"x": out})
    run = time_points.FillRun(None, res, None, None, 30.0, None, 1)
    assert run.checks([(1, 0.5)]) == []
    assert starts == ["the traced point", "the traced point at 1 Hz"]
    (p,) = run.points
    assert p["kind"] == "check" and p["hbm_off"] == pytest.approx(1.0)
    # found from another start, 100 % off where the point is estimated 50 %: maybe another
    # branch, so it is not read as the HBM's error
    assert not p["own_start"] and not p["same_branch"]
    note = fill_note({"points": [p], "stretches": [], "skipped": [], "seconds": 1.0, "budget": 30.0}, [5])
    assert "off by" not in note and "1 check found from another start" in note and "beyond the point's estimate" in note
