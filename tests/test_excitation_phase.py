"""Forces out of phase (``[excitation] phase_deg``): engine-order / travelling-wave excitation.

``F_i cos(w t - p_i)`` enters the balance as a cosine part ``F_i cos p_i`` and a sine part
``F_i sin p_i`` at harmonic 1, and the time stepper applies the same load."""
import pathlib

import numpy as np
import pytest

import hbm
from hbm.interface.case import CaseError, case_from_dict
from hbm.balance.condensed import condensed_balance
from hbm.balance.energy import energy_balance
from hbm.balance.fourier import FourierBasis
from hbm.analyses.response import build_problem, solve_at
from hbm.timedomain.timesim import TimeSimOptions, timesim

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _pair(phase, coupled=0.0, damping=2.0):
    """Two unit masses on 4e4 N/m springs, each with a Jenkins contact to ground, optionally
    coupled by a spring; 5 N on each with phases ``phase`` (degrees)."""
    k = 4e4
    return {"model": {"mass": [1.0, 1.0], "stiffness": [[k + coupled, -coupled], [-coupled, k + coupled]],
                      "damping": [damping, damping]},
            "element": [{"type": "jenkins", "dofs": [0], "kt": 2.667e4, "slip_force": 2.0},
                        {"type": "jenkins", "dofs": [1], "kt": 2.667e4, "slip_force": 2.0}],
            "excitation": {"dofs": [0, 1], "amplitude": [5.0, 5.0], "phase_deg": phase},
            "analysis": {"harmonics": 7, "time_samples": 256, "frequency_hz": [25.0, 45.0],
                         "outputs": {"x1": 0, "x2": 1}}}


def test_a_phase_is_a_time_shift_of_the_response():
    """Uncoupled identical oscillators, the second forced 90 degrees late: its response is the
    first's delayed by a quarter period, so harmonic h is rotated by h * 90 degrees."""
    X, basis, _ = solve_at(case_from_dict(_pair([0.0, 90.0])), 36.0)
    for h in (1, 3, 5, 7):
        r = basis.row_of(h, "c")
        a, b = X[r, 0], X[r + 1, 0]                      # x1 = a cos + b sin
        ph = h * np.pi / 2
        rot = (a * np.cos(ph) - b * np.sin(ph), a * np.sin(ph) + b * np.cos(ph))
        assert X[r, 1] == pytest.approx(rot[0], abs=1e-12 + 1e-9 * abs(a))
        assert X[r + 1, 1] == pytest.approx(rot[1], abs=1e-12 + 1e-9 * abs(b))
    r1, r3 = basis.row_of(1, "c"), basis.row_of(3, "c")
    assert np.hypot(*X[r3:r3 + 2, 0]) > 1e-3 * np.hypot(*X[r1:r1 + 2, 0])    # really nonlinear (0.3 %)


def test_balance_agrees_with_time_integration():
    case = case_from_dict(_pair([0.0, 60.0], coupled=1e4, damping=20.0))
    X, basis, problem = solve_at(case, 36.0)
    ts = timesim(case, 36.0, TimeSimOptions(steps=512, tol=1e-9))
    assert ts.converged
    for name, g in zip(("x1", "x2"), case.analysis.output_rows(case.n_dof)):
        x = X @ g
        r = basis.row_of(1, "c")
        h1 = np.hypot(x[r], x[r + 1])
        assert h1 == pytest.approx(ts.h1[name], rel=max(3 * ts.error_estimate, 1e-4))
    # the loads differ: with the phase the two masses no longer move alike
    assert abs(ts.h1["x1"] - ts.h1["x2"]) > 1e-3 * ts.h1["x1"]


def test_travelling_wave_rig_balances_energy():
    case = hbm.load_case(ROOT / "rigs" / "blade_pair_travelling.toml")
    assert np.allclose(case.excitation.force_sine[[0, 2]], [0.0, 1.0])
    res = hbm.frf(case, stability=False)
    assert res.ok and res.energy_error.max() < 1e-10
    a, b = res.outputs["blade_a"].h1, res.outputs["blade_b"].h1
    assert np.max(np.abs(a - b) / np.maximum(a, b)) > 0.05     # not the in-phase response


@pytest.mark.parametrize("change, needle", [
    (lambda t: t["excitation"].update(phase_deg=[0.0]), "one per DOF"),
    (lambda t: t["excitation"].update(phase_deg=[0.0, "x"]), "phase_deg must be a number"),
])
def test_bad_phases_are_refused(change, needle):
    raw = _pair([0.0, 90.0])
    change(raw)
    with pytest.raises(CaseError, match=needle):
        hbm.frf(case_from_dict(raw), stability=False)


@pytest.mark.parametrize("strategy", ["compiled", "dense"])
def test_condensed_solver_agrees_with_the_full_one(strategy):
    """Phased forces through the condensed solver (an excitation row for the cosine parts and
    one for the sine parts): with every mode kept it is the full model exactly."""
    raw = _pair([0.0, 60.0], coupled=1e4, damping=20.0)
    full = case_from_dict(raw)
    raw["model"].update(solver="condensed", modes="all")
    cond = case_from_dict(raw)
    basis = FourierBasis(full.analysis.harmonics, full.analysis.time_samples)
    ref, _ = build_problem(cond, basis, "auto")
    ex = cond.excitation
    p = condensed_balance(ref.linear.reduced, cond.elements, basis, ex.cos_sin,
                                 ref.nl.transform, ref.linear.output_rows, linear_strategy=strategy)
    assert p.linear._builder.strategy == strategy and p.linear.F_e.shape[1] == 2
    Xf, _, pf = solve_at(full, 36.0)
    w = 2 * np.pi * 36.0
    Xc = Xf @ p.linear.contact_rows.T                      # the contact coordinates of the full solution
    R = p.residual(Xc, w)[0]
    assert np.abs(R).max() <= 1e-9 * np.abs(pf.load(w)).max()
    assert np.allclose(p.recover_outputs(Xc, w), Xf @ full.analysis.output_rows(full.n_dof).T, rtol=0, atol=1e-12)
    e, ef = p.energy_balance(Xc, w), energy_balance(pf, Xf, w)
    assert e.excitation == pytest.approx(ef.excitation, rel=1e-8) and e.relative_error < 1e-8
    res = hbm.frf(cond, stability=False)
    assert res.ok and res.energy_error.max() < 1e-10
