"""Marches at fixed frequencies across the gaps the continuation leaves (hbm.analyses.gap_bridge):
they pass kinks and bands where Newton fails, stop at jumps, and the points they add are
solutions of the balance."""
import sys
from pathlib import Path

import numpy as np

import hbm
from hbm.analyses import gap_bridge
from hbm.analyses.gap_bridge import MAX_CHANGE, MEET, march

sys.path.insert(0, str(Path(__file__).resolve().parent / "stress"))
import cases  # noqa: E402


class _Exact:
    """A marcher whose Newton lands on ``path(w)`` (n,) wherever that is defined (not None)."""

    def __init__(self, path, budget=400):
        self.path, self.budget, self.frequencies = path, budget, []

    def solve(self, guess):
        self.budget -= 1
        w = float(guess[-1])
        self.frequencies.append(w)
        u = self.path(w)
        return None if u is None else (np.r_[u, w], 3, 0.0, 0)

    def change(self, new, old):
        return gap_bridge._rel(new, old)


def _v(path, w):
    return np.r_[path(w), w]


def _kinked(w):
    """Continuous; at w = 1.5 its slope grows 2000-fold (a contact starting to slip)."""
    return np.array([1.0 + 1e-4 * w + 0.2 * max(w - 1.5, 0.0), 2.0])


def _jumping(w):
    """A 2 % jump at w = 1.5 (another branch), under the march's largest step change."""
    return np.array([1.0 + 1e-4 * w + (0.05 if w >= 1.5 else 0.0), 2.0])


def test_a_kink_is_passed_and_the_march_joins_the_target():
    m = _Exact(_kinked)
    pts, joined = march(m, _v(_kinked, 1.0), 2.0, _v(_kinked, 2.0), rate=1e-4 / 2.2)
    assert joined
    ws = [p[0][-1] for p in pts]
    assert np.all(np.diff(ws) > 0) and ws[0] > 1.0 and ws[-1] < 2.0
    assert any(1.5 < w < 1.6 for w in ws)                     # it went on past the kink in steps


def test_a_jump_ends_the_march_next_to_it():
    m = _Exact(_jumping)
    pts, joined = march(m, _v(_jumping, 1.0), 2.0, _v(_jumping, 2.0), rate=1e-4 / 2.2)
    assert not joined
    last = pts[-1][0][-1]
    assert 1.5 - 1e-3 < last < 1.5                            # stopped within a few smallest steps
    assert all(p[0][0] < 1.01 for p in pts)                   # no point taken on the other side


def test_a_band_where_newton_fails_is_leapt_over():
    def holed(w):
        return None if 1.30 < w < 1.33 else _kinked(w)
    m = _Exact(holed)
    pts, joined = march(m, _v(holed, 1.0), 2.0, _v(holed, 2.0), rate=1e-4 / 2.2)
    assert joined and not any(1.30 < p[0][-1] < 1.33 for p in pts)


def test_a_march_that_arrives_on_another_solution_does_not_join():
    m = _Exact(_kinked)
    other = _v(_kinked, 2.0) * (1 + 10 * MEET)
    _, joined = march(m, _v(_kinked, 1.0), 2.0, other, rate=1e-4 / 2.2)
    assert not joined


def test_the_stuck_contacts_slip_onset_is_bridged_with_solutions_of_the_balance():
    """friction3d, force ratio 100, kt/k = 1e4, H = 5, closed: the path stops where the stuck
    contact starts to slip on its needle resonance (15.8365 Hz; the slider's offset then turns
    steeply at a kink); the march up from the stop and the one down from the restart meet on
    one solution, and the FRF has no gap.  Every point added solves the balance and closes the
    energy, and no step changes the response by more than the march allows."""
    case = hbm.case_from_dict(cases.friction3d_2dof(100.0, 1e4, 5, False))
    res = hbm.frf(case, stability=False, error_estimate=False)
    assert res.status == "finished" and not res.settings.get("gaps") and "gap_warning" not in res.settings
    (b,) = res.settings["gaps_bridged"]
    assert b["joined"] and b["points"] >= 3 and 15.83 < b["from_hz"] < b["to_hz"] < 15.84
    inside = np.flatnonzero((res.freq_hz >= b["from_hz"]) & (res.freq_hz <= b["to_hz"]))
    assert inside.size == b["points"] + 2 and np.all(np.diff(inside) == 1)
    problem, _ = hbm.analyses.problem_setup.build_problem(case, res.basis, res.settings["transform"],
                                                         res.settings["fmax_hz"])
    load = np.linalg.norm(problem.residual(problem.expand(np.zeros(problem.n_unknowns)), 1.0)[0])
    for i in inside:
        R = problem.residual(res.X[i], 2 * np.pi * res.freq_hz[i])[0]
        assert np.linalg.norm(R) < 1e-8 * load
        assert res.energy_error[i] < 1e-8
    u = res.X[inside].reshape(inside.size, -1)
    step = np.linalg.norm(np.diff(u, axis=0), axis=1) / np.linalg.norm(u[1:], axis=1)
    assert step.max() <= MAX_CHANGE * 1.001


def test_a_gap_not_matching_two_segments_is_kept_as_it_is():
    settings = {"gaps": [{"from_hz": 1.0, "to_hz": 2.0, "reason": "r", "h1_change": 0.5, "change": 0.5}]}
    pts = gap_bridge.TracedPoints()
    for w in (1.0, 3.0):
        for name, val in zip(pts.FIELDS, (np.zeros((1, 1)), w, np.zeros((1, 1)), 1, 0.0, 0)):
            getattr(pts, name).append(val)
    case = type("C", (), {"analysis": type("A", (), {"max_points": 100})()})()
    gap_bridge.bridge_gaps(None, case, pts, [[0, 1], [1, 2]], settings, None, 1.0)
    assert settings["gaps"][0]["from_hz"] == 1.0 and settings["gaps_bridged"] == [] and len(pts.w) == 2


def test_the_console_says_what_the_marches_did(capsys):
    from hbm.interface.frf_console import _print_notes
    _print_notes({"gaps_bridged": [{"from_hz": 1.0, "to_hz": 1.1, "points": 14, "joined": True},
                                   {"from_hz": 2.0, "to_hz": 2.1, "points": 3, "joined": False}]})
    out = capsys.readouterr().out
    assert "2 stop(s) of the continuation marched across at fixed frequencies (17 points)" in out
    assert "1 joined the path again, 1 narrowed" in out


def _stuck_and_slipping_points():
    """A marcher on the friction3d point contact and one of its points per force ratio: 1e5
    (the contact sticks the whole period) and 1 (it slips)."""
    from hbm.analyses.problem_setup import (_first_point, _residual_scale, _unknown_scale, build_problem,
                                            resolve_settings)
    from hbm.balance.fourier import FourierBasis
    out = []
    for ratio in (1e5, 1.0):
        case = hbm.case_from_dict(cases.friction3d_2dof(ratio, 1.0, 3, False))
        h, N, lo, hi, tr = resolve_settings(case)
        problem, _ = build_problem(case, FourierBasis(h, N), tr, hi)
        w = 2 * np.pi * 0.2
        xscale = _unknown_scale(problem, case, 2 * np.pi * lo, 2 * np.pi * hi)
        r_scale = _residual_scale(problem, w)
        X, _ = _first_point(problem, case, w, xscale, r_scale)
        out.append((gap_bridge._Marcher(problem, xscale, r_scale), np.r_[problem.unknowns(X), w], problem))
    return out


def test_a_stuck_contacts_static_offset_is_no_change_of_the_path():
    """Where a contact sticks the whole period its slider offset, hence the mean of the
    solution, is one of a family: a march compares the harmonics above the mean alone there
    (it passes the point where the contact starts to open, whose offset the motion fixes),
    and every coefficient where the contact slips."""
    (stuck, v, problem), (slipping, v2, _) = _stuck_and_slipping_points()
    nc = problem.basis.n_coef
    static = np.zeros(v.size, dtype=bool)
    static[:-1] = np.repeat((problem.basis.h_of_row == 0)[:, None], (v.size - 1) // nc, axis=1).ravel()
    moved = v + 0.3 * static * np.abs(v).max()
    assert gap_bridge._rel(moved, v) > 0.05
    assert stuck.change(moved, v) == 0.0
    shaken = v * np.where(static, 1.0, 1.1)
    assert np.isclose(stuck.change(shaken, v), gap_bridge._rel(shaken[~static], v[~static]))
    moved2 = v2 + 0.3 * static * np.abs(v2).max()
    assert slipping.change(moved2, v2) == gap_bridge._rel(moved2, v2) > 0.05
