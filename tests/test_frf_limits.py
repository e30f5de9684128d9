"""Closed-form limits of the Jenkins FRF and the energy balance at every point."""
import numpy as np
import pytest

import hbm
from conftest import sdof_jenkins_case


def receptance(m, c, k, F, f_hz):
    w = 2 * np.pi * f_hz
    return F / np.abs(k - w * w * m + 1j * w * c)


@pytest.mark.parametrize("fs, k_eff", [(1e9, 2.0), (0.0, 1.0), (1e-9, 1.0)])
def test_stuck_and_free_limits(fs, k_eff):
    case = sdof_jenkins_case(k=1.0, kt=1.0, fs=fs, c=0.05, f_hz=(0.08, 0.35), H=3, N=32)
    res = hbm.frf(case)
    assert res.ok, res.message
    ref = receptance(1.0, 0.05, k_eff, 1.0, res.freq_hz)
    assert np.allclose(res.outputs["x"].h1, ref, rtol=1e-8, atol=1e-12)
    assert np.allclose(res.outputs["x"].max, ref, rtol=1e-6)
    # the path covers the whole range, ends on the bound, and passes the resonance peak
    assert res.freq_hz[0] == pytest.approx(0.08) and res.freq_hz[-1] == pytest.approx(0.35)
    f_peak = res.freq_hz[np.argmax(res.outputs["x"].h1)]
    assert f_peak == pytest.approx(np.sqrt(k_eff) / (2 * np.pi), rel=0.02)


def test_energy_balance_every_point_sdof_and_3dof():
    case = sdof_jenkins_case(kt=1.0, fs=0.3, F=1.0, c=0.02, H=7, N=128)
    res = hbm.frf(case)
    assert res.ok, res.message
    assert res.freq_hz.size > 20
    assert np.all(res.energy_error < 1e-8), res.energy_error.max()
    data = {
        "model": {"mass": [[1, 0, 0], [0, 1, 0], [0, 0, 0.5]],
                  "stiffness": [[2, -1, 0], [-1, 2, -1], [0, -1, 1]], "rayleigh": [0.0, 0.01]},
        "element": [{"type": "jenkins", "dofs": [0, 1], "kt": 0.8, "slip_force": 0.05},
                    {"type": "jenkins", "dofs": [2], "kt": 0.5, "slip_force": 0.08}],
        "excitation": {"dofs": [0], "amplitude": [0.2]},
        "analysis": {"harmonics": 5, "time_samples": 64, "frequency_hz": [0.05, 0.35],
                     "outputs": {"a": 0, "b": 2}},
    }
    res = hbm.frf(hbm.case.case_from_dict(data))
    assert res.ok, res.message
    assert np.all(res.energy_error < 1e-8), res.energy_error.max()
    # friction dissipates: the response is below the undamped-by-friction free linear peak
    assert res.outputs["a"].h1.max() < 50
