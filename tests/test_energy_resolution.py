"""The energy balance's resolution on a condensed FE contact patch next to a mode its stuck
contacts block (hbm.balance.condensed.CondensedLinear.work_resolution).

Two small clamped columns (882 DOFs, ``tests/fe_patch.py``) meet on 16 ``friction3d``
contacts that stay stuck (0.05 % modal damping): the response is linear and its exact
solution is one linear solve.  The free structure (contacts open) has a mode pair at
7004.7 Hz that the stuck contacts block; there ``H_cc`` is nearly singular and the
residual's ``Z = H_cc^{-1}`` and the works' modal sums agree only to ``eps cond(H_cc)``: the
energy imbalance of the exact solution (1e-8 of the works, residual 1e-13) is that
disagreement, which the resolution states."""
import numpy as np
import pytest

from fe_patch import column_patch_case
from hbm.analyses.problem_setup import build_problem, resolve_settings
from hbm.analyses.response import frf
from hbm.balance.fourier import FourierBasis

F_MODE = 7004.74          # Hz, the blocked mode pair of column_pair(n_s=6, n_z=3)


@pytest.fixture(scope="module")
def patch_case(tmp_path_factory):
    return column_patch_case(tmp_path_factory.mktemp("cols"), 16, 0.0005, (6900.0, 7100.0))


def _exact_stuck(problem, w):
    X = problem.linear_solution(w, problem.stuck_stiffness())
    for _ in range(3):
        R, J, _ = problem.residual(X, w)
        X = problem.expand(problem.unknowns(X) - np.linalg.solve(J, R))
    return X


def test_imbalance_of_the_exact_stuck_solution_is_the_resolution(patch_case):
    h, N, _, hi, tr = resolve_settings(patch_case)
    problem, _ = build_problem(patch_case, FourierBasis(h, N), tr, hi)
    assert np.any(np.abs(problem.linear.reduced.omega / (2 * np.pi) - F_MODE) < 0.01)
    rng = np.random.default_rng(0)
    for f in (0.998 * F_MODE, 1.002 * F_MODE):
        w = 2 * np.pi * f
        X = _exact_stuck(problem, w)
        R = problem.residual(X, w)[0]
        assert np.abs(R).max() < 1e-12 * 20.0
        eb = problem.energy_balance(X, w)
        imbalance = abs(eb.excitation - eb.viscous - eb.nonlinear)
        assert eb.relative_error > 1e-9                       # far above what |R| explains
        assert abs(imbalance - problem.energy_resolution(X, w)) <= 0.01 * imbalance
        # a point off the solution by 1e-5 of its motion (|R| ~ 1e-4 of the force): the
        # resolution is the linear part's, not the point's, and the balance still sees it
        Xb = X * (1 + 1e-5 * rng.standard_normal(X.shape))
        eb_b = problem.energy_balance(Xb, w)
        assert abs(problem.energy_resolution(Xb, w) / problem.energy_resolution(X, w) - 1) < 0.01
        assert abs(eb_b.excitation - eb_b.viscous - eb_b.nonlinear) > 30 * problem.energy_resolution(Xb, w)


def test_frf_through_the_blocked_mode_is_not_stopped_by_the_balance(patch_case):
    """Points whose imbalance is the resolution's are kept (with their error as computed):
    the FRF is one segment over the window.  Judged against 1e-8 alone, points near the mode
    (errors 5e-8) ended the path four times and 6994-7020 Hz was left untraced."""
    res = frf(patch_case, stability=False, error_estimate=False)
    assert res.status == "finished", res.message
    assert res.settings["segments"] == [[0, res.freq_hz.size]]
    assert res.freq_hz.max() >= 7100.0 * (1 - 1e-9)
