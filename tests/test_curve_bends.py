"""Chords within CURVE_TOL of the path (issue 18 item 3): the drawn curve of NLvib's examples 02
(cubic springs, folds) and 08 (a clamped beam with a saturation friction law, stick-to-slip
corners) and of the 3-DOF two-Jenkins chain, against a path traced in steps ten times shorter."""
import dataclasses

import numpy as np
import pytest

import hbm
import hbm.analyses.curve_bends as cb
from continuation import ArclengthOptions
from hbm.analyses.curve_bends import CURVE_TOL, chord_sags
from test_truncation import three_dof


def test_sag_estimate_on_a_circle():
    r, d = 0.5, 0.02                 # radius and angle between points, in (ln f, ln a)
    phi = -1.2 + d * np.arange(40)
    w = np.exp(1.0 + r * np.cos(phi))
    a = np.exp(r * np.sin(phi))
    sag = chord_sags(w, a[:, None])
    true = r * (1 - np.cos(d / 2))
    assert sag == pytest.approx(np.full(39, true), rel=1e-3)
    assert chord_sags(np.exp(np.linspace(0, 1, 9)), np.exp(np.linspace(0, 2, 9))[:, None]) \
        == pytest.approx(np.zeros(8), abs=1e-15)


def _beam(L=2.0, n_nodes=9, E=185e9, rho=7830.0):
    """Clamped-free Euler-Bernoulli beam of NLvib's example 08 (height L/20, width 3 heights)."""
    h = 0.05 * L
    b, le = 3 * h, L / (n_nodes - 1)
    A, I = b * h, b * h**3 / 12
    k = E * I / le**3 * np.array([[12, 6 * le, -12, 6 * le], [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                                  [-12, -6 * le, 12, -6 * le], [6 * le, 2 * le**2, -6 * le, 4 * le**2]])
    m = rho * A * le / 420 * np.array([[156, 22 * le, 54, -13 * le], [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                                       [54, 13 * le, 156, -22 * le], [-13 * le, -3 * le**2, -22 * le, 4 * le**2]])
    n = 2 * n_nodes
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for e in range(n_nodes - 1):
        K[2 * e:2 * e + 4, 2 * e:2 * e + 4] += k
        M[2 * e:2 * e + 4, 2 * e:2 * e + 4] += m
    return K[2:, 2:], M[2:, 2:]


def nlvib08():
    """Example 08: friction (limit force 1.5, regularised by NLvib's eps) at node 4, 0.2 N at the
    tip, 1 % stiffness-proportional damping of the stuck mode, H = 13, from 0.9 times the free
    to 1.5 times the stuck first resonance; the saturation law instead of tanh."""
    from scipy.linalg import eigh
    K, M = _beam()
    n, nl, tip = K.shape[0], 4, K.shape[0] - 2
    keep = [i for i in range(n) if i != nl]
    om_free = np.sqrt(eigh(K, M, eigvals_only=True)[0])
    om_stuck = np.sqrt(eigh(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], eigvals_only=True)[0])
    D = 2e-2 / om_stuck * K
    F = np.zeros(n)
    F[tip] = 0.2
    eps = om_free * abs(np.linalg.solve(-(1.5 * om_stuck)**2 * M + 1.5j * om_stuck * D + K, F)[nl])
    return hbm.case_from_dict({
        "model": {"mass": M, "stiffness": K, "damping": D},
        "element": [{"type": "coulomb_regularised", "dofs": [nl], "slip_force": 1.5, "v_r": float(eps),
                     "law": "linear"}],
        "excitation": {"dofs": [tip], "amplitude": [0.2]},
        "analysis": {"harmonics": 13, "time_samples": 128,
                     "frequency_hz": [0.9 * om_free / (2 * np.pi), 1.5 * om_stuck / (2 * np.pi)],
                     "outputs": {"tip": tip, "friction": nl}}})


def nlvib02():
    """Example 02: masses 1 and 0.05, springs 1 and 0.0453, dampers 0.002 and 0.013, cubic
    springs 1 (ground) and 0.0042 (between), force 0.11, 0.8-1.4 rad/s."""
    return hbm.case_from_dict({
        "model": {"mass": [1.0, 0.05], "stiffness": [[1.0453, -0.0453], [-0.0453, 0.0453]],
                  "damping": [[0.015, -0.013], [-0.013, 0.013]]},
        "element": [{"type": "cubic", "dofs": [0], "k3": 1.0}, {"type": "cubic", "dofs": [0, 1], "k3": 0.0042}],
        "excitation": {"dofs": [0], "amplitude": [0.11]},
        "analysis": {"harmonics": 7, "time_samples": 256, "frequency_hz": [0.8 / (2 * np.pi), 1.4 / (2 * np.pi)],
                     "outputs": {"x1": 0, "x2": 1}}})


def curve_distance(res, ref, name):
    """Largest distance of the reference path's points from the drawn chords of ``res``, in
    (ln f, ln a) (a relative error in frequency or amplitude)."""
    P = np.c_[np.log(ref.freq_hz), np.log(ref.outputs[name].h1)]
    V = np.c_[np.log(res.freq_hz), np.log(res.outputs[name].h1)]
    A = np.concatenate([V[s:e - 1] for s, e in res.settings["segments"]])
    B = np.concatenate([V[s + 1:e] for s, e in res.settings["segments"]])
    d = B - A
    t = np.clip(((P[:, None] - A[None]) * d[None]).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0, 1)
    return np.sqrt(((P[:, None] - A[None] - t[..., None] * d[None])**2).sum(-1)).min(axis=1).max()


def _reference(case):
    fine = dataclasses.replace(case, analysis=dataclasses.replace(case.analysis, max_points=100000))
    return hbm.frf(fine, stability=False, error_estimate=False, options=ArclengthOptions(ds_max=0.001, max_steps=50000))


@pytest.mark.parametrize("make, needed", [(nlvib08, False), (three_dof, True), (nlvib02, False)])
def test_drawn_curve_within_the_tolerance(make, needed, monkeypatch):
    """``needed``: without the bend points the chords of this case stray beyond the tolerance
    (a bump at 0.12 Hz that one long step jumped over, 0.78 %)."""
    case = make()
    ref = _reference(case)
    assert ref.ok, ref.message
    told = []
    res = hbm.frf(case, stability=False, error_estimate=False, progress=lambda n, f: told.append(n))
    assert res.ok and res.settings["bend_points_added"] > 0
    st = res.settings       # the chords traced again report their points too
    assert max(told) >= res.freq_hz.size - st["peak_points_added"] - 1
    assert res.energy_error.max() < 1e-8
    for name in case.analysis.outputs:
        assert curve_distance(res, ref, name) < CURVE_TOL, name
    if needed:
        monkeypatch.setattr(cb, "ROUNDS", 0)
        plain = hbm.frf(case, stability=False, error_estimate=False)
        assert max(curve_distance(plain, ref, n) for n in case.analysis.outputs) > CURVE_TOL


def test_a_chord_between_two_branches_is_not_filled():
    """Two solutions at nearby frequencies on the upper and the lower branch of example 02 (between
    its folds): a trace from one never arrives at the other, so nothing is inserted; the same
    chord on one branch is filled."""
    from hbm.analyses.curve_bends import retrace_chord
    from hbm.analyses.problem_setup import _residual_scale, _unknown_scale, build_problem, resolve_settings
    from hbm.analyses.traced_points import TracedPoints
    from hbm.balance.fourier import FourierBasis
    case = nlvib02()
    res = hbm.frf(case, stability=False, error_estimate=False)
    w = 2 * np.pi * res.freq_hz
    turn = int(np.flatnonzero(np.diff(w) < 0)[0])     # the first fold: the upper branch ends there
    lower = turn + 1 + int(np.argmin(np.abs(w[turn + 1:] - w[turn - 3])))
    h, N, lo, hi, tr = resolve_settings(case, None, None, None, None, None)
    problem, _ = build_problem(case, FourierBasis(h, N), tr)
    xscale = _unknown_scale(problem, case, 2 * np.pi * lo, 2 * np.pi * hi)
    r_scale = _residual_scale(problem, 2 * np.pi * lo)

    def chord(i, j):
        pts = TracedPoints()
        for k in (i, j):
            pts.X.append(res.X[k]), pts.w.append(w[k]), pts.Y.append(res.Y[k])
            pts.its.append(1), pts.err.append(0.0), pts.unclosed.append(0)
        segments = [[0, 2]]
        n = retrace_chord(problem, case, pts, segments, 0, 0, 4, xscale, r_scale)
        return n, len(pts.w), segments

    assert abs(w[lower] - w[turn - 3]) < 0.01 * w[turn]
    assert res.outputs["x1"].h1[turn - 3] > 1.5 * res.outputs["x1"].h1[lower]
    assert chord(turn - 3, lower) == (0, 2, [[0, 2]])
    n, size, segments = chord(turn - 6, turn - 3)
    assert n >= 1 and size == n + 2 and segments == [[0, n + 2]]
