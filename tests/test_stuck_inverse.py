"""The stuck-contact inverse of a condensed balance (hbm.balance.stuck_inverse) as the first
preconditioner of the Newton solves (continuation.linsolve.BlockPreconditioned).

A 16-contact FE patch (``tests/fe_patch.py``; Woodbury form, 336 unknowns): with every contact
stuck the approximate inverse is the Jacobian's inverse; in a solve it is taken first and
GMRES then stops after one iteration, scaled or bordered; where contacts slip the solves
still give the direct path's FRF."""
import numpy as np
import pytest

import continuation.linsolve as linsolve
from continuation.linsolve import BlockPreconditioned, direct_solve
from fe_patch import column_patch_case
from hbm.analyses.problem_setup import build_problem, resolve_settings
from hbm.analyses.stuck import stuck_contacts
from hbm.balance.fourier import FourierBasis


@pytest.fixture(scope="module")
def patch(tmp_path_factory):
    case = column_patch_case(tmp_path_factory.mktemp("cols"), 16, 0.002, (8200.0, 8700.0), force=200.0)
    h, N, _, hi, tr = resolve_settings(case)
    problem, _ = build_problem(case, FourierBasis(h, N), tr, hi)
    return case, problem


def _stuck_state(problem, f_hz):
    """A small response (every contact stuck) at ``f_hz``: ``(X, w, R, J, dR/dw)``."""
    w = 2 * np.pi * f_hz
    X = 1e-3 * problem.linear_solution(w, problem.stuck_stiffness())
    R, J, dRw = problem.residual(X, w)
    return X, w, R, J, dRw


def test_inverse_is_exact_when_every_contact_sticks(patch):
    _, problem = patch
    st = problem.solver_structure()
    assert problem.linear._builder.strategy == "woodbury" and st.approximate is not None
    rng = np.random.default_rng(0)
    for f in (8250.0, 8600.0):
        X, w, R, J, _ = _stuck_state(problem, f)
        assert stuck_contacts(problem, X[None], np.array([w]))[0] == 16
        v = rng.normal(size=R.size)
        y = st.approximate()(v)
        ref = np.linalg.solve(J, v)
        assert np.abs(y - ref).max() <= 1e-9 * np.abs(ref).max()


def test_solver_takes_it_first_on_a_scaled_bordered_matrix(patch):
    """Column-scaled and bordered like the continuation's Newton matrix: one GMRES iteration
    on the approximate inverse, no block factorisation, the direct solution."""
    _, problem = patch
    X, w, R, J, dRw = _stuck_state(problem, 8400.0)
    n = R.size
    rng = np.random.default_rng(1)
    scale = np.r_[np.abs(problem.unknowns(X)).max() * (1 + rng.random(n)), 2 * np.pi * 100.0]
    A = np.empty((n + 1, n + 1))
    A[:n, :n], A[:n, n] = J, dRw
    A[n] = rng.normal(size=n + 1)
    A *= scale
    B = rng.normal(size=(n + 1, 1))
    s = linsolve.make_solver(n + 1, problem.solver_structure(), scale=scale)
    Xs = s(A, B)
    assert s.approximate_solves == 1 and s.block_solves == 0 and s.krylov_iterations == 1
    ref = direct_solve(A.copy(order="F"), B)
    assert np.abs(Xs - ref).max() <= 1e-6 * np.abs(ref).max()
    assert np.abs(A @ Xs - B).max() <= 1e-6 * np.abs(B).max()


def test_a_failing_approximate_inverse_falls_back_and_pauses():
    """An approximate inverse that does not precondition (the identity, on a matrix far from
    it) costs one failed GMRES; the blocks solve exactly and the next calls skip it."""
    rng = np.random.default_rng(2)
    n = 40
    A = rng.normal(size=(n, n)) + 3 * np.eye(n)
    calls = []
    s = BlockPreconditioned([(0, 20), (20, 40)], rtol=1e-10, max_krylov=5,
                            approximate=lambda: calls.append(1) or (lambda v: v.copy()))
    B = rng.normal(size=(n, 1))
    for k in range(3):
        Xs = s(A, B)
        assert np.abs(A @ Xs - B).max() <= 1e-8 * np.abs(B).max()
    assert len(calls) == 1 and s.approximate_solves == 0 and s._skip == linsolve.APPROXIMATE_PAUSE - 2


def test_frf_with_the_stuck_inverse_equals_the_direct_path(patch, monkeypatch):
    """200 N on the 16-contact patch, 8200-8700 Hz: all contacts stick at 43 points and some
    slip at 49; the
    FRF solved with the stuck inverse first equals the direct LU path's to 1e-8 at every
    point's frequency (``tests/test_linsolve._same_frf``, each Newton solve started from the
    direct path's point nearest in frequency: the two paths step differently, 92 and 94
    points)."""
    from types import SimpleNamespace
    from hbm.analyses.response import frf
    from test_linsolve import _same_frf
    case, _ = patch
    new = frf(case, stability=False, error_estimate=False)
    assert 0 < np.count_nonzero(new.stuck < 16) < new.freq_hz.size     # both states on the path
    monkeypatch.setattr(linsolve, "BLOCK_MIN_SIZE", 10 ** 9)
    ref = frf(case, stability=False, error_estimate=False)
    near = [int(np.argmin(np.abs(ref.freq_hz - f))) for f in new.freq_hz]
    _same_frf(case, SimpleNamespace(status=ref.status, freq_hz=ref.freq_hz[near], X=ref.X[near]), new)


def test_hill_system_through_the_stuck_stiffness_equals_the_whole_solve(patch, monkeypatch):
    """Hill's modal system (hbm.analyses.modal_hill) formed through the stuck stiffness
    (a system of the slipping rows only; none where every contact sticks) equals the whole
    system's (every row of ``I + R J_nl``), to 1e-10, at points where all 16 contacts stick,
    where some slip and where most do."""
    import hbm.analyses.modal_hill as mh
    from hbm.analyses.hill_system import HillSystem
    from hbm.analyses.modal_hill import modal_hill_system
    from hbm.analyses.response import frf
    case, problem = patch
    res = frf(case, stability=False, error_estimate=False)
    picks = [int(np.argmax(res.stuck)), int(np.argmin(np.abs(res.stuck - 8))), int(np.argmin(res.stuck))]
    assert res.stuck[picks[0]] == 16 and res.stuck[picks[2]] < 4 and 0 < res.stuck[picks[1]] < 16
    hs = HillSystem(problem)
    modal = problem.modal_data()
    assert modal.K_ref is not None and np.any(modal.K_ref)
    for i in picks:
        w = 2 * np.pi * res.freq_hz[i]
        J_nl = problem.nonlinear_jacobian(res.X[i], w, hs._nl)
        monkeypatch.setattr(mh, "WHOLE_SHARE", 1.0)              # the slipping rows' system
        Jr = modal_hill_system(modal, J_nl, hs.basis, w)[0]
        monkeypatch.setattr(mh, "WHOLE_SHARE", -1.0)             # the whole system
        J0 = modal_hill_system(modal, J_nl, hs.basis, w)[0]
        assert np.abs(Jr - J0).max() <= 1e-10 * np.abs(J0).max()
