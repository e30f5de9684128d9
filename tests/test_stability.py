"""Hill stability: exact Floquet exponents of linear systems, Duffing folds and jumps against
a stepped-sine time integration, friction-damped FRF, CLI outputs."""
import csv
import json
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

import hbm
from hbm.interface.cli import main
from hbm.balance.fourier import FourierBasis
from hbm.analyses.jumps import predict_jumps, stable_pieces
from hbm.model.linear import LinearModel
from hbm.balance.dense_part import dense_balance
from hbm.analyses.hill_system import point_stability
from hbm.analyses.stability import fold_exponents, hill_matrix, hill_stability, select_exponents
from hbm.balance.transforms import make_transform

from conftest import sdof_jenkins_case
from test_duffing import C, F, K, K3, M, duffing_case

ROOT = Path(__file__).resolve().parents[1]


def linear_problem(model, basis):
    n = model.n_dof
    return dense_balance(model, [], basis, np.ones(n), make_transform(basis, "dft"))


def exact_exponents(model, w):
    """Eigenvalues of the first-order state matrix, folded into (-w/2, w/2]."""
    n = model.n_dof
    Minv = np.linalg.inv(model.M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ model.K, -Minv @ model.C]])
    return fold_exponents(np.linalg.eigvals(A), w)


def same_set(a, b):
    a = np.sort_complex(np.round(a, 12))
    b = np.sort_complex(np.round(b, 12))
    return np.max(np.abs(a - b))


@pytest.mark.parametrize("harmonics", [[0, 1, 2, 3], [1, 2, 3, 4, 5], [1, 3, 5]])
@pytest.mark.parametrize("w_ratio", [0.3, 0.9, 1.0, 1.7, 4.0])
def test_linear_sdof_exponents_exact(harmonics, w_ratio):
    m, k, c = 2.0, 3.0, 0.3
    model = LinearModel.with_damping([[m]], [[k]], damping=[[c]])
    wn = np.sqrt(k / m)
    zeta = c / (2.0 * np.sqrt(k * m))
    wd = wn * np.sqrt(1.0 - zeta**2)
    w = w_ratio * wn
    basis = FourierBasis(harmonics, 32)
    prob = linear_problem(model, basis)
    r = point_stability(prob, prob.linear_solution(w), w)
    expect = fold_exponents(np.array([-zeta * wn + 1j * wd, -zeta * wn - 1j * wd]), w)
    assert r.exponents.shape == (2,)
    assert same_set(r.exponents, expect) < 1e-8
    assert r.stable and r.max_real == pytest.approx(-zeta * wn, abs=1e-10)
    # all Hill eigenvalues are members of the two families lambda - i j w
    fam = np.concatenate([expect + 1j * j * w for j in range(-12, 13)])
    assert max(np.min(np.abs(fam - lam)) for lam in r.hill_eigenvalues) < 1e-8


def test_linear_2dof_coupled_mass_exponents_exact():
    Mm = np.array([[2.0, 0.3], [0.3, 1.0]])
    Kk = np.array([[5.0, -2.0], [-2.0, 3.0]])
    Cc = 0.02 * Mm + 0.03 * Kk + np.array([[0.05, 0.0], [0.0, 0.0]])
    model = LinearModel(Mm, Cc, Kk)
    for harmonics in ([0, 1, 2, 3], [1, 2, 3, 4]):
        basis = FourierBasis(harmonics, 32)
        prob = linear_problem(model, basis)
        for w in (0.8, 1.5, 2.6):
            r = point_stability(prob, prob.linear_solution(w), w)
            assert r.exponents.shape == (4,)
            assert same_set(r.exponents, exact_exponents(model, w)) < 1e-8
            assert r.stable


def test_sign_of_velocity_coupling_matters():
    # with the opposite sign of the 2 h w M coupling of Delta_1 the exact families are lost
    model = LinearModel.with_damping([[1.0]], [[1.0]], damping=[[0.1]])
    basis = FourierBasis([1, 2, 3], 16)
    prob = linear_problem(model, basis)
    w = 1.3
    _, J, _ = prob.residual(prob.linear_solution(w), w)
    fam = np.concatenate([exact_exponents(model, w) + 1j * j * w for j in range(-8, 9)])
    dist = lambda lam: np.array([np.min(np.abs(fam - x)) for x in lam])
    good = np.linalg.eigvals(hill_matrix(J, model.M, model.C, basis, w))
    bad = np.linalg.eigvals(hill_matrix(J, model.M, model.C, basis, -w))  # flips only 2 h w M
    assert dist(good).max() < 1e-10
    assert dist(bad).min() > 1e-3


def test_unstable_linear_system_detected():
    # negative damping: the exponents' real part is positive and the point is unstable
    basis = FourierBasis([1, 2, 3], 16)
    M_, C_, w = np.eye(1), np.array([[-0.1]]), 1.2
    model = LinearModel.with_damping([[1.0]], [[1.0]], damping=[[0.1]])
    prob = linear_problem(model, basis)
    _, J, _ = prob.residual(prob.linear_solution(w), w)
    # J of the negatively damped system: flip the sign of the damping cross-blocks
    Jneg = J.copy()
    for r in (0, 2, 4):
        Jneg[r, r + 1] *= -1.0
        Jneg[r + 1, r] *= -1.0
    r = hill_stability(Jneg, M_, C_, basis, w)
    assert not r.stable and r.max_real == pytest.approx(0.05, abs=1e-10)


def test_filter_prefers_strip_then_central_members():
    w = 1.0
    lam = np.array([0.1 + 0.9j, -0.2 + 0.1j, -0.2 - 0.1j, 0.3 + 0.0j, -0.4 + 1.6j])
    mean = np.array([1.0, 0.2, -0.2, 1.9, 0.0])
    # in the strip: indices 1, 2, 3; the two most central are 1 and 2
    assert sorted(select_exponents(lam, mean, 1, w)) == [1, 2]
    # asking for more than the strip holds fills with the smallest |Im| outside it
    assert list(select_exponents(lam, mean, 2, w)) == [1, 2, 3, 0]
    # the strip is half-open: Im = +w/2 is inside, Im = -w/2 outside
    assert list(select_exponents(np.array([-0.5j, 0.5j, 0.7j]), np.zeros(3), 1, w)) == [1, 0]
    f = fold_exponents(np.array([1.6j, -0.5j, 0.5j, -2.4j]), w)
    assert np.allclose(f.imag, [-0.4, 0.5, 0.5, -0.4])


def stability_changes(stable):
    return np.flatnonzero(stable[1:] != stable[:-1])


@pytest.mark.parametrize("H", [3, 5])
def test_duffing_middle_branch_unstable(H):
    res = hbm.frf(duffing_case(H))
    assert res.ok, res.message
    s = res.stable
    assert s is not None and s.shape == res.freq_hz.shape and s.dtype == bool
    ch = stability_changes(s)
    assert len(ch) == 2 and len(res.folds_hz) == 2
    assert s[0] and not s[ch[0] + 1] and s[-1]
    # each change sits at a fold: the frequency reverses at point i or i+1 (the change is
    # between points i and i+1), and the located fold is within a step of that point
    f = res.freq_hz
    df = np.diff(f)
    turns = np.flatnonzero(np.sign(df[1:]) != np.sign(df[:-1])) + 1
    assert len(turns) == 2
    for i, k, f_fold in zip(ch, turns, res.folds_hz):
        assert k in (i, i + 1)
        assert abs(f_fold - f[k]) <= max(abs(df[k - 1]), abs(df[k]))
    # the unstable part is the one along which the frequency decreases (between the folds)
    assert np.all(df[ch[0] + 1:ch[1]] < 0)
    assert np.all(df[:ch[0]] > 0) and np.all(df[ch[1] + 1:] > 0)
    # a real exponent crossed zero: on the middle branch it is real and positive
    mid = (ch[0] + ch[1]) // 2
    case = duffing_case(H)
    prob = dense_balance(case.model, case.elements, res.basis, case.excitation.force,
                           make_transform(res.basis, "dft"))
    r = point_stability(prob, res.X[mid], 2 * np.pi * res.freq_hz[mid])
    top = r.exponents[0]
    assert top.real > 1e-3 and abs(top.imag) < 1e-9


def test_jenkins_frf_all_stable():
    res = hbm.frf(sdof_jenkins_case(F=1.0))
    assert res.ok, res.message
    assert res.stable.all() and not res.folds_hz
    res = hbm.frf(hbm.load_case(ROOT / "rigs" / "sdof_jenkins.toml"), harmonics=5)
    assert res.ok and res.stable.all()


def test_stability_off_leaves_none():
    res = hbm.frf(duffing_case(1), stability=False)
    assert res.stable is None


# ---------------------------------------------------------------- jumps on a synthetic S-curve

def s_curve(n=241):
    # f(s) = s^3 - 0.75 s: folds at s = -0.5 (f = 0.25) and s = 0.5 (f = -0.25);
    # the branch s in (-0.5, 0.5) is the unstable one; amplitude a = -s
    s = np.linspace(-1.2, 1.2, n)
    return s**3 - 0.75 * s, -s, np.abs(s) > 0.5


def test_predict_jumps_s_curve():
    f, a, st = s_curve()
    j = predict_jumps(f, a, st, folds_hz=[0.25, -0.25])
    assert len(j["up"]) == 1 and len(j["down"]) == 1
    up, down = j["up"][0], j["down"][0]
    h = 2.4 / 240
    # up: leaves the first branch at the fold f = 0.25 (s = -0.5), lands at s = 1 (a = -1)
    assert up["from_hz"] == 0.25
    assert up["amplitude_before"] == pytest.approx(0.5, abs=1.5 * h)
    assert up["amplitude_after"] == pytest.approx(-1.0, abs=1e-3)
    # down: leaves the third branch at f = -0.25 (s = 0.5), lands at s = -1 (a = 1)
    assert down["from_hz"] == -0.25
    assert down["amplitude_before"] == pytest.approx(-0.5, abs=1.5 * h)
    assert down["amplitude_after"] == pytest.approx(1.0, abs=1e-3)
    # without fold locations the jump is at the last stable point
    j = predict_jumps(f, a, st)
    i_last = np.flatnonzero(st)[np.flatnonzero(np.diff(st.astype(int)) == -1)[0]]
    assert j["up"][0]["from_hz"] == pytest.approx(f[i_last])
    assert 0.25 - j["up"][0]["from_hz"] < 3 * h * h
    # the same path traced backwards gives the same jumps
    jb = predict_jumps(f[::-1], a[::-1], st[::-1], folds_hz=[-0.25, 0.25])
    assert jb["up"][0]["from_hz"] == 0.25 and jb["down"][0]["from_hz"] == -0.25
    assert jb["up"][0]["amplitude_after"] == pytest.approx(-1.0, abs=1e-3)


def test_predict_jumps_no_fold_and_lost_stability():
    f = np.linspace(0.0, 1.0, 11)
    assert predict_jumps(f, f**2, np.ones(11, bool)) == {"up": [], "down": []}
    st = f < 0.55          # stability lost with no fold and no other branch
    j = predict_jumps(f, f, st)
    assert j["up"] == [{"from_hz": 0.5, "amplitude_before": 0.5, "amplitude_after": None}]
    assert j["down"] == []        # a downward sweep starts on the top stable point: none
    assert stable_pieces(np.array([0, 1, 2, 1, 0.5]), np.ones(5, bool)) == [(0, 2), (2, 4)]
    with pytest.raises(ValueError):
        predict_jumps(f, f[:-1], st)


def test_a_landing_at_the_same_amplitude_is_no_jump():
    # a branch that twists back by a hair (two points flagged unstable) and goes on along the
    # same curve: a sweep lands where it was (zero size), which is no jump; landing 5 % higher
    # still is one
    f = np.r_[np.linspace(0.0, 0.5, 11), 0.52, 0.51, np.linspace(0.49, 1.0, 12)]
    st = np.ones(f.size, bool)
    st[[11, 12]] = False
    assert predict_jumps(f, 1.0 + f, st) == {"up": [], "down": []}
    a_step = np.where(np.arange(f.size) > 12, 1.05, 1.0) * (1.0 + f)
    j = predict_jumps(f, a_step, st)
    assert len(j["up"]) == 1 and len(j["down"]) == 1
    assert j["up"][0]["amplitude_after"] == pytest.approx(1.05 * 1.5)


# ---------------------------------------------------------------- stepped sine in the time domain

@numba.njit(cache=True)
def _duffing_rhs(x, v, phi):
    return (F * np.cos(phi) - C * v - K * x - K3 * x * x * x) / M


@numba.njit(cache=True)
def _phase(t, w0, w1, t_ramp):
    """Excitation phase for a frequency ramped linearly from w0 to w1 over t_ramp, then held."""
    if t < t_ramp:
        return w0 * t + 0.5 * (w1 - w0) * t * t / t_ramp
    return 0.5 * (w0 + w1) * t_ramp + w1 * (t - t_ramp)


@numba.njit(cache=True)
def _step_to(x, v, phi0, w0, w1, steps, ramp_periods, max_periods, tol):
    """RK4 from (x, v) at phase phi0: ramp the frequency w0 -> w1 over ramp_periods, then
    hold whole periods until the period map moves less than tol.  Returns the state, the
    phase and the first-harmonic amplitude of the last period."""
    T = 2.0 * np.pi / w1
    dt = T / steps
    t_ramp = ramp_periods * T
    t = 0.0
    for k in range(ramp_periods * steps):
        x, v = _rk4(x, v, t, dt, phi0, w0, w1, t_ramp)
        t += dt
    a = 0.0
    for p in range(max_periods):
        x0, v0 = x, v
        hc = 0.0
        hs = 0.0
        for k in range(steps):
            ph = phi0 + _phase(t, w0, w1, t_ramp)
            hc += x * np.cos(ph)
            hs += x * np.sin(ph)
            x, v = _rk4(x, v, t, dt, phi0, w0, w1, t_ramp)
            t += dt
        a = 2.0 / steps * np.sqrt(hc * hc + hs * hs)
        if abs(x - x0) + abs(v - v0) / w1 < tol and p > 5:
            break
    return x, v, phi0 + _phase(t, w0, w1, t_ramp), a


@numba.njit(cache=True)
def _rk4(x, v, t, dt, phi0, w0, w1, t_ramp):
    p1 = phi0 + _phase(t, w0, w1, t_ramp)
    p2 = phi0 + _phase(t + 0.5 * dt, w0, w1, t_ramp)
    p3 = phi0 + _phase(t + dt, w0, w1, t_ramp)
    k1x, k1v = v, _duffing_rhs(x, v, p1)
    k2x, k2v = v + 0.5 * dt * k1v, _duffing_rhs(x + 0.5 * dt * k1x, v + 0.5 * dt * k1v, p2)
    k3x, k3v = v + 0.5 * dt * k2v, _duffing_rhs(x + 0.5 * dt * k2x, v + 0.5 * dt * k2v, p2)
    k4x, k4v = v + dt * k3v, _duffing_rhs(x + dt * k3x, v + dt * k3v, p3)
    return x + dt / 6.0 * (k1x + 2 * k2x + 2 * k3x + k4x), v + dt / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v)


def stepped_sine(freqs, ramp_periods=40):
    """Steady first-harmonic amplitudes of a stepped sine: each step ramps the frequency
    (phase-continuously) from the previous one and starts from the previous state."""
    x, v, phi, amps = 0.0, 0.0, 0.0, []
    w_prev = 2 * np.pi * freqs[0]
    for f in freqs:
        w = 2 * np.pi * f
        x, v, phi, a = _step_to(x, v, phi % (2 * np.pi), w_prev, w, 96, ramp_periods, 4000, 1e-9)
        amps.append(a)
        w_prev = w
    return np.array(amps)


def test_jumps_agree_with_stepped_sine():
    res = hbm.frf(duffing_case(5))
    assert res.ok
    # frf's jumps: landing amplitudes solved exactly; the path-only prediction has the
    # same frequencies and leaving amplitudes
    (up,), (down,) = res.jumps["x"]["up"], res.jumps["x"]["down"]
    j = predict_jumps(res.freq_hz, res.outputs["x"].h1, res.stable, res.folds_hz)
    for a, b in ((up, j["up"][0]), (down, j["down"][0])):
        assert a["from_hz"] == b["from_hz"] and a["amplitude_before"] == b["amplitude_before"]
        assert a["amplitude_after"] == pytest.approx(b["amplitude_after"], rel=0.05)
    df = 0.002
    grid = np.round(np.arange(0.1, 0.3 + 1e-12, df), 10)
    a_up = stepped_sine(grid)
    a_dn = stepped_sine(grid[::-1])[::-1]
    # the up sweep drops between grid[k] and grid[k+1]; the down sweep rises between grid[m+1] and grid[m]
    k = int(np.argmax(a_up[:-1] / a_up[1:]))
    m = int(np.argmax(a_dn[:-1] / a_dn[1:]))
    assert a_up[k] / a_up[k + 1] > 10 and a_dn[m] / a_dn[m + 1] > 2
    assert grid[k] <= up["from_hz"] <= grid[k + 1]
    assert grid[m] <= down["from_hz"] <= grid[m + 1]
    assert up["from_hz"] > down["from_hz"] + 0.05          # hysteresis
    # landing amplitudes: bracketed by the other sweep's steady states on the landing branch
    # at the two grid frequencies around the jump (0.1 % for the H = 5 truncation)
    lo, hi = sorted((a_dn[k], a_dn[k + 1]))
    assert lo * 0.999 <= up["amplitude_after"] <= hi * 1.001
    lo, hi = sorted((a_up[m], a_up[m + 1]))
    assert lo * 0.999 <= down["amplitude_after"] <= hi * 1.001
    # leaving amplitudes: the last stable HBM point (0.3 Hz from the fold) against the grid point
    assert up["amplitude_before"] == pytest.approx(a_up[k], rel=0.01)
    assert a_dn[m + 1] < down["amplitude_before"] < down["amplitude_after"]


# ---------------------------------------------------------------- CLI

DUFFING_TOML = f"""
name = "Duffing"
[model]
mass = [[{M}]]
stiffness = [[{K}]]
damping = [[{C}]]
[[element]]
type = "cubic"
dofs = [0]
k3 = {K3}
[excitation]
dofs = [0]
amplitude = [{F}]
[analysis]
harmonics = 3
time_samples = 32
frequency_hz = [0.1, 0.3]
outputs = {{ x = 0 }}
"""


def run(*args):
    return subprocess.run([sys.executable, "-m", "hbm", *args], capture_output=True, text=True)


def test_cli_stable_column_and_jumps(tmp_path, capsys):
    case = tmp_path / "duffing.toml"
    case.write_text(DUFFING_TOML)
    out = tmp_path / "o"
    r = run("frf", str(case), "-o", str(out), "-q")
    assert r.returncode == 0, r.stderr
    rows = list(csv.reader(open(out / "frf.csv")))
    assert rows[0][-1] == "stable"
    col = [row[-1] for row in rows[1:]]
    assert set(col) == {"0", "1"}
    st = np.array([c == "1" for c in col])
    assert len(stability_changes(st)) == 2 and st[0] and st[-1]
    s = json.loads((out / "summary.json").read_text())
    assert s["n_unstable"] == int((~st).sum()) > 0
    (up,), (down,) = s["jumps"]["x"]["up"], s["jumps"]["x"]["down"]
    assert up["from_hz"] == pytest.approx(max(s["folds"]))
    assert down["from_hz"] == pytest.approx(min(s["folds"]))
    assert up["amplitude_before"] > 10 * up["amplitude_after"]
    assert down["amplitude_after"] > down["amplitude_before"]
    assert "jump x (sweep up)" in r.stdout

    out2 = tmp_path / "o2"                                # in-process: the same entry point
    assert main(["frf", str(case), "-o", str(out2), "-q", "--no-stability"]) == 0
    assert "jump" not in capsys.readouterr().out
    rows = list(csv.reader(open(out2 / "frf.csv")))
    assert all(row[-1] == "" for row in rows[1:])
    s = json.loads((out2 / "summary.json").read_text())
    assert s["jumps"] is None and s["stability_computed"] is False
