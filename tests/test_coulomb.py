"""Coulomb laws: static/kinetic stick-slip return mapping and velocity-regularised friction."""
import numpy as np
import pytest

from elements import ELEMENTS, CoulombStickSlip, CoulombRegularised
from elements.kernels import march, law_step
from hbm.balance.fourier import FourierBasis

KT, NLOAD, MUS, MUK = 10.0, 1.0, 0.5, 0.3      # break loose at 0.5, slide at 0.3


def stepper(el):
    s = np.zeros(el.n_state)
    A = np.zeros((el.n_state, el.n_state))
    B = np.zeros((el.n_state, el.n_input))

    def step(zj):
        nonlocal s
        s_new = np.zeros(el.n_state)
        law_step(el.kind, el.params, s, np.atleast_1d(np.asarray(zj, dtype=float)), s_new, A, B)
        s = s_new
        return s.copy()
    return step


def sk():
    return CoulombStickSlip(np.eye(1), kt=KT, normal_load=NLOAD, mu_static=MUS, mu_kinetic=MUK)


def test_static_kinetic_break_loose_slide_restick():
    el = sk()
    step = stepper(el)
    # load from rest: stuck (f = kt u) up to mu_s N
    for u in np.linspace(0.0, 0.049, 8):
        s = step(u)
        assert s[2] == 0.0 and s[0] == pytest.approx(KT * u, abs=1e-15)
    s = step(0.0501)                       # trial 0.501 > mu_s N: breaks loose
    assert s[2] == 1.0 and s[0] == MUK * NLOAD
    s = step(0.052)                        # trial 0.3 + 0.019 is inside mu_s but slip goes on
    assert s[2] == 1.0 and s[0] == MUK * NLOAD
    s = step(0.09)
    assert s[2] == 1.0 and s[0] == MUK * NLOAD
    s = step(0.089)                        # reversal: re-sticks from the kinetic force
    assert s[2] == 0.0 and s[0] == pytest.approx(MUK * NLOAD - KT * 0.001, rel=1e-12)
    s = step(0.091)                        # forward again: stuck until mu_s N, not mu_k N
    assert s[2] == 0.0 and s[0] == pytest.approx(MUK * NLOAD + KT * 0.001, rel=1e-12)
    s = step(0.0)                          # back through the whole stick range (-0.6 < -0.5)
    assert s[2] == 1.0 and s[0] == -MUK * NLOAD
    # one big step across to the other side beyond mu_s N: sticks, then breaks loose forward
    s = step(0.2)
    assert s[2] == 1.0 and s[0] == MUK * NLOAD
    # a big step across but short of mu_s N on the other side: stuck
    s = step(0.2 - 0.07)
    assert s[2] == 0.0 and s[0] == pytest.approx(MUK * NLOAD - 0.7, rel=1e-12)


def test_static_kinetic_periodic_loop():
    n = 200
    th = 2 * np.pi * np.arange(n) / n
    u = 0.2 * np.cos(th)
    el = sk()
    f, _ = el.march(u[:, None], np.zeros((n, 1, 1)))
    f = f[:, 0]
    assert np.abs(f).max() <= MUS * NLOAD + 1e-15
    sliding = np.isclose(np.abs(f), MUK * NLOAD, rtol=0, atol=1e-14)
    assert 0.3 < sliding.mean() < 0.9
    # it breaks loose where kt (u_max - u) first exceeds mu_s N + mu_k N
    down = (th > 0) & (th < np.pi)
    stuck_down = down & (KT * (0.2 - u) <= (MUS + MUK) * NLOAD)
    np.testing.assert_allclose(f[stuck_down], MUK * NLOAD - KT * (0.2 - u[stuck_down]), rtol=1e-12)
    assert np.all(f[down & ~stuck_down] == -MUK * NLOAD)
    # odd symmetry of the loop
    np.testing.assert_allclose(f[n // 2:], -f[:n // 2], atol=1e-13)
    # small amplitude: pure stick from the rest state (f = kt u)
    f2, _ = el.march((0.04 * np.cos(th))[:, None], np.zeros((n, 1, 1)))
    np.testing.assert_allclose(f2[:, 0], KT * 0.04 * np.cos(th), rtol=0, atol=1e-14)


BASIS = FourierBasis(np.array([0, 1, 2, 3]), 64)


def coeff_march(el, X, w=1.0):
    """F = P f and dF/dX (n_coef, 1, n_coef) from the seeded march; velocities for rate laws."""
    E, nc = BASIS.E, BASIS.n_coef
    z = E @ X
    dz = np.zeros((BASIS.n_samples, el.n_input, nc))
    dz[:, 0, :] = E
    if el.velocity:
        z = np.hstack([z, w * (BASIS.dE @ X)])
        dz[:, 1, :] = w * BASIS.dE
    f, df, passes = march(el.kind, el.params, el.n_state, el.n_local, np.ascontiguousarray(z), dz,
                          el.start_index(z[:, :1]), el.max_passes, el.closure_tol)
    assert passes > 0
    return BASIS.P @ f, np.einsum("kj,jap->kap", BASIS.P, df), f


def fd_error(el, X, w=1.0, rel_step=1e-6):
    F, dF, f = coeff_march(el, X, w)
    h = rel_step * np.abs(X).max()
    fd = np.empty_like(dF)
    for p in range(X.shape[0]):
        Xp, Xm = X.copy(), X.copy()
        Xp[p] += h
        Xm[p] -= h
        fd[:, :, p] = (coeff_march(el, Xp, w)[0] - coeff_march(el, Xm, w)[0]) / (2 * h)
    return np.abs(dF - fd).max() / np.abs(fd).max(), f


def random_x(seed, amp):
    rng = np.random.default_rng(seed)
    decay = np.array([0.05, 1, 1, 0.3, 0.3, 0.1, 0.1])[:, None]
    return amp * decay * rng.standard_normal((BASIS.n_coef, 1))


@pytest.mark.parametrize("amp, seed, regime", [(0.02, 1, "stick"), (0.15, 2, "stick-slip"),
                                               (0.4, 3, "stick-slip")])
def test_static_kinetic_fd_jacobian(amp, seed, regime):
    el = sk()
    err, f = fd_error(el, random_x(seed, amp))
    sliding = np.isclose(np.abs(f[:, 0]), MUK * NLOAD, rtol=0, atol=1e-14)
    assert (sliding.any() if regime == "stick-slip" else not sliding.any())
    assert err < 1e-6, err


def reg(law, F0=0.5, vr=0.2):
    return CoulombRegularised(np.eye(1), slip_force=F0, v_r=vr, law=law)


@pytest.mark.parametrize("law", ["linear", "arctan", "tanh"])
def test_regularised_closed_form(law):
    el = reg(law)
    v = np.linspace(-1.0, 1.0, 41)
    step = stepper(el)
    f = np.array([step([123.0, vv])[0] for vv in v])     # u does not matter
    expect = {"linear": 0.5 * np.clip(v / 0.2, -1.0, 1.0), "arctan": 0.5 * (2 / np.pi) * np.arctan(v / 0.2),
              "tanh": 0.5 * np.tanh(v / 0.2)}[law]
    np.testing.assert_allclose(f, expect, rtol=1e-14, atol=1e-16)
    assert el.velocity and not el.needs_mean and el.n_input == 2


@pytest.mark.parametrize("law, amp", [("linear", 0.1), ("linear", 0.5), ("arctan", 0.5), ("tanh", 0.5)])
def test_regularised_fd_jacobian_with_velocity_seeds(law, amp):
    el = reg(law)
    w = 1.7
    X = random_x(11, amp)
    err, f = fd_error(el, X, w)
    if law == "linear" and amp > 0.2:        # both branches are visited
        assert np.any(np.abs(f) == 0.5) and np.any(np.abs(f) < 0.5)
    assert err < 1e-6, err
    # the displacement does not enter: a mean shift leaves the force unchanged
    X2 = X.copy()
    X2[0] += 3.0
    np.testing.assert_array_equal(coeff_march(el, X2, w)[2], f)


def test_from_spec_keys_and_validation():
    assert ELEMENTS["coulomb_stick_slip"] is CoulombStickSlip
    assert ELEMENTS["coulomb_regularised"] is CoulombRegularised
    spec = {"type": "coulomb_stick_slip", "dofs": [1, 0], "kt": 3e4, "normal_load": 2.0,
            "mu_static": 0.4, "mu_kinetic": 0.3}
    el = CoulombStickSlip.from_spec(spec, 2)
    np.testing.assert_array_equal(el.gather, [[-1.0, 1.0]])
    np.testing.assert_array_equal(el.params, [3e4, 2.0, 0.4, 0.3])
    with pytest.raises(ValueError, match="'mu'"):
        CoulombStickSlip.from_spec({**spec, "mu": 0.3}, 2)
    with pytest.raises(ValueError, match="mu_kinetic"):
        CoulombStickSlip.from_spec({**spec, "mu_kinetic": 0.5}, 2)
    with pytest.raises(ValueError, match="kt"):
        CoulombStickSlip.from_spec({**spec, "kt": 0}, 2)
    rspec = {"type": "coulomb_regularised", "dofs": "x", "slip_force": 0.5, "v_r": 1e-3,
             "law": "arctan"}
    el = CoulombRegularised.from_spec(rspec, 2, dof_index={"x": 1})
    np.testing.assert_array_equal(el.gather, [[0.0, 1.0]])
    assert el.law == "arctan"
    assert CoulombRegularised.from_spec({k: v for k, v in rspec.items() if k != "law"}, 2,
                                        dof_index={"x": 1}).law == "linear"
    with pytest.raises(ValueError, match="law"):
        CoulombRegularised.from_spec({**rspec, "law": "sigmoid"}, 2, dof_index={"x": 1})
    assert CoulombRegularised.from_spec({**rspec, "law": "tanh"}, 2, dof_index={"x": 1}).law == "tanh"
    with pytest.raises(ValueError, match="v_r"):
        CoulombRegularised.from_spec({**rspec, "v_r": 0.0}, 2, dof_index={"x": 1})
    with pytest.raises(ValueError, match="'mu'"):
        CoulombRegularised.from_spec({**rspec, "mu": 0.1}, 2, dof_index={"x": 1})
