"""Newton's linear solves: GMRES on a kept LU (continuation.linsolve) against direct LU, and a
whole FRF traced with the kept LU against the direct path."""
import numpy as np

import continuation.arclength as arclength
from continuation.linsolve import ReusedLU, direct_solve


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


def test_frf_with_kept_lu_equals_direct_path(monkeypatch):
    """The FRF of a 4-contact condensed chain (H = 3, 28 unknowns, 0.5-0.8 Hz) traced with the kept LU
    (forced on below its size threshold) lands on the direct path's points to 1e-8."""
    from test_condensed_residual import _case
    from hbm.analyses.response import frf
    case = _case("modal", 5)
    ref = frf(case, stability=False, fmax=0.8)
    monkeypatch.setattr(arclength, "REUSE_MIN_SIZE", 1)
    new = frf(case, stability=False, fmax=0.8)
    assert ref.status == new.status == "finished"
    assert new.freq_hz.size == ref.freq_hz.size
    assert np.abs(new.freq_hz - ref.freq_hz).max() <= 1e-8 * ref.freq_hz.max()
    a, b = new.outputs["tip"].h1, ref.outputs["tip"].h1
    assert np.abs(a - b).max() <= 1e-8 * b.max()


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
