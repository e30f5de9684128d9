"""A hysteresis loop that does not close within the element's max_passes is stated, never
used silently: the FRF's settings count the points and carry a warning."""
import numpy as np

from hbm.interface.case import load_case
from hbm.analyses.response import frf


def _case(max_passes=None):
    case = load_case("rigs/inclined_contact.toml")
    if max_passes is not None:
        for e in case.elements:
            e.max_passes = max_passes
    return case


def test_default_passes_close_every_loop():
    res = frf(_case(), stability=False)
    assert res.status == "finished"
    assert res.settings["unclosed_loop_points"] == 0 and "closure_warning" not in res.settings


def test_a_loop_cut_after_one_period_is_reported():
    """One period from rest does not close the loop of a friction3d contact whose normal load
    varies (its start state is not the periodic one; two periods do on this rig): the points
    are counted and the warning names the first."""
    res = frf(_case(max_passes=1), stability=False)
    n = res.settings["unclosed_loop_points"]
    assert 0 < n <= res.freq_hz.size
    assert "did not close" in res.settings["closure_warning"]
    first = float(res.settings["closure_warning"].split("first ")[1].split(" Hz")[0])
    assert np.isclose(first, res.freq_hz, rtol=1e-5).any()
