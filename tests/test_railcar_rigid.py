"""The railcar wedge's rigid-contact model (rigs/studies/railcar_rigid.py): the event-driven
closed form against an independent integration, its frictionless limit against the penalty
model's linear algebra, its stick phases, and the rig's numbers that the document quotes."""
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "rigs"))

import make_railcar_wedge_model as mk                     # noqa: E402
from rigs.studies import railcar_rigid as rr              # noqa: E402


def _regularised(rig, y0, v0, periods, eps):
    """The same one-DOF law with sgn(v) replaced by tanh(v / eps), by LSODA."""
    def rhs(t, z):
        s = np.tanh(z[1] / eps)
        up = rig.drive(1, t) - rr.W2 * rig.slip[1][0] * z[0]
        down = rig.drive(-1, t) - rr.W2 * rig.slip[-1][0] * z[0]
        return [z[1], 0.5 * (1 + s) * up + 0.5 * (1 - s) * down]
    T = rig.period
    sol = solve_ivp(rhs, (0, periods * T), [y0, v0], method="LSODA", rtol=1e-9, atol=1e-13,
                    dense_output=True)
    return sol.sol((periods - 1) * T + np.arange(512) * T / 512)[0]


@pytest.mark.parametrize("freq, tol", [(33.0, 2e-3), (40.0, 2e-4)])
def test_events_agree_with_a_regularised_integration(freq, tol):
    # 33 Hz sticks twice a period, 40 Hz slips throughout; a tanh law with eps = 1e-6 m/s
    # converges to the event solution like eps (measured: 33 Hz 5.9e-2, 7.2e-3, 8.5e-4 at
    # eps = 1e-4, 1e-5, 1e-6; 40 Hz 4.6e-3, 4.7e-4, 4.7e-5)
    rig = rr.Rig.at(freq, 2e-4)
    st = rr.steady_state(rig)
    assert st.converged and st.stable
    y = st.samples(512)[1]
    yr = _regularised(rig, st.y0, st.v0, 4, 1e-6)
    assert np.max(np.abs(yr - y)) <= tol * np.ptp(y)


def test_frictionless_limit_is_the_penalty_models_linear_response():
    # mu = 0: the rigid model is linear; the penalty model's harmonic response with stiff
    # normal springs (1e9 N/m) must give the same relative amplitude
    f, A = 40.0, 2e-4
    W = 2 * np.pi * f
    M, K = mk.matrices()
    idx = {n: i for i, n in enumerate(mk.DOF_NAMES)}
    for side in "RL":
        for face in mk.contact_rows(side):
            n = np.zeros(len(idx))
            for d, c in face["n"].items():
                n[idx[d]] = c
            K = K + 1e9 * np.outer(n, n)
    Z = K - W ** 2 * M
    q = np.linalg.solve(Z[1:, 1:], -Z[1:, 0] * A)
    penalty = q[0] - A                                   # b.y - sf.y
    rig = rr.Rig.at(f, A, mu_k=0.0)
    F, G, _ = rig.slip[1]
    rigid = G * A * W ** 2 / (rr.W2 * F - W ** 2)
    assert rigid == pytest.approx(penalty, rel=1e-5)
    st = rr.steady_state(rig, settle=2)                  # undamped: found by shooting
    assert st.method == "shooting"
    assert np.ptp(st.samples()[1]) == pytest.approx(2 * abs(rigid), rel=1e-6)


def test_phases_join_and_stop_at_zero_velocity():
    rig = rr.Rig.at(31.0, 2e-4)
    st = rr.steady_state(rig)
    ph = st.phases
    assert {p.s for p in ph} == {-1, 0, 1}
    for a, b in zip(ph[:-1], ph[1:]):
        assert a.t1 == b.t0
        assert float(a.y(a.t1, rig.W)) == pytest.approx(float(b.y(b.t0, rig.W)), abs=1e-15)
        if a.s != 0 and b.s != a.s:                      # a slip that ends stops
            assert abs(float(a.v(a.t1, rig.W))) < 1e-12
    # while stuck, neither direction can start (static coefficients)
    for p in ph:
        if p.s == 0:
            t = np.linspace(p.t0, p.t1, 50)[1:-1]
            assert np.all(rig.drive(1, t, stick=True) - rr.W2 * rig.stick[1][0] * p.y0 <= 1e-9)
            assert np.all(rig.drive(-1, t, stick=True) - rr.W2 * rig.stick[-1][0] * p.y0 >= -1e-9)


def test_below_break_loose_it_stays_stuck():
    st = rr.steady_state(rr.Rig.at(25.0, 0.1e-3))
    assert st.converged and st.periods == 1
    assert np.ptp(st.samples()[1]) == 0.0
    assert rr.stick_events(st) == []


def test_static_friction_below_kinetic_is_refused():
    with pytest.raises(ValueError, match="mu_s"):
        rr.Rig.at(30.0, 2e-4, mu_k=0.3, mu_s=0.2)


def test_rig_numbers_quoted_in_the_document():
    # rigs/railcar_wedge.md, "Rigid contacts": every point 28-40 Hz periodic; pk-pk at 40 Hz;
    # two type-B sticks of 11.8 ms at 30 Hz; a period-2 motion at 28 Hz with mu_s > mu_k
    for f in np.arange(28.0, 40.01, 1.0):
        st = rr.steady_state(rr.Rig.at(f, 2e-4))
        assert st.converged and st.stable and st.multiple == 1, f
    st = rr.steady_state(rr.Rig.at(40.0, 2e-4))
    assert np.ptp(st.samples()[1]) == pytest.approx(0.2737e-3, rel=1e-3)
    ev = rr.stick_events(rr.steady_state(rr.Rig.at(30.0, 2e-4)))
    assert [e.kind for e in ev] == ["B", "B"]
    assert [e.duration for e in ev] == pytest.approx([11.83e-3, 11.85e-3], abs=0.02e-3)
    st = rr.steady_state(rr.Rig.at(28.0, 0.22e-3, mu_k=0.2, mu_s=0.29))
    assert st.converged and st.multiple == 2


@pytest.mark.parametrize("freq", [31.0, 40.0])
def test_energy_balance_over_a_period(freq):
    # split Eq. (1) into the frictionless law (mu = 0: conservative plus the side-frame's
    # inertial load) and the friction's part; over a steady period the load's work must be
    # what friction dissipates (stuck phases do no work), and friction must dissipate
    rig = rr.Rig.at(freq, 2e-4)
    st = rr.steady_state(rig)
    F0, G0, H0 = rr.Rig.at(freq, 2e-4, mu_k=0.0).slip[1]
    n = 200_000
    t = (np.arange(n) + 0.5) * rig.period / n              # midpoint rule
    y, v = rr.sample(st.phases, t, rig.W)
    ge = mk.G_ACC - rig.A * rig.W ** 2 * np.cos(rig.W * t)  # gravity + side-frame inertia
    friction = np.zeros(n)
    for s in (1, -1):
        F, G, H = rig.slip[s]
        m = np.sign(v) == s
        friction[m] = -(rr.W2 * (F - F0) * y[m] + (H - H0) * mk.G_ACC + (G - G0) * ge[m])
    dt = rig.period / n
    w_load, w_friction = np.sum(-G0 * ge * v) * dt, np.sum(friction * v) * dt
    assert w_friction < 0
    assert abs(w_load + w_friction) <= 1e-7 * abs(w_friction)


def test_stick_types_and_a_stick_across_the_period_end():
    # type A keeps the direction across a stick, type B reverses it (the paper's Fig. 8); a
    # stick cut by the end of the period is joined to its start
    rig = rr.Rig.at(30.0, 2e-4)
    T = rig.period
    ph = [rr.Phase(0, 0.0, 0.1 * T, 0.0), rr.Phase(1, 0.1 * T, 0.3 * T, 0.0),
          rr.Phase(0, 0.3 * T, 0.4 * T, 0.0), rr.Phase(1, 0.4 * T, 0.6 * T, 0.0),
          rr.Phase(0, 0.6 * T, 0.7 * T, 0.0), rr.Phase(-1, 0.7 * T, 0.9 * T, 0.0),
          rr.Phase(0, 0.9 * T, T, 0.0)]
    st = rr.Steady(rig, 0.0, 0.0, ph, True, "marching", 1)
    ev = rr.stick_events(st)
    assert [e.kind for e in ev] == ["A", "B", "B"]
    assert [e.start / T for e in ev] == pytest.approx([0.3, 0.6, 0.9])
    assert [e.duration / T for e in ev] == pytest.approx([0.1, 0.1, 0.2])
