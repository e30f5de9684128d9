"""The fixed-frequency polish of a traced point (hbm.analyses.polish.polish): it runs Newton
when the residual's work explains the energy imbalance, and returns the point after one
evaluation when it cannot (the imbalance is then not the residual's, so no update closes it)."""
import numpy as np

from hbm.analyses.problem_setup import solve_at
from hbm.analyses.polish import polish as _polish
from hbm.balance.energy import EnergyBalance
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
    Xq, err, floor = _polish(problem, Xp, w, np.full(problem.n_unknowns, 1.0), 1.0, eb)
    assert len(calls) >= 2 and floor == 0.0
    assert err < 1e-3 * eb.relative_error
    np.testing.assert_allclose(Xq, X, atol=1e-12 * np.abs(X).max())


def test_polish_skips_an_imbalance_the_residual_cannot_explain():
    w = 2 * np.pi * 0.13
    X, _, problem = solve_at(three_dof(), 0.13)
    true = problem.energy_balance(X, w)
    fake = EnergyBalance(true.excitation * (1 + 1e-6), true.viscous, true.nonlinear, true.bound)
    calls = counted(problem)
    Xq, err, floor = _polish(problem, X, w, np.full(problem.n_unknowns, 1.0), 1.0, fake)
    assert len(calls) == 1 and Xq is X and err == fake.relative_error
    assert floor == 0.0         # a full model's works use the residual's own matrices: no floor
