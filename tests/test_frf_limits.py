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
    res = hbm.frf(hbm.interface.case.case_from_dict(data))
    assert res.ok, res.message
    assert np.all(res.energy_error < 1e-8), res.energy_error.max()
    # friction dissipates: the response is below the undamped-by-friction free linear peak
    assert res.outputs["a"].h1.max() < 50


def test_linear_resonances_of_both_limits_and_the_step_limit():
    from hbm.analyses.resonances import ResonanceStepLimit, linear_resonances
    from hbm.analyses.response import _step_limit, build_problem
    from hbm.balance.fourier import FourierBasis
    case = sdof_jenkins_case(m=1.0, k=4e4, c=2.0, kt=2.667e4, fs=2.0, f_hz=(20, 50), H=3, N=32)
    problem, _ = build_problem(case, FourierBasis([1, 2, 3], 32), "auto")
    lim = _step_limit(problem, case, (2 * np.pi * 20, 2 * np.pi * 50))
    w0, ws = np.sqrt(4e4), np.sqrt(4e4 + 2.667e4)
    assert np.allclose(sorted(lim.omega), [w0, ws], rtol=1e-12)
    assert np.allclose(sorted(lim.width), [1.0, 1.0], rtol=1e-12)   # zeta w = c / (2 m)
    # ahead: at most 0.7 of the distance; inside the band: half its half-width; behind: free
    assert lim(w0 - 10.0, +1) == pytest.approx(7.0)
    assert lim(w0 + 0.5, +1) == pytest.approx(0.5)
    assert lim(w0 + 2.0, +1) == pytest.approx(0.7 * (ws - w0 - 2.0))
    assert lim(w0 + 0.5, -1) == pytest.approx(0.5)
    assert lim(ws + 5.0, +1) == np.inf
    # resonances outside the path's window are left out
    assert _step_limit(problem, case, (w0 + 2.0, 400.0)).omega.tolist() == [ws]
    # undamped modes get the floor width, not zero (no endless approach)
    assert ResonanceStepLimit([10.0], [0.0])(10.0, 1) == pytest.approx(0.5 * 1e-4 * 10.0)
    om, z = linear_resonances(problem.modal_data(), np.zeros((1, 1)), np.zeros((1, 1)))
    assert np.allclose(om, [w0, w0]) and np.allclose(z, 1.0 / w0)


@pytest.mark.parametrize("tol", [1e-8, 1e-9, 1e-10])
def test_a_stuck_resonance_is_not_stepped_over(tol):
    """A contact that never slips leaves a linear peak 0.3 Hz wide in a 30 Hz window, and every
    step converges at once and grows.  Without the resonance step limit, tol = 1e-9 lands one
    step on the far side of the peak (10 points, peak amplitude 4 % of the true one)."""
    from continuation import ArclengthOptions
    case = sdof_jenkins_case(m=1.0, k=4e4, c=2.0, kt=2.667e4, fs=300.0, F=5.0, f_hz=(20, 50), H=3, N=32)
    res = hbm.frf(case, stability=False, options=ArclengthOptions(tol=tol))
    assert res.ok, res.message
    ws = np.sqrt(4e4 + 2.667e4)
    i = np.argmax(res.outputs["x"].h1)
    assert res.outputs["x"].h1[i] == pytest.approx(5.0 / (2.0 * ws), rel=0.03)
    assert res.freq_hz[i] == pytest.approx(ws / (2 * np.pi), rel=2e-3)


def test_a_needle_resonance_is_passed_once():
    """A stuck contact 1e4 times stiffer than the structure: its resonance is a circle in the
    (cos, sin) plane over a ten-thousandth of the window.  Seen from the end of the circle, the
    start of it lies one step away; the corrector landed there and the path went round the
    circle 30 times (1062 points) until a rule rejected steps whose parameter moves against
    the tangents at both ends."""
    case = sdof_jenkins_case(m=1.0, k=1.0, c=0.02, kt=1e4, fs=0.01, F=1e-7, f_hz=(0.5 / (2 * np.pi), 150.0 / (2 * np.pi)),
                             H=5, N=64)
    res = hbm.frf(case, stability=False)
    assert res.ok, res.message
    w = 2 * np.pi * res.freq_hz
    assert np.all(np.diff(w) > 0)                     # linear: one pass, no reversal
    st = res.settings       # the continuation's own points, without those placed after it
    assert res.freq_hz.size - st["fill_points_added"] - st["bend_points_added"] - st["peak_points_added"] < 150
    ws = np.sqrt(1.0 + 1e4)
    assert res.outputs["x"].h1.max() == pytest.approx(1e-7 / (0.02 * ws), rel=0.03)
