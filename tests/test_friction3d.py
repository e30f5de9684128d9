"""friction3d: exact marched Jacobian, reduction to Jenkins, 2D gross slip on a circle,
variable normal load against a sequential time march, separation, case keys."""
import numpy as np
import pytest

from elements import ELEMENTS, Friction3D, Jenkins
from elements.kernels import law_step
from elements.closure import march_newton
from hbm.balance.fourier import FourierBasis

KT, KN, MU, N0 = 1.0, 2.0, 0.5, 1.0       # mu N0 / kt = 0.5


def make(nt=2, kt=KT, kn=KN, mu=MU, n0=N0):
    return Friction3D(np.eye(nt + 1), kt=kt, kn=kn, mu=mu, normal_preload=n0)


def run(el, z, dz=None):
    """March through the element's closure kernel directly so that the closure is asserted."""
    z = np.ascontiguousarray(z, dtype=float)
    if dz is None:
        dz = np.zeros(z.shape + (1,))
    f, df, passes = march_newton(el.kind, el.params, el.n_state, el.n_local, z, np.ascontiguousarray(dz),
                          el.start_index(z[:, :el.n_local]), el.max_passes, el.closure_tol)
    assert passes > 0, "loop did not close"
    return f, df


def coeff_march(el, basis, X):
    """F = P f(E X) and dF/dX (n_coef, nloc, n_coef * nloc) from the seeded march."""
    nloc = el.n_local
    z = basis.E @ X
    nc = basis.n_coef
    dz = np.zeros((basis.n_samples, nloc, nc * nloc))
    for k in range(nc):
        for a in range(nloc):
            dz[:, a, k * nloc + a] = basis.E[:, k]
    f, df = run(el, z, dz)
    return basis.P @ f, np.einsum("kj,jap->kap", basis.P, df), f, z


def fd_error(el, basis, X, rel_step=1e-6):
    F, dF, f, z = coeff_march(el, basis, X)
    h = rel_step * np.abs(X).max()
    x = X.reshape(-1)
    fd = np.empty_like(dF)
    for p in range(x.size):
        xp = x.copy()
        xp[p] += h
        xm = x.copy()
        xm[p] -= h
        Fp = coeff_march(el, basis, xp.reshape(X.shape))[0]
        Fm = coeff_march(el, basis, xm.reshape(X.shape))[0]
        fd[:, :, p] = (Fp - Fm) / (2 * h)
    return np.abs(dF - fd).max() / np.abs(fd).max(), el.summary(f, z)


BASIS = FourierBasis(np.array([0, 1, 2, 3]), 64)


def random_coeffs(rng, amps, mean=0.05):
    """Random coefficients (n_coef, nloc) with amplitudes ``amps`` per coordinate."""
    decay = np.array([mean, 1, 1, 0.3, 0.3, 0.1, 0.1])[:, None]
    return rng.standard_normal((BASIS.n_coef, len(amps))) * decay * np.asarray(amps)[None, :]


def ellipse_coeffs(a1, a2, phase, an, phase_n, rng, nt=2):
    """First-harmonic ellipse in (t1, t2), normal motion, plus a little random 2nd/3rd harmonic."""
    X = 0.03 * random_coeffs(rng, [a1, a2, an][-(nt + 1):] if nt == 2 else [a1, an])
    c, s = BASIS.row_of(1, "c"), BASIS.row_of(1, "s")
    X[c, 0] += a1
    if nt == 2:
        X[c, 1] += a2 * np.cos(phase)
        X[s, 1] -= a2 * np.sin(phase)
    X[c, -1] += an * np.cos(phase_n)
    X[s, -1] -= an * np.sin(phase_n)
    return X


PATHS = ["stick2d", "slip1d", "mixed1d", "mixed2d", "separation1d", "separation2d", "line3d"]


@pytest.mark.parametrize("case", PATHS)
def test_fd_jacobian_paths(case):
    rng = np.random.default_rng(100 + PATHS.index(case))
    if case == "stick2d":
        el, X = make(2), random_coeffs(rng, [0.08, 0.08, 0.05])
    elif case == "slip1d":
        el, X = make(1), ellipse_coeffs(3.0, 0, 0, 0.1, 0.4, rng, nt=1)
    elif case == "mixed1d":
        el, X = make(1), ellipse_coeffs(0.6, 0, 0, 0.25, 0.7, rng, nt=1)
    elif case == "mixed2d":
        el, X = make(2), ellipse_coeffs(0.9, 0.5, 1.1, 0.2, 2.0, rng)
    elif case == "separation1d":
        el, X = make(1), ellipse_coeffs(0.8, 0, 0, 0.9, 0.3, rng, nt=1)
    elif case == "separation2d":
        el, X = make(2), ellipse_coeffs(0.8, 0.6, 0.7, 0.9, 2.5, rng)
    else:
        # 3D contact slipping along a line (no t2 motion): the state is periodic after one
        # pass but the transverse derivative is not; closure must converge the seeds too
        el, X = make(2), ellipse_coeffs(1.5, 0.0, 0.0, 0.1, 0.5, rng)
        X[:, 1] = 0.0
    err, summ = fd_error(el, BASIS, X)
    # the path really is of the advertised kind
    if case.startswith("stick"):
        assert summ["slip_fraction"] == 0.0 and summ["open_fraction"] == 0.0
    elif case.startswith("slip") or case == "line3d":
        assert summ["slip_fraction"] > 0.5 and summ["open_fraction"] == 0.0
    elif case.startswith("mixed"):
        assert 0.0 < summ["slip_fraction"] < 1.0 and summ["open_fraction"] == 0.0
    else:
        assert 0.0 < summ["open_fraction"] < 1.0 and summ["slip_fraction"] > 0.0
    assert err < 1e-6, (case, err)


@pytest.mark.parametrize("phase", [0.3, np.pi / 4, np.pi / 2, 2.4])
def test_fd_jacobian_elliptical_phases(phase):
    rng = np.random.default_rng(7)
    el = make(2)
    X = ellipse_coeffs(1.0, 0.7, phase, 0.15, 1.3, rng)
    err, summ = fd_error(el, BASIS, X)
    assert summ["slip_fraction"] > 0.0
    assert err < 1e-6, (phase, err)


def test_reduces_to_jenkins():
    """u_n = 0 and only t1 moving: same forces as Jenkins(kt, mu N0), in 2D and 3D variants."""
    N = 128
    th = 2 * np.pi * np.arange(N) / N
    jen = Jenkins(np.eye(1), kt=KT, slip_force=MU * N0)
    for amp in (0.3, 0.7, 2.0):          # stick, mixed, gross slip
        u = amp * np.cos(th) + 0.2 * amp * np.sin(3 * th + 0.4)
        fj, _ = jen.march(u[:, None], np.zeros((N, 1, 1)))
        for nt in (1, 2):
            z = np.zeros((N, nt + 1))
            z[:, 0] = u
            f, _ = run(make(nt), z)
            np.testing.assert_allclose(f[:, 0], fj[:, 0], rtol=0, atol=1e-14)
            assert np.all(f[:, 1:] == 0.0)


def test_circular_gross_slip():
    r"""Circle of radius R, kt R > mu N: |f| = mu N at every sample, rotating with the motion.

    Steady state: the slider moves on a circle of radius r with its velocity (tangent to that
    circle) along f = kt (u - w), so u - w is perpendicular to w and
    r = sqrt(R^2 - (mu N / kt)^2); the dissipation per cycle is 2 pi mu N r.
    (Not R - mu N / kt: the slider trails the contact point by a quarter turn of the force.)
    On N samples (step angle D = 2 pi / N) the return mapping puts w_{j-1}, w_j and u_j on one
    line, so u - w_j is perpendicular to the chord bisector instead of to w_j; with
    c = mu N / kt this gives R^2 = r_N^2 + 2 r_N c sin(D/2) + c^2, i.e.
    r_N = sqrt(R^2 - c^2 cos^2(D/2)) - c sin(D/2) (first order in 1/N), and the slider
    polygon is regular: dissipation exactly mu N * N * 2 r_N sin(D/2).
    """
    R, n = 1.0, 256
    th = 2 * np.pi * np.arange(n) / n
    el = make(2)
    z = np.stack([R * np.cos(th), R * np.sin(th), np.zeros(n)], axis=1)
    f, _ = run(el, z)
    mun = MU * N0
    np.testing.assert_allclose(np.hypot(f[:, 0], f[:, 1]), mun, rtol=1e-12)
    lag = np.angle(np.exp(1j * (np.arctan2(f[:, 1], f[:, 0]) - th)))
    assert np.ptp(lag) < 1e-9
    summ = el.summary(f, z)
    assert summ["slip_fraction"] == 1.0
    w = z[:, :2] - f[:, :2] / KT
    r_n = np.hypot(w[:, 0], w[:, 1])
    assert np.ptp(r_n) < 1e-12
    np.testing.assert_allclose(summ["dissipation"], mun * n * 2 * r_n[0] * np.sin(np.pi / n), rtol=1e-10)
    c, sh = mun / KT, np.sin(np.pi / n)
    np.testing.assert_allclose(r_n, np.sqrt(R ** 2 - c ** 2 * (1 - sh ** 2)) - c * sh, rtol=1e-12)
    r = np.sqrt(R ** 2 - c ** 2)
    e_cont = 2 * np.pi * mun * r
    rel = abs(summ["dissipation"] - e_cont) / e_cont
    assert rel < 1.2 * c * np.pi / (n * r)          # first-order discretisation error only
    assert abs(summ["dissipation"] - 2 * np.pi * mun * (R - c)) > 0.3 * e_cont    # not R - mu N/kt
    # the trapezoidal work of f on the contact point agrees (all of it is dissipated)
    work = np.sum(0.5 * (f + np.roll(f, 1, 0))[:, :2] * (z - np.roll(z, 1, 0))[:, :2])
    assert abs(work - e_cont) / e_cont < 1.2 * c * np.pi / (n * r)


def time_march(el, z, periods):
    """Sequential steps of the same law_step from the rest state at q = 0."""
    s = np.zeros(el.n_state)
    s_new = np.zeros(el.n_state)
    A = np.zeros((el.n_state, el.n_state))
    B = np.zeros((el.n_state, z.shape[1]))
    out = np.empty((z.shape[0], el.n_local))
    for _ in range(periods):
        for j in range(z.shape[0]):
            law_step(el.kind, el.params, s, np.ascontiguousarray(z[j]), s_new, A, B)
            s, s_new = s_new, s
            out[j] = s[:el.n_local]
    return out


def test_variable_normal_load_against_time_march():
    """Normal load in phase with t1: asymmetric loop; the march equals time stepping."""
    n = 128
    th = 2 * np.pi * np.arange(n) / n
    el = make(1)
    z = np.stack([1.5 * np.cos(th), 0.3 * np.cos(th)], axis=1)
    f, _ = run(el, z)
    assert f[:, 0].max() > 1.3 * -f[:, 0].min()     # mu N is larger while u_t > 0
    np.testing.assert_allclose(f[:, 0].max(), MU * (N0 + KN * 0.3), rtol=1e-12)
    jmin = np.argmin(z[:, 0])                        # slipping at the lower reversal, smallest N
    np.testing.assert_allclose(f[jmin, 0], -MU * (N0 - KN * 0.3), rtol=1e-12)
    ft = time_march(el, z, 4)
    np.testing.assert_allclose(ft, f, rtol=0, atol=1e-12)
    e_march, e_time = el.summary(f, z)["dissipation"], el.summary(ft, z)["dissipation"]
    assert e_march > 0
    assert abs(e_march - e_time) <= 1e-10 * e_march


def test_variable_normal_load_2d_against_time_march():
    n = 64
    th = 2 * np.pi * np.arange(n) / n
    el = make(2)
    z = np.stack([1.2 * np.cos(th), 0.8 * np.sin(th + 0.5), 0.25 * np.cos(th + 0.3)], axis=1)
    f, _ = run(el, z)
    ft = time_march(el, z, 200)
    np.testing.assert_allclose(ft, f, rtol=0, atol=1e-10)
    e_march, e_time = el.summary(f, z)["dissipation"], el.summary(ft, z)["dissipation"]
    assert abs(e_march - e_time) <= 1e-10 * e_march


def test_separation_forces():
    """Open samples: f_t = 0 and f_n = -N0 exactly; re-contact re-sticks unloaded, at the
    instant between the samples where the normal load crosses zero."""
    n0, n = 0.1, 128
    th = 2 * np.pi * np.arange(n) / n
    el = make(2, n0=n0)
    z = np.stack([0.8 * np.cos(th + 0.2), 0.5 * np.sin(th), 1.0 * np.cos(th)], axis=1)
    f, _ = run(el, z)
    open_ = n0 + KN * z[:, 2] <= 0
    assert 0.3 < open_.mean() < 0.7
    assert np.all(f[open_, :2] == 0.0)
    assert np.all(f[open_, 2] == -n0)
    np.testing.assert_allclose(f[~open_, 2], KN * z[~open_, 2], rtol=1e-14)
    summ = el.summary(f, z)
    assert summ["open_fraction"] == open_.mean()
    assert summ["normal_load_min"] == 0.0
    np.testing.assert_allclose(summ["normal_load_max"], n0 + KN, rtol=1e-12)
    # first closed sample after the gap: trial force kt (1 - theta) (u_j - u_{j-1}) from zero
    j = next(j for j in range(n) if open_[j - 1] and not open_[j])
    Np, Nj = n0 + KN * z[j - 1, 2], n0 + KN * z[j, 2]
    theta = Np / (Np - Nj)
    assert 0.0 < theta < 1.0
    trial = KT * (1.0 - theta) * (z[j, :2] - z[j - 1, :2])
    limit = MU * (n0 + KN * z[j, 2])
    expect = trial if np.linalg.norm(trial) <= limit else limit * trial / np.linalg.norm(trial)
    np.testing.assert_allclose(f[j, :2], expect, rtol=1e-13)


def test_summary_counts_a_re_contact_step_by_the_law_s_own_trial_force():
    """Re-contact a third of the way through a step (N_p = -0.1, N = 0.2): the law's trial
    force is kt (2/3) du = 0.08, inside mu N = 0.1, so the contact re-sticks; the summary's
    slip count recomputes that trial (kt du = 0.12 would count a slip)."""
    el = make(1, kt=1.0, kn=2.0, mu=0.5, n0=0.1)
    n = 16
    zn = np.where(np.arange(n) < 8, -0.1, 0.05)                 # open, then closed from sample 8
    zt = np.where((np.arange(n) >= 4) & (np.arange(n) < 8), -0.12, 0.0)   # moves while open
    z = np.stack([zt, zn], axis=1)
    f, _ = run(el, z)
    np.testing.assert_allclose(f[8:, 0], 0.08, rtol=1e-14)
    summ = el.summary(f, z)
    assert summ["open_fraction"] == 0.5 and summ["slip_fraction"] == 0.0


def test_forces_are_continuous_as_re_contact_crosses_a_sample():
    """The balance must be continuous in the unknowns: as the mean normal approach moves the
    re-contact instant across samples, the force harmonics change in proportion (the largest
    increment over a fine grid within 5x the median one).  Re-sticking at the last open
    sample made them jump by ``kt`` times one sample's tangential motion (with a large mu the
    contact sticks for most of the closed stretch, which keeps the jump)."""
    el = make(1, mu=20.0, n0=0.1)
    X = np.zeros((BASIS.n_coef, 2))
    X[BASIS.row_of(1, "c"), 0], X[BASIS.row_of(1, "s"), 0] = 0.4, 0.3
    X[BASIS.row_of(1, "c"), 1] = 0.5
    means = np.linspace(0.0, 0.25, 501)        # the open stretch shrinks by several samples
    F, opened = [], []
    for m in means:
        X[BASIS.row_of(0, "c"), 1] = m
        Fm, _, f, z = coeff_march(el, BASIS, X)
        F.append(Fm[:, 0])
        opened.append(el.summary(f, z)["open_fraction"])
    steps = np.linalg.norm(np.diff(np.array(F), axis=0), axis=1)
    assert len(set(opened)) >= 4                           # re-contact crossed samples
    assert steps.max() <= 5.0 * np.median(steps), (steps.max(), np.median(steps))


def test_rest_is_force_free_and_init():
    el = make(2)
    z = np.zeros((16, 3))
    f, _ = run(el, z)
    assert np.all(f == 0.0)
    assert el.needs_mean and not el.velocity and el.n_state == 6
    np.testing.assert_array_equal(el.linear_stiffness(), np.diag([KT, KT, KN]))


def test_from_spec_keys_and_validation():
    cls = ELEMENTS["friction3d"]
    assert cls is Friction3D
    spec = {"type": "friction3d", "dofs": {"t1": [3, 0], "t2": [4, 1], "n": [5, 2]},
            "kt": 1e6, "kn": 2e6, "mu": 0.5, "normal_preload": 100.0, "name": "c1"}
    el = cls.from_spec(spec, 6)
    assert el.n_local == 3 and el.name == "c1" and el.n_state == 6
    G = np.zeros((3, 6))
    G[0, 3], G[0, 0], G[1, 4], G[1, 1], G[2, 5], G[2, 2] = 1, -1, 1, -1, 1, -1
    np.testing.assert_array_equal(el.gather, G)
    el2 = cls.from_spec({**spec, "dofs": {"t1": "a", "n": ["b"]}}, 6, dof_index={"a": 1, "b": 2})
    assert el2.n_local == 2 and el2.coord_names == ("t1", "n") and el2.n_state == 4
    np.testing.assert_array_equal(el2.gather[:, :3], [[0, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="'friction'"):
        cls.from_spec({**spec, "friction": 0.3}, 6)
    with pytest.raises(ValueError, match="'t3'"):
        cls.from_spec({**spec, "dofs": {"t1": 0, "t3": 1, "n": 2}}, 6)
    with pytest.raises(ValueError, match="'n'"):
        cls.from_spec({**spec, "dofs": {"t1": 0}}, 6)
    with pytest.raises(ValueError, match="'normal_preload'"):
        cls.from_spec({k: v for k, v in spec.items() if k != "normal_preload"}, 6)
    for key, bad in (("kt", 0.0), ("kn", -1.0), ("mu", -0.1), ("normal_preload", -5.0)):
        with pytest.raises(ValueError, match=key):
            cls.from_spec({**spec, key: bad}, 6)


# first-harmonic-dominated coefficients (units of 1e-5 m) of a contact of an FE patch
# (benchmarks/contact_patch.py, 16 contacts): a thin ellipse in (t1, t2) that barely slips
PATCH_U = np.array([[1.832e-04, 1.6556e-05, 0.0],
                    [9.5797e-01, 2.1606e-02, -3.2649e-03],
                    [8.0727e-01, 3.7429e-02, 2.6584e-05],
                    [-2.5728e-04, 2.4512e-04, 2.036e-10],
                    [-5.8976e-05, 5.4021e-05, 8.4831e-11],
                    [-5.5929e-04, -1.9993e-05, -8.9913e-09],
                    [-7.8120e-04, -2.5433e-05, -1.6894e-08]])


def _newton_and_plain(el, U, plain_passes, plain_tol):
    """One loop of ``el`` on coefficients ``U`` (n_coef, 3), H = 3, N = 128:
    ``(z, f, passes, f_plain, plain)``, the samples, the Newton closure's forces and passes,
    and the plain passes' (at most ``plain_passes``)."""
    from elements.law_march import march_of, CLOSE_PLAIN
    basis = FourierBasis(np.array([0, 1, 2, 3]), 128)
    z = np.ascontiguousarray(basis.E @ U)
    dz = np.zeros(z.shape + (1,))
    start = el.start_index(z[:, :el.n_local])
    f, _, passes = march_newton(el.kind, el.params, el.n_state, el.n_local, z, dz, start, el.max_passes,
                                el.closure_tol)
    f_plain, _, plain = march_of(el.kind, CLOSE_PLAIN)(el.params, el.n_state, el.n_local, z, dz, start,
                                                      plain_passes, plain_tol)
    return z, f, passes, f_plain, plain


@pytest.mark.parametrize("unit", [1e-5, 1.0])
def test_newton_closure_does_not_mix_units(unit):
    """The same loop in SI units (kt = 1.25e6 N/m, |u| ~ 1e-5 m) and in scaled units closes in
    a few passes (the period map contracts by 0.99 per pass) and equals the loop closed by
    plain passes.  The closure's condition number of ``I - M`` once mixed the force and
    displacement states (1e14 in SI units): Newton was refused and 1000 plain passes did not
    close the loop."""
    el = make(2, kt=12.5 / unit, kn=25.0 / unit, mu=0.5, n0=31.25)
    z, f, passes, f_plain, plain = _newton_and_plain(el, PATCH_U * unit, 20000, 1e-14)
    assert 0 < passes <= 12
    assert plain > 200                              # a slowly contracting loop indeed
    np.testing.assert_allclose(f, f_plain, atol=1e-9 * 15.6)
    assert el.summary(f, z)["slip_fraction"] > 0


# a contact of a 4-contact FE patch (tests/fe_patch.py, 200 N near 8300 Hz; units of 1e-5 m)
# that barely slips in 2D: kt |u_t| = 62.6 N against mu N0 = 62.5 N; its transverse force
# relaxes by 1.2e-4 of its change per period
BARELY_U = np.zeros((7, 3))
BARELY_U[:3] = [[5.0385049058e-03, 1.5198505862e-03, 0.0],
                [1.2382566370e+00, 9.3172258051e-02, -3.1292135848e-02],
                [1.4550979782e-01, 4.9456278427e-03, 3.3672218879e-04]]


def test_newton_closure_is_tried_again_after_a_pass_that_did_not_contract():
    """A Newton step across a change of the stick/slip pattern raises the residual; plain
    passes then follow for a while and Newton is tried again.  Turned off for good (as it was),
    this loop marched its 1000 periods unclosed; plain passes alone need 99 190."""
    el = make(2, kt=5e6, kn=1e7, mu=0.5, n0=125.0)
    _, f, passes, f_plain, plain = _newton_and_plain(el, BARELY_U * 1e-5, 200000, el.closure_tol)
    assert 0 < passes <= 50
    assert plain > 50000
    # the plain march stops within tol / (1 - 0.99988) of its fixed point: 1e-8 relative
    np.testing.assert_allclose(f, f_plain, atol=2e-8 * 62.5)
