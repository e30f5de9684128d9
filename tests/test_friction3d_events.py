"""The (t1, n) point contact's exact, event-based AFT (``aft = "events"`` on ``friction3d``,
:mod:`elements.friction2d_events`): forces and Jacobian against the sampled AFT as ``N`` grows
and against finite differences, in slip, separation, with a gap and stuck at either end of
the slider's interval; the fallback of a loop stuck at rest; the Jenkins limit and den
Hartog's closed form reached with a rigid contact; the case key."""
import sys
from pathlib import Path

import numpy as np
import pytest

import hbm
from elements import Friction3D, Jenkins
from hbm.balance.aft import NonlinearForces
from hbm.balance.fourier import FourierBasis
from hbm.balance.transforms import make_transform
from hbm.interface.case import CaseError, case_from_dict
from test_jacobians import fd_check
from test_jenkins_events import den_hartog_errors

sys.path.insert(0, str(Path(__file__).parent / "stress"))
import cases  # noqa: E402

HARMONICS = list(range(0, 6))


def forces(N, aft, kt=10.0, kn=5.0, mu=0.4, N0=1.0, gap=0.0):
    """``X -> (F, J)`` of one contact on DOFs (t1, n) = (0, 1) with ``N`` samples."""
    b = FourierBasis(HARMONICS, N)
    e = Friction3D(np.eye(2), kt, kn, mu, N0, aft=aft, normal_gap=gap)
    nl = NonlinearForces(b, [e], 2, make_transform(b, "dft"))
    return b, nl


def motion(b, at, an, noise, mean_t=0.0, seed=1):
    """Coefficients (nc, 2): ``u_t ~ at cos``, ``u_n ~ an (sin + 0.3 cos)``, plus noise on every
    harmonic (minor loops, several slips per period)."""
    X = noise * np.random.default_rng(seed).normal(size=(b.n_coef, 2))
    X[b.row_of(1, "c"), 0] += at
    X[b.row_of(1, "s"), 1] += an
    X[b.row_of(1, "c"), 1] += 0.3 * an
    X[0, 0] += mean_t
    return X


REGIMES = {                     # at, an, noise, mean_t, contact keywords
    "slip, closed": (0.5, 0.05, 0.02, 0.0, {}),
    "separating": (0.5, 0.4, 0.02, 0.0, {}),
    "gap": (0.5, 0.6, 0.03, 0.0, {"gap": 0.1}),
    "stuck at the upper end": (0.01, 0.05, 0.0, 0.1, {}),
    "stuck at the lower end": (0.01, 0.05, 0.0, -0.1, {}),
}


@pytest.mark.parametrize("regime", REGIMES)
def test_the_sampled_aft_converges_to_the_exact_forces(regime):
    """Forces within 1e-9 of the sampled AFT at N = 131072, the sampled error falling by more
    than 1000 from N = 1024 (measured 3400 to 85000: about ``1/N^2``, less regular where the
    contact opens); the Jacobian within 1e-4, its error falling by more than 30 (53 to 420)."""
    at, an, noise, mean_t, kw = REGIMES[regime]
    b, nl = forces(64, "events", **kw)
    X = motion(b, at, an, noise, mean_t)
    assert nl.elements[0].harmonic_forces(X, *nl._kinds) is not None
    F, J, _ = nl.evaluate(X, 1.0)
    errors = []
    for N in (1024, 16384, 131072):
        Fs, Js, _ = forces(N, "sampled", **kw)[1].evaluate(X, 1.0)
        errors.append((np.abs(Fs - F).max() / np.abs(F).max(), np.abs(Js - J).max() / np.abs(J).max()))
    (f0, j0), (f1, j1), (f2, j2) = errors
    assert f2 < 1e-9 and f0 / f2 > 1000 and f0 > f1 > f2
    assert j2 < 1e-4 and j0 / j2 > 30


@pytest.mark.parametrize("regime", REGIMES)
def test_jacobian_against_finite_differences(regime):
    at, an, noise, mean_t, kw = REGIMES[regime]
    b, nl = forces(64, "events", **kw)
    X = motion(b, at, an, noise, mean_t, seed=3)

    def fun(x):
        F, J, _ = nl.evaluate(x.reshape(X.shape), 1.0)
        return F.ravel(), J
    assert fd_check(fun, X.ravel(), eps=1e-7) <= 1e-7


def test_a_loop_stuck_with_the_slider_at_rest_is_left_to_the_march():
    b, nl = forces(64, "events")
    X = motion(b, 0.01, 0.05, 0.0)
    assert nl.elements[0].harmonic_forces(X, *nl._kinds) is None
    F, _, _ = nl.evaluate(X, 1.0)
    np.testing.assert_allclose(F, X * [10.0, 5.0], rtol=0, atol=1e-14)      # linear, stuck from rest


def test_with_a_constant_normal_load_it_is_the_jenkins_element():
    """``u_n = 0``: ``N = N0`` throughout, the contact is a Jenkins element of slip force
    ``mu N0`` (its own event-based AFT), to round-off, stiff or not."""
    b = FourierBasis(list(range(1, 10)), 64)
    X = motion(b, 0.5, 0.0, 0.02)
    X[:, 1] = 0.0
    for kt in (10.0, 1e8):
        f3 = NonlinearForces(b, [Friction3D(np.eye(2), kt, 5.0, 0.4, 1.0, aft="events")], 2, make_transform(b, "dft"))
        jk = NonlinearForces(b, [Jenkins(np.array([[1.0]]), kt, 0.4, aft="events")], 1, make_transform(b, "dft"))
        F3, J3, _ = f3.evaluate(X, 1.0)
        Fj, Jj, _ = jk.evaluate(X[:, :1], 1.0)
        scale = np.abs(Fj).max()
        assert np.abs(F3[:, 0] - Fj[:, 0]).max() < 1e-11 * scale
        assert np.abs(J3[0::2, 0::2] - Jj).max() < 1e-11 * kt


def rigid_sdof(kt):
    """den Hartog's oscillator (m = k = 1, c = 0.1, slip force 0.3, force 1) on the t1 DOF of a
    friction3d contact whose normal DOF is not forced (``u_n = 0``, ``N = N0``)."""
    return case_from_dict({
        "model": {"mass": np.eye(2).tolist(), "stiffness": np.eye(2).tolist(),
                  "damping": [[0.1, 0.0], [0.0, 0.1]]},
        "element": [{"type": "friction3d", "dofs": {"t1": 0, "n": 1}, "kt": kt, "kn": 1.0, "mu": 0.3,
                     "normal_preload": 1.0, "aft": "events"}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 15, "frequency_hz": [0.8 / (2 * np.pi), 1.3 / (2 * np.pi)],
                     "outputs": {"x": 0}},
    })


def test_a_rigid_contact_reaches_den_hartog():
    """kt / k = 1e10 (the rigid limit) at H = 15: within 0.5 % of the closed form for viscous +
    Coulomb damping (1931), the truncation's 0.32 %, as the Jenkins element with events."""
    res = hbm.frf(rigid_sdof(1e10), stability=False)
    assert res.ok, res.message
    assert np.all(res.energy_error < 1e-8)
    assert den_hartog_errors(res) < 5e-3


def test_a_separating_contact_traced_with_events_matches_the_fine_sampled_one():
    """The stress matrix's separating contact (force ratio 10, kt / k = 1, H = 3): the FRF with
    events finishes, closes its energy balance, and its peaks agree with the sampled AFT at
    N = 4096 (sampling error ~1e-6) to 1e-4."""
    data = cases.friction3d_2dof(10.0, 1.0, 3, True)
    data["element"][0]["aft"] = "events"
    ev = hbm.frf(case_from_dict(data), stability=False, error_estimate=False)
    assert ev.ok, ev.message
    assert np.all(ev.energy_error < 1e-8)
    data["element"][0]["aft"] = "sampled"
    fine = hbm.frf(case_from_dict(data), samples=4096, stability=False, error_estimate=False)
    for name in ("t", "n"):
        assert ev.outputs[name].h1.max() == pytest.approx(fine.outputs[name].h1.max(), rel=1e-4)


def test_case_key():
    data = rigid_sdof(10.0)
    assert data.elements[0].aft == "events"
    tree = {
        "model": {"mass": np.eye(3).tolist(), "stiffness": np.eye(3).tolist()},
        "element": [{"type": "friction3d", "dofs": {"t1": 0, "t2": 1, "n": 2}, "kt": 1.0, "kn": 1.0, "mu": 0.3,
                     "normal_preload": 1.0, "aft": "events"}],
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"harmonics": 3, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}},
    }
    with pytest.raises(CaseError, match="aft.*t2"):
        case_from_dict(tree)
    tree["element"][0]["dofs"] = {"t1": 0, "n": 2}
    tree["element"][0]["aft"] = "exact"
    with pytest.raises(CaseError, match="aft"):
        case_from_dict(tree)


def test_a_stopped_run_with_a_stiff_sampled_point_contact_suggests_events():
    """The hint of a run that stops or leaves gaps names a stiff sampled (t1, n) contact, not one
    with t2 (no event-based AFT there) nor one already on events."""
    from hbm.analyses.response import stiff_contact_hint

    def case(dofs, aft, n=2):
        return case_from_dict({
            "model": {"mass": np.eye(n).tolist(), "stiffness": np.eye(n).tolist()},
            "element": [{"type": "friction3d", "dofs": dofs, "kt": 300.0, "kn": 1.0, "mu": 0.3,
                         "normal_preload": 1.0, "aft": aft, "name": "pad"}],
            "excitation": {"dofs": [0], "amplitude": [1.0]},
            "analysis": {"harmonics": 3, "frequency_hz": [0.1, 0.2], "outputs": {"x": 0}},
        })
    hint = stiff_contact_hint(case({"t1": 0, "n": 1}, "sampled"))
    assert "pad: kt = 300 x" in hint and 'aft = "events"' in hint
    assert stiff_contact_hint(case({"t1": 0, "n": 1}, "events")) == ""
    assert stiff_contact_hint(case({"t1": 0, "t2": 1, "n": 2}, "sampled", n=3)) == ""
