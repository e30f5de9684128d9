"""Large systems (n >= REUSE_MIN_SIZE): Jacobians written into the corrector's Newton matrix.

``Arclength(..., fun_into=...)`` must trace the same path as ``fun`` alone while holding two
``n x n`` arrays (the Newton matrix and the kept LU) instead of five or more.  The system is
``M`` hardening Duffing oscillators (cos/sin unknowns each, forces slightly apart, too weak to
fold) with a weak chain coupling, through their resonance.
"""
import tracemalloc

import numpy as np
import pytest

from continuation import Arclength, ArclengthOptions
from continuation.linsolve import REUSE_MIN_SIZE
from continuation.tangent import null_tangent

M = REUSE_MIN_SIZE // 2 + 5            # oscillators: n = 2 M unknowns
C, Q, EPS = 0.02, 0.075, 1e-3
F = 0.005 * (1.0 + 0.01 * np.linspace(-1, 1, M))


def _fill(x, out):
    """Residual (n,) of the oscillator chain; ``[dR/dy, dR/dw]`` written into ``out`` (n, n+1)."""
    a, b, w = x[0:-1:2], x[1:-1:2], x[-1]
    D = 1.0 - w * w
    A2 = a * a + b * b
    n = 2 * M
    out[:] = 0.0
    i = np.arange(M)
    out[2 * i, 2 * i] = D + Q * (A2 + 2 * a * a)
    out[2 * i, 2 * i + 1] = C * w + 2 * Q * a * b
    out[2 * i + 1, 2 * i] = -C * w + 2 * Q * a * b
    out[2 * i + 1, 2 * i + 1] = D + Q * (A2 + 2 * b * b)
    out[2 * i, n] = -2 * w * a + C * b
    out[2 * i + 1, n] = -2 * w * b - C * a
    R = np.empty(n)
    R[0::2] = D * a + C * w * b + Q * A2 * a - F
    R[1::2] = D * b - C * w * a + Q * A2 * b
    y = x[:-1]
    R[:-2] += EPS * (y[:-2] - y[2:])          # chain coupling between neighbouring oscillators
    R[2:] += EPS * (y[2:] - y[:-2])
    j = np.arange(n - 2)
    out[j, j] += EPS
    out[j, j + 2] -= EPS
    out[j + 2, j + 2] += EPS
    out[j + 2, j] -= EPS
    return R


def _fun(x):
    out = np.empty((2 * M, 2 * M + 1))
    return _fill(x, out), out


def _trace(into: bool):
    x0 = np.r_[np.zeros(2 * M), 0.5]
    x0[0:-1:2] = F / 0.75                     # near the linear response at w = 0.5
    solver = Arclength(_fun, x0, scale=np.r_[np.full(2 * M, 0.2 * np.sqrt(2 * M)), 1.5], lam_bounds=(0.5, 2.0),
                       options=ArclengthOptions(ds0=0.05, max_steps=400), overwrite_jacobian=True,
                       fun_into=_fill if into else None)
    tracemalloc.start()
    pts = solver.run()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return solver, pts, peak


@pytest.fixture(scope="module")
def both():
    return _trace(False), _trace(True)


def test_jacobians_in_the_newton_matrix_trace_the_same_path(both):
    (s0, p0, _), (s1, p1, _) = both
    assert s0.status == s1.status == "finished", (s0.message, s1.message)
    assert len(p0) == len(p1)
    x0 = np.array([p.x for p in p0])
    x1 = np.array([p.x for p in p1])
    assert np.abs(x1 - x0).max() <= 1e-9 * np.abs(x0).max()


def test_jacobians_in_the_newton_matrix_hold_two_square_arrays(both):
    (_, _, peak0), (_, _, peak1) = both
    square = (2 * M + 1) ** 2 * 8
    assert peak1 < 2.5 * square, peak1 / square
    assert peak0 > 3.5 * square, peak0 / square         # what it saves


def test_null_tangent_in_the_newton_matrix_equals_the_allocating_one():
    rng = np.random.default_rng(1)
    n = 40
    work = np.empty((n + 1, n + 1))
    work[:n] = rng.standard_normal((n, n + 1))
    Js = work[:n].copy()
    t_ref = rng.standard_normal(n + 1)
    t_ref /= np.linalg.norm(t_ref)
    t0 = null_tangent(Js, t_ref)
    t1 = null_tangent(work[:n], t_ref, work)
    assert np.abs(t1 - t0).max() < 1e-12
    assert np.abs(Js @ t0).max() < 1e-12 * np.abs(Js).max() and t0 @ t_ref > 0


def test_frf_with_the_jacobian_in_the_newton_matrix_equals_the_direct_one(monkeypatch):
    """The FRF's residual writes its Jacobian into the corrector's matrix (``call_into``) on
    large problems; forced onto a 3-DOF case (kept LU and GMRES from 0 unknowns) it finds the
    same response: every point solves the balance and the peaks agree."""
    import hbm
    import continuation.linsolve as linsolve
    from hbm.analyses.problem_setup import build_problem, resolve_settings
    from hbm.balance.fourier import FourierBasis
    from test_truncation import three_dof
    case = three_dof()
    ref = hbm.frf(case, stability=False, error_estimate=False)
    monkeypatch.setattr(linsolve, "REUSE_MIN_SIZE", 1)
    got = hbm.frf(case, stability=False, error_estimate=False)
    assert ref.ok and got.ok, (ref.message, got.message)
    a_ref, a_got = ref.outputs["x3"].h1, got.outputs["x3"].h1
    assert abs(a_got.max() / a_ref.max() - 1) < 1e-7
    h, N, _, _, tr = resolve_settings(case)
    problem, _ = build_problem(case, FourierBasis(h, N), tr)
    F = np.abs(problem.load(2 * np.pi * got.freq_hz[0])).max()
    for X, f in zip(got.X, got.freq_hz):
        R = problem.residual(X, 2 * np.pi * f)[0]
        assert np.abs(R).max() < 1e-8 * F
