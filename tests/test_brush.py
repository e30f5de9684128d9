"""brush: one bristle is friction3d, a flat brush is a summed friction3d, microslip energy
(cube law, exact bristle sum, gross slip at mu N), Winkler load against the closed form,
Hertz-equivalent stiffness, FD Jacobian with rotations, case keys."""
import math

import numpy as np
import pytest

from elements import ELEMENTS, Brush, Friction3D
from elements.hertz import hertz_contact, winkler_load
from elements.loops import describing_function, dissipated_energy, harmonic_motion, loop_forces
from hbm.balance.fourier import FourierBasis

BASIS = FourierBasis(np.array([0, 1, 2, 3]), 64)
ALL = ("t1", "t2", "n", "rx", "ry")


def seeds(basis, nloc):
    nc = basis.n_coef
    dz = np.zeros((basis.n_samples, nloc, nc * nloc))
    for k in range(nc):
        for a in range(nloc):
            dz[:, a, k * nloc + a] = basis.E[:, k]
    return dz


def coeff_march(el, X, basis=BASIS):
    z = basis.E @ X
    f, df = el.march(z, seeds(basis, el.n_local))
    return basis.P @ f, np.einsum("kj,jap->kap", basis.P, df)


def fd_error(el, X, rel_step=1e-6):
    F, dF = coeff_march(el, X)
    h = rel_step * np.abs(X).max()
    x = X.reshape(-1)
    fd = np.empty_like(dF)
    for p in range(x.size):
        xp, xm = x.copy(), x.copy()
        xp[p] += h
        xm[p] -= h
        fd[:, :, p] = (coeff_march(el, xp.reshape(X.shape))[0] - coeff_march(el, xm.reshape(X.shape))[0]) / (2 * h)
    return np.abs(dF - fd).max() / np.abs(fd).max()


def first_harmonic(X, col, amp, phase):
    c, s = BASIS.row_of(1, "c"), BASIS.row_of(1, "s")
    X[c, col] += amp * np.cos(phase)
    X[s, col] -= amp * np.sin(phase)


# ---------------------------------------------------------------- one bristle = friction3d
@pytest.mark.parametrize("path", ["stick", "slip", "mixed2d", "separation"])
def test_single_bristle_equals_friction3d(path):
    rng = np.random.default_rng(3)
    kt, kn, mu, n0 = 1.0, 2.0, 0.5, 1.0
    amp = {"stick": (0.1, 0.1, 0.05), "slip": (3.0, 0.0, 0.1), "mixed2d": (0.9, 0.5, 0.2),
           "separation": (0.8, 0.6, 0.9)}[path]
    X = 0.03 * rng.standard_normal((BASIS.n_coef, 3)) * np.r_[amp][None, :]
    for col, (a, ph) in enumerate(zip(amp, (0.0, 1.1, 2.0))):
        first_harmonic(X, col, a, ph)
    br = Brush(np.eye(3), ("t1", "t2", "n"), kn=kn, kt=kt, mu=mu, normal_preload=n0, radius_x=1.0,
               radius_y=2.0, lx=0.1, ly=0.1, nx=1, ny=1)
    fr = Friction3D(np.eye(3), kt=kt, kn=kn, mu=mu, normal_preload=n0)
    z = BASIS.E @ X
    dz = seeds(BASIS, 3)
    fb, dfb, counts = br.march_counts(z, dz)
    ff, dff = fr.march(z, dz)
    assert counts[1 if path == "stick" else 2] == 1        # the advertised path (shortcut or march)
    np.testing.assert_allclose(fb, ff, rtol=0, atol=1e-14 * np.abs(ff).max())
    np.testing.assert_allclose(dfb, dff, rtol=0, atol=1e-14 * np.abs(dff).max())
    if path != "stick":
        assert np.array_equal(fb, ff) and np.array_equal(dfb, dff)   # the same kernel, bit for bit


def test_flat_uniform_brush_is_summed_friction3d():
    """Flat indenter, uniform motion (rotations zero): one friction3d with summed kt, kn, N0."""
    nx, ny, kt, kn, mu, n0 = 3, 2, 0.5, 1.5, 0.4, 3.0
    nb = nx * ny
    G = np.zeros((5, 3))
    G[:3] = np.eye(3)
    br = Brush(G, ALL, kn=kn, kt=kt, mu=mu, normal_preload=n0, radius_x=math.inf, radius_y=math.inf,
               lx=1.0, ly=0.5, nx=nx, ny=ny)
    assert br.n_unique == nb                       # rotation coordinates keep the bristles apart
    fr = Friction3D(np.eye(3), kt=nb * kt, kn=nb * kn, mu=mu, normal_preload=n0)
    rng = np.random.default_rng(5)
    for amp in ((0.2, 0.1, 0.1), (2.0, 1.2, 0.4), (1.5, 0.5, 2.5)):   # stick, 2D slip, separation
        X = np.zeros((BASIS.n_coef, 3))
        for col, (a, ph) in enumerate(zip(amp, rng.uniform(0, 2 * np.pi, 3))):
            first_harmonic(X, col, a, ph)
        z3 = BASIS.E @ X
        z5 = np.hstack([z3, np.zeros((z3.shape[0], 2))])
        fb = loop_forces(br, z5)
        ff = loop_forces(fr, z3)
        np.testing.assert_allclose(fb[:, :3], ff, rtol=1e-12, atol=1e-12 * np.abs(ff).max())
        np.testing.assert_allclose(fb[:, 3:], 0.0, atol=1e-12 * np.abs(ff).max())   # no moments


# ---------------------------------------------------------------- microslip
def line_brush(nx=400, kt_ratio=0.3, k=1.2e16, load=50.0):
    R, lx, ly = 2.6e-3, 30e-6, 1e-3
    area = (2 * lx / nx) * (2 * ly)
    return Brush(np.eye(2), ("t1", "n"), kn=k * area, kt=kt_ratio * k * area, mu=0.14, normal_preload=load,
                 radius_x=R, radius_y=math.inf, lx=lx, ly=ly, nx=nx, ny=1)


def test_microslip_energy_cube_law_and_gross_slip():
    br = line_brush()
    Nb = br.kn * np.maximum(br.delta0 - br.h, 0.0)
    kt_total = br.kt * np.count_nonzero(Nb)
    a_gross = 0.14 * 50.0 / kt_total          # where a macroslip element of the same stiffness slips
    amps = a_gross * np.geomspace(0.05, 0.25, 5)
    _, c_eq, W = describing_function(br, amps, n_samples=512)
    assert np.all(W > 0) and np.all(np.diff(W) > 0)
    # exact: every bristle is a Jenkins element, W_b = 4 mu N_b (a - mu N_b / kt)+
    W_exact = np.array([np.sum(4 * 0.14 * Nb * np.maximum(a - 0.14 * Nb / br.kt, 0.0)) for a in amps])
    np.testing.assert_allclose(W, W_exact, rtol=1e-4)
    slope = np.polyfit(np.log(amps), np.log(W), 1)[0]
    assert abs(slope - 3.0) < 0.15, slope
    # a macroslip point contact with the same stuck stiffness and limit dissipates nothing here
    macro = Friction3D(np.eye(2), kt=kt_total, kn=br.kn * np.count_nonzero(Nb), mu=0.14, normal_preload=50.0)
    _, _, W_macro = describing_function(macro, amps, n_samples=512)
    assert np.all(np.abs(W_macro) < 1e-12 * W.max())
    # gross slip: the loop saturates at mu N exactly
    z = harmonic_motion(256, [3 * a_gross, 0.0])
    f = loop_forces(br, z)
    np.testing.assert_allclose(np.abs(f[:, 0]).max(), 0.14 * 50.0, rtol=1e-12)
    assert np.all(f[:, 1] == 0.0)               # constant normal load: no dynamic normal force
    np.testing.assert_allclose(dissipated_energy(z, f),
                               np.sum(4 * 0.14 * Nb * np.maximum(3 * a_gross - 0.14 * Nb / br.kt, 0.0)), rtol=1e-3)


def test_masing_symmetry_and_variable_load_asymmetry():
    br = line_brush(nx=60)
    z = harmonic_motion(256, [1.5e-8, 0.0])
    f = loop_forces(br, z)
    j = np.arange(256)
    np.testing.assert_allclose(f[(j + 128) % 256, 0], -f[:, 0], atol=1e-12 * np.abs(f).max())
    zv = harmonic_motion(256, [1.5e-8, 0.2 * br.delta0])     # approach in phase with the slip
    fv = loop_forces(br, zv)
    assert fv[:, 0].max() > 1.2 * -fv[:, 0].min()
    assert fv[:, 1].max() > 0 > fv[:, 1].min()


# ---------------------------------------------------------------- Winkler normal load
def test_winkler_load_converges_to_closed_form():
    rx, ry, k, N0 = 25e-3, 2.5e-3, 1.7e15, 50.0
    delta = math.sqrt(N0 / (math.pi * k * math.sqrt(rx * ry)))
    ax, ay = math.sqrt(2 * rx * delta), math.sqrt(2 * ry * delta)
    errs, d_errs = [], []
    for n in (10, 20, 40):
        lx, ly = 1.15 * ax, 1.15 * ay
        area = (2 * lx / n) * (2 * ly / n)
        br = Brush(np.eye(3), ("t1", "t2", "n"), kn=k * area, kt=1e5, mu=0.14, normal_preload=0.0,
                   radius_x=rx, radius_y=ry, lx=lx, ly=ly, nx=n, ny=n)
        # impose the approach delta statically: f_n = total load (N0 = 0 at rest)
        z = np.zeros((4, 3))
        z[:, 2] = delta - br.delta0
        fn = loop_forces(br, z)[0, 2]
        errs.append(abs(fn / winkler_load(delta, k, rx, ry) - 1.0))
        br0 = Brush(np.eye(3), ("t1", "t2", "n"), kn=k * area, kt=1e5, mu=0.14, normal_preload=N0,
                    radius_x=rx, radius_y=ry, lx=lx, ly=ly, nx=n, ny=n)
        d_errs.append(abs(br0.delta0 / delta - 1.0))
    assert errs[0] > errs[1] > errs[2] and errs[2] < 2e-4, errs
    assert d_errs[0] > d_errs[2] and d_errs[2] < 1e-4, d_errs
    assert errs[0] / errs[2] > 8          # measured 2.0e-3, 1.1e-3, 4.6e-5 (n = 10, 20, 40)


def test_hertz_equivalent_foundation():
    E = 1.1e11
    pt = hertz_contact(50.0, 5e-3, 5e-3, E)
    np.testing.assert_allclose(pt.a, (3 * 50.0 * 5e-3 / (4 * E)) ** (1 / 3), rtol=1e-14)
    np.testing.assert_allclose(pt.k_winkler * pt.b / E, 16 / (3 * np.pi), rtol=1e-12)      # 1.70
    ln = hertz_contact(50.0, math.inf, 2.6e-3, E, length=13e-3)
    np.testing.assert_allclose(ln.k_winkler * ln.b / E, 3 * np.pi / 8, rtol=1e-12)        # 1.18
    el = hertz_contact(50.0, 25e-3, 2.5e-3, E)
    near = hertz_contact(50.0, 5e-3 * (1 + 1e-4), 5e-3, E)
    np.testing.assert_allclose([near.a, near.b], [pt.a, pt.b], rtol=1e-4)
    assert el.a > el.b
    # the foundation really has the Hertz contact area at that load
    d = math.sqrt(50.0 / (math.pi * el.k_winkler * math.sqrt(25e-3 * 2.5e-3)))
    np.testing.assert_allclose(math.pi * 2 * d * math.sqrt(25e-3 * 2.5e-3), math.pi * el.a * el.b, rtol=1e-12)
    spec = dict(type="brush", dofs={"t1": 0, "n": 1}, mu=0.14, normal_preload=50.0, radius_x=25e-3,
                radius_y=2.5e-3, lx=0.35e-3, ly=0.11e-3, nx=15, ny=9, e_star=E, gamma_t=0.15)
    br = Brush.from_spec(spec, 2)
    np.testing.assert_allclose(br.kn, el.k_winkler * br.area, rtol=1e-12)
    np.testing.assert_allclose(br.kt, 0.15 * E * br.area / el.b, rtol=1e-12)


# ---------------------------------------------------------------- Jacobian
def rolling_brush(nt=2, mu=0.3, pivot=0.0):
    names = ("t1", "t2", "n", "rx", "ry") if nt == 2 else ("t1", "n", "ry")
    return Brush(np.eye(len(names)), names, kn=1.0, kt=0.6, mu=mu, normal_preload=3.0, radius_x=2.0,
                 radius_y=1.0, lx=2.0, ly=1.5, nx=6, ny=5, pivot_height=pivot)


FD_CASES = ["slip2d_rolling", "tilt_separation", "stick_rolling_1d", "pivot_rolling"]


@pytest.mark.parametrize("case", FD_CASES)
def test_fd_jacobian_with_rotations(case):
    rng = np.random.default_rng(FD_CASES.index(case))
    if case == "slip2d_rolling":
        br = rolling_brush()
        amp, ph = (1.2, 0.7, 0.1, 0.08, 0.1), (0.0, 1.2, 0.4, 2.0, 0.9)
    elif case == "pivot_rolling":
        br = rolling_brush(pivot=4.0)
        amp, ph = (0.3, 0.2, 0.1, 0.08, 0.1), (0.0, 1.2, 0.4, 2.0, 0.9)
    elif case == "tilt_separation":
        br = rolling_brush()
        amp, ph = (0.5, 0.3, 0.6, 0.25, 0.3), (0.0, 2.2, 0.3, 1.0, 2.5)
    else:
        br = rolling_brush(nt=1)
        amp, ph = (0.1, 0.05, 0.03), (0.0, 0.5, 1.4)
    X = 0.02 * rng.standard_normal((BASIS.n_coef, br.n_local)) * np.r_[amp][None, :]
    for col, (a, p) in enumerate(zip(amp, ph)):
        first_harmonic(X, col, a, p)
    _, _, counts = br.march_counts(BASIS.E @ X, np.zeros((BASIS.n_samples, br.n_local, 1)))
    assert counts[2] > 0 and counts[3] > 0          # some bristles are marched, and their loops closed
    if case == "tilt_separation":
        assert counts[0] > 0 and counts[2] >= 20
    if case == "stick_rolling_1d":
        assert counts[1] > 0                         # stuck shortcut and marched bristles together
    err = fd_error(br, X)
    assert err < 1e-6, (case, err)


def test_pivot_rotation_is_contact_slip_plus_moment():
    """Rotation about a pivot c above the contact = the same rotation about the contact centre
    plus the tangential motion c theta; the friction force adds the moment c f_t."""
    c = 4.0
    rng = np.random.default_rng(11)
    X = np.zeros((BASIS.n_coef, 5))
    for col, a in enumerate((0.3, 0.2, 0.1, 0.08, 0.1)):
        first_harmonic(X, col, a, rng.uniform(0, 2 * np.pi))
    z = BASIS.E @ X
    zc = z.copy()
    zc[:, 0] += c * z[:, 4]
    zc[:, 1] -= c * z[:, 3]
    fp = loop_forces(rolling_brush(pivot=c), z)
    f0 = loop_forces(rolling_brush(), zc)
    np.testing.assert_allclose(fp[:, :3], f0[:, :3], rtol=0, atol=1e-13)
    np.testing.assert_allclose(fp[:, 3], f0[:, 3] - c * f0[:, 1], rtol=0, atol=1e-13)
    np.testing.assert_allclose(fp[:, 4], f0[:, 4] + c * f0[:, 0], rtol=0, atol=1e-13)
    assert np.abs(f0[:, :2]).max() > 0.1


@pytest.mark.parametrize("pivot", [0.0, 4.0])
def test_rest_state_and_linear_stiffness(pivot):
    br = rolling_brush(pivot=pivot)
    f = loop_forces(br, np.zeros((8, 5)))
    assert np.all(f == 0.0)
    # stuck tangent at rest = derivative of a tiny motion
    X = np.zeros((BASIS.n_coef, 5))
    X[BASIS.row_of(1, "c")] = 1e-9
    _, dF = coeff_march(br, X)
    c = BASIS.row_of(1, "c")
    K = dF[c, :, c * 5:(c + 1) * 5]
    np.testing.assert_allclose(K, br.linear_stiffness(), rtol=1e-10, atol=1e-12)
    st = br.static_state()
    Nb = br.kn * np.maximum(st["approach"] - br.h, 0.0)
    np.testing.assert_allclose(Nb.sum(), 3.0, rtol=1e-13)
    np.testing.assert_allclose([np.sum(Nb * br.x), np.sum(Nb * br.y)], 0.0, atol=1e-12)


# ---------------------------------------------------------------- case keys
def test_from_spec_keys_and_validation():
    cls = ELEMENTS["brush"]
    assert cls is Brush
    spec = {"type": "brush", "dofs": {"t1": [0, 3], "n": [2, 5], "ry": [1, 4]}, "kn": 1.0, "kt": 0.5,
            "mu": 0.2, "normal_preload": 2.0, "radius_x": 1.0, "radius_y": math.inf, "lx": 2.0, "ly": 1.0,
            "nx": 8, "ny": 3, "name": "c1"}
    br = cls.from_spec(spec, 6)
    assert br.coord_names == ("t1", "n", "ry") and br.n_local == 3 and br.name == "c1"
    assert br.n_unique == 8                     # flat along y: the 3 rows are one
    np.testing.assert_array_equal(br.gather[0], [1, 0, 0, -1, 0, 0])
    with pytest.raises(ValueError, match="'friction'"):
        cls.from_spec({**spec, "friction": 0.3}, 6)
    with pytest.raises(ValueError, match="'rz'"):
        cls.from_spec({**spec, "dofs": {"t1": 0, "n": 1, "rz": 2}}, 6)
    with pytest.raises(ValueError, match="either"):
        cls.from_spec({**spec, "e_star": 1e11}, 6)
    with pytest.raises(ValueError, match="'kt'"):
        cls.from_spec({k: v for k, v in spec.items() if k != "kt"}, 6)
    with pytest.raises(ValueError, match="edge"):
        cls.from_spec({**spec, "lx": 0.5}, 6)
    with pytest.raises(ValueError, match="nx"):
        cls.from_spec({**spec, "nx": 0}, 6)
    with pytest.raises(ValueError, match="flat"):
        cls.from_spec({k: v for k, v in spec.items() if k not in ("kn", "kt")}
                      | {"radius_x": math.inf, "e_star": 1e11, "gamma_t": 0.1}, 6)


# ---------------------------------------------------------------- beam-damper-beam rig
