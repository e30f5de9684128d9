"""The condensed residual (all harmonics at once, compiled linear part) against the per-harmonic
blocks of :class:`hbm.model.condensed_model.CondensedModel`, finite differences and its own energy check."""
import numpy as np
import pytest

from hbm.interface.case import case_from_dict
from hbm.balance.condensed import CondensedLinear, condensed_balance
from hbm.balance.condensed_kernels import _invert
from hbm.balance.fourier import FourierBasis
from hbm.model.real_blocks import apply_blocks
from hbm.analyses.response import build_problem


def chain(n=12, seed=0):
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 1.5, n)
    k = rng.uniform(800.0, 1200.0, n)
    K = np.diag(k + np.r_[k[1:], 0.0]) - np.diag(k[1:], 1) - np.diag(k[1:], -1)
    return np.diag(m), K


M, K = chain()
C = 1e-4 * K + 0.02 * M
C[5, 5] += 0.4                       # non-proportional
ELEMENTS = [{"type": "jenkins", "dofs": [11, 10], "kt": 500.0, "slip_force": 0.3},
            {"type": "friction3d", "dofs": {"t1": 5, "t2": [8, 9], "n": 6}, "kt": 800.0, "kn": 900.0,
             "mu": 0.3, "normal_preload": 5.0}]
DAMPING = {"modal": {"modal_damping": 0.01}, "matrix": {"damping": C.tolist()}}


def _case(damping, modes):
    return case_from_dict({
        "model": {"mass": M.tolist(), "stiffness": K.tolist(), "solver": "condensed", "modes": modes,
                  **DAMPING[damping]},
        "element": ELEMENTS,
        "excitation": {"dofs": [11], "amplitude": [1.0]},
        "analysis": {"harmonics": 3, "time_samples": 32, "frequency_hz": [0.5, 3.0],
                     "outputs": {"tip": 11, "mid": 4}},
    })


def problem(damping, modes):
    case = _case(damping, modes)
    p, _ = build_problem(case, FourierBasis(case.analysis.harmonics, case.analysis.time_samples), "auto")
    assert isinstance(p.linear, CondensedLinear)
    return p


def state(p, seed=3):
    """Coefficients large enough to slip the contacts part of the period."""
    rng = np.random.default_rng(seed)
    return 5e-3 * rng.normal(size=(p.basis.n_coef, p.n_dof))


@pytest.mark.parametrize("damping, modes", [("modal", "all"), ("matrix", "all"), ("modal", 5), ("matrix", 5)])
def test_residual_equals_per_harmonic_blocks(damping, modes):
    p = problem(damping, modes)
    assert p.linear.reduced.proportional == (damping == "modal") and 0 in p.basis.harmonics
    X = state(p)
    for f_hz in (0.7, 1.9):
        w = 2 * np.pi * f_hz
        R, J, dRw = p.residual(X, w)
        Zb, dZb = p.linear.condensed.stiffness_blocks(p.basis, w)
        Feq, dFeq = p.linear.condensed.equivalent_force(p.basis, w, p.linear.F_e)
        _, _, dFnw = p.nl.evaluate(X[:, p.nl.dofs], w)
        ZX = apply_blocks(Zb, p.basis, X)
        R_ref = ZX + p.nonlinear_forces(X, w) - Feq
        dRw_ref = apply_blocks(dZb, p.basis, X) + dFnw - dFeq
        scale = np.abs(ZX).max()
        assert np.abs(R - R_ref.ravel()).max() <= 1e-12 * scale
        assert np.abs(dRw - dRw_ref.ravel()).max() <= 1e-11 * np.abs(dRw_ref).max()
        assert np.allclose(p.load(w), Feq, rtol=0, atol=1e-13 * np.abs(Feq).max())


@pytest.mark.parametrize("damping", ["modal", "matrix"])
def test_jacobians_finite_differences(damping):
    p = problem(damping, 5)
    X = state(p)
    w = 2 * np.pi * 1.3
    R, J, dRw = p.residual(X, w)
    x = X.ravel()
    h = 1e-7 * np.abs(x).max()
    fd = np.empty_like(J)
    for j in range(x.size):
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        fd[:, j] = (p.residual(xp.reshape(X.shape), w)[0] - p.residual(xm.reshape(X.shape), w)[0]) / (2 * h)
    assert np.abs(J - fd).max() <= 1e-5 * np.abs(J).max()
    dw = 1e-6 * w
    fdw = (p.residual(X, w + dw)[0] - p.residual(X, w - dw)[0]) / (2 * dw)
    assert np.abs(dRw - fdw).max() <= 1e-5 * np.abs(dRw).max()


@pytest.mark.parametrize("damping", ["modal", "matrix"])
def test_outputs_and_linear_solution_against_blocks(damping):
    p = problem(damping, 5)
    X = state(p)
    w = 2 * np.pi * 1.1
    Y = p.recover_outputs(X, w)
    Y_ref = p.linear.condensed.recover_outputs(p.basis, w, X, p.linear.F_e)
    assert np.abs(Y - Y_ref).max() <= 1e-11 * np.abs(Y_ref).max()
    Ks = p.stuck_stiffness()
    U = p.linear_solution(w, Ks)
    Zb, _ = p.linear.condensed.stiffness_blocks(p.basis, w)
    lhs = apply_blocks([z + np.kron(np.eye(z.shape[0] // p.n_dof), Ks) for z in Zb], p.basis, U)
    assert np.abs(lhs - p.load(w)).max() <= 1e-11 * np.abs(p.load(w)).max()


def test_peak_amplitudes_against_single_frequency_receptances():
    p = problem("matrix", 5)
    ws = 2 * np.pi * np.linspace(0.5, 3.0, 7)
    Ks = p.stuck_stiffness()
    free, stuck = p.linear_peak_amplitudes(ws, Ks)
    ref_f, ref_s = np.zeros(p.n_dof), np.zeros(p.n_dof)
    for w in ws:
        Hcc, _ = p.linear.condensed.receptance("c", "c", w)
        u = p.linear.condensed.receptance("c", "e", w)[0][:, 0]
        ref_f = np.maximum(ref_f, np.abs(u))
        ref_s = np.maximum(ref_s, np.abs(np.linalg.solve(np.eye(p.n_dof) + Hcc @ Ks, u)))
    assert np.allclose(free, ref_f, rtol=1e-12, atol=0) and np.allclose(stuck, ref_s, rtol=1e-12, atol=0)


def test_energy_balance_does_not_depend_on_the_last_evaluation():
    """The linear part keeps its last frequency's parts: a balance after a residual at the same
    point and one after a residual elsewhere are the same numbers, and a wrong solution still
    fails the check."""
    p = problem("modal", 5)
    X = state(p)
    w = 2 * np.pi * 1.3
    p.residual(X, w)
    reused = p.energy_balance(X, w)
    p.residual(2.0 * X, 1.01 * w)
    fresh = p.energy_balance(X, w)
    for a, b in ((reused.excitation, fresh.excitation), (reused.viscous, fresh.viscous),
                 (reused.nonlinear, fresh.nonlinear)):
        assert abs(a - b) <= 1e-13 * abs(b)
    assert reused.relative_error > 1e-3              # X is not a solution
    assert np.array_equal(p.nonlinear_forces(1.5 * X, w), p.nonlinear_forces(1.5 * X, w))
    assert not np.allclose(p.nonlinear_forces(1.5 * X, w), p.nonlinear_forces(X, w))


def test_energy_balance_of_a_linear_solution_closes():
    """Without elements the linear solution balances exactly (both dampings); a scaled one does not."""
    for damping in ("modal", "matrix"):
        case = case_from_dict({
            "model": {"mass": M.tolist(), "stiffness": K.tolist(), "solver": "condensed", "modes": 5,
                      **DAMPING[damping]},
            "excitation": {"dofs": [11], "amplitude": [1.0]},
            "analysis": {"harmonics": 3, "time_samples": 16, "frequency_hz": [0.5, 3.0],
                         "outputs": {"tip": 11}},
        })
        p, _ = build_problem(case, FourierBasis(case.analysis.harmonics, 16), "auto")
        w = 2 * np.pi * 1.4
        U = p.linear_solution(w)
        assert np.abs(p.residual(U, w)[0]).max() <= 1e-12 * np.abs(p.load(w)).max()
        e = p.energy_balance(U, w)
        assert e.relative_error <= 1e-10 and e.excitation > 0 and e.nonlinear == 0.0
        assert p.energy_balance(1.01 * U, w).relative_error > 1e-3


def test_compiled_inverse():
    rng = np.random.default_rng(7)
    for n in (1, 2, 6):
        A = rng.normal(size=(n, n)) + 1j * rng.normal(size=(n, n))
        out = np.empty_like(A)
        assert _invert(A, out)
        assert np.abs(out - np.linalg.inv(A)).max() <= 1e-12 * np.abs(np.linalg.inv(A)).max()
    A = np.ones((3, 3), dtype=complex)
    assert not _invert(A, np.empty_like(A))


@pytest.mark.parametrize("damping", ["modal", "matrix"])
def test_receptance_stack_matches_single_frequency(damping):
    from hbm.balance.condensed_kernels import modal_receptances
    from hbm.model.reduction import receptance_stack
    p = problem(damping, 5)
    r = p.linear.reduced
    phi = r.phi[:4]
    Rk = r.residual[:4, :4]
    Ws = 2 * np.pi * np.array([0.0, 0.8, 1.7, 2.9])
    H, dH = receptance_stack(phi, r.omega, r.modal_c, r.proportional, Rk, Ws)
    for W, h, dh in zip(Ws, H, dH):
        ref, dref = r.receptance(W, derivative=True)
        assert np.abs(h - ref[:4, :4]).max() <= 1e-12 * np.abs(ref).max()
        assert np.abs(dh - dref[:4, :4]).max() <= 1e-12 * np.abs(dref).max()
    if r.proportional:
        ia, ib = np.triu_indices(4)
        Hk, dHk = modal_receptances(np.ascontiguousarray(phi[ia].T * phi[ib].T), ia, ib, 4, r.omega ** 2,
                                    np.diag(r.modal_c).copy(), Rk[ia, ib].copy(), Ws)
        assert np.abs(Hk - H).max() <= 1e-12 * np.abs(H).max()
        assert np.abs(dHk - dH).max() <= 1e-12 * np.abs(dH).max()


def _rebuilt(case, basis, ref, strategy):
    """``ref``'s problem with its linear part formed by ``strategy``."""
    return condensed_balance(ref.linear.reduced, case.elements, basis, case.excitation.force, ref.nl.transform,
                                    ref.linear.output_rows, linear_strategy=strategy)


@pytest.mark.parametrize("damping", ["modal", "matrix"])
@pytest.mark.parametrize("strategy", ["woodbury", "dense"])
def test_linear_strategies_give_the_same_numbers(damping, strategy):
    """Woodbury (R_cc positive definite with 5 of 12 modes) and dense LAPACK inverses against
    the compiled Gauss-Jordan path: residual, Jacobians, outputs and energy balance."""
    case = _case(damping, 5)
    basis = FourierBasis(case.analysis.harmonics, case.analysis.time_samples)
    # 5 modes reach 5.4 Hz: they cover frequencies to 2.7 Hz (hbm.model.mode_cover), the test's 1.9 Hz
    ref, _ = build_problem(case, basis, "auto", fmax_hz=2.5)
    assert ref.linear._builder.strategy == "compiled" and ref.linear.reduced.n_modes == 5
    p = _rebuilt(case, basis, ref, strategy)
    assert p.linear._builder.strategy == strategy
    X = state(ref)
    for f_hz in (0.7, 1.9):
        w = 2 * np.pi * f_hz
        for a, b in zip(p.residual(X, w), ref.residual(X, w)):
            assert np.abs(a - b).max() <= 1e-10 * np.abs(b).max()
        Y, Yr = p.recover_outputs(X, w), ref.recover_outputs(X, w)
        assert np.abs(Y - Yr).max() <= 1e-10 * np.abs(Yr).max()
        e, er = p.energy_balance(X, w), ref.energy_balance(X, w)
        assert abs(e.excitation - er.excitation) <= 1e-10 * abs(er.excitation)
        assert abs(e.viscous - er.viscous) <= 1e-10 * abs(er.viscous)
    Ks = ref.stuck_stiffness()
    free, stuck = p.linear_peak_amplitudes(2 * np.pi * np.array([0.6, 1.4]), Ks)
    free_r, stuck_r = ref.linear_peak_amplitudes(2 * np.pi * np.array([0.6, 1.4]), Ks)
    assert np.allclose(free, free_r, rtol=1e-10) and np.allclose(stuck, stuck_r, rtol=1e-10)


def test_woodbury_needs_a_positive_definite_residual_flexibility():
    """With every mode kept the residual flexibility is zero: the Woodbury form is refused by
    name, and the automatic choice for many contacts falls back to the dense inverse."""
    case = _case("modal", "all")
    basis = FourierBasis(case.analysis.harmonics, case.analysis.time_samples)
    ref, _ = build_problem(case, basis, "auto")
    with pytest.raises(ValueError, match="positive definite residual flexibility"):
        _rebuilt(case, basis, ref, "woodbury")
    from hbm.balance.condensed_linear import LinearBuilder
    b = ref.linear._builder
    auto = LinearBuilder(ref.linear.reduced, b.phi, b.R, 4, 1, b.hs, b.rows, b.i1, "auto")
    assert auto.strategy == "compiled"                 # 4 contacts: below the Woodbury threshold
    import hbm.balance.condensed_linear as cl
    old, cl.WOODBURY_MIN_CONTACTS = cl.WOODBURY_MIN_CONTACTS, 1
    try:
        assert LinearBuilder(ref.linear.reduced, b.phi, b.R, 4, 1, b.hs, b.rows, b.i1, "auto").strategy == "dense"
    finally:
        cl.WOODBURY_MIN_CONTACTS = old
