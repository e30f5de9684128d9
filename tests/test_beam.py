"""Beam builder: cantilever frequencies against closed forms, axial/torsion, rigid offsets."""
import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from hbm.model.linear import LinearModel
from hbm.model.reduction import reduce_model
from hbm.builders import BUILDERS
from hbm.builders.beam import Section, build_beam_model, rigid_offset_rows

E, RHO, NU = 210e9, 7800.0, 0.3
L, B, H = 0.5, 0.02, 0.01
BETA_L = np.array([1.8751, 4.6941, 7.8548])


def modes(model):
    lam, phi = sla.eigh(model.K, model.M)
    return np.sqrt(lam), phi


def plane_frequencies(model, labs, count=3):
    """Lowest frequencies of modes whose motion is dominated by DOFs ``*.lab`` for lab in labs."""
    om, phi = modes(model)
    sel = [i for i, n in enumerate(model.dof_names) if n.split(".")[1] in labs]
    frac = (phi[sel] ** 2).sum(axis=0) / (phi ** 2).sum(axis=0)
    return om[frac > 0.5][:count]


@pytest.mark.parametrize("lumped", [False, True])
def test_cantilever_bending_both_planes(lumped):
    m = BUILDERS["beam"](length=L, n_elements=30, E=E, rho=RHO, nu=NU, width=B, height=H,
                         lumped_mass=lumped)
    sec = Section.rectangle(B, H)
    for lab, I in ((("uy", "rz"), sec.Iz), (("uz", "ry"), sec.Iy)):
        exact = BETA_L**2 * np.sqrt(E * I / (RHO * sec.area * L**4))
        got = plane_frequencies(m, lab)
        err = np.abs(got / exact - 1.0)
        print(f"lumped={lumped} plane {lab}: relative errors {err}")
        assert np.all(err < 5e-3)


def test_axial_and_torsion():
    m = build_beam_model(length=L, n_elements=20, E=E, rho=RHO, nu=NU, width=B, height=H)
    sec = Section.rectangle(B, H)
    G = E / (2 * (1 + NU))
    tip = 20
    # static tip loads are exact for these elements
    f = np.zeros(m.n_dof)
    f[m.dof_index(f"n{tip}.ux")] = 1000.0
    f[m.dof_index(f"n{tip}.rx")] = 3.0
    u = np.linalg.solve(m.K, f)
    assert np.isclose(u[m.dof_index(f"n{tip}.ux")], 1000.0 * L / (E * sec.area), rtol=1e-10)
    assert np.isclose(u[m.dof_index(f"n{tip}.rx")], 3.0 * L / (G * sec.J), rtol=1e-10)
    # first axial and torsional frequencies of the fixed-free rod
    om_ax = np.pi / (2 * L) * np.sqrt(E / RHO)
    om_t = np.pi / (2 * L) * np.sqrt(G * sec.J / (RHO * sec.Ip))
    assert abs(plane_frequencies(m, ("ux",), 1)[0] / om_ax - 1) < 5e-3
    assert abs(plane_frequencies(m, ("rx",), 1)[0] / om_t - 1) < 5e-3


def test_rectangle_torsion_constant_square():
    s = Section.rectangle(1.0, 1.0)
    assert np.isclose(s.J, 0.1406, rtol=2e-3)     # tabulated 0.1406 a^4 for a square


def test_rigid_offset_maps_rotation_to_translation():
    r = np.array([0.0, 0.1, 0.0])
    T = rigid_offset_rows(r)
    q = np.array([0, 0, 0, 0, 0, 1e-3])            # rotation about z
    assert np.allclose(T @ q, [-1e-4, 0.0, 0.0])
    rng = np.random.default_rng(0)
    for _ in range(5):
        r = rng.normal(size=3)
        u, th = rng.normal(size=3), rng.normal(size=3)
        assert np.allclose(rigid_offset_rows(r) @ np.r_[u, th], u + np.cross(th, r))
    m = build_beam_model(length=L, n_elements=4, E=E, rho=RHO, width=B, height=H,
                         points={"platform": (4, (0.0, 0.0, 0.01))})
    G = m.point_rows("platform")
    q = np.zeros(m.n_dof)
    q[m.dof_index("n4.ry")] = 2e-3                 # rotation about y: r = 0.01 z -> ux = +2e-5
    assert np.allclose(G @ q, [2e-5, 0.0, 0.0])
    assert set(m.point_dofs("platform")) == {m.dof_index(f"n4.{d}") for d in ("ux", "uy", "uz", "rx", "ry")}


def test_point_masses_add_mass():
    base = build_beam_model(length=L, n_elements=4, E=E, rho=RHO, width=B, height=H)
    m = build_beam_model(length=L, n_elements=4, E=E, rho=RHO, width=B, height=H,
                         points={"p": (4, (0.0, 0.05, 0.0))}, point_masses={2: 0.3, "p": 0.2})
    dM = m.M - base.M
    ones = np.zeros(m.n_dof)
    ones[[m.dof_index(f"n{i}.ux") for i in range(1, 5)]] = 1.0   # rigid translation along x
    assert np.isclose(ones @ dM @ ones, 0.5)
    # mass at the offset point also gives rotary inertia about x: m r^2
    e = np.zeros(m.n_dof); e[m.dof_index("n4.rx")] = 1.0
    assert np.isclose(e @ dM @ e, 0.2 * 0.05**2)


def test_sparse_output_and_names():
    m = build_beam_model(length=L, n_elements=10, E=E, rho=RHO, width=B, height=H, sparse=True)
    assert sp.issparse(m.K) and m.n_dof == 60
    assert m.dof_names[0] == "n1.ux" and m.dof_names[-1] == "n10.rz"
    d = build_beam_model(length=L, n_elements=10, E=E, rho=RHO, width=B, height=H)
    assert np.allclose(m.K.toarray(), d.K)


def test_beam_residual_flexibility_ratio():
    """Truncated beam FRF at tip and mid-span: residual flexibility against plain truncation."""
    m = build_beam_model(length=L, n_elements=20, E=E, rho=RHO, width=B, height=H)
    keep = [m.dof_index("n20.uy"), m.dof_index("n10.uy"), m.dof_index("n20.uz")]
    lin = LinearModel.with_damping(m.M, m.K, modal_damping=0.01)
    om = np.sqrt(sla.eigh(m.K, m.M, eigvals_only=True))
    Ws = np.linspace(0.05 * om[0], 1.1 * om[3], 400)
    errs = []
    for resid in (False, True):
        red = reduce_model(m.M, m.K, n_modes=6, modal_damping=0.01, keep_dofs=keep,
                           residual_flexibility=resid)
        num = den = 0.0
        for W in Ws:
            Hx = np.linalg.inv(lin.K - W * W * lin.M + 1j * W * lin.C)[np.ix_(keep, keep)]
            num += np.abs(red.receptance(W) - Hx).sum() ** 2
            den += np.abs(Hx).sum() ** 2
        errs.append(np.sqrt(num / den))
    print(f"beam FRF error: plain {errs[0]:.3e}, residual {errs[1]:.3e}, ratio {errs[0] / errs[1]:.1f}")
    assert errs[0] / errs[1] >= 10.0


def test_bad_inputs():
    with pytest.raises(ValueError, match="width/height or area"):
        build_beam_model(length=1, n_elements=2, E=E, rho=RHO, width=B, height=H, area=1.0)
    with pytest.raises(ValueError, match="clamp"):
        build_beam_model(length=1, n_elements=2, E=E, rho=RHO, width=B, height=H, clamp=())
    with pytest.raises(ValueError, match="unknown point"):
        build_beam_model(length=1, n_elements=2, E=E, rho=RHO, width=B, height=H,
                         point_masses={"nope": 1.0})
    with pytest.raises(ValueError, match="positive"):
        build_beam_model(length=1, n_elements=2, E=-1.0, rho=RHO, width=B, height=H)
