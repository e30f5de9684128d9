"""Modal reduction, receptance blocks and condensation against direct solves of the full model."""
import numpy as np
import pytest
import scipy.sparse as sp

from hbm.balance.fourier import FourierBasis
from hbm.model.linear import LinearModel, harmonic_blocks
from hbm.model.condensed_model import condense
from hbm.model.real_blocks import apply_blocks, real_block
from hbm.model.reduction import reduce_model, reduce_linear_model


def chain(n=30, seed=0):
    """Spring-mass chain clamped at its left end (K non-singular)."""
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 1.5, n)
    k = rng.uniform(800.0, 1200.0, n)
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += k[i]
        if i > 0:
            K[i - 1, i - 1] += k[i]
            K[i - 1, i] -= k[i]
            K[i, i - 1] -= k[i]
    return np.diag(m), K


def direct(M, C, K, W):
    return np.linalg.inv(K - W * W * M + 1j * W * C)


def test_real_block_is_complex_inverse_convention():
    rng = np.random.default_rng(1)
    A = rng.normal(size=(3, 3)) + 1j * rng.normal(size=(3, 3))
    assert np.allclose(real_block(np.linalg.inv(A)), np.linalg.inv(real_block(A)))
    assert np.allclose(real_block(A @ A.T), real_block(A) @ real_block(A.T))


@pytest.mark.parametrize("kind", ["modal", "rayleigh", "general"])
def test_all_modes_no_residual_equals_full_frf(kind):
    M, K = chain()
    n = M.shape[0]
    if kind == "modal":
        lin = LinearModel.with_damping(M, K, modal_damping=0.02)
        red = reduce_model(M, K, modal_damping=0.02, residual_flexibility=False)
    elif kind == "rayleigh":
        lin = LinearModel.with_damping(M, K, rayleigh=(0.3, 2e-4))
        red = reduce_model(M, K, rayleigh=(0.3, 2e-4), residual_flexibility=False)
    else:  # non-proportional: a dashpot between masses 10 and 11 and one to ground at 3
        C = 1e-4 * K
        C[10, 10] += 2.0; C[11, 11] += 2.0; C[10, 11] -= 2.0; C[11, 10] -= 2.0
        C[3, 3] += 1.5
        lin = LinearModel(M, C, K)
        red = reduce_model(M, K, damping=C, residual_flexibility=False)
        assert not red.proportional
    assert red.n_modes == n
    for W in np.linspace(0.0, 80.0, 41):
        Hx = direct(lin.M, lin.C, lin.K, W)
        H = red.receptance(W)
        assert np.abs(H - Hx).max() <= 1e-8 * np.abs(Hx).max()
    # the LinearModel path (C projected) gives the same
    red2 = reduce_linear_model(lin, residual_flexibility=False)
    assert np.allclose(red2.receptance(33.0), direct(lin.M, lin.C, lin.K, 33.0), rtol=1e-8, atol=0)


@pytest.mark.parametrize("kind", ["modal", "general"])
def test_blocks_are_inverse_of_harmonic_blocks(kind):
    M, K = chain(12)
    if kind == "modal":
        lin = LinearModel.with_damping(M, K, modal_damping=0.05)
    else:
        C = 0.01 * np.eye(12); C[4, 4] += 3.0
        lin = LinearModel(M, C, K)
    red = reduce_linear_model(lin)
    basis = FourierBasis([0, 1, 2, 3, 5], 32)
    w = 9.3
    Z, _ = harmonic_blocks(lin, basis, w)
    Hb, _ = red.receptance_blocks(basis, w)
    for h, z, hb in zip(basis.harmonics, Z, Hb):
        assert hb.shape == z.shape
        assert np.allclose(hb, np.linalg.inv(z), rtol=1e-9, atol=1e-12 * np.abs(hb).max()), h
    # and the coefficient action x = Z^-1 f
    f = np.random.default_rng(0).normal(size=(basis.n_coef, 12))
    x = apply_blocks(Hb, basis, f)
    assert np.allclose(apply_blocks(Z, basis, x), f)


@pytest.mark.parametrize("kind", ["modal", "general"])
def test_block_derivatives_finite_differences(kind):
    M, K = chain(10)
    C = 0.02 * np.eye(10)
    C[2, 2] += 1.0
    red = reduce_model(M, K, n_modes=4, modal_damping=[0.01, 0.02, 0.03, 0.04]) if kind == "modal" \
        else reduce_model(M, K, n_modes=6, damping=C, keep_dofs=[1, 4, 9])
    basis = FourierBasis([0, 1, 2, 3], 16)
    w, dw = 7.7, 1e-6
    _, dB = red.receptance_blocks(basis, w)
    Bp, _ = red.receptance_blocks(basis, w + dw)
    Bm, _ = red.receptance_blocks(basis, w - dw)
    for d, p, m in zip(dB, Bp, Bm):
        fd = (p - m) / (2 * dw)
        assert np.abs(d - fd).max() <= 1e-6 * max(np.abs(fd).max(), 1e-12)


def frf_error(red, Mx, Kx, Cx, dofs, Ws):
    num = den = 0.0
    for W in Ws:
        Hx = direct(Mx, Cx, Kx, W)[np.ix_(dofs, dofs)]
        num += np.abs(red.receptance(W) - Hx).sum() ** 2
        den += np.abs(Hx).sum() ** 2
    return np.sqrt(num / den)


def test_residual_flexibility_cuts_truncation_error():
    M, K = chain(40, seed=3)
    keep = [5, 17, 39]
    z = 0.01
    lin = LinearModel.with_damping(M, K, modal_damping=z)
    om = np.sqrt(np.linalg.eigvalsh(np.linalg.solve(np.sqrt(M), np.linalg.solve(np.sqrt(M), K).T)))
    Ws = np.linspace(0.05 * om[0], 1.1 * om[2], 301)   # across the first three resonances
    plain = reduce_model(M, K, n_modes=6, modal_damping=z, keep_dofs=keep, residual_flexibility=False)
    resid = reduce_model(M, K, n_modes=6, modal_damping=z, keep_dofs=keep, residual_flexibility=True)
    e_plain = frf_error(plain, lin.M, lin.K, lin.C, keep, Ws)
    e_resid = frf_error(resid, lin.M, lin.K, lin.C, keep, Ws)
    print(f"truncated FRF error: plain {e_plain:.3e}, residual {e_resid:.3e}, "
          f"ratio {e_plain / e_resid:.1f}")
    assert e_plain / e_resid >= 10.0
    # static flexibility exact with the residual term
    assert np.allclose(resid.receptance(0.0).real, np.linalg.inv(K)[np.ix_(keep, keep)], rtol=1e-10)


def test_sparse_shift_invert_matches_dense():
    M, K = chain(60, seed=5)
    keep = [3, 30, 59]
    d = reduce_model(M, K, n_modes=5, modal_damping=0.02, keep_dofs=keep)
    s = reduce_model(sp.csr_matrix(M), sp.csr_matrix(K), n_modes=5, modal_damping=0.02,
                     keep_dofs=keep, sigma=0.0)
    assert np.allclose(s.omega, d.omega, rtol=1e-10)
    for W in (0.0, 3.0, 17.0):
        assert np.allclose(s.receptance(W), d.receptance(W), rtol=1e-8, atol=0)


@pytest.mark.parametrize("n_modes", [None, 15])
def test_condensed_linear_frf_with_contact_spring(n_modes):
    """Condensed solve (Z_c + k_s) U_c = F_eq, then output recovery, against the full solve."""
    M, K = chain(25, seed=7)
    n = 25
    C = 2e-4 * K + 0.05 * M
    C[8, 8] += 0.7                                       # non-proportional
    contact, exc, out = [6, 15], [20], [24, 2, 6]
    keep = sorted(set(contact + exc + out))
    red = reduce_model(M, K, damping=C, n_modes=n_modes, keep_dofs=keep)
    cm = condense(red, contact, out, exc)
    basis = FourierBasis([0, 1, 3], 16)
    w = 11.0
    ks = np.array([[400.0, -100.0], [-100.0, 250.0]])   # linear stand-in for F_nl = ks U_c
    F_e = np.zeros((basis.n_coef, 1))
    F_e[basis.row_of(0)] = 2.0
    F_e[basis.row_of(1, "c")] = 1.0
    F_e[basis.row_of(3, "s")] = 0.5
    Zc, _ = cm.stiffness_blocks(basis, w)
    F_eq, _ = cm.equivalent_force(basis, w, F_e)
    U = []
    k = 0
    for h, Z in zip(basis.harmonics, Zc):
        if h == 0:
            U.append(np.linalg.solve(Z + ks, F_eq[k])[None]); k += 1
        else:
            A = Z + np.kron(np.eye(2), ks)
            U.append(np.linalg.solve(A, F_eq[k:k + 2].reshape(-1)).reshape(2, -1)); k += 2
    U = np.vstack(U)
    Y = cm.recover_outputs(basis, w, U, F_e)
    # full model: spring ks between contact DOFs and ground, direct solve per harmonic
    Kf = K.copy()
    Kf[np.ix_(contact, contact)] += ks
    full = LinearModel(M, C, Kf)
    Zf, _ = harmonic_blocks(full, basis, w)
    f = np.zeros((basis.n_coef, n))
    f[:, exc] = F_e
    Xf = apply_blocks([np.linalg.inv(z) for z in Zf], basis, f)
    tol = 1e-8 if n_modes is None else 2e-2
    assert np.abs(U - Xf[:, contact]).max() <= tol * np.abs(Xf[:, contact]).max()
    assert np.abs(Y - Xf[:, out]).max() <= tol * np.abs(Xf[:, out]).max()


def test_condensed_derivatives_and_gather_rows():
    M, K = chain(15, seed=2)
    red = reduce_model(M, K, n_modes=6, rayleigh=(0.1, 1e-4), keep_dofs=[2, 3, 9, 14])
    rows = np.zeros((1, 15)); rows[0, 3] = 1.0; rows[0, 2] = -1.0   # relative u = q3 - q2
    cm = condense(red, np.vstack([rows, np.eye(15)[9]]), [14], [14])
    basis = FourierBasis([0, 1, 2], 8)
    w, dw = 6.1, 1e-6
    for fun in (cm.stiffness_blocks, cm.excitation_blocks):
        _, d = fun(basis, w)
        p, _ = fun(basis, w + dw)
        m, _ = fun(basis, w - dw)
        for a, b, c in zip(d, p, m):
            fd = (b - c) / (2 * dw)
            assert np.abs(a - fd).max() <= 1e-6 * np.abs(fd).max()
    Z, _ = cm.stiffness_blocks(basis, 0.0)
    H0 = np.linalg.inv(K)
    G = np.vstack([rows, np.eye(15)[9]])
    assert np.allclose(Z[0], np.linalg.inv(G @ H0 @ G.T))


def test_bad_input_messages():
    M, K = chain(5)
    with pytest.raises(ValueError, match="n_modes"):
        reduce_model(M, K, n_modes=9)
    with pytest.raises(ValueError, match="keep_dofs"):
        reduce_model(M, K, keep_dofs=[0, 7])
    with pytest.raises(ValueError, match="only one"):
        reduce_model(M, K, modal_damping=0.1, rayleigh=(0, 1))
    red = reduce_model(M, K, keep_dofs=[0, 1])
    with pytest.raises(ValueError, match="not among the kept"):
        condense(red, [0], [4], [1])
    Ksing = np.array([[1.0, -1.0], [-1.0, 1.0]])
    with pytest.raises(ValueError, match="singular"):
        reduce_model(np.eye(2), Ksing)


@pytest.mark.parametrize("sparse", [False, True])
def test_residual_flexibility_of_stiffnesses_on_very_different_scales(sparse):
    """A DOF held only by a weak spring beside stiff ones (a damper on its anchor beside a
    beam) made the static solve look singular (scipy warned, rcond 1e-16); the flexibility is
    solved on the diagonally scaled stiffness: exact, and no warning."""
    import warnings
    Mc, Kc = chain(30, seed=7)
    M, K = np.zeros((31, 31)), np.zeros((31, 31))
    M[:30, :30], K[:30, :30] = Mc, 1e10 * Kc
    M[30, 30], K[30, 30] = 1e-6, 1e-4    # a DOF of its own on a weak spring (a damper's anchor)
    keep = [4, 29, 30]
    KK = sp.csr_matrix(K) if sparse else K
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        red = reduce_model(sp.csr_matrix(M) if sparse else M, KK, n_modes=4, modal_damping=0.01,
                           keep_dofs=keep)
    exact = np.linalg.inv(K)[np.ix_(keep, keep)]
    assert np.allclose(red.receptance(0.0).real, exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())
