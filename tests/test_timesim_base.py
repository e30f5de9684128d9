"""Base (support) excitation in the time-domain reference: transmissibility of a base-excited
SDOF against its closed form, friction against a moving support against the HBM, bad input."""
import numpy as np
import pytest

import hbm
import hbm.analyses.response
from hbm.interface.case import case_from_dict, CaseError
from hbm.timedomain.timesim import TimeSimOptions, timesim, transient

A = 1e-3


def base_case(fs=None, kt=50.0, c=0.5, m=2.0, k=1000.0, H=5, m_support=1.0):
    """DOF 0 is the support (moved as A cos wt), DOF 1 the mass on spring k and damper c."""
    data = {
        "model": {"mass": [[m_support, 0.0], [0.0, m]], "stiffness": [[k, -k], [-k, k]],
                  "damping": [[c, -c], [-c, c]]},
        "excitation": {"base": {"dofs": [0], "amplitude": [A]}},
        "analysis": {"harmonics": H, "time_samples": 64, "frequency_hz": [1.0, 8.0],
                     "outputs": {"x": 1, "rel": [1, 0]}},
    }
    if fs is not None:
        data["element"] = [{"type": "jenkins", "dofs": [1, 0], "kt": kt, "slip_force": fs}]
    return case_from_dict(data)


def transmissibility(k, c, m, f_hz):
    w = 2 * np.pi * f_hz
    return A * abs((k + 1j * w * c) / (k - w * w * m + 1j * w * c))


@pytest.mark.parametrize("f_hz", [2.0, 3.5, 5.0])
def test_transmissibility_closed_form(f_hz):
    # resonance at sqrt(1000/2)/(2 pi) = 3.56 Hz, zeta = 0.5 / (2 sqrt(2000)) = 0.56 %
    case = base_case()
    res = timesim(case, f_hz, TimeSimOptions(steps=256, tol=1e-9))
    exact = transmissibility(1000.0, 0.5, 2.0, f_hz)
    assert res.converged
    err = abs(res.h1["x"] - exact) / exact
    # Newmark's relative period error (w dt)^2 / 12 (2n = 512 steps per period) shifts the
    # response by that times the sensitivity |d ln|T| / d ln w| of the closed form: the
    # error must be that and no more (7e-4 at 3.5 Hz, near the resonance; 1e-5 at 2 Hz)
    sens = abs(np.log(transmissibility(1000.0, 0.5, 2.0, f_hz * (1 + 1e-6)) / exact)) / 1e-6
    predicted = sens * (2 * np.pi / 512) ** 2 / 12
    assert err < 1.1 * predicted + 1e-7, (err, predicted)
    assert err <= res.error_estimate
    # the relative motion against its closed form
    def rel(f):
        w = 2 * np.pi * f
        return A * abs(w * w * 2.0 / (1000.0 - w * w * 2.0 + 1j * w * 0.5))
    sens = abs(np.log(rel(f_hz * (1 + 1e-6)) / rel(f_hz))) / 1e-6
    predicted = sens * (2 * np.pi / 512) ** 2 / 12
    assert res.h1["rel"] == pytest.approx(rel(f_hz), rel=1.1 * predicted + 1e-7)


def test_support_mass_and_stiffness_do_not_matter():
    # the support's own row is dropped: its mass is irrelevant
    a = timesim(base_case(m_support=1.0), 3.0, TimeSimOptions(steps=128)).h1["x"]
    b = timesim(base_case(m_support=1e4), 3.0, TimeSimOptions(steps=128)).h1["x"]
    assert a == pytest.approx(b, rel=1e-10)


def test_friction_against_moving_support_matches_hbm():
    # Jenkins element between the mass and the moving support, slipping part of the period
    case = base_case(fs=0.08, H=31)
    f_hz = 3.0
    X, basis, problem = hbm.analyses.response.solve_at(case, f_hz, harmonics=31, samples=512)
    g = case.analysis.outputs["rel"]
    h1_hbm, _ = hbm.analyses.response.output_amplitudes(basis, X @ g)
    res = timesim(case, f_hz, TimeSimOptions(steps=512, tol=1e-10))
    assert res.converged
    # the element did slip (its force reached the slip limit), so this is not a linear check
    assert np.abs(res.history.forces).max() == pytest.approx(0.08, rel=1e-9)
    assert res.h1["rel"] == pytest.approx(h1_hbm, rel=2e-3)
    # the recorded element velocity is the derivative of the recorded coordinate
    h = res.history
    dt = h.t[1] - h.t[0]
    dudt = np.gradient(h.disp[:, 0], dt)
    assert np.allclose(h.vel[2:-2, 0], dudt[2:-2], atol=2e-3 * np.abs(h.vel).max())


def test_switch_off_with_base_is_an_error():
    with pytest.raises(CaseError, match="switch-off"):
        transient(base_case(), 3.0, 4, switch_off_at=0.5, options=TimeSimOptions(steps=32))


@pytest.mark.parametrize("fs", [None, 0.3])
def test_floquet_check_of_a_base_excited_balance_point(fs):
    """The period map runs with the support on its imposed motion (the railcar rig's Hill
    verdicts are checked this way): without friction the largest multiplier is the damped
    free motion's decay over a period, exp(-c T / 2 m); with a slipping Jenkins element the
    orbit is the balance point's and stable."""
    from hbm.analyses.problem_setup import solve_at
    from hbm.timedomain.floquet_check import check_point
    case = base_case(fs=fs)
    X, basis, _ = solve_at(case, 3.0)
    chk = check_point(case, basis, X, 3.0, steps=512)
    assert chk.converged and chk.stable and chk.distance < 1e-3
    if fs is None:
        assert chk.largest == pytest.approx(np.exp(-0.5 / (2 * 2.0) / 3.0), rel=1e-5)
