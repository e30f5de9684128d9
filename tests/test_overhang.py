"""Branches that overhang a jump (:mod:`hbm.analyses.overhang`): the traces from both sides of
a junction of two segments, against the time domain, and how they are spliced."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import hbm
from hbm.analyses import overhang
from hbm.analyses.traced_points import TracedPoints
from hbm.interface.frf_plot import gap_starts
from hbm.timedomain.floquet_check import check_point

sys.path.insert(0, str(Path(__file__).parent / "stress"))
import cases  # noqa: E402


def test_a_separating_contacts_upper_branch_is_traced_round_its_fold():
    """friction3d, force ratio 100, kt/k = 1e4, H = 15, the contact separating: the softening
    resonance jumps at 0.2094 Hz; the path stopped where the contact starts to open and the
    marches met across the jump, so the upper branch below it was missing (the peak drawn
    11.1; it is 41.2, at 0.1915 Hz).  Traced from the jump's upper side it creeps where the
    stuck contact's slider offset is nearly free, hops on past that by a march and turns the
    branch's fold at 0.1913 Hz; the lower branch is turned at its fold too, so every frequency
    lies on a traced branch, the middle branch left between the folds is stated, and
    upper-branch points are the periodic time solution."""
    case = hbm.case_from_dict(cases.friction3d_2dof(100.0, 1e4, 15, True))
    res = hbm.frf(case, stability=False, error_estimate=False)
    assert res.status == "finished" and not res.settings.get("gaps"), res.settings.get("gap_warning")
    assert np.all(res.energy_error < 1e-8)
    n, f = res.outputs["n"].h1, res.freq_hz
    assert n.max() > 40.0
    (mid,) = res.settings["middle_gaps"]
    assert "every frequency of the window lies on a traced branch" in res.settings["middle_gap_note"]
    # the upper branch's fold is its lowest frequency traced, a fold of the path
    near = (f > 0.17) & (f < 0.22)
    f_fold = f[near & (n > 12.0)].min()
    assert np.abs(np.array(res.folds_hz) - f_fold).min() < 1e-5 * f_fold and f_fold < mid["from_hz"]
    for target in (0.1915, 0.206):
        upper = np.flatnonzero(near & (n > 12.0))
        i = upper[np.argmin(np.abs(f[upper] - target) - 1e-3 * n[upper])]      # the upper branch there
        got = check_point(case, res.basis, res.X[i], f[i], steps=2048)
        assert got.converged and got.distance < 0.05
        assert abs(got.h1["n"] - n[i]) < 1e-3 * n[i], (f[i], got.h1["n"], n[i])
    assert any(o["sides_folded"] == 2 for o in res.settings["overhangs"])
    # segments that are not one path are drawn apart (no chord across the middle branch)
    assert gap_starts(res.settings) == [s[0] for s in res.settings["segments"][1:]]


def _path(ws, level):
    pts = TracedPoints()
    for w in ws:
        pts.append(np.array([[level + w]]), w, np.array([[level + w]]), 1, 0.0, 0)
    return pts


class _Seen:
    def __init__(self, chord=None, folds=0):
        self.chord, self.folds, self.folds_hz, self.seen = chord, folds, [], 3


def test_a_trace_from_above_that_arrives_below_is_spliced_in_reversed(monkeypatch):
    """The trace down from the upper segment turns two folds and arrives on the lower segment's
    chord 1 (between its points 1 and 2, travelling against them): the path is the lower
    segment up to that chord, the trace reversed, then the upper segment."""
    low, high = _path([1.0, 2.0, 3.0], 0.0), _path([3.0, 4.0], 10.0)
    down = _path([2.9, 2.8, 2.5], 5.0)        # kept points after the start, in tracing order
    runs = iter([(TracedPoints(), _Seen()), (down, _Seen(chord=1, folds=2))])
    monkeypatch.setattr(overhang, "_run", lambda *a: next(runs))
    joined, path, rest, _, _ = overhang._overhang(None, low, high)
    assert joined and rest is None
    assert path.w == [1.0, 2.0, 2.5, 2.8, 2.9, 3.0, 4.0]


def test_a_trace_that_arrives_on_the_other_side_continues_with_its_next_point(monkeypatch):
    low, high = _path([1.0, 2.0], 0.0), _path([2.0, 3.0, 4.0], 10.0)
    up = _path([2.5, 3.5], 10.0)
    monkeypatch.setattr(overhang, "_run", lambda *a: (up, _Seen(chord=1, folds=2)))
    joined, path, _, _, _ = overhang._overhang(None, low, high)
    assert joined and path.w == [1.0, 2.0, 2.5, 3.5, 4.0]


def test_the_watch_joins_only_travelling_the_way_the_other_side_continues():
    target = _path([1.0, 2.0, 3.0], 0.0)
    w = overhang._Watch(target, +1, budget=50, along=1)
    assert not w(np.array([[0.5]]), 0.5)                     # the start
    assert w(np.array([[1.5]]), 1.5) and w.chord == 0         # on chord 0, going up as it does
    back = overhang._Watch(target, +1, budget=50, along=-1)
    back(np.array([[0.5]]), 0.5)
    assert not back(np.array([[1.5]]), 1.5)                   # same place, wrong way for a splice
    assert back(np.array([[1.0]]), 1.0) and back.chord == 0 and back.folds == 1   # turned, arriving against it
