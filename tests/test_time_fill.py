"""Time-domain points where the continuation left the window untraced (hbm/analyses/time_fill.py).

The case: the undamped Jenkins oscillator at kt/k = 1e5, H = 15 (issue 17's den Hartog case).
Below 0.1015 Hz its mass sticks for most of the period and slips in short bursts: the
truncated series rings by far more than the contact's stick range (1.8e-5), so no
continuation reaches the window's start, and the traced point next to the stop is
estimated 55 % off.  The time integration answers there.
"""
from __future__ import annotations

import csv
from types import SimpleNamespace

import numpy as np
import pytest

import hbm
from hbm.analyses.time_fill import MIN_WIDTH, fill_frequencies, fill_untraced, spread_order, untraced_stretches
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


def _stiff_oscillator():
    return case_from_dict({
        "name": "undamped Jenkins, kt/k = 1e5",
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.0]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 1e5, "slip_force": 0.9}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 15, "frequency_hz": [0.0795775, 0.2], "outputs": {"x": 0}},
    })


def test_a_stop_short_of_the_window_is_answered_by_time_simulations(tmp_path):
    case = _stiff_oscillator()
    res = hbm.frf(case, stability=False)
    assert res.status == "failed"                    # the window's start is not reached (module doc)
    (a, b), = untraced_stretches(res)
    assert a == pytest.approx(0.0795775) and 0.09 < b < 0.11
    rec = fill_untraced(case, res, budget=12.0, max_points=3)
    assert res.settings["time_fill"] is rec
    freqs = [p["freq_hz"] for p in rec["points"]] + rec["skipped"]
    assert sorted(freqs)[0] == pytest.approx(a) and all(a <= f < b for f in freqs)
    ok = [p for p in rec["points"] if p["ok"]]
    assert ok, rec["note"]
    p = ok[0]                                        # the same answer as hbm timesim there
    ref = hbm.timesim(case, p["freq_hz"])
    assert p["h1"]["x"] == pytest.approx(ref.h1["x"], rel=1e-9) and p["error_estimate"] < 1e-2
    assert p["h1"]["x"] > 0.8                        # the HBM point next to the stop has 0.64-0.74
    (f_near, e_near), = rec["stretches"][0]["neighbour_errors"]
    assert f_near == pytest.approx(b) and e_near > 0.3
    assert "estimated" in rec["note"] and "H = 15" in rec["note"]
    write_frf(case, res, tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "frf_timedomain.csv")))
    assert [float(r["freq_hz"]) for r in rows] == pytest.approx([q["freq_hz"] for q in rec["points"]])
    assert all((r["x_h1"] != "") == bool(int(r["periodic"])) for r in rows)
    assert (tmp_path / "frf.png").stat().st_size > 0


def test_no_budget_simulates_nothing_and_says_so():
    case = _stiff_oscillator()
    res = hbm.frf(case, stability=False, error_estimate=False)
    rec = fill_untraced(case, res, budget=0.0, max_points=4)
    assert rec["points"] == [] and len(rec["skipped"]) == 4
    assert "0 of 4" in rec["note"] and "4 not simulated (budget 0 s)" in rec["note"]


def test_hbm_frf_writes_the_time_domain_points_and_says_where(tmp_path):
    import subprocess
    import sys
    toml = tmp_path / "stiff.toml"
    toml.write_text('name = "stiff"\n[model]\nmass = [[1.0]]\nstiffness = [[1.0]]\ndamping = [[0.0]]\n'
                    '[[element]]\ntype = "jenkins"\ndofs = [0]\nkt = 1e5\nslip_force = 0.9\n'
                    '[excitation]\ndofs = [0]\namplitude = [1.0]\n'
                    '[analysis]\nharmonics = 15\nfrequency_hz = [0.0795775, 0.2]\noutputs = { x = 0 }\n')
    run = lambda out, *extra: subprocess.run(   # noqa: E731
        [sys.executable, "-m", "hbm", "frf", str(toml), "-o", str(tmp_path / out), "--harmonics", "15",
         "--no-stability", "-q", *extra], capture_output=True, text=True)
    r = run("fill", "--time-fill", "3")
    assert r.returncode == 1, r.stderr              # the HBM run still stopped: said, not hidden
    assert "untraced 0.0795775..0.10146" in r.stdout and "frf_timedomain.csv" in r.stdout
    assert (tmp_path / "fill" / "frf_timedomain.csv").exists()
    r = run("none", "--time-fill", "0")
    assert r.returncode == 1 and not (tmp_path / "none" / "frf_timedomain.csv").exists()
    assert "time-domain points" not in r.stdout
