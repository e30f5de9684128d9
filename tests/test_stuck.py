"""Points where a hysteretic contact sticks for the whole period are counted (issue 18 item 4):
there the periodic solution is a family (any slider offset), which the FRF now says."""
import pathlib

import numpy as np

import hbm
from hbm.interface.report import format_csv

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _sdof(slip_force):
    raw = hbm.load_case(ROOT / "rigs" / "sdof_jenkins.toml").raw
    raw["element"][0]["slip_force"] = slip_force
    raw["analysis"]["harmonics"] = 3
    return hbm.case_from_dict(raw)


def test_stuck_everywhere_and_nowhere():
    stuck = hbm.frf(_sdof(1e6), stability=False)          # never reaches the slip force
    assert stuck.ok and np.all(stuck.stuck == 1) and stuck.settings["stuck_points"] == stuck.freq_hz.size
    slipping = hbm.frf(_sdof(2.0), stability=False)       # slips at every point of the window
    assert slipping.ok and np.all(slipping.stuck == 0) and slipping.settings["stuck_points"] == 0
    lines = format_csv(stuck).splitlines()
    assert lines[0].split(",")[-2:] == ["stuck_contacts", "stable"] and lines[1].split(",")[-2] == "1"


def test_part_of_the_window_sticks():
    """blade_pair_wedge: the damper sticks at the window's ends and through the in-phase mode
    (it would have to roll), and slides at the out-of-phase peak, which opens the gap."""
    res = hbm.frf(hbm.load_case(ROOT / "rigs" / "blade_pair_wedge.toml"), stability=False)
    s = res.stuck
    assert 0 < np.count_nonzero(s) < s.size and s[0] == 1 and s[-1] == 1
    oop = res.freq_hz > 120.0
    peak = np.flatnonzero(oop)[int(np.argmax(res.outputs["blade_a"].h1[oop]))]
    assert s[peak] == 0


def test_no_hysteretic_contact_no_column():
    raw = {"model": {"mass": [1.0], "stiffness": [1.0], "damping": [0.05]},
           "element": [{"type": "cubic", "dofs": [0], "k3": 0.1}],
           "excitation": {"dofs": [0], "amplitude": [0.1]},
           "analysis": {"harmonics": 3, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}}}
    res = hbm.frf(hbm.case_from_dict(raw), stability=False)
    assert res.stuck is None and "stuck_points" not in res.settings
    assert "stuck_contacts" not in format_csv(res).splitlines()[0]
