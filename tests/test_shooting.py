"""Monodromy matrix of the time integrator's period map (exact step derivatives), Floquet
multipliers against the closed form, and the steady state by shooting."""
import numpy as np
import pytest

from hbm.interface.case import case_from_dict
from hbm.timedomain.shooting import set_state, start_sensitivity, state_vector
from hbm.timedomain.time_parts import pack_elements
from hbm.timedomain.time_state import TimeState
from hbm.timedomain.timesim import TimeSimOptions, _integrate, _one_period, floquet, steady_state


def two_dof(elements, c=0.02):
    return case_from_dict({
        "model": {"mass": [[1.0, 0.0], [0.0, 1.0]], "stiffness": [[2.0, -1.0], [-1.0, 1.0]],
                  "damping": [[c, 0.0], [0.0, c]]},
        "element": list(elements),
        "excitation": {"dofs": [1], "amplitude": [1.0]},
        "analysis": {"frequency_hz": [0.1, 0.3], "outputs": {"x": 1}},
    })


def sdof(c):
    return case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[c]]},
        "excitation": {"dofs": [0], "amplitude": [1.0]},
        "analysis": {"frequency_hz": [0.1, 0.3], "outputs": {"x": 0}},
    })


ELEMENTS = {
    "cubic": [{"type": "cubic", "dofs": [0], "k3": 0.5}],
    # closed all period (N0 = 10 against kn |u_n| < 3): smooth stick/slip-free tangents
    "friction3d_closed": [{"type": "friction3d", "dofs": {"t1": [0], "n": [1]}, "kt": 1.0, "kn": 3.0,
                           "mu": 0.3, "normal_preload": 10.0}],
    "regularised_coulomb": [{"type": "coulomb_regularised", "dofs": [0], "slip_force": 0.2, "law": "tanh",
                             "v_r": 0.5}],
}


@pytest.mark.parametrize("name", list(ELEMENTS))
def test_monodromy_matches_finite_differences(name):
    """``Y`` from the exact step derivatives against central differences of the period map,
    column by column, on cases whose map is smooth (no status change within the period)."""
    case = two_dof(ELEMENTS[name])
    f, N = 0.2, 256
    opts = TimeSimOptions(steps=N)
    packed = pack_elements(case.elements, case.n_dof)
    st = TimeState(case, packed, 2 * np.pi * f)
    _integrate(case, f, opts, N, 30, False, None, st, None)
    one = _one_period(case, f, opts, N, packed)
    y0 = state_vector(st)
    Y = start_sensitivity(2, st.S.size, np.zeros(2, dtype=int))
    one(st.copy(), Y)
    none = np.zeros((0, 0))
    fd = np.empty_like(Y)
    for j in range(y0.size):
        h = 1e-6 * max(abs(y0[j]), 1e-3 * np.abs(y0).max())
        ends = []
        for sign in (1.0, -1.0):
            s = st.copy()
            y = y0.copy()
            y[j] += sign * h
            set_state(s, y, packed.laws)
            one(s, none)
            ends.append(state_vector(s))
        fd[:, j] = (ends[0] - ends[1]) / (2 * h)
    err = np.abs(Y - fd).max() / np.abs(Y).max()
    assert err < 1e-5, err          # measured 3e-7 .. 2e-6 (FD truncation and Newton noise)


def test_floquet_multipliers_of_a_damped_oscillator():
    """Linear SDOF: the multipliers are ``exp((-zeta w0 +- i w_d) T)`` up to Newmark's errors
    of order ``(w0 dt)^2`` in the decay exponent ``zeta w0 T`` and the phase ``w_d T``
    (measured 1.2e-6 of |mu|); the acceleration is no unknown of the map (the equations of
    motion fix it), so there are two."""
    m, k, c, f, N = 1.0, 1.0, 0.02, 0.2, 512
    case = sdof(c)
    packed = pack_elements(case.elements, case.n_dof)
    st = TimeState(case, packed, 2 * np.pi * f)
    stable, big, mu = floquet(case, f, st, TimeSimOptions(steps=N), N)
    T = 1.0 / f
    w0 = np.sqrt(k / m)
    zeta = c / (2 * np.sqrt(k * m))
    wd = w0 * np.sqrt(1 - zeta ** 2)
    exact = np.exp((-zeta * w0 + 1j * wd) * T)
    mu = mu[np.argsort(-np.abs(mu))]
    h2 = (w0 * T / N) ** 2
    assert stable and big == pytest.approx(abs(exact), rel=zeta * w0 * T * h2)
    # phase: the period elongation (w0 dt)^2 / 12 of w_d T (measured 4e-5 rad, the elongation alone 4e-5)
    assert abs(abs(np.angle(mu[0])) - abs(np.angle(exact))) < 2 * h2 / 12 * wd * T
    assert np.conj(mu[0]) == pytest.approx(mu[1], rel=1e-12)
    assert mu.size == 2


def test_shooting_finds_the_steady_state_of_a_nearly_undamped_oscillator():
    """zeta = 5e-5: the transient decays by |mu| = 0.99984 a period, so the plain periods
    would need some 10^5 periods for 1e-8; shooting after 5 periods lands on the periodic
    solution (the map is affine: one Newton step) and matches the closed form to Newmark's
    error."""
    c, f, N = 1e-4, 0.2, 512
    case = sdof(c)
    run = steady_state(case, f, TimeSimOptions(steps=N, shoot_after=5, max_periods=40))
    assert run.converged and run.periods < 15, (run.periods, run.change)
    assert run.shooting is not None and run.shooting.converged and run.shooting.iterations <= 3
    w = 2 * np.pi * f
    exact = 1.0 / abs(1.0 - w * w + 1j * c * w)
    # Newmark shifts the natural frequency by (w0 dt)^2 / 12: a relative amplitude change of
    # about that times w^2 / |1 - w^2| away from resonance
    assert run.h1["x"] == pytest.approx(exact, rel=5 * (2 * np.pi / N) ** 2 / 12 * 1.6 / 0.6)


def test_shooting_agrees_with_plain_periods_on_the_brush_rig():
    """rigs/beam_damper_beam.toml with coarse brushes at 536 Hz (damper stuck, bristles
    neutral: multipliers exactly 1): plain periods reach 1e-8 after about 640 periods, shooting
    after 20 + 2; the two steady states agree to the periodicity tolerance."""
    import tomllib
    from pathlib import Path
    path = Path(__file__).resolve().parents[1] / "rigs" / "beam_damper_beam.toml"
    data = tomllib.loads(path.read_text())
    for el in data["element"]:
        el.update(nx=8, lx=14e-6)
    case = case_from_dict(data, str(path), path.parent)
    plain = steady_state(case, 536.0, TimeSimOptions(steps=256, shoot_after=5000, max_periods=3000))
    shot = steady_state(case, 536.0, TimeSimOptions(steps=256, shoot_after=20, max_periods=3000))
    assert plain.converged and shot.converged and plain.shooting is None
    assert shot.periods < 40 < plain.periods, (shot.periods, plain.periods)
    for name in plain.h1:
        assert shot.h1[name] == pytest.approx(plain.h1[name], rel=1e-6)


def duffing(extra=()):
    return case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.05]]},
        "element": [{"type": "cubic", "dofs": [0], "k3": 0.5}] + list(extra),
        "excitation": {"dofs": [0], "amplitude": [0.3]},
        "analysis": {"frequency_hz": [0.1, 0.35], "outputs": {"x": 0}, "harmonics": [1, 3, 5, 7, 9],
                     "time_samples": 64},
    })


def test_floquet_check_agrees_with_hill_on_the_duffing_branches():
    """Hardening Duffing with three coexisting solutions: shooting from each balance point
    converges next to it (unstable ones too) and its multipliers give Hill's verdict: the
    middle branch unstable (|mu| up to 1.9), the others stable."""
    import hbm
    from hbm.timedomain.floquet_check import check_point
    case = duffing()
    res = hbm.frf(case)
    unstable = np.flatnonzero(~res.stable)
    assert unstable.size > 10
    for i in list(unstable[::4]) + list(np.flatnonzero(res.stable)[::12]):
        c = check_point(case, res.basis, res.X[i], float(res.freq_hz[i]), steps=1024)
        assert c.converged and c.distance < 1e-3, (res.freq_hz[i], c)   # 2.8e-4 at most (next to the fold)
        assert c.stable == res.stable[i], (res.freq_hz[i], c.largest)
        assert (c.largest > 1.05) == (not res.stable[i])


def test_floquet_confirmation_keeps_true_instability_and_clears_a_false_flag():
    """With a non-smooth law in the model (a Jenkins element that never slips) the FRF checks
    Hill's unstable points by Floquet: the Duffing middle branch stays unstable (a short run's
    middle point, a long run's samples, are checked and confirm it); a stable point flagged
    unstable by hand is cleared and reported."""
    import hbm
    from hbm.timedomain.floquet_check import confirm_unstable
    case = duffing([{"type": "jenkins", "dofs": [0], "kt": 0.2, "slip_force": 1e6}])
    res = hbm.frf(case)
    from hbm.timedomain.floquet_check import LONG_RUN, RUN_SAMPLES
    bad = np.flatnonzero(~res.stable)
    runs = np.split(bad, np.flatnonzero(np.diff(bad) > 1) + 1)
    samples = sum(1 if r.size <= LONG_RUN else RUN_SAMPLES for r in runs)
    assert bad.size > 10 and res.settings["floquet_checked"] == samples    # each run's samples confirm it
    assert "floquet_overrides_hz" not in res.settings
    fake = res.stable.copy()
    k = int(np.flatnonzero(res.stable)[3])
    fake[k] = False
    settings = {}
    out = confirm_unstable(case, res.basis, res.X, res.freq_hz, fake, settings)
    assert out[k] and np.array_equal(out, res.stable)
    assert settings["floquet_overrides_hz"] == [round(float(res.freq_hz[k]), 6)]
