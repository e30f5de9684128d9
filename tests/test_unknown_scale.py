"""The unknowns' scale: a coordinate that no linear response moves weighs the same on a full
and on a condensed model (the largest scale of the model, excitation and outputs included).

Measured cause (the coarse UPD flanks rig): a damper's out-of-plane position, held only by its
anchor springs once the flanks slip, took the condensed model's largest *contact* scale, 100x
below the full model's, and Newton's harmless wander along it was refused as a branch jump
at every step near a fold tip.
"""
import numpy as np

from hbm.analyses.problem_setup import _unknown_scale, build_problem
from hbm.balance.fourier import FourierBasis
from hbm.interface.case import case_from_dict


def _case(solver):
    """A 4-DOF chain excited at its tip (DOF 3) and two DOFs (4, 5) that only the contact
    reaches: the out-of-plane (t2) and normal (n) sides of a friction3d contact on DOF 1,
    each held by a weak anchor spring."""
    k = 1000.0
    K = np.zeros((6, 6))
    for i in range(3):
        K[i:i + 2, i:i + 2] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[0, 0] += k
    K[4, 4] = K[5, 5] = 5.0
    M = np.diag([1.0, 1.0, 1.0, 1.0, 0.05, 0.05])
    return case_from_dict({
        "model": {"mass": M.tolist(), "stiffness": K.tolist(), "modal_damping": 0.01, "solver": solver,
                  **({"modes": "all"} if solver == "condensed" else {})},
        "element": [{"type": "friction3d", "dofs": {"t1": 1, "t2": 4, "n": 5}, "kt": 2000.0, "kn": 2000.0,
                     "mu": 0.3, "normal_preload": 10.0}],
        "excitation": {"dofs": [3], "amplitude": [1.0]},
        "analysis": {"harmonics": 3, "time_samples": 32, "frequency_hz": [1.0, 8.0], "outputs": {"tip": 3}},
    })


def _scales(solver):
    case = _case(solver)
    basis = FourierBasis(case.analysis.harmonics, case.analysis.time_samples)
    p, _ = build_problem(case, basis, "auto")
    w_lo, w_hi = (2 * np.pi * f for f in case.analysis.freq_hz)
    s = _unknown_scale(p, case, w_lo, w_hi)[:p.n_unknowns // basis.n_coef]
    return p, s


def test_unreached_coordinate_takes_the_models_largest_scale_full_and_condensed():
    pf, sf = _scales("full")
    pc, sc = _scales("condensed")
    rows = pc.linear.contact_rows
    t2 = int(np.flatnonzero(np.abs(rows[:, 4]) > 0.5 * np.abs(rows).max())[0])
    assert np.count_nonzero(rows[t2]) == 1, "the t2 side is a contact coordinate of its own"
    # the full model: the unreached DOF takes the largest scale, the tip's
    assert sf[4] == sf.max() and sf[4] > 2 * sf[1]
    # the condensed model: the same scale, though no contact coordinate moves that much
    assert np.isclose(sc[t2], sf[4], rtol=1e-6)
    t1 = int(np.flatnonzero(np.abs(rows[:, 1]) > 0.5 * np.abs(rows).max())[0])
    assert sc[t2] > 2 * sc[t1]      # before: the largest contact scale, the t1 side's


def test_observed_peak_amplitudes_add_the_excitation_and_outputs():
    """Condensed: the free and stuck peaks of the excitation and output coordinates follow the
    contact ones, equal to the full model's at the same DOFs."""
    pf, _ = _scales("full")
    pc, _ = _scales("condensed")
    ws = 2 * np.pi * np.linspace(1.0, 8.0, 9)
    ff, stf = pf.linear_peak_amplitudes(ws, pf.stuck_stiffness(), observed=True)
    fc, stc = pc.linear_peak_amplitudes(ws, pc.stuck_stiffness(), observed=True)
    nc = pc.n_unknowns // pc.basis.n_coef
    assert fc.shape == (nc + 2,) and ff.shape == (6,)      # excitation and tip: DOF 3 twice
    for got, ref in ((fc, ff), (stc, stf)):
        assert np.allclose(got[nc:], ref[3], rtol=1e-9)
