"""Seed 004 rig: railcar friction wedge damper, side-frame shaken vertically (rigs/railcar_wedge.toml)."""
import sys
from pathlib import Path

import numpy as np
import pytest

import hbm

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "rigs"))

import make_railcar_wedge_model as mk                     # noqa: E402
from rigs.studies import railcar_wedge_sweep as st        # noqa: E402

CASE = ROOT / "rigs" / "railcar_wedge.toml"


def test_geometry_reproduces_table_2():
    # the paper's non-dimensional coefficients (Table 2) from our face geometry and spring
    # offsets with rigid contacts: fixes every sign convention of the model
    c = mk.kaiser_coefficients()
    table2 = {"F+": 1.1918, "F-": 1.3735, "G+": 1.0122, "G-": 1.0369, "H+": 0.7561, "H-": -0.5237}
    for k, v in table2.items():
        assert c[k] == pytest.approx(v, abs=6e-5), (k, c[k])


def test_case_matches_the_model_script():
    case = hbm.load_case(CASE)
    Yb, Ns, Nb = mk.static_equilibrium()
    assert len(case.elements) == 4
    idx = case.model.dof_index
    for el in case.elements:
        name, side = el.name.split("_")
        column, bolster = mk.contact_rows(side)
        rows = column if name == "column" else bolster
        assert el.normal_preload == pytest.approx(Ns if name == "column" else Nb, rel=1e-9)
        for r, key in enumerate(("t1", "n")):
            g = np.zeros(case.n_dof)
            for d, c in rows[key].items():
                g[idx[d]] = c
            assert np.allclose(el.gather[r], g, atol=1e-9)
    M, K = mk.matrices()
    assert np.array_equal(case.model.M, M) and np.array_equal(case.model.K, K)


def test_static_equilibrium_balances():
    # frictionless equilibrium: bolster and wedge forces vanish with the computed loads
    Yb, Ns, Nb = mk.static_equilibrium()
    assert Ns > 0 and Nb > 0
    t_s, n_s, t_b, n_b = mk.face_vectors()
    Gam = np.tan(mk.ALPHA) / (np.tan(mk.ALPHA) + np.tan(mk.GAMMA))
    wedge = Ns * n_s + Nb * n_b + np.array([0.0, mk.K_W * (-mk.Y_W0 - Gam * Yb) - mk.M_W * mk.G_ACC])
    bolster = mk.K_B * (-mk.Y_B0 - Yb) - mk.M_B * mk.G_ACC - 2 * Nb * n_b[1]
    assert np.allclose(wedge, 0, atol=1e-9) and abs(bolster) < 1e-9
    # inside the paper's static dead band y in [-(H+ + G+)/F+, -(H- + G-)/F-]
    c = mk.kaiser_coefficients()
    y = (mk.K_B / mk.M_B) / mk.G_ACC * Yb
    assert -(c["H+"] + c["G+"]) / c["F+"] < y < -(c["H-"] + c["G-"]) / c["F-"]


@pytest.fixture(scope="module")
def runs():
    case = hbm.load_case(CASE)
    return case, {f: st.analyse(case, f) for f in (30.0, 40.0)}


def test_stick_slip_near_30_hz_not_at_40(runs):
    case, r = runs
    assert r[30.0]["converged"] and r[40.0]["converged"]
    ivs = r[30.0]["intervals"]
    assert len(ivs) >= 2
    assert {iv.kind for iv in ivs} == {"A", "B"}             # both types of stick event
    assert all(1.5e-3 <= iv.duration <= 5e-3 for iv in ivs)   # paper: 2 to 3.5 ms
    assert r[40.0]["intervals"] == []
    # at 40 Hz the contacts stick only at the velocity reversals, briefly (penalty elasticity)
    assert r[40.0]["stuck"].mean() < 0.1


def test_relative_motion_rises_from_30_to_40_hz(runs):
    case, r = runs
    assert r[40.0]["pkpk_x"] > 4.0 * r[30.0]["pkpk_x"], (r[30.0]["pkpk_x"], r[40.0]["pkpk_x"])
    # and the pure-slip response at 40 Hz is of the order of the track input (A = 0.2 mm)
    assert 0.5 * 2e-4 < r[40.0]["pkpk_x"] < 4 * 2e-4


def test_harmonic_content_against_table_3(runs):
    # rigs/studies/railcar_table3.py: the strongest higher harmonic of the relative displacement
    # at 30 Hz is the 3rd, as in the paper's Table 3 (AR 8.7; ours 5.4: more distorted); at
    # 40 Hz the 2nd and 3rd lead, as in the paper (which has the 2nd four times stronger)
    from rigs.studies.railcar_table3 import PAPER, peaks
    case, r = runs
    (ar30, h30), *_ = peaks(r[30.0]["x"])
    assert h30 == PAPER[30.0][0][1] == 3 and ar30 == pytest.approx(5.42, rel=0.05)
    assert {h for _, h in peaks(r[40.0]["x"])[:2]} == {h for _, h in PAPER[40.0][:2]} == {2, 3}
