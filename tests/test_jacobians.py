"""Finite-difference checks of every element's marched Jacobian and of the full residual."""
import numpy as np
import pytest

from elements import Jenkins, Cubic
from hbm.balance.aft import NonlinearForces
from hbm.balance.fourier import FourierBasis
from hbm.model.linear import LinearModel
from hbm.balance.dense_part import dense_balance
from hbm.balance.transforms import make_transform


def fd_check(fun, x0, eps=1e-7):
    F0, J = fun(x0)
    Jfd = np.zeros_like(J)
    for i in range(x0.size):
        xp = x0.copy(); xp[i] += eps
        xm = x0.copy(); xm[i] -= eps
        Jfd[:, i] = (fun(xp)[0] - fun(xm)[0]) / (2 * eps)
    return np.abs(J - Jfd).max() / max(np.abs(J).max(), 1e-12)


def element_fun(el, basis, w=1.3):
    nl = NonlinearForces(basis, [el], el.gather.shape[1], make_transform(basis, "dft"))

    def fun(x):
        X = x.reshape(basis.n_coef, -1)
        F, dF, _ = nl.evaluate(X, w)
        return F.ravel(), dF
    return fun


# amplitude regimes for fs = 0.3, kt = 1: stuck (< 0.3), mixed stick-slip, gross slip
@pytest.mark.parametrize("amp", [0.1, 0.6, 5.0])
@pytest.mark.parametrize("harm", [[1, 2, 3, 4, 5], [0, 1, 3, 5], [1, 3, 5, 7]])
def test_jenkins_jacobian(amp, harm, rng):
    b = FourierBasis(np.array(harm), 64)
    el = Jenkins(np.array([[1.0]]), 1.0, 0.3)
    for _ in range(3):
        X = rng.standard_normal((b.n_coef, 1)) * 0.3 * amp
        X[b.row_of(1, "c")] = amp
        assert fd_check(element_fun(el, b), X.ravel()) < 1e-6


def test_relative_jenkins_and_cubic_jacobian(rng):
    b = FourierBasis(np.arange(0, 6), 64)
    els = [Jenkins(np.array([[1.0, -1.0, 0.0]]), 2.0, 0.5), Cubic(np.array([[0.0, 1.0, -1.0]]), 3.0)]
    for el in els:
        X = rng.standard_normal((b.n_coef, 2))  # each element touches 2 of the 3 DOFs
        assert fd_check(element_fun(el, b), X.ravel()) < 1e-6


def test_residual_jacobian_wrt_X_and_w(rng):
    M = np.diag([1.0, 2.0, 1.0])
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    model = LinearModel.with_damping(M, K, damping=0.02 * np.eye(3))
    els = [Jenkins(np.array([[1.0, -1, 0]]), 1.0, 0.3), Jenkins(np.array([[0, 0, 1.0]]), 2.0, 0.2),
           Cubic(np.array([[1.0, 0, 0]]), 0.5)]
    b = FourierBasis(np.arange(0, 6), 64)
    hb = dense_balance(model, els, b, np.array([1.0, 0, 0]), make_transform(b, "dft"))
    X = rng.standard_normal((b.n_coef, 3)) * 0.5
    x0 = np.r_[X.ravel(), 0.9]
    assert fd_check(hb, x0) < 1e-7


def test_dense_assembly_equals_block_assembly(rng):
    """The one-call dense path (stored Z0, Z1, Z2; hbm.balance.dense_kernels) gives the numbers of the
    harmonic-block path, for a model with and without elements."""
    M = np.diag([1.0, 2.0, 1.0])
    K = np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 2]])
    model = LinearModel.with_damping(M, K, damping=0.02 * np.eye(3))
    b = FourierBasis(np.arange(0, 6), 64)
    for els in ([Jenkins(np.array([[1.0, -1, 0]]), 1.0, 0.3), Cubic(np.array([[0, 0, 1.0]]), 0.5),
                 Cubic(np.array([[1.0, 0, 0]]), 0.5)], []):
        dense = dense_balance(model, els, b, np.array([1.0, 0, 0]), make_transform(b, "dft"))
        block = dense_balance(model, els, b, np.array([1.0, 0, 0]), make_transform(b, "dft"))
        block.linear._templates = None
        assert dense.linear._templates is not None
        x = np.r_[rng.standard_normal(b.n_coef * 3) * 0.5, 0.9]
        (R1, J1), (R2, J2) = dense(x), block(x)
        assert np.abs(R1 - R2).max() <= 1e-13 * np.abs(R2).max()
        assert np.abs(J1 - J2).max() <= 1e-13 * np.abs(J2).max()


def test_transforms_agree(rng):
    M = np.eye(2)
    K = np.array([[2.0, -1], [-1, 1]])
    model = LinearModel.with_damping(M, K, rayleigh=[0.01, 0.001])
    els = [Jenkins(np.array([[1.0, -1.0]]), 1.0, 0.3), Cubic(np.array([[0.0, 1.0]]), 0.4)]
    for harm, N in (([0, 1, 2, 3], 32), ([1, 3, 5, 7, 9], 64), (list(range(0, 26)), 256)):
        b = FourierBasis(np.array(harm), N)
        X = rng.standard_normal((b.n_coef, 2))
        out = {}
        for name in ("dft", "numpy", "fftw"):
            hb = dense_balance(model, els, b, np.array([1.0, 0.0]), make_transform(b, name))
            out[name] = hb(np.r_[X.ravel(), 1.1])
        for name in ("numpy", "fftw"):
            assert np.abs(out[name][0] - out["dft"][0]).max() < 1e-12 * np.abs(out["dft"][0]).max()
            assert np.abs(out[name][1] - out["dft"][1]).max() < 1e-12 * np.abs(out["dft"][1]).max()
