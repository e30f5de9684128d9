"""The compiled AFT of law elements (hbm/balance/aft_kernel.py) against the generic path, its linear shortcut and
the closed-form start rule."""
import numpy as np
import pytest

from elements import Jenkins, Cubic, Friction3D
from elements.coulomb import CoulombStickSlip, CoulombRegularised
from elements.law_march import principal_reversal_index, linear_shortcut
from hbm.balance.aft import NonlinearForces
from hbm.balance.aft_kernel import aft_law
from hbm.interface.case import case_from_dict
from hbm.balance.fourier import FourierBasis
from hbm.balance.transforms import make_transform


def both_paths(el, basis, X, w):
    """(fused, generic) results of NonlinearForces.evaluate on the same input; the fused
    forces-only path must give the same forces as both."""
    n = el.gather.shape[1]
    fused = NonlinearForces(basis, [el], n, make_transform(basis, "dft"))
    generic = NonlinearForces(basis, [el], n, make_transform(basis, "numpy"))
    assert fused._parts[0] is not None and generic._parts[0] is None
    a, b = fused.evaluate(X, w), generic.evaluate(X, w)
    F = fused.forces(X, w)
    assert np.abs(F - b[0]).max() <= 1e-11 * max(np.abs(b[0]).max(), 1e-300)
    assert np.abs(generic.forces(X, w) - b[0]).max() <= 1e-11 * max(np.abs(b[0]).max(), 1e-300)
    same_samples(fused, generic, X, w)
    return a, b


def same_samples(fused, generic, X, w):
    """The sampled element forces (element outputs, stuck count) from the compiled AFT equal
    the element's own march (the generic path)."""
    for (z1, f1), (z2, f2) in zip(fused.element_forces(X, w), generic.element_forces(X, w)):
        assert np.array_equal(z1.shape, z2.shape) and f1.shape == f2.shape
        assert np.abs(z1 - z2).max() <= 1e-12 * max(np.abs(z2).max(), 1e-300)
        assert np.abs(f1 - f2).max() <= 1e-11 * max(np.abs(f2).max(), 1e-300)


def assert_same(a, b, rtol=1e-11):
    for x, y in zip(a, b):
        scale = max(np.abs(y).max(), 1e-300)
        assert np.abs(x - y).max() <= rtol * scale


def f3d_input(basis, amp_t, amp_n, mean_n, rng, nt=2):
    X = np.zeros((basis.n_coef, nt + 1))
    X[basis.row_of(0, "c"), nt] = mean_n
    for a in range(nt):
        X[basis.row_of(1, "c"), a] = amp_t
        X[basis.row_of(1, "s"), a] = amp_t * (0.3 + 0.4 * a)
    X[basis.row_of(1, "c"), nt] = amp_n
    X[basis.row_of(2, "s")] += 0.05 * amp_t * rng.standard_normal(nt + 1)
    return X


@pytest.mark.parametrize("amp", [0.1, 0.6, 5.0])
def test_jenkins_fused_equals_generic(amp, rng):
    b = FourierBasis(np.arange(1, 8), 64)
    el = Jenkins(np.array([[1.0, -1.0]]), 1.0, 0.3)
    X = rng.standard_normal((b.n_coef, 2)) * 0.2 * amp
    X[b.row_of(1, "c"), 0] = amp
    assert_same(*both_paths(el, b, X, 1.3))


@pytest.mark.parametrize("case", ["stuck", "slip", "open", "mixed"])
@pytest.mark.parametrize("nt", [1, 2])
def test_friction3d_fused_equals_generic(case, nt, rng):
    b = FourierBasis(np.arange(0, 4), 32)
    el = Friction3D(np.eye(nt + 1), kt=1e3, kn=2e3, mu=0.4, normal_preload=10.0)
    amp_t, amp_n, mean_n = {"stuck": (1e-3, 1e-3, 0.0), "slip": (0.05, 1e-3, 0.0),
                            "open": (0.01, 1e-3, -0.02), "mixed": (0.02, 8e-3, 0.0)}[case]
    X = f3d_input(b, amp_t, amp_n, mean_n, rng, nt)
    assert_same(*both_paths(el, b, X, 2.0))


@pytest.mark.parametrize("el", [
    CoulombStickSlip(np.array([[1.0]]), 1.0, 1.0, 0.5, 0.3),
    CoulombRegularised(np.array([[1.0]]), 0.4, 0.05),
    CoulombRegularised(np.array([[1.0]]), 0.4, 0.05, law="arctan"),
    Cubic(np.array([[1.0]]), 2.0),
], ids=["coulomb_sk", "regularised_linear", "regularised_arctan", "cubic"])
def test_other_laws_fused_equal_generic(el, rng):
    b = FourierBasis(np.arange(0, 6), 64)
    X = 0.3 * rng.standard_normal((b.n_coef, 1))
    X[b.row_of(1, "c")] = 1.2
    assert_same(*both_paths(el, b, X, 1.7))


def test_wedge_contacts_fused_equal_generic(rng):
    case = case_from_dict({
        "name": "pair", "model": {"mass": np.eye(4).tolist(), "stiffness": (1e4 * np.eye(4)).tolist(),
                                  "dof_names": ["A.x", "A.y", "B.x", "B.y"], "modal_damping": 0.01},
        "element": [{"type": "wedge_damper", "left": {"x": "A.x", "y": "A.y"},
                     "right": {"x": "B.x", "y": "B.y"}, "angles_deg": [45.0, 40.0], "mass": 0.05,
                     "cf": 20.0, "mu": 0.3, "kt": 2e5, "kn": 4e5}],
        "excitation": {"dofs": ["A.x"], "amplitude": [1.0]},
        "analysis": {"harmonics": 3, "time_samples": 32, "frequency_hz": [10.0, 20.0],
                     "outputs": {"a": "A.x"}}})
    el = case.elements[0]
    b = FourierBasis(np.arange(0, 4), 32)
    n = el.gather.shape[1]
    X = 2e-4 * rng.standard_normal((b.n_coef, n))
    fused = NonlinearForces(b, [el], n, make_transform(b, "dft"))
    generic = NonlinearForces(b, [el], n, make_transform(b, "numpy"))
    assert len(fused._parts[0]) == 2
    Xn = X[:, fused.dofs]
    assert_same(fused.evaluate(Xn, 50.0), generic.evaluate(Xn, 50.0))
    same_samples(fused, generic, Xn, 50.0)


def run_kernel(el, b, X, w=1.0):
    (G, sp), = [(np.ascontiguousarray(el.gather), sp) for _, sp in el.law_parts()]
    nc, nn = X.shape
    F, J4, dFdw = np.zeros((nc, nn)), np.zeros((nc, nn, nc, nn)), np.zeros((nc, nn))
    row0 = b.row_of(0, "c") if 0 in b.harmonics else -1
    passes = aft_law(sp, G, np.ascontiguousarray(X), w, np.ascontiguousarray(b.E),
                     np.ascontiguousarray(b.dE), np.ascontiguousarray(b.P), row0, F, J4, dFdw)
    return passes, F, J4.reshape(nc * nn, nc * nn)


def test_linear_shortcut_is_taken_only_when_linear(rng):
    b = FourierBasis(np.arange(0, 4), 32)
    el = Friction3D(np.eye(3), kt=1e3, kn=2e3, mu=0.4, normal_preload=10.0)
    for case, expect_linear in (("stuck", True), ("open", True), ("slip", False), ("mixed", False)):
        amp_t, amp_n, mean_n = {"stuck": (1e-3, 1e-3, 0.0), "slip": (0.05, 1e-3, 0.0),
                                "open": (0.01, 1e-3, -0.02), "mixed": (0.02, 8e-3, 0.0)}[case]
        X = f3d_input(b, amp_t, amp_n, mean_n, rng)
        passes, F, J = run_kernel(el, b, X)
        assert (passes == 0) == expect_linear, case
        if case == "stuck":
            # closed and stuck: F = diag(kt, kt, kn) U, J = that stiffness on every coefficient
            assert np.allclose(F, X * np.array([1e3, 1e3, 2e3]), rtol=1e-13, atol=0)
            assert np.allclose(J, np.kron(np.eye(b.n_coef), np.diag([1e3, 1e3, 2e3])), rtol=0, atol=1e-9)
        if case == "open":
            expect = np.zeros_like(F)
            expect[b.row_of(0, "c"), 2] = -10.0
            assert np.array_equal(F, expect) and not J.any()
    # Jenkins: stuck below kt |u| = fs, marched above
    el = Jenkins(np.array([[1.0]]), 1.0, 0.3)
    X = np.zeros((b.n_coef, 1))
    X[b.row_of(1, "c")] = 0.29
    assert run_kernel(el, b, X)[0] == 0
    X[b.row_of(1, "c")] = 0.31
    assert run_kernel(el, b, X)[0] >= 1


def test_shortcut_rejects_a_single_slipping_sample():
    z = np.zeros((16, 3))
    z[:, 0] = 1e-3
    K, f0 = np.zeros((3, 3)), np.zeros(3)
    p = np.array([1e3, 2e3, 0.4, 10.0, 2.0])
    assert linear_shortcut(2, p, z, K, f0)
    z[7, 1] = 0.0101          # |kt u_t| just above mu N0 = 4 at one sample (kt u = 10.1 > 4)
    assert not linear_shortcut(2, p, z, K, f0)


def test_principal_reversal_closed_form_matches_eigenvector(rng):
    for _ in range(50):
        N = int(rng.integers(8, 80))
        th = 2 * np.pi * np.arange(N) / N
        A = rng.standard_normal((2, 2))
        u = np.c_[np.cos(th + rng.uniform(0, 6)), 0.3 * np.sin(3 * th)] @ A + rng.standard_normal(2)
        c = u - u.mean(axis=0)
        v = np.linalg.eigh(c.T @ c)[1][:, -1]
        proj = c @ v
        j0 = principal_reversal_index(np.ascontiguousarray(u), 2)
        # the largest excursion along the major axis, on the side where the larger component
        # of the eigenvector is positive
        s = np.sign(v[np.argmax(np.abs(v))])
        assert np.isclose(s * proj[j0], (s * proj).max(), rtol=1e-12, atol=0)


def test_closure_elimination_matches_lapack(rng):
    from elements.closure import _solve_small
    for n in (1, 3, 5):
        K = rng.standard_normal((n, n)) + n * np.eye(n)
        R = rng.standard_normal((n, 4))
        Y, cond = _solve_small(K, R)
        assert np.abs(Y - np.linalg.solve(K, R)).max() < 1e-12 * np.abs(Y).max()
        assert np.isclose(cond, np.linalg.cond(K, 1), rtol=1e-12)
    K = np.array([[1.0, 2.0], [2.0, 4.0]])          # singular: infinite condition number
    assert _solve_small(K, np.ones((2, 1)))[1] == np.inf
