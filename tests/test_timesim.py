"""The time-domain reference (``hbm.timedomain.timesim``): accuracy, step convergence, transient, CLI."""
import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hbm.interface.case import case_from_dict
from hbm.timedomain.timesim import TimeSimOptions, steady_state, timesim, transient
from conftest import sdof_jenkins_case
from timeref import jenkins_sdof_steady

ROOT = Path(__file__).resolve().parents[1]
JENKINS = dict(m=1.0, k=1.0, c=0.02, kt=1.0, fs=0.3, F=1.0)


def linear_case(m=1.0, k=1.0, c=0.02, F=1.0, elements=()):
    return case_from_dict({
        "model": {"mass": [[m]], "stiffness": [[k]], "damping": [[c]]},
        "element": list(elements),
        "excitation": {"dofs": [0], "amplitude": [F]},
        "analysis": {"frequency_hz": [0.1, 0.3], "outputs": {"x": 0}},
    })


@pytest.mark.parametrize("f_hz", [0.12, 0.159, 0.2])
def test_linear_sdof_closed_form(f_hz):
    m, k, c, F = 1.0, 1.0, 0.02, 1.0
    w = 2 * np.pi * f_hz
    exact = abs(F / (k - m * w * w + 1j * c * w))
    N = 1024
    # Newmark's relative period error (w dt)^2 / 12 shifts the response by at most about
    # that over 2 zeta near resonance: 1.6e-4 here; the scheme does far better
    bound = (2 * np.pi / N) ** 2 / 12 / c
    res = timesim(linear_case(m, k, c, F), f_hz, TimeSimOptions(steps=N // 2))
    err = abs(res.h1["x"] - exact) / exact
    assert res.converged and res.fine.steps == N
    assert err < bound, (err, bound)
    assert err < 3e-5, err
    assert err <= res.error_estimate          # the estimate bounds the true error
    # a harmonic response: max over the period equals h1 up to the sampling of the peak
    assert res.max["x"] == pytest.approx(exact, rel=(2 * np.pi / N) ** 2 + 2 * bound)


def test_stuck_jenkins_is_linear_and_hht_option():
    # a slip force nobody reaches: the element is a spring kt in parallel with k
    m, k, c, kt, F, f_hz = 1.0, 1.0, 0.02, 1.0, 1.0, 0.2
    case = linear_case(m, k, c, F, [{"type": "jenkins", "dofs": [0], "kt": kt, "slip_force": 1e9}])
    w = 2 * np.pi * f_hz
    exact = abs(F / (k + kt - m * w * w + 1j * c * w))
    r = steady_state(case, f_hz, TimeSimOptions(steps=1024))
    assert abs(r.h1["x"] - exact) / exact < 1e-4
    assert r.stats["refinements"] == 0          # no status change, no sub-steps
    # HHT with a little numerical damping: still close (its damping is O(alpha (w dt)^3))
    r2 = steady_state(case, f_hz, TimeSimOptions(steps=1024, alpha=-0.1))
    assert abs(r2.h1["x"] - exact) / exact < 1e-3


@pytest.mark.parametrize("f_hz", [0.12, 0.16, 0.2])
def test_jenkins_sdof_against_independent_reference(f_hz):
    p = JENKINS
    case = sdof_jenkins_case(**p)
    h1_ref, max_ref, _ = jenkins_sdof_steady(p["m"], p["c"], p["k"], p["kt"], p["fs"], p["F"],
                                             2 * np.pi * f_hz, steps=8000)
    res = timesim(case, f_hz, TimeSimOptions(steps=256))
    assert res.converged
    e_h1 = abs(res.h1["x"] - h1_ref) / h1_ref
    e_max = abs(res.max["x"] - max_ref) / max_ref
    assert e_h1 < 2e-3 and e_max < 2e-3, (e_h1, e_max)
    # the element really slips: its force reaches the slip limit
    assert np.abs(res.history.forces).max() == pytest.approx(p["fs"], rel=1e-12)


def test_step_halving_error_estimate():
    case = sdof_jenkins_case(**JENKINS)
    f_hz = 0.16                                   # near the resonance: the hardest point
    r1 = timesim(case, f_hz, TimeSimOptions(steps=128))   # values at 256, estimate 128 vs 256
    r2 = timesim(case, f_hz, TimeSimOptions(steps=256))   # values at 512
    for key in ("h1", "max"):
        y2, y4 = getattr(r1, key)["x"], getattr(r2, key)["x"]
        change = abs(y4 - y2) / y4
        assert change < r1.error_estimate, (key, change, r1.error_estimate)
    # second order: halving the step divides the estimate by about 4
    assert r2.error_estimate < r1.error_estimate / 2.5, (r1.error_estimate, r2.error_estimate)


def test_transient_free_decay_friction_arrests_slip():
    # no viscous damping: after switch-off only friction dissipates; once the amplitude is
    # below the slip onset the slider sticks and a finite oscillation remains (energy kept)
    p = dict(JENKINS, c=0.0)
    case = sdof_jenkins_case(**p)
    f_hz, N, P, P_off = 0.16, 128, 80, 20
    T = 1.0 / f_hz
    run = transient(case, f_hz, P, switch_off_at=P_off * T, options=TimeSimOptions(steps=N))
    h = run.history
    assert h.t.size == P * N + 1 and h.t[-1] == pytest.approx(P * T)
    x = h.q[:, 0]
    f = h.forces[:, 0]
    per = x[1:].reshape(P, N)
    amp_on = np.abs(per[P_off - 1]).max()
    amp = np.array([0.5 * (row.max() - row.min()) for row in per])
    # decays after switch-off ...
    assert amp[-1] < 0.5 * amp_on, (amp[-1], amp_on)
    # (amplitudes from the sampled peaks: tolerance of the peak sampling, ~(w dt)^2 / 8)
    assert np.all(np.diff(amp[P_off + 1:]) <= 1e-3 * amp[P_off + 2:])
    # ... until the slider sticks for good: its position u - f/kt no longer moves.  The force
    # touches the limit at every reversal (undamped after sticking); as the sampling phase
    # drifts, a later sample may land nearer the peak and slip by at most the peak-sampling
    # error of the force, (w dt)^2 / 8 of its amplitude (measured: one slip of 3.6e-9 amp_on
    # in the last 10 periods with newton_tol 1e-12, none with 1e-10)
    tail = slice((P - 10) * N, None)
    slider = h.disp[:, 0] - f / p["kt"]
    w_free = np.sqrt((p["k"] + p["kt"]) / p["m"])
    sampling = (w_free * T / N) ** 2 / 8 * 0.5 * np.ptp(f[tail]) / p["kt"]
    assert np.ptp(slider[tail]) <= sampling, (np.ptp(slider[tail]), sampling)
    assert np.ptp(slider[tail]) < 1e-5 * np.ptp(slider[P_off * N:])
    assert np.ptp(slider[P_off * N:]) > 1.0                  # it did slip after switch-off
    assert np.abs(f).max() <= p["fs"] * (1 + 1e-12)
    # then linear and undamped: constant amplitude (average acceleration adds no damping)
    assert amp[-1] > 0.002 * amp_on
    assert abs(amp[-1] - amp[-10]) < 1e-3 * amp[-1]
    # the oscillation is about an offset that static equilibrium allows: |k x| <= fs
    centre = 0.5 * (x[tail].max() + x[tail].min())
    assert abs(centre) <= p["fs"] / p["k"]
    # with the force on for the whole run the amplitude does not collapse
    run_on = transient(case, f_hz, P, options=TimeSimOptions(steps=N))
    assert np.abs(run_on.history.q[-N:, 0]).max() > 0.8 * amp_on


def test_two_dof_energy_balance_with_mixed_elements():
    # relative Jenkins between the masses and a cubic spring to ground: the work of the force
    # over the steady period equals viscous plus friction dissipation (cubic: conservative)
    data = {
        "model": {"mass": [[1.0, 0.0], [0.0, 0.5]], "stiffness": [[2.0, -1.0], [-1.0, 1.0]],
                  "damping": [[0.03, -0.01], [-0.01, 0.01]]},
        "element": [{"type": "jenkins", "dofs": [1, 0], "kt": 2.0, "slip_force": 0.2},
                    {"type": "cubic", "dofs": [0], "k3": 0.5}],
        "excitation": {"dofs": [1], "amplitude": [0.5]},
        "analysis": {"frequency_hz": [0.1, 0.3], "outputs": {"a": 0, "b": 1}},
    }
    case = case_from_dict(data)
    f_hz = 0.1
    w = 2 * np.pi * f_hz
    r = steady_state(case, f_hz, TimeSimOptions(steps=1024))
    assert r.converged
    h = r.history
    q = h.q
    dq = np.diff(q, axis=0)
    dt = h.t[1] - h.t[0]
    v = dq / dt                                    # midpoint velocity
    F = case.excitation.force
    fex = 0.5 * (np.cos(w * h.t[1:]) + np.cos(w * h.t[:-1]))[:, None] * F
    w_ex = np.sum(fex * dq)
    w_visc = np.sum((v @ case.model.C) * dq)
    fr = 0.5 * (h.forces[1:] + h.forces[:-1])
    du = np.diff(h.disp, axis=0)
    w_fr = np.sum(fr[:, 0] * du[:, 0])
    w_cub = np.sum(fr[:, 1] * du[:, 1])
    assert h.force_names == ("jenkins0_f", "cubic1_f")
    assert w_fr > 0.05 * w_ex                      # the friction joint slips and dissipates
    assert abs(w_cub) < 1e-4 * w_ex
    assert abs(w_ex - w_visc - w_fr) < 1e-4 * w_ex, (w_ex, w_visc, w_fr)   # measured 3e-6


def test_hbm_matches_time_domain_at_H15():
    cont = pytest.importorskip("continuation")
    if not hasattr(cont, "Arclength"):
        pytest.skip("continuation package not merged yet")
    from hbm.analyses.response import solve_at, output_amplitudes
    case = sdof_jenkins_case(**JENKINS)
    for f_hz in (0.12, 0.16, 0.2):
        X, basis, _ = solve_at(case, f_hz, harmonics=15, samples=512)
        h1_hbm, max_hbm = output_amplitudes(basis, X[:, 0])
        res = timesim(case, f_hz, TimeSimOptions(steps=512))
        assert res.converged and res.error_estimate < 1e-3
        assert abs(h1_hbm - res.h1["x"]) / res.h1["x"] < 2e-3, (f_hz, h1_hbm, res.h1["x"])
        assert abs(max_hbm - res.max["x"]) / res.max["x"] < 2e-3, (f_hz, max_hbm, res.max["x"])


def test_bad_options_raise_case_error():
    from hbm.interface.case import CaseError
    case = sdof_jenkins_case(**JENKINS)
    for call in (lambda: timesim(case, -1.0), lambda: timesim(case, 0.0),
                 lambda: timesim(case, 0.1, TimeSimOptions(steps=4)),
                 lambda: timesim(case, 0.1, TimeSimOptions(alpha=0.2)),
                 lambda: transient(case, 0.1, 0)):
        with pytest.raises(CaseError):
            call()


# ---------------------------------------------------------------- command line

CASE = """
name = "sdof"
[model]
mass = [[1.0]]
stiffness = [[1.0]]
damping = [[0.05]]
[[element]]
type = "jenkins"
dofs = [0]
kt = 1.0
slip_force = 0.3
[excitation]
dofs = [0]
amplitude = [1.0]
[analysis]
frequency_hz = [0.1, 0.25]
outputs = { x = 0 }
"""


def run(*args):
    return subprocess.run([sys.executable, "-m", "hbm", *args], capture_output=True, text=True)


def test_cli_writes_files(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(CASE)
    out = tmp_path / "out"
    r = run("timesim", str(case), "--freq-hz", "0.2", "-o", str(out), "--steps", "64", "--tol", "1e-7",
            "--floquet")
    assert r.returncode == 0, r.stderr
    rows = list(csv.reader(open(out / "timesim.csv")))
    assert rows[0] == ["freq_hz", "x_h1", "x_max", "error_estimate", "periods", "floquet_max", "stable"]
    assert len(rows) == 2
    vals = [float(v) for v in rows[1]]
    assert vals[0] == 0.2 and vals[1] > 0 and vals[2] >= vals[1] * 0.9 and 0 < vals[3] < 0.05 and vals[4] > 2
    assert 0 < vals[5] < 1 and vals[6] == 1 and "Floquet: largest |multiplier|" in r.stdout
    hist = list(csv.reader(open(out / "history.csv")))
    assert hist[0] == ["t", "x", "jenkins0_f", "jenkins0_u", "jenkins0_v"] and len(hist) == 2 + 128   # last period at 2n steps
    assert (out / "timesim.png").stat().st_size > 1000
    assert "error estimate" in r.stdout
    # transient mode: the whole history
    r = run("timesim", str(case), "--freq-hz", "0.2", "-o", str(out), "--steps", "32",
            "--periods", "5", "--switch-off-at", "10")
    assert r.returncode == 0, r.stderr
    assert len(list(csv.reader(open(out / "history.csv")))) == 2 + 5 * 64


def test_cli_no_steady_state_exits_1_and_keeps_the_files(tmp_path):
    """Two periods cannot reach the periodicity tolerance from rest: stated on stderr, the
    last period written, exit status 1 (a solver failure), not 0."""
    case = tmp_path / "case.toml"
    case.write_text(CASE)
    out = tmp_path / "out"
    r = run("timesim", str(case), "--freq-hz", "0.2", "-o", str(out), "--steps", "32", "--max-periods", "2")
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert "no periodic steady state within 2 periods" in r.stderr
    assert (out / "timesim.csv").is_file()


@pytest.mark.parametrize("args, needle", [
    (["--freq-hz", "-1"], "freq"),
    (["--freq-hz", "0"], "freq"),
    (["--freq-hz", "0.2", "--switch-off-at", "3"], "periods"),
    (["--freq-hz", "0.2", "--steps", "0"], "steps"),
    (["--freq-hz", "0.2", "--alpha", "0.5"], "alpha"),
])
def test_cli_bad_input_one_line_exit_2(tmp_path, args, needle):
    case = tmp_path / "case.toml"
    case.write_text(CASE)
    r = run("timesim", str(case), "-o", str(tmp_path / "o"), *args)
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert needle in lines[0].lower(), lines[0]
