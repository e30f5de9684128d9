"""The fixed-frequency polish of a traced point (hbm.analyses.polish): it runs Newton when the
residual's work explains the energy imbalance or when the residual itself is loose, returns
the point after one evaluation when neither (the imbalance is then not the residual's, so no
update closes it), and refuses a point whose residual stays loose."""
import math

import numpy as np

import hbm
from hbm.analyses.polish import FORCE_LIMIT, POLISH_ENERGY, POLISH_FORCE, closed_balance, refused
from hbm.analyses.polish import polish as _polish
from hbm.analyses.problem_setup import _residual_scale, build_problem, solve_at
from hbm.balance.energy import EnergyBalance
from hbm.balance.fourier import FourierBasis
from test_truncation import three_dof


def counted(problem):
    calls = []
    real = problem.jacobian_into

    def wrapped(*a):
        calls.append(1)
        return real(*a)
    problem.jacobian_into = wrapped
    return calls


def test_polish_closes_an_imbalance_the_residual_explains():
    w = 2 * np.pi * 0.13
    X, _, problem = solve_at(three_dof(), 0.13)
    Xp = X * (1 + 1e-6)                                    # a residual of ~1e-6 of the load
    eb = problem.energy_balance(Xp, w)
    calls = counted(problem)
    Xq, err, floor, res = _polish(problem, Xp, w, np.full(problem.n_unknowns, 1.0), 1.0, eb, 1e-6)
    assert len(calls) >= 2 and floor == 0.0
    assert err < 1e-3 * eb.relative_error and res < 1e-12
    np.testing.assert_allclose(Xq, X, atol=1e-12 * np.abs(X).max())


def test_polish_skips_an_imbalance_the_residual_cannot_explain():
    w = 2 * np.pi * 0.13
    X, _, problem = solve_at(three_dof(), 0.13)
    true = problem.energy_balance(X, w)
    fake = EnergyBalance(true.excitation * (1 + 1e-6), true.viscous, true.nonlinear, true.bound)
    calls = counted(problem)
    Xq, err, floor, res = _polish(problem, X, w, np.full(problem.n_unknowns, 1.0), 1.0, fake, 0.0)
    assert len(calls) == 1 and Xq is X and err == fake.relative_error
    assert floor == 0.0         # a full model's works use the residual's own matrices: no floor


def test_a_residual_that_does_no_work_is_polished():
    """A point off the solution along a direction whose residual is orthogonal to the
    velocity: its energy balance is closed to second order, so only the residual check can
    see it (the continuation reported such a point at 2e-3 of the load on a stiff contact)."""
    f = 0.13
    w = 2 * np.pi * f
    X, _, problem = solve_at(three_dof(), f)
    R, J, _ = problem.residual(X, w)
    dx = problem.unknowns(problem.basis.D @ X)              # the residual's work is pi R . (D X)
    u = np.random.default_rng(1).standard_normal(dx.size)
    u -= (u @ dx) / (dx @ dx) * dx
    r_scale = _residual_scale(problem, w)
    v = np.linalg.solve(J, u)
    Xp = problem.expand(problem.unknowns(X) + 1e-7 * r_scale / np.abs(u).max() * v)
    eb, r = problem.balance_check(Xp, w, residual=True)
    assert eb.relative_error < POLISH_ENERGY < POLISH_FORCE < r / r_scale      # energy alone passes
    Xq, err, floor, res = closed_balance(problem, Xp, w, np.full(problem.n_unknowns, 1.0), r_scale)
    assert res < 1e-12 and err < 1e-12 and not refused(err, floor, res)
    np.testing.assert_allclose(Xq, X, atol=1e-10 * np.abs(X).max())


def test_a_loose_residual_is_refused():
    assert refused(0.0, 0.0, 2 * FORCE_LIMIT) and not refused(0.0, 0.0, 0.5 * FORCE_LIMIT)


def test_every_reported_point_of_a_stiff_contact_is_a_solution():
    """Undamped Jenkins oscillator, kt/k = 1e5, H = 15, exact switches: the path stops where
    the truncated motion cannot stick, and traced from the top down its residual test is
    relative to a row norm ~1e6 (the mass term at fmax).  Before the residual check its last
    point was reported with |R| = 2e-3 of the load (energy error 2e-10): every point's
    residual is now within FORCE_LIMIT of the load."""
    case = hbm.case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.0]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 1e5, "slip_force": 0.9, "aft": "events"}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 15, "frequency_hz": [0.5 / (2 * math.pi), 1.5 * math.sqrt(1 + 1e5) / (2 * math.pi)],
                     "outputs": {"x": 0}}})
    res = hbm.frf(case, stability=False, error_estimate=False)
    assert res.X.shape[0] > 100
    problem, _ = build_problem(case, FourierBasis(res.basis.harmonics, res.basis.n_samples), "auto", None)
    ws = 2 * np.pi * res.freq_hz
    r_scale = _residual_scale(problem, ws.min())
    worst = max(np.abs(problem.residual(X, w)[0]).max() for X, w in zip(res.X, ws)) / r_scale
    assert worst <= FORCE_LIMIT
