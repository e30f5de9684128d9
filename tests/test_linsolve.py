"""Newton's linear solves: GMRES on a kept LU (continuation.linsolve) against direct LU, and a
whole FRF traced with the kept LU against the direct path."""
import numpy as np

import continuation.linsolve as linsolve
from continuation.linsolve import BlockPreconditioned, ReusedLU, direct_solve


def _matrix(n, seed):
    rng = np.random.default_rng(seed)
    return np.asfortranarray(rng.normal(size=(n, n)) + n * np.eye(n)), rng.normal(size=(n, 2))


def test_kept_lu_solves_nearby_matrices_by_krylov_and_refactors_far_ones():
    A, B = _matrix(60, 0)
    s = ReusedLU(rtol=1e-12)
    X = s(A.copy(order="F"), B)
    assert s.factorisations == 1 and np.abs(A @ X - B).max() <= 1e-10 * np.abs(B).max()
    rng = np.random.default_rng(1)
    A2 = A + 0.05 * rng.normal(size=A.shape)                     # a nearby matrix: Krylov only
    X2 = s(np.asfortranarray(A2), B)
    assert s.factorisations == 1 and s.krylov_iterations > 0
    assert np.abs(A2 @ X2 - B).max() <= 1e-9 * np.abs(B).max()
    A3 = np.asfortranarray(rng.normal(size=A.shape))             # far away: a new factorisation
    X3 = s(A3.copy(order="F"), B)
    assert s.factorisations == 2
    assert np.allclose(X3, np.linalg.solve(A3, B), rtol=0, atol=1e-9 * np.abs(np.linalg.solve(A3, B)).max())


def test_singular_matrix_gives_none_both_ways():
    A = np.asfortranarray(np.ones((5, 5)))
    B = np.ones((5, 1))
    assert direct_solve(A.copy(order="F"), B) is None
    assert ReusedLU()(A.copy(order="F"), B) is None


def _same_frf(case, ref, new, fmax=None):
    """At every point of ``new`` (an FRF), its coefficients equal those of a direct Newton
    solve at its frequency started from ``ref``'s point of the same index, to 1e-8."""
    from hbm.analyses.problem_setup import build_problem, resolve_settings
    from hbm.balance.fourier import FourierBasis
    from hbm.balance.newton import newton
    assert ref.status == new.status == "finished"
    assert new.freq_hz.size == ref.freq_hz.size
    h, N, _, hi, tr = resolve_settings(case, fmax=fmax)
    problem, _ = build_problem(case, FourierBasis(h, N), tr, hi)      # the modes cover fmax
    F = np.abs(problem.load(2 * np.pi * ref.freq_hz[0])).max()
    for X, f, X0 in zip(new.X, new.freq_hz, ref.X):
        w = 2 * np.pi * f
        res = newton(lambda u: problem.residual(problem.expand(u), w)[:2], problem.unknowns(X0),
                     r_scale=F, tol=1e-13, linear_solve=direct_solve)
        assert res.converged, res.message
        assert np.abs(X - problem.expand(res.x)).max() <= 1e-8 * np.abs(X).max()


def test_frf_with_iterative_solves_equals_direct_path(monkeypatch):
    """The FRF of a 4-contact condensed chain (H = 3, 28 unknowns, 0.5-0.8 Hz) traced with the
    iterative solves (block-preconditioned GMRES, kept LU; forced on below their size
    threshold) is the direct path's FRF to 1e-8: the same points along the path (GMRES's
    tolerance moves each a little along the curve, not off it) and, at every point's own
    frequency, the coefficients of a direct Newton solve started from the direct path's point."""
    from test_condensed_residual import _case
    from hbm.analyses.response import frf
    case = _case("modal", 5)
    ref = frf(case, stability=False, fmax=0.8)
    monkeypatch.setattr(linsolve, "REUSE_MIN_SIZE", 1)
    monkeypatch.setattr(linsolve, "BLOCK_MIN_SIZE", 1)
    monkeypatch.setattr(linsolve, "_blocks_pay", lambda n, blocks: True)
    new = frf(case, stability=False, fmax=0.8)
    monkeypatch.setattr(linsolve, "REUSE_MIN_SIZE", 10 ** 9)
    monkeypatch.setattr(linsolve, "BLOCK_MIN_SIZE", 10 ** 9)
    assert np.abs(new.freq_hz - ref.freq_hz).max() <= 1e-6 * ref.freq_hz.max()
    _same_frf(case, ref, new, fmax=0.8)


def test_row_ordered_matrix_is_factored_as_its_transpose_without_a_copy():
    A, B = _matrix(40, 2)
    Ac = np.ascontiguousarray(A)
    s = ReusedLU(rtol=1e-12)
    X = s(Ac.copy(), B)
    assert s._trans == 1 and np.abs(A @ X - B).max() <= 1e-10 * np.abs(B).max()
    A2 = A + 0.01 * np.random.default_rng(3).normal(size=A.shape)
    X2 = s(np.ascontiguousarray(A2), B)                   # Krylov on the kept transposed LU
    assert s.factorisations == 1 and np.abs(A2 @ X2 - B).max() <= 1e-9 * np.abs(B).max()


def test_kept_lu_survives_the_caller_refilling_its_matrix():
    """The corrector refills one array for every Newton iteration: the kept LU must not live
    in it (else the next Krylov solve is preconditioned by garbage and refactors)."""
    A, B = _matrix(50, 4)
    s = ReusedLU(rtol=1e-12)
    buf = np.array(A, order="C")
    s(buf, B)
    buf[...] = A + 1e-3 * np.random.default_rng(5).normal(size=A.shape)
    X = s(buf, B)
    assert s.factorisations == 1 and s.krylov_iterations <= 12       # two right-hand sides
    assert np.abs(buf @ X - B).max() <= 1e-9 * np.abs(B).max()


def _blocky(n_blocks, size, coupling, seed):
    """A matrix of ``n_blocks`` diagonal blocks (``size`` each) and off-block entries of
    relative size ``coupling``, with a border row and column; two right-hand sides."""
    rng = np.random.default_rng(seed)
    n = n_blocks * size
    A = coupling * rng.normal(size=(n + 1, n + 1))
    for k in range(n_blocks):
        s = slice(k * size, (k + 1) * size)
        A[s, s] = rng.normal(size=(size, size)) + 3 * np.sqrt(size) * np.eye(size)
    A[n, :n] = rng.normal(size=n)
    A[:n, n] = rng.normal(size=n)
    A[n, n] = 0.5
    blocks = [(k * size, (k + 1) * size) for k in range(n_blocks)]
    return np.ascontiguousarray(A), rng.normal(size=(n + 1, 2)), blocks


def test_block_preconditioner_is_exact_on_a_block_diagonal_bordered_matrix():
    """Zero off-block entries (every contact stuck): the bordered block elimination is the
    inverse, so GMRES stops after one iteration per right-hand side and nothing is factored whole."""
    A, B, blocks = _blocky(4, 30, 0.0, 6)
    s = BlockPreconditioned(blocks, rtol=1e-12)
    X = s(A.copy(), B)
    assert s.factorisations == 0 and s.block_solves == 2 and s.krylov_iterations == 2
    assert np.abs(A @ X - B).max() <= 1e-10 * np.abs(B).max()
    n = A.shape[0] - 1                      # the same blocks serve the matrix without its border
    x = s(A[:n, :n].copy(), B[:n, :1])
    assert s.factorisations == 0 and np.abs(A[:n, :n] @ x - B[:n, :1]).max() <= 1e-10 * np.abs(B).max()


def test_block_preconditioner_takes_a_few_krylov_steps_on_weak_coupling_and_refactors_strong():
    A, B, blocks = _blocky(4, 30, 0.02, 7)
    s = BlockPreconditioned(blocks, rtol=1e-12)
    X = s(A.copy(), B)
    assert s.factorisations == 0 and 2 < s.krylov_iterations <= 2 * s.max_krylov
    assert np.abs(A @ X - B).max() <= 1e-10 * np.abs(B).max()
    A2, B2, _ = _blocky(4, 30, 3.0, 8)          # off-block entries as large as the blocks
    X2 = s(A2.copy(), B2)
    assert s.factorisations == 1
    assert np.allclose(X2, np.linalg.solve(A2, B2), rtol=0, atol=1e-9 * np.abs(np.linalg.solve(A2, B2)).max())


def test_singular_blocks_fall_back_to_the_whole_matrix():
    """A singular diagonal block (e.g. at a fold of a harmonic) with a regular whole matrix:
    the whole matrix is factored and the answer is exact."""
    A, B, blocks = _blocky(3, 10, 0.0, 9)
    A[:10, :10] = 0.0
    A[:10, 10:20] = np.eye(10)
    A[10:20, :10] = np.eye(10)
    s = BlockPreconditioned(blocks, rtol=1e-12)
    X = s(A.copy(), B)
    assert s.factorisations == 1 and np.abs(A @ X - B).max() <= 1e-9 * np.abs(B).max()


def test_tangent_on_the_block_solver_equals_the_direct_tangent():
    """null_tangent's bordered system solved by the path's block solver (no LU of the whole
    matrix) gives the tangent of the in-place LU."""
    from continuation.tangent import null_tangent
    A, _, blocks = _blocky(4, 30, 0.01, 10)
    n = A.shape[0] - 1
    Js = np.ascontiguousarray(A[:n])                      # (n, n + 1): a Jacobian with its w column
    t_ref = np.ones(n + 1) / np.sqrt(n + 1)
    work = np.empty((n + 1, n + 1))
    work[:n] = Js
    t_direct = null_tangent(Js, t_ref, work)
    s = BlockPreconditioned(blocks, rtol=1e-12)
    work[:n] = Js
    t_block = null_tangent(Js, t_ref, work, linear_solve=s)
    assert s.factorisations == 0 and s.block_solves == 1
    assert np.abs(Js @ t_block).max() <= 1e-10 * np.abs(Js).max()
    np.testing.assert_allclose(t_block, t_direct, atol=1e-10)


def test_paired_blocks_are_exact_on_time_invariant_harmonics():
    """Blocks [[P, Q], [-Q, P]] (cosine and sine rows of one harmonic under an operator that
    does not vary over the period) are solved exactly through the complex matrix P - iQ: one
    Krylov step per right-hand side; a block that breaks the pairing (a slipping contact's
    stiffness varying over the period) is still solved, in a few more steps."""
    rng = np.random.default_rng(11)
    m, n_pairs = 12, 3
    n = 10 + 2 * m * n_pairs
    A = np.zeros((n + 1, n + 1))
    A[:10, :10] = rng.normal(size=(10, 10)) + 8 * np.eye(10)
    blocks = [(0, 10, False)]
    for k in range(n_pairs):
        a = 10 + 2 * m * k
        P, Q = rng.normal(size=(m, m)) + 8 * np.eye(m), rng.normal(size=(m, m))
        A[a:a + 2 * m, a:a + 2 * m] = np.block([[P, Q], [-Q, P]])
        blocks.append((a, a + 2 * m, True))
    A[n, :n], A[:n, n], A[n, n] = rng.normal(size=n), rng.normal(size=n), 0.5
    B = rng.normal(size=(n + 1, 2))
    s = BlockPreconditioned(blocks, rtol=1e-12)
    X = s(np.ascontiguousarray(A), B)
    assert s.factorisations == 0 and s.krylov_iterations == 2
    assert np.abs(A @ X - B).max() <= 1e-10 * np.abs(B).max()
    A2 = A.copy()
    A2[10:10 + m, 10:10 + m] += 0.3 * np.eye(m)                  # D != A in the first pair
    X2 = s(np.ascontiguousarray(A2), B)
    assert s.factorisations == 0 and s.krylov_iterations > 4
    assert np.abs(A2 @ X2 - B).max() <= 1e-10 * np.abs(B).max()


def test_block_solves_give_the_direct_frf_on_a_4_contact_fe_patch(monkeypatch, tmp_path):
    """The issue's check on an FE patch: 4 friction3d contacts between two brick columns (84
    unknowns, condensed; 1 kN, every contact slipping, so the blocks only precondition),
    traced on the block solver (forced on below its size) and by direct LUs: at each point's
    frequency the block path's coefficients equal a direct Newton solve's from the direct
    path's point to 1e-8.  (The points themselves lie up to 6e-6 of the frequency apart
    along the path: each corrector stops at its own iterate.)"""
    from fe_patch import column_patch_case
    from hbm.analyses.response import frf
    case = column_patch_case(tmp_path, 4, 0.002, (8200.0, 8700.0), force=1000.0)
    ref = frf(case, stability=False, error_estimate=False)
    monkeypatch.setattr(linsolve, "BLOCK_MIN_SIZE", 1)
    monkeypatch.setattr(linsolve, "_blocks_pay", lambda n, blocks: True)
    new = frf(case, stability=False, error_estimate=False)
    monkeypatch.setattr(linsolve, "BLOCK_MIN_SIZE", 10 ** 9)
    assert np.all(new.stuck == 0)
    _same_frf(case, ref, new)


def test_many_small_blocks_are_left_to_a_dense_lu():
    """26 harmonic blocks of 12 unknowns (the railcar rig at H = 25: block solves 1.9x slower
    than dense LUs) do not pay; 4 blocks of 84 (a 16-contact patch at H = 3) do."""
    from continuation.linsolve import BlockPreconditioned, _blocks_pay, direct_solve
    rail = [(12 * k, 12 * (k + 1)) for k in range(26)]
    assert not _blocks_pay(306, rail) and _blocks_pay(336, [(0, 48), (48, 144), (144, 240), (240, 336)])
    assert linsolve.make_solver(306, rail) is direct_solve
    wide = [(50 * k, 50 * (k + 1)) for k in range(26)]          # a dense LU of 1300 costs more
    assert isinstance(linsolve.make_solver(1300, wide), BlockPreconditioned)
