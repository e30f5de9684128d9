"""The condensed solver keeps enough modes for its window (issue 22 item 1): with the default
40 modes a 300-DOF chain excited near its 45th mode lost that mode altogether; the modes are
now added until the highest kept one reaches twice the window's top, and summary says so."""
import numpy as np
import pytest

import hbm
import hbm.model.mode_cover as mc

N_DOF = 300


def _chain(modes=None):
    K = 2 * np.eye(N_DOF) - np.eye(N_DOF, k=1) - np.eye(N_DOF, k=-1)
    K[-1, -1] = 1.0
    model = {"mass": np.ones(N_DOF), "stiffness": K, "modal_damping": 0.002, "solver": "condensed"}
    if modes is not None:
        model["modes"] = modes
    return hbm.case_from_dict({
        "model": model,
        "element": [{"type": "jenkins", "dofs": [N_DOF - 1], "kt": 0.05, "slip_force": 2e-3}],
        "excitation": {"dofs": [N_DOF - 1], "amplitude": [1e-3]},
        "analysis": {"harmonics": 3, "frequency_hz": [0.0725, 0.0745], "outputs": {"tip": N_DOF - 1}}})


def _peak(res):
    assert res.ok, res.message
    i = int(np.argmax(res.outputs["tip"].h1))
    return res.outputs["tip"].h1[i], res.freq_hz[i]


@pytest.fixture(scope="module")
def reference():
    return _peak(hbm.frf(_chain("all"), stability=False))


def test_default_modes_are_extended_to_the_window(reference):
    res = hbm.frf(_chain(), stability=False)
    st = res.settings
    assert st["modes_requested"] == 40 and st["modes_added"] > 0
    assert st["highest_kept_mode_hz"] >= mc.MARGIN * 0.0745
    a, f = _peak(res)
    assert a == pytest.approx(reference[0], rel=2e-3) and f == pytest.approx(reference[1], rel=1e-3)


def test_without_the_check_the_answer_is_wrong(reference, monkeypatch):
    """What the check prevents: 40 modes, all below the window."""
    monkeypatch.setattr(mc, "MARGIN", 0.0)
    res = hbm.frf(_chain(), stability=False)
    assert res.settings["modes_added"] == 0 and res.settings["highest_kept_mode_hz"] < 0.0725
    assert abs(_peak(res)[0] / reference[0] - 1) > 0.2
