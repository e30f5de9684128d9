"""Unbounded resonances (den Hartog's condition, :mod:`hbm.analyses.bounded`): a window that
holds one is refused with the reason and what to change, not traced to max_points."""
import subprocess
import sys

import numpy as np
import pytest

import hbm
from hbm.interface.case import CaseError, case_from_dict


def sdof(slip, c=0.0, window=(0.1, 0.25)):
    return case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[c]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 100.0, "slip_force": slip}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 7, "frequency_hz": list(window), "outputs": {"x": 0}},
    })


def test_den_hartog_condition_on_one_mass():
    """No viscous damping: slip force 0.7 < pi/4 of the force 1 is unbounded at 1 rad/s (the
    solver crept to max_points = 2000 at 0.159138 Hz with x = 2115 before); 0.8 is bounded."""
    with pytest.raises(CaseError, match=r"unbounded response at 0.159155 Hz.*raise the slip forces more than 1.12x"):
        hbm.frf(sdof(0.7))
    res = hbm.frf(sdof(0.8))
    assert res.ok, res.message
    assert res.outputs["x"].h1.max() < 2.0


@pytest.mark.parametrize("kw", [{"c": 1e-3}, {"window": (0.17, 0.25)}])
def test_damping_or_a_window_clear_of_it_is_traced(kw):
    res = hbm.frf(sdof(0.7, **kw))
    assert res.ok, res.message


def test_a_mode_the_friction_does_not_see():
    """Two masses, springs ground-m0-m1-ground, a Jenkins between them: the in-phase mode
    (1 rad/s) does not move the contact, so no slip force bounds it."""
    case = case_from_dict({
        "model": {"mass": np.eye(2).tolist(), "stiffness": [[2.0, -1.0], [-1.0, 2.0]],
                  "damping": np.zeros((2, 2)).tolist()},
        "element": [{"type": "jenkins", "dofs": [0, 1], "kt": 10.0, "slip_force": 5.0}],
        "excitation": {"dofs": [0, 1], "amplitude": [0.1, 0.1]},
        "analysis": {"harmonics": 5, "frequency_hz": [0.1, 0.3], "outputs": {"x": 0}},
    })
    with pytest.raises(CaseError, match="mode 1 has no viscous damping"):
        hbm.frf(case)


def test_cli_says_it_in_one_line_with_exit_status_2(tmp_path):
    p = tmp_path / "undamped.toml"
    p.write_text('[model]\nmass = [[1.0]]\nstiffness = [[1.0]]\n\n[[element]]\ntype = "jenkins"\n'
                 'dofs = [0]\nkt = 100.0\nslip_force = 0.7\n\n[excitation]\ndofs = [0]\namplitude = [1.0]\n\n'
                 '[analysis]\nharmonics = 7\nfrequency_hz = [0.1, 0.25]\noutputs = { x = 0 }\n')
    r = subprocess.run([sys.executable, "-m", "hbm", "frf", str(p), "-o", str(tmp_path / "out"), "-q"],
                       capture_output=True, text=True)
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "unbounded response at 0.159155 Hz" in lines[0], r.stderr
