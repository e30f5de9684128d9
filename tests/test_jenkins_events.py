"""The Jenkins element's exact, event-based AFT (``aft = "events"``,
:mod:`elements.jenkins_events`): forces and Jacobian against the sampled AFT as ``N`` grows
and against finite differences, the fallback of a loop that never slips, and den Hartog's
closed form (viscous + Coulomb, 1931) reached by stiff penalties."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import hbm
from den_hartog import den_hartog
from elements import Jenkins
from elements.jenkins_events import gauss_table, jenkins_harmonics, row_kinds
from hbm.balance.aft import NonlinearForces
from hbm.balance.fourier import FourierBasis
from hbm.balance.transforms import make_transform
from hbm.interface.case import CaseError, case_from_dict
from test_jacobians import fd_check

KT, FS = 10.0, 1.5


def coefficients(harmonics, seed=1, noise=0.08):
    b = FourierBasis(list(harmonics), 2 * max(harmonics) + 2)
    U = noise * np.random.default_rng(seed).normal(size=b.n_coef)
    U[b.row_of(1, "c")] += 1.0
    U[b.row_of(1, "s")] += 0.3
    return b, U


def exact(b, U, kt=KT, fs=FS):
    h, s = row_kinds(b.h_of_row)
    gx, gw = gauss_table(int(h.max()))
    F, J = np.zeros(U.size), np.zeros((U.size, U.size))
    ok = jenkins_harmonics(h, s, U, kt, fs, 16 * max(int(h.max()), 4), gx, gw, F, J)
    return (F, J) if ok else None


def sampled(harmonics, U, N, kt=KT, fs=FS):
    b = FourierBasis(list(harmonics), N)
    nl = NonlinearForces(b, [Jenkins(np.array([[1.0]]), kt, fs)], 1, make_transform(b, "dft"))
    F, J, _ = nl.evaluate(U[:, None], 1.0)
    return F[:, 0], J


@pytest.mark.parametrize("harmonics", [range(1, 8), range(0, 8), [1, 3, 5, 7]])
def test_the_sampled_aft_converges_to_the_exact_forces(harmonics):
    """Minor loops included (noise on every harmonic); the sampled forces' error falls as
    ``1/N^2`` (a switch moved to the grid), their Jacobian's as ``1/N``."""
    b, U = coefficients(harmonics)
    F, J = exact(b, U)
    errors = []
    for N in (1024, 16384, 262144):
        Fs, Js = sampled(harmonics, U, N)
        errors.append((np.abs(Fs - F).max() / np.abs(F).max(), np.abs(Js - J).max() / np.abs(J).max()))
    (f0, j0), (f1, j1), (f2, j2) = errors
    assert f2 < 2e-9 and f1 / f2 > 100 and f0 / f1 > 100
    assert j2 < 1e-4 and j1 / j2 > 8 and j0 / j1 > 8


@pytest.mark.parametrize("harmonics", [range(1, 8), range(0, 8)])
def test_jacobian_against_finite_differences(harmonics):
    b, U = coefficients(harmonics, seed=3)
    assert fd_check(lambda u: exact(b, u), U, eps=1e-6) <= 1e-8


def test_stiff_contact_keeps_its_round_off_small():
    """``kt = 1e8``: the stick segments are short and ``kt (u - u_i)`` is taken from the
    difference of the basis functions, so the forces are not ``kt |u| eps`` noisy."""
    b, U = coefficients(range(1, 16), noise=0.002)
    F, _ = exact(b, U, kt=1e8, fs=0.3)
    F2, _ = exact(b, U * (1 + 1e-15), kt=1e8, fs=0.3)
    assert np.abs(F2 - F).max() < 1e-12


def test_a_loop_that_never_slips_is_left_to_the_sampled_march():
    b, U = coefficients(range(1, 6), noise=0.0)
    assert exact(b, 0.01 * U) is None             # swing 2.1 * 0.01 * kt < 2 fs: stuck
    assert exact(b, 0 * U) is None
    nl = NonlinearForces(b, [Jenkins(np.array([[1.0]]), KT, FS, aft="events")], 1, make_transform(b, "dft"))
    F, J, _ = nl.evaluate(0.01 * U[:, None], 1.0)
    np.testing.assert_allclose(F[:, 0], KT * 0.01 * U, rtol=0, atol=1e-14)     # linear, stuck from rest


def sdof(kt, aft, harmonics=15, c=0.1, window=(0.8, 1.3)):
    return case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[c]]},
        "element": [{"type": "jenkins", "dofs": [0], "kt": kt, "slip_force": 0.3, "aft": aft}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": harmonics, "frequency_hz": [window[0] / (2 * np.pi), window[1] / (2 * np.pi)],
                     "outputs": {"x": 0}},
    })


def test_den_hartog_closed_form_against_a_regularised_integration():
    """The oracle itself: the sign law smoothed by tanh(v / 1e-5), integrated for 150 periods."""
    w = 1.1
    A, _ = den_hartog(1.0, 0.1, 1.0, 0.3, 1.0, w)
    rhs = lambda t, y: [y[1], np.cos(w * t) - 0.1 * y[1] - y[0] - 0.3 * np.tanh(y[1] / 1e-5)]
    T = 2 * np.pi / w
    sol = solve_ivp(rhs, [0, 150 * T], [0.0, 0.0], method="LSODA", rtol=1e-10, atol=1e-12, max_step=T / 200,
                    t_eval=np.linspace(149 * T, 150 * T, 2001))
    assert np.abs(sol.y[0]).max() == pytest.approx(A, rel=1e-5)
    with pytest.raises(ValueError, match="sticks"):
        den_hartog(1.0, 0.1, 1.0, 0.3, 1.0, 0.5)          # stops and sticks: form not valid


def den_hartog_errors(res):
    """Largest relative error of x's maximum and first harmonic against den Hartog, over the
    points where the motion is continuous."""
    errs = []
    for f, a, h1 in zip(res.freq_hz, res.outputs["x"].max, res.outputs["x"].h1):
        A, H1 = den_hartog(1.0, 0.1, 1.0, 0.3, 1.0, 2 * np.pi * f)
        errs.append(max(abs(a / A - 1), abs(h1 / H1 - 1)))
    return max(errs)


def test_stiff_jenkins_with_events_reaches_den_hartog():
    """kt / k = 1e4, 1e6, 1e10 at H = 15 across 0.8 .. 1.3 rad/s (continuous motion; the
    resonance at 1): every FRF finishes, and the error against the closed form falls with the
    penalty to the truncation's 0.32 % (measured 0.57 %, 0.33 %, 0.32 %).  The sampled AFT at
    its default N stays at 1.3 % whatever kt (its switches sit on the grid)."""
    errors = []
    for kt in (1e4, 1e6, 1e10):
        res = hbm.frf(sdof(kt, "events"))
        assert res.ok, res.message
        assert np.all(res.energy_error < 1e-8)
        errors.append(den_hartog_errors(res))
    assert errors[0] > errors[1] >= errors[2] * 0.999 and errors[2] < 5e-3
    res = hbm.frf(sdof(1e6, "sampled"))
    assert res.ok, res.message
    assert den_hartog_errors(res) > 2 * errors[1]


def test_case_key():
    assert sdof(1e3, "events").elements[0].aft == "events"
    with pytest.raises(CaseError, match="aft"):
        sdof(1e3, "exact")


def test_a_stopped_run_with_stiff_sampled_contacts_says_what_to_try():
    """The hint `hbm frf` prints when a path stops or leaves gaps: stiff (kt >= 100 x the
    structure along the contact), sampled Jenkins elements are named; events or soft ones not."""
    from hbm.analyses.response import stiff_contact_hint

    def case(kt, aft):
        return case_from_dict({
            "model": {"mass": [[1.0, 0.0], [0.0, 1.0]], "stiffness": [[2.0, -1.0], [-1.0, 2.0]]},
            "element": [{"type": "jenkins", "dofs": [0, 1], "kt": kt, "slip_force": 0.9, "aft": aft, "name": "c"}],
            "excitation": {"dofs": [0], "amplitude": [1.0]},
            "analysis": {"harmonics": 5, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}},
        })
    # along u = q0 - q1 the structure's stiffness is g K g^T / g g^T = 6 / 2 = 3
    assert "c: kt = 1e+03 x" in stiff_contact_hint(case(3e3, "sampled"))
    assert 'aft = "events"' in stiff_contact_hint(case(3e3, "sampled"))
    assert stiff_contact_hint(case(3e3, "events")) == ""
    assert stiff_contact_hint(case(30.0, "sampled")) == ""
