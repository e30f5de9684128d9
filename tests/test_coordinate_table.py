"""Element coordinates as linear combinations ``{dof = coefficient}`` (inclined contact faces)."""
import numpy as np
import pytest

from hbm.interface.case import case_from_dict, CaseError


def case(dofs):
    return case_from_dict({
        "model": {"mass": [1.0, 1.0, 1.0], "stiffness": [1.0, 1.0, 1.0], "dof_names": ["x", "y", "s"]},
        "element": [{"type": "friction3d", "dofs": dofs, "kt": 1.0, "kn": 2.0, "mu": 0.3,
                     "normal_preload": 1.0}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"frequency_hz": [0.1, 0.2], "outputs": {"x": 0}},
    })


def test_inclined_coordinates_gather_rows():
    c, s = np.cos(0.3), np.sin(0.3)
    el = case({"t1": {"x": s, "y": c, "s": -c}, "n": {"x": c, "y": -s, "2": s}}).elements[0]
    assert np.allclose(el.gather, [[s, c, -c], [c, -s, s]])
    # the older forms still work beside it
    el = case({"t1": ["y", "s"], "n": 0}).elements[0]
    assert np.allclose(el.gather, [[0, 1, -1], [1, 0, 0]])


@pytest.mark.parametrize("dofs, needle", [
    ({"t1": {"x": 1.0, "w": 2.0}, "n": 0}, "unknown DOF name 'w'"),
    ({"t1": {"x": "a"}, "n": 0}, "coefficient of DOF 'x'"),
    ({"t1": {}, "n": 0}, "empty"),
    ({"t1": {"x": 0.0}, "n": 0}, "all coefficients are zero"),
    ({"t1": {"7": 1.0}, "n": 0}, "out of range"),
])
def test_bad_coordinate_tables(dofs, needle):
    with pytest.raises(CaseError, match=needle):
        case(dofs)
