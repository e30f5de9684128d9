"""The platforms' in-plane rotation in the wedge damper's flank contacts (key ``rz``).

A rigid rotation of damper and platforms together must leave every contact undeformed; a
rotation of a platform alone must press one end of its flank and lift the other, without
tangential motion; and a case with the key must load, reject a misspelt one and pass the
rotation through weighted DOFs.
"""
import numpy as np
import pytest

from elements.wedge import WedgeDamper
from elements.wedge_params import parse_params
from elements.wedge_statics import flank_frames
from hbm.interface.case import case_from_dict

GEOM = {"points_per_flank": 4, "inertia": 3e-7, "flank_length": 0.008,
        "centres": [[-0.005, 0.002], [0.004, 0.0025]]}
# DOFs: left platform x, y, rz = 0, 1, 2; right 3, 4, 5; damper x, y, rz = 6, 7, 8
SPEC = {"type": "wedge_damper", "name": "upd", "left": {"x": 0, "y": 1}, "right": {"x": 3, "y": 4},
        "angles_deg": [40.0, 50.0], "mass": 0.03, "cf": 500.0, "mu": 0.4, "kt": 1e6, "kn": 2e6, **GEOM}


def damper(turns=({2: 1.0}, {5: 1.0})):
    p = parse_params(SPEC)
    return WedgeDamper(p, [(0, 1), (3, 4)], [6, 7, 8], 9, "upd", turns)


def test_a_rigid_rotation_of_damper_and_platforms_deforms_no_contact():
    w = damper()
    c = np.array(GEOM["centres"])
    th = 1e-3
    q = np.zeros(9)
    for s, (ix, iy, ir) in enumerate(((0, 1, 2), (3, 4, 5))):
        q[ix], q[iy], q[ir] = -th * c[s, 1], th * c[s, 0], th     # the platform at its flank centre
    q[8] = th
    assert np.abs(w.gather @ q).max() < 1e-15
    # without the platforms' rotation the same motion opens and presses the flank ends
    w0 = damper(turns=({}, {}))
    assert np.abs(w0.gather @ q).max() > 0.5 * th * GEOM["flank_length"] / 2


def test_a_platform_rotation_presses_one_end_and_lifts_the_other():
    w = damper()
    t, n = flank_frames(w.wedge.angles)
    offsets = w.wedge.point_offsets()
    th = 1e-3
    q = np.zeros(9)
    q[2] = th                                     # left platform turns, all else at rest
    z = (w.gather @ q).reshape(-1, 2)             # (t1, n) per contact point, left flank first
    p = len(offsets)
    assert np.abs(z[:, 0]).max() < 1e-18          # no tangential motion
    assert np.abs(z[p:, 1]).max() == 0.0          # right flank untouched
    tn = t[0, 0] * n[0, 1] - t[0, 1] * n[0, 0]
    assert np.allclose(z[:p, 1], -offsets * tn * th, rtol=1e-12, atol=0)
    assert z[0, 1] * z[p - 1, 1] < 0                # one end closes, the other opens


def case_data(rz_left, rz_right):
    names = ["A.x", "A.y", "A.r", "B.x", "B.y", "B.r"]
    K = np.diag([1e5, 1e5, 1.0, 1e5, 1e5, 1.0])
    M = np.diag([0.1, 0.1, 1e-5, 0.1, 0.1, 1e-5])
    el = dict(SPEC, left={"x": "A.x", "y": "A.y", "rz": rz_left},
              right={"x": "B.x", "y": "B.y", "rz": rz_right})
    return {"name": "turning platforms", "element": [el],
            "model": {"mass": M.tolist(), "stiffness": K.tolist(), "dof_names": names,
                      "modal_damping": 0.01},
            "excitation": {"dofs": ["A.x"], "amplitude": [1.0]},
            "analysis": {"harmonics": 3, "time_samples": 64, "frequency_hz": [100.0, 200.0],
                         "outputs": {"ax": "A.x"}}}


def test_the_case_key_takes_a_dof_or_weighted_dofs_and_rejects_unknown_keys():
    case = case_from_dict(case_data("A.r", {"B.r": -1.0}))
    w = case.elements[0]
    idx = {n: i for i, n in enumerate(case.model.dof_names)}
    G = w.gather
    # the left flank rows read +A.r, the right flank rows read -B.r with the same offsets
    p = w.wedge.points_per_flank
    left, right = G[: 2 * p], G[2 * p:]
    assert np.any(left[:, idx["A.r"]] != 0) and np.all(left[:, idx["B.r"]] == 0)
    assert np.any(right[:, idx["B.r"]] != 0) and np.all(right[:, idx["A.r"]] == 0)
    ref = damper()
    assert np.allclose(right[:, idx["B.r"]], -ref.gather[2 * p:, 5], rtol=1e-14, atol=0)
    bad = case_data("A.r", "B.r")
    bad["element"][0]["left"]["rot"] = "A.r"
    with pytest.raises(ValueError, match="rot"):
        case_from_dict(bad)
    with pytest.raises(ValueError, match="left.rz"):
        case_from_dict(case_data("A.q", "B.r"))
