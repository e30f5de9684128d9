"""The unilateral spring with a gap: a law added in two files (its module and the registry).

Checked against its describing function (closed form), finite-difference Jacobians, the
linear limits (never closed, always closed), the time-domain reference and the case format
(keys by name)."""
import numpy as np
import pytest

import hbm
from elements import ELEMENTS, UnilateralSpring
from elements.law_march import linear_shortcut
from elements.laws.registry import UNILATERAL
from hbm.balance.aft import NonlinearForces
from hbm.interface.case import CaseError, case_from_dict
from hbm.balance.dense_part import dense_balance
from hbm.balance.fourier import FourierBasis
from hbm.model.linear import LinearModel
from hbm.timedomain.timesim import TimeSimOptions, steady_state
from hbm.balance.transforms import make_transform

K, GAP = 3.0, 0.4


def describing(a, g, k):
    """Mean and first cosine harmonic of ``k max(a cos t - g, 0)`` for ``|g| < a``."""
    beta = np.arccos(g / a)
    return k * a / np.pi * (np.sin(beta) - beta * np.cos(beta)), k * a / np.pi * (beta - np.sin(beta) * np.cos(beta))


@pytest.mark.parametrize("gap", [0.4, -0.3])
def test_first_harmonic_and_mean_match_the_describing_function(gap):
    b = FourierBasis(range(0, 4), 4096)
    nl = NonlinearForces(b, [UnilateralSpring(np.array([[1.0]]), K, gap)], 1, make_transform(b, "numpy"))
    X = np.zeros((b.n_coef, 1))
    X[b.row_of(1, "c"), 0] = 1.0
    F = nl.forces(X, 1.0)
    f0, f1 = describing(1.0, gap, K)
    # the kink's sampling error falls as 1/N^2: 4096 samples give about 1e-6
    assert F[b.row_of(0, "c"), 0] == pytest.approx(f0, rel=1e-5)
    assert F[b.row_of(1, "c"), 0] == pytest.approx(f1, rel=1e-5)
    assert abs(F[b.row_of(1, "s"), 0]) < 1e-9 * f1          # memoryless: no sine part


def test_jacobian_against_finite_differences():
    b = FourierBasis(range(0, 6), 256)
    model = LinearModel(np.diag([1.0, 2.0]), np.diag([0.01, 0.02]), np.array([[2.0, -1.0], [-1.0, 2.0]]))
    els = [UnilateralSpring(np.array([[1.0, -1.0]]), K, GAP)]
    hb = dense_balance(model, els, b, np.array([1.0, 0.0]), make_transform(b, "dft"))
    rng = np.random.default_rng(4)
    x = np.r_[rng.normal(size=b.n_coef * 2) * 0.6, 1.3]
    R, A = hb(x)
    h = 1e-7
    fd = np.empty_like(A)
    for j in range(x.size):
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        fd[:, j] = (hb(xp)[0] - hb(xm)[0]) / (2 * h)
    # samples sitting within h of the gap would make differences disagree; with 256 random
    # samples none does at this seed, so the match is to difference round-off
    assert np.abs(A - fd).max() <= 1e-6 * np.abs(A).max()


def test_linear_shortcut_open_and_closed():
    p = np.array([K, GAP])
    Kl, f0 = np.zeros((1, 1)), np.zeros(1)
    z = np.linspace(-1.0, 0.39, 64)[:, None]
    assert linear_shortcut(UNILATERAL, p, z, Kl, f0) and Kl[0, 0] == 0.0 and f0[0] == 0.0
    z = np.linspace(0.41, 2.0, 64)[:, None]
    assert linear_shortcut(UNILATERAL, p, z, Kl, f0) and Kl[0, 0] == K and f0[0] == -K * GAP
    z = np.linspace(0.0, 1.0, 64)[:, None]
    assert not linear_shortcut(UNILATERAL, p, z, Kl, f0)


def sdof(gap, amplitude, window=(0.1, 0.4), extra=None):
    el = {"type": "unilateral_spring", "dofs": [0], "k": K, "gap": gap, "name": "stop"}
    el.update(extra or {})
    return case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.05]]},
        "element": [el],
        "excitation": {"dofs": [0], "amplitude": [amplitude]},
        "analysis": {"harmonics": 9, "time_samples": 256, "frequency_hz": list(window), "outputs": {"x": 0}},
    })


def test_linear_limits_never_touching_and_preloaded():
    """Far from the stop the FRF is the linear one; with an interference large enough never to
    open, it is the linear one of k + K (its static offset apart)."""
    w = 2 * np.pi * np.array([0.1, 0.25, 0.4])
    res = hbm.frf(sdof(50.0, 0.05))
    assert res.ok, res.message
    lin = 0.05 / np.abs(1.0 - w ** 2 + 0.05j * w)
    assert np.interp(w, 2 * np.pi * res.freq_hz, res.outputs["x"].h1) == pytest.approx(lin, rel=1e-3)
    res = hbm.frf(sdof(-50.0, 0.05))
    assert res.ok, res.message
    lin = 0.05 / np.abs(1.0 + K - w ** 2 + 0.05j * w)
    assert np.interp(w, 2 * np.pi * res.freq_hz, res.outputs["x"].h1) == pytest.approx(lin, rel=1e-3)


def test_frf_with_impacts_balances_energy_and_matches_the_time_domain():
    case = sdof(GAP, 0.1, window=(0.1, 0.3))
    res = hbm.frf(case)
    assert res.ok, res.message
    assert np.all(res.energy_error < 1e-8)
    h1 = res.outputs["x"].h1
    assert h1.max() > 1.5 * GAP                 # the stop is hit near resonance
    # 0.16 Hz: impacting (h1 = 0.54 > gap) and below the lower fold (0.178 Hz): one branch
    i = np.argmin(np.abs(res.freq_hz - 0.16))
    assert h1[i] > 1.2 * GAP and res.freq_hz[i] < min(res.folds_hz)
    run = steady_state(case, float(res.freq_hz[i]), TimeSimOptions(steps=1024))
    assert run.converged
    assert run.h1["x"] == pytest.approx(h1[i], rel=2e-4)      # measured 2e-5 at H = 9


def test_case_keys_by_name():
    with pytest.raises(CaseError, match="unknown key 'gapp'"):
        sdof(GAP, 0.1, extra={"gapp": 1.0})
    with pytest.raises(CaseError, match="k must be > 0"):
        sdof(GAP, 0.1, extra={"k": -1.0})
    with pytest.raises(CaseError, match="missing key 'gap'"):
        case_from_dict({"model": {"mass": [[1.0]], "stiffness": [[1.0]]},
                        "element": [{"type": "unilateral_spring", "dofs": [0], "k": 1.0}],
                        "excitation": {"dofs": [0], "amplitude": [1.0]},
                        "analysis": {"harmonics": 3, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}}})
    assert ELEMENTS["unilateral_spring"] is UnilateralSpring
    e = UnilateralSpring(np.array([[1.0]]), K, -0.1)
    assert e.linear_stiffness()[0, 0] == K and e.parameter("gap") == -0.1
    assert UnilateralSpring(np.array([[1.0]]), K, 0.1).linear_stiffness()[0, 0] == 0.0


def test_nlvib_example_07_three_dof_chain_with_five_nonlinear_elements():
    """NLvib's EXAMPLES/07 as a case file: a 3-DOF chain (unit masses and springs, dampers
    0.02 x springs, force 1 on the middle mass) with two Jenkins elements (20, 1), two cubic
    springs and a unilateral spring (1, gap 0.25), H = 7, N = 1024, 0.5 .. 2 rad/s.  The case
    format could not express the unilateral spring before.  The FRF crosses the window through
    its folds with the energy balanced at every point, and the time integration agrees where
    the response is single-valued (measured: 2e-5 at 0.1 Hz, 0.26 % at 0.2 Hz: H = 7)."""
    K = np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 2.0]])
    case = case_from_dict({
        "model": {"mass": np.eye(3).tolist(), "stiffness": K.tolist(), "damping": (0.02 * K).tolist()},
        "element": [{"type": "jenkins", "dofs": [0], "kt": 20.0, "slip_force": 1.0},
                    {"type": "jenkins", "dofs": [1, 0], "kt": 20.0, "slip_force": 1.0},
                    {"type": "cubic", "dofs": [1], "k3": 1.0},
                    {"type": "cubic", "dofs": [2, 1], "k3": 1.0},
                    {"type": "unilateral_spring", "dofs": [2], "k": 1.0, "gap": 0.25}],
        "excitation": {"dofs": [1], "amplitude": [1.0]},
        "analysis": {"harmonics": 7, "time_samples": 1024, "frequency_hz": [0.5 / (2 * np.pi), 2.0 / (2 * np.pi)],
                     "outputs": {"x1": 0, "x2": 1, "x3": 2}},
    })
    res = hbm.frf(case, stability=False)
    assert res.ok and res.freq_hz.max() == pytest.approx(2.0 / (2 * np.pi)), res.message
    assert np.all(res.energy_error < 1e-8)
    assert len(res.folds_hz) >= 2 and min(res.folds_hz) > 0.2
    for f, rel in ((0.1, 1e-4), (0.2, 5e-3)):
        i = np.argmin(np.abs(res.freq_hz - f))
        run = steady_state(case, float(res.freq_hz[i]), TimeSimOptions(steps=1024))
        assert run.converged
        for name in ("x1", "x2", "x3"):
            assert run.h1[name] == pytest.approx(res.outputs[name].h1[i], rel=rel), (f, name)
        if f == 0.2:
            assert res.outputs["x3"].h1[i] > 0.25          # the unilateral spring is hit
