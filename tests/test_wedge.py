"""Wedge (cottage-roof) underplatform damper: static loads, stuck limit, IP/OoP behaviour,
optimal CF, rolling with points along the flanks, exact Jacobian, case keys, the rig file."""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import fsolve

import hbm
from hbm.interface.case import CaseError, case_from_dict
from hbm.balance.fourier import FourierBasis
from hbm.balance.newton import newton
from hbm.analyses.postprocess import element_summaries
from hbm.balance.dense_part import dense_balance
from hbm.analyses.response import _unknown_scale
from hbm.balance.transforms import make_transform
from elements.wedge_statics import static_normal_loads

ROOT = Path(__file__).resolve().parents[1]
KB = (2 * np.pi * 100.0) ** 2          # blade bending stiffness (1 kg: 100 Hz)


# ----------------------------------------------------------------------------- statics
@pytest.mark.parametrize("a_deg", [30.0, 45.0, 60.0])
@pytest.mark.parametrize("mu", [0.0, 0.2, 0.6])
def test_static_loads_symmetric_eq2(a_deg, mu):
    a = math.radians(a_deg)
    if abs(2 * a - 2 * math.atan(mu)) < 1e-3:
        pytest.skip("singular")
    cf = 123.0
    N = static_normal_loads(cf, [a, a], mu)
    ref = cf / (2 * (math.cos(a) + mu * math.sin(a)))
    assert N == pytest.approx([ref, ref], rel=1e-12)


def _equilibrium_residual(N, cf, aL, aR, muL, muR):
    """Forces on the damper written from the geometry: platform pushes along -n (into the
    damper), friction opposes the damper's outward slide, i.e. acts along minus the flank
    direction that the unit radial motion (0, 1) projects onto."""
    total = np.array([0.0, cf])
    for Ns, a, mu, side in ((N[0], aL, muL, -1), (N[1], aR, muR, +1)):
        normal_out = np.array([side * math.sin(a), math.cos(a)])     # damper -> platform
        slide = np.array([0.0, 1.0]) - normal_out * math.cos(a)       # tangential part of e_y
        slide /= np.linalg.norm(slide)
        total += -Ns * normal_out - mu * Ns * slide
    return total


@pytest.mark.parametrize("angles, mus", [((40.0, 55.0), (0.3, 0.3)), ((35.0, 50.0), (0.25, 0.45)),
                                         ((60.0, 30.0), (0.1, 0.2))])
def test_static_loads_unequal_against_direct_solve(angles, mus):
    aL, aR = (math.radians(a) for a in angles)
    cf = 80.0
    N = static_normal_loads(cf, [aL, aR], list(mus))
    ref = fsolve(_equilibrium_residual, [cf / 2, cf / 2], args=(cf, aL, aR, *mus), xtol=1e-10)
    assert np.abs(_equilibrium_residual(ref, cf, aL, aR, *mus)).max() < 1e-9
    assert N == pytest.approx(ref, rel=1e-10)
    assert abs(N[0] - N[1]) > 1.0          # really unequal


def test_static_loads_reject_angles_straddling_friction_angle():
    with pytest.raises(ValueError, match="friction angle"):
        static_normal_loads(10.0, [math.radians(10), math.radians(60)], 0.5)   # atan(0.5) = 26.6 deg


# ----------------------------------------------------------------------------- cases
def blade_k(sign, beta=0.2):
    """Platform-edge stiffness (x, y) of a blade whose bending mode moves along (1, sign*beta)."""
    e = np.array([1.0, sign * beta]) / math.hypot(1.0, beta)
    ep = np.array([-e[1], e[0]])
    return KB * np.outer(e, e) + 10 * KB * np.outer(ep, ep)


GEOM2 = {"inertia": 0.05 * 0.01 ** 2 / 6, "flank_length": 0.01,
         "centres": [[-0.005, 0.003], [0.005, 0.003]]}


def pair_data(cf=30.0, drive=(1.0, 0.0), ppf=1, three_d=False, mu=0.3, damping=None, f_hz=(90.0, 135.0),
              **extra):
    nd = 3 if three_d else 2
    K = np.zeros((2 * nd, 2 * nd))
    K[:2, :2] = blade_k(+1)
    K[nd:nd + 2, nd:nd + 2] = blade_k(-1)
    if three_d:
        K[2, 2] = K[nd + 2, nd + 2] = 10 * KB
    names = [f"{b}.{c}" for b in "AB" for c in ("xyz" if three_d else "xy")]
    el = {"type": "wedge_damper", "name": "upd", "left": {"x": "A.x", "y": "A.y"},
          "right": {"x": "B.x", "y": "B.y"}, "angles_deg": [45.0, 45.0], "mass": 0.05, "cf": cf,
          "mu": mu, "kt": 2e5, "kn": 4e5, "points_per_flank": ppf}
    if three_d:
        el["left"]["z"], el["right"]["z"] = "A.z", "B.z"
    if ppf >= 2:
        el.update(GEOM2)
    el.update(extra)
    model = {"mass": np.eye(2 * nd).tolist(), "stiffness": K.tolist(), "dof_names": names}
    if damping is None:
        model["modal_damping"] = 0.005
    else:
        model["rayleigh"] = list(damping)
    return {"name": "blade pair", "model": model, "element": [el],
            "excitation": {"dofs": ["A.x", "B.x"], "amplitude": list(drive)},
            "analysis": {"harmonics": 3, "time_samples": 64, "frequency_hz": list(f_hz),
                         "outputs": {"ax": "A.x", "bx": "B.x"}}}


# ----------------------------------------------------------------------------- stuck limit
def stuck_reference(case, data, freqs, ppf):
    """Linear FRF of the blades coupled through the stuck flanks, assembled here by hand."""
    el = data["element"][0]
    n_pl = 6
    m, kt, kn = el["mass"], el["kt"], el["kn"]
    ka = el["anchor_stiffness"]
    kw = el.get("wire_stiffness", 0.0)
    L = el.get("flank_length", 0.0)
    Mb = np.array(data["model"]["mass"])
    Kb = np.array(data["model"]["stiffness"])
    a, b = data["model"]["rayleigh"]
    rot = ppf >= 2
    nint = 4 if rot else 3
    n = n_pl + nint
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    M[:n_pl, :n_pl] = Mb
    K[:n_pl, :n_pl] = Kb
    C[:n_pl, :n_pl] = a * Mb + b * Kb
    dx, dy, dz = n_pl, n_pl + 1, n_pl + 2
    M[dx, dx] = M[dy, dy] = M[dz, dz] = m
    K[dx, dx] = K[dz, dz] = ka
    K[dy, dy] = ka + kw
    if rot:
        M[n_pl + 3, n_pl + 3] = el["inertia"]
        K[n_pl + 3, n_pl + 3] = ka * (L / 2) ** 2
    for side, plat in ((-1, (0, 1, 2)), (+1, (3, 4, 5))):
        ang = math.radians(45.0)
        nrm = np.array([side * math.sin(ang), math.cos(ang)])      # outward normal of the flank
        tan = np.array([math.cos(ang), -side * math.sin(ang)])     # along the flank (either sense)
        centre = np.array(el["centres"][0 if side < 0 else 1]) if rot else np.zeros(2)
        offsets = [-L / 2, L / 2] if rot else [0.0]
        for o in offsets:
            r = centre + o * tan
            # displacement of the damper point: (dx - r_y rz, dy + r_x rz, dz); minus the platform
            B = np.zeros((3, n))
            for row, v in enumerate((tan, None, nrm)):
                if v is None:
                    B[row, dz], B[row, plat[2]] = 1.0, -1.0
                    continue
                B[row, dx], B[row, dy] = v
                if rot:
                    B[row, n_pl + 3] = -r[1] * v[0] + r[0] * v[1]
                B[row, plat[0]], B[row, plat[1]] = -v
            D = np.diag([kt, kt, kn]) / len(offsets)
            K += B.T @ D @ B
    f = np.zeros(n)
    f[0] = 1.0
    out = []
    for fr in freqs:
        w = 2 * np.pi * fr
        out.append(np.linalg.solve(K - w * w * M + 1j * w * C, f))
    return np.abs(np.array(out))


@pytest.mark.parametrize("ppf", [1, 2])
def test_stuck_damper_is_linear_coupling(ppf):
    data = pair_data(cf=1e9, drive=(1.0, 0.0), ppf=ppf, three_d=True, damping=(2.0, 2e-6),
                     anchor_stiffness=50.0, wire_stiffness=3e4, f_hz=(80.0, 140.0))
    data["analysis"]["outputs"] = {"ax": "A.x", "by": "B.y", "bz": "B.z", "dx": "upd.x", "dz": "upd.z"}
    if ppf == 2:
        data["analysis"]["outputs"]["rz"] = "upd.rz"
        # asymmetric geometry, so the rotation couples into everything
        data["element"][0]["centres"] = [[-0.006, 0.002], [0.004, 0.0035]]
    # an excitation that also drives z
    data["excitation"] = {"dofs": ["A.x", "A.z"], "amplitude": [1.0, 0.0]}
    case = case_from_dict(data)
    res = hbm.frf(case)
    assert res.ok, res.message
    assert res.freq_hz.size > 20
    ref = stuck_reference(case, data, res.freq_hz, ppf)
    cols = {"ax": 0, "by": 4, "bz": 5, "dx": 6, "dz": 8, "rz": 9}
    for name, o in res.outputs.items():
        r = ref[:, cols[name]]
        assert np.allclose(o.h1, r, rtol=1e-7, atol=1e-12 * ref.max()), name
    # the resonances are in range and the comparison is not trivial
    assert ref[:, 0].max() > 20 * ref[0, 0]
    if ppf == 2:
        assert ref[:, 9].max() > 1e-4 * ref[:, 0].max() / 0.005


# ----------------------------------------------------------------------------- IP / OoP
def grid_solutions(case, freqs, X0=None):
    """Harmonic-balance solutions along a frequency grid, Newton warm-started point to point."""
    b = FourierBasis(case.analysis.harmonics, case.analysis.time_samples)
    p = dense_balance(case.model, case.elements, b, case.excitation.force, make_transform(b, "auto"))
    sc = _unknown_scale(p, case, 2 * np.pi * freqs.min(), 2 * np.pi * freqs.max())
    Ks = p.stuck_stiffness()
    fs = float(np.linalg.norm(case.excitation.force))
    X, out = X0, []
    for f in freqs:
        w = 2 * np.pi * f
        fun = lambda x, w=w: p.residual(x.reshape(p.load(w).shape), w)[:2]
        starts = ([X] if X is not None else []) + [p.linear_solution(w, Ks), p.linear_solution(w)]
        for g in starts:
            res = newton(fun, g.ravel(), scale=sc, r_scale=fs, max_iter=40)
            if res.converged:
                break
        assert res.converged, (f, res.message)
        X = res.x.reshape(p.load(w).shape)
        out.append(X)
    return b, p, np.array(out)


def peak(case, f_lo, f_hi, dof=0):
    """Peak first-harmonic amplitude of ``dof`` in [f_lo, f_hi]: 1 Hz grid, then 0.05 Hz around."""
    coarse = np.arange(f_lo, f_hi + 1e-9, 1.0)
    b, p, Xs = grid_solutions(case, coarse)
    rc = b.row_of(1, "c")
    amp = np.hypot(Xs[:, rc, dof], Xs[:, rc + 1, dof])
    i = int(np.argmax(amp))
    fine = np.arange(coarse[max(i - 1, 0)], coarse[min(i + 1, coarse.size - 1)] + 1e-9, 0.05)
    b, p, Xf = grid_solutions(case, fine, Xs[max(i - 1, 0)])
    amp = np.hypot(Xf[:, rc, dof], Xf[:, rc + 1, dof])
    j = int(np.argmax(amp))
    return fine[j], amp[j], p, Xf[j]


IP, OOP = (1.0, 1.0), (1.0, -1.0)


def test_out_of_phase_mode_damped_and_shifted_far_more_than_in_phase():
    f_free = 100.0
    free_peak = 1.0 / (2 * 0.005 * KB) / math.hypot(1.0, 0.2)     # x amplitude of a blade, no damper
    f_ip, a_ip, p, X = peak(case_from_dict(pair_data(cf=10.0, drive=IP)), 92, 108)
    f_oop, a_oop, p2, X2 = peak(case_from_dict(pair_data(cf=10.0, drive=OOP)), 100, 132)
    shift_ip, shift_oop = abs(f_ip - f_free) / f_free, abs(f_oop - f_free) / f_free
    att_ip, att_oop = a_ip / free_peak, a_oop / free_peak
    # measured: IP 99.35 Hz (-0.65 %), 0.66 of the free peak; OoP 121.9 Hz (+22 %), 0.051
    assert shift_oop > 10 * shift_ip and shift_oop > 0.1
    assert att_oop < 0.15 < 0.4 < att_ip
    # friction really slips at the OoP peak (not a stuck, detuned linear peak)
    s = element_summaries(p2, X2, 2 * np.pi * f_oop)[0]
    assert s["left"]["slip_fraction"] > 0.1 and s["right"]["slip_fraction"] > 0.1


def test_optimal_cf_inside_the_sweep():
    cfs = [3.0, 5.0, 10.0, 20.0, 40.0, 100.0]
    # measured OoP peaks (m): 3.1e-5, 1.1e-5, 1.3e-5, 2.2e-5, 4.0e-5, 9.6e-5 (stuck limit 1.6e-4)
    peaks = [peak(case_from_dict(pair_data(cf=cf, drive=OOP)), 96, 132)[1] for cf in cfs]
    k = int(np.argmin(peaks))
    assert 0 < k < len(cfs) - 1, peaks
    assert min(peaks[0], peaks[-1]) > 1.5 * peaks[k], peaks


# ----------------------------------------------------------------------------- rolling
def test_two_points_per_flank_roll_in_the_in_phase_mode():
    cf = 30.0
    f1, a1, p1, X1 = peak(case_from_dict(pair_data(cf=cf, drive=IP, ppf=1)), 94, 106)
    f2, a2, p2, X2 = peak(case_from_dict(pair_data(cf=cf, drive=IP, ppf=2)), 94, 106)
    s = element_summaries(p2, X2, 2 * np.pi * f2)[0]
    L = GEOM2["flank_length"]
    roll = s["rotation_amplitude"] * L / 2
    # the damper rolls: edge motion from the rotation is a clear fraction of its translation
    assert roll > 0.03 * s["damper"]["x"]["amplitude"]
    # one edge of each flank unloads towards zero, the other keeps (or gains) load
    n_static = s["left"]["static_normal_load"] / 2
    for side in ("left", "right"):
        mins = s[side]["point_normal_load_min"]
        assert min(mins) < 0.3 * n_static and max(mins) > 0.8 * n_static, (side, mins, n_static)
    # the IP response differs from the 3-translation model's
    assert abs(a2 - a1) > 0.1 * a1
    # OoP: a pure translation when driven symmetrically ...
    f4, a4, p4, X4 = peak(case_from_dict(pair_data(cf=cf, drive=OOP, ppf=2)), 112, 132)
    s4 = element_summaries(p4, X4, 2 * np.pi * f4)[0]
    assert s4["rotation_amplitude"] * L / 2 < 1e-9 * s4["damper"]["y"]["amplitude"]
    # ... and nearly so with the shaker on one blade (the off-resonant IP part rolls a little);
    # measured: edge motion from rotation 2 % of the translation (IP: 8 %), rotation 1/170 of IP's
    case = case_from_dict(pair_data(cf=cf, drive=(1.0, 0.0), ppf=2))
    f3, a3, p3, X3 = peak(case, 112, 132)
    s3 = element_summaries(p3, X3, 2 * np.pi * f3)[0]
    trans = max(s3["damper"]["x"]["amplitude"], s3["damper"]["y"]["amplitude"])
    assert s3["rotation_amplitude"] * L / 2 / trans < 0.5 * roll / s["damper"]["x"]["amplitude"]
    assert s3["rotation_amplitude"] < 0.02 * s["rotation_amplitude"]


# ----------------------------------------------------------------------------- Jacobian
def fd_check(fun, x0, steps):
    F0, J = fun(x0)
    Jfd = np.zeros_like(J)
    for i in range(x0.size):
        xp = x0.copy(); xp[i] += steps[i]
        xm = x0.copy(); xm[i] -= steps[i]
        Jfd[:, i] = (fun(xp)[0] - fun(xm)[0]) / (2 * steps[i])
    return np.abs(J - Jfd).max() / np.abs(J).max()


@pytest.mark.parametrize("amp", [2e-5, 6e-5])
def test_exact_jacobian_with_damper_dofs_and_rotation(amp):
    data = pair_data(cf=20.0, ppf=2, three_d=True, mu=[0.3, 0.35], wire_stiffness=2e4)
    data["element"][0]["centres"] = [[-0.006, 0.002], [0.004, 0.0035]]
    case = case_from_dict(data)
    b = FourierBasis(np.arange(0, 4), 64)
    p = dense_balance(case.model, case.elements, b, case.excitation.force, make_transform(b, "dft"))
    rng = np.random.default_rng(7)
    n = case.n_dof
    scale = np.full(n, amp)
    scale[-1] = amp / 0.005                 # rotation, rad
    X = rng.standard_normal((b.n_coef, n)) * scale * np.array([0.1, 1, 1, 0.3, 0.3, 0.1, 0.1])[:, None]
    w = 2 * np.pi * 110.0
    x0 = np.r_[X.ravel(), w]
    steps = np.r_[np.tile(1e-6 * scale, b.n_coef), 1e-6 * w]
    err = fd_check(p, x0, steps)
    s = element_summaries(p, X, w)[0]
    slip = [s[k]["slip_fraction"] for k in ("left", "right")]
    assert any(0 < v < 1 for v in slip), s          # mixed stick-slip on some flank
    if amp > 5e-5:
        assert max(s[k]["open_fraction"] for k in ("left", "right")) > 0   # and separation
    assert err < 1e-6, err


# ----------------------------------------------------------------------------- case keys
def test_case_keys_and_internal_dofs():
    data = pair_data(cf=30.0, ppf=2)
    data["analysis"]["outputs"] = {"damper_x": "upd.x", "roll": "upd.rz"}
    case = case_from_dict(data)
    assert case.model.dof_names == ("A.x", "A.y", "B.x", "B.y", "upd.x", "upd.y", "upd.rz")
    rows = {k: int(np.flatnonzero(g)[0]) for k, g in case.analysis.outputs.items()}
    assert rows == {"damper_x": 4, "roll": 6}
    e = case.elements[0]
    assert e.n_local == 2 * 2 * 2           # 2 flanks x 2 points x (t1, n)
    st = e.static_state()
    assert st["normal_load_left"] == pytest.approx(30.0 / (2 * (math.cos(math.pi / 4) * 1.3)))
    assert st["anchor_stiffness"] == pytest.approx(1e-6 * 4e5)
    assert st["normal_preload_per_point"] == pytest.approx([st["normal_load_left"] / 2] * 4)
    assert case.model.M[6, 6] == GEOM2["inertia"] and case.model.M[4, 4] == 0.05

    def bad(mutate, match):
        d = pair_data(cf=30.0)
        mutate(d["element"][0])
        with pytest.raises(CaseError, match=match):
            case_from_dict(d, "x.toml")

    bad(lambda e: e.update(bogus=1), "unknown key 'bogus'")
    bad(lambda e: e["left"].update(w=3), "unknown key 'w'")
    bad(lambda e: e["left"].update(z="A.x"), "z on both")
    bad(lambda e: e.update(points_per_flank=2), "needs key 'inertia'")
    bad(lambda e: e.update(angles_deg=[10.0, 60.0], mu=0.5), "friction angle")
    bad(lambda e: e.update(angles_deg=[45.0]), "angles_deg")
    bad(lambda e: e.update(cf=-1.0), "cf must be > 0")
    bad(lambda e: e.update(left={"x": "A.q", "y": "A.y"}), "unknown DOF name 'A.q'")
    d = pair_data(cf=30.0)
    d["model"]["dof_names"][0] = "upd.x"
    d["element"][0]["left"]["x"] = "upd.x"
    with pytest.raises(CaseError, match="used twice"):
        case_from_dict(d, "x.toml")


# ----------------------------------------------------------------------------- rig file
def test_rig_blade_pair_wedge_runs_with_energy_balance():
    case = hbm.load_case(ROOT / "rigs" / "blade_pair_wedge.toml")
    res = hbm.frf(case)
    assert res.ok, res.message
    assert res.freq_hz.size > 30
    assert np.all(res.energy_error < 1e-8), res.energy_error.max()
    from hbm.interface.report import summary_dict
    st = summary_dict(case, res)["elements"][0]["static_state"]
    assert st["normal_load_left"] == pytest.approx(50.0 / (2 * (math.cos(math.pi / 4) * 1.3)))
    # two resonances: IP near the free blades (~100 Hz), OoP stiffened by the wedge (> 120 Hz)
    h = res.outputs["blade_a"].h1
    lo = res.freq_hz < 112
    assert 98 < res.freq_hz[lo][np.argmax(h[lo])] < 102
    assert res.freq_hz[~lo][np.argmax(h[~lo])] > 120


def test_time_domain_steps_the_wedge_through_its_flank_contacts():
    # the wedge was packed for time stepping as one friction3d law with no parameters (its
    # forces came out of uninitialised memory); it now steps through its flank contacts and
    # agrees with the harmonic balance (H = 7) well within the time reference's error estimate
    from hbm.analyses.response import output_amplitudes, recover_outputs, solve_at
    from hbm.timedomain.timesim import TimeSimOptions, timesim
    case = hbm.load_case(ROOT / "rigs" / "blade_pair_wedge.toml")
    f = 100.0
    X, basis, problem = solve_at(case, f, harmonics=7, samples=128)
    Y = recover_outputs(problem, case, X, 2 * np.pi * f)
    td = timesim(case, f, TimeSimOptions(steps=256, tol=1e-7))    # (1e-8: the slow slider drift)
    assert td.converged
    for i, name in enumerate(case.analysis.outputs):
        h1 = output_amplitudes(basis, Y[:, i])[0]
        assert abs(td.h1[name] / h1 - 1) < max(td.error_estimate, 1e-3)
    assert np.all(np.isfinite(td.history.forces)) and np.abs(td.history.forces).max() < 1e3
