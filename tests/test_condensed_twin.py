"""The condensed model in the time domain (kept modes + the residual flexibility's static
coordinates) is the model the condensed harmonic balance solves, and its Floquet verdicts
are those of the full model when every mode is kept."""
import numpy as np
import pytest

import hbm
from hbm.analyses.problem_setup import build_problem, solve_at
from hbm.interface.case import case_from_dict
from hbm.timedomain.condensed_twin import time_twin, twin_coefficients
from hbm.timedomain.floquet_check import check_point, confirm_unstable
from hbm.timedomain.shooting import static_dofs


def chain_case(solver, modes="all", elements=None, amplitude=0.3, window=(0.1, 0.3)):
    n = 8
    K = 2.0 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    K[-1, -1] = 1.0
    M = np.diag([1.0, 1.0, 0.5, 0.8, 1.0, 1.0, 0.5, 0.8])
    elements = elements or [{"type": "jenkins", "dofs": [7], "kt": 0.6, "slip_force": 0.1},
                            {"type": "jenkins", "dofs": [3, 7], "kt": 0.4, "slip_force": 0.08}]
    return case_from_dict({
        "model": {"mass": M.tolist(), "stiffness": K.tolist(), "rayleigh": [0.01, 0.01],
                  "solver": solver, "modes": modes, "residual_flexibility": modes != "all"},
        "element": elements,
        "excitation": {"dofs": [7, 0], "amplitude": [amplitude, 0.1 * amplitude], "phase_deg": [0.0, 30.0]},
        "analysis": {"harmonics": 5, "time_samples": 64, "frequency_hz": list(window), "outputs": {"tip": 7}},
    })


def condensed_problem(case, basis):
    problem, info = build_problem(case, basis, "dft")
    assert info["solver"] == "condensed"
    return problem


def test_twin_receptances_are_the_condensed_ones():
    """Eliminating the static coordinates from the twin's dynamic stiffness gives the reduced
    model's contact and excitation receptances exactly (some of eight modes kept)."""
    case = chain_case("condensed", modes=2, window=(0.02, 0.045))
    res = hbm.frf(case, stability=False, error_estimate=False)
    problem = condensed_problem(case, res.basis)
    lin = problem.linear
    twin = time_twin(lin)
    m = twin.n_modes
    assert m < 8 and twin.n_dof > m
    assert np.array_equal(static_dofs((twin.model.M, twin.model.C)), np.arange(twin.n_dof) >= m)
    for W in (0.3, 1.1, 2.9):
        D = twin.model.K - W * W * twin.model.M + 1j * W * twin.model.C
        Hcc = twin.B @ np.linalg.solve(D, twin.B.T)
        Fw = twin.excitation.cos_sin[0] - 1j * twin.excitation.cos_sin[1]
        u = twin.B @ np.linalg.solve(D, Fw)
        ref_cc, _ = lin.condensed.receptance("c", "c", W)
        ref_ce, _ = lin.condensed.receptance("c", "e", W)
        fe = np.array([1.0, -1j])[:ref_ce.shape[1]]
        assert np.abs(Hcc - ref_cc).max() < 1e-12 * np.abs(ref_cc).max()
        assert np.abs(u - ref_ce @ fe).max() < 1e-12 * np.abs(ref_ce @ fe).max()


def test_twin_coefficients_satisfy_the_twin_balance():
    """At a converged condensed point the twin's coefficients balance the twin's equations
    harmonic by harmonic, with the element forces of its contact motion from the AFT."""
    case = chain_case("condensed", modes=2, window=(0.02, 0.045))
    res = hbm.frf(case, stability=False, error_estimate=False)
    problem = condensed_problem(case, res.basis)
    twin = time_twin(problem.linear)
    basis = res.basis
    for i in (5, res.freq_hz.size // 2, res.freq_hz.size - 3):
        w = 2 * np.pi * res.freq_hz[i]
        Y = twin_coefficients(problem.linear, twin, res.X[i], w)
        assert np.allclose(Y @ twin.B.T, res.X[i], rtol=0, atol=1e-12 * np.abs(res.X[i]).max())
        d = problem.nl.dofs
        Fn = np.zeros_like(res.X[i])                            # element forces on u
        Fn[:, d] = problem.nl.forces(res.X[i][:, d], w)
        lhs = Y @ twin.model.K.T + (w * w) * (basis.D @ basis.D @ Y) @ twin.model.M.T \
            + w * (basis.D @ Y) @ twin.model.C.T + Fn @ twin.B
        F = np.zeros_like(Y)
        F[basis.row_of(1, "c")] = twin.excitation.cos_sin[0]
        F[basis.row_of(1, "s")] = twin.excitation.cos_sin[1]
        assert np.abs(lhs - F).max() < 1e-7 * np.abs(F).max()


@pytest.fixture(scope="module")
def full_and_condensed():
    full = chain_case("full")
    res = hbm.frf(full, stability=False, error_estimate=False)
    return full, res, chain_case("condensed")


def test_floquet_of_the_twin_equals_the_full_models(full_and_condensed):
    """Every mode kept: the twin is the full model in modal coordinates, and Newmark's map is
    the same in any coordinates, so the multipliers agree at points of the full path."""
    full, res, cond = full_and_condensed
    problem = condensed_problem(cond, res.basis)
    assert time_twin(problem.linear).n_dof == 8        # every mode, no static coordinate
    for i in (3, res.freq_hz.size // 2):
        f = float(res.freq_hz[i])
        a = check_point(full, res.basis, res.X[i], f, steps=256)
        U = res.X[i] @ problem.linear.contact_rows.T
        b = check_point(cond, res.basis, U, f, steps=256, problem=problem)
        assert a.converged and b.converged, (a.message, b.message)
        assert abs(a.largest - b.largest) < 1e-5, (f, a.largest, b.largest)
        assert a.distance < 0.05 and b.distance < 0.05


def duffing_chain(solver):
    return chain_case(solver, "all", [{"type": "cubic", "dofs": [7], "k3": 0.5},
                                      {"type": "jenkins", "dofs": [7], "kt": 0.05, "slip_force": 1e6}],
                      amplitude=0.02, window=(0.03, 0.09))


def test_condensed_frf_confirms_its_unstable_branch():
    """A condensed Duffing chain with a non-smooth law (a Jenkins element that never slips):
    Hill's unstable middle branch is checked by Floquet on the twin and stays unstable; a
    stable point flagged by hand is cleared."""
    case = duffing_chain("condensed")
    res = hbm.frf(case)
    bad = np.flatnonzero(~res.stable)
    assert bad.size > 5 and res.settings["floquet_checked"] >= 1
    assert "floquet_overrides_hz" not in res.settings
    problem = condensed_problem(case, res.basis)
    fake = res.stable.copy()
    k = int(np.flatnonzero(res.stable)[3])
    fake[k] = False
    st = {}
    out = confirm_unstable(case, res.basis, res.X, res.freq_hz, fake, st, problem)
    assert np.array_equal(out, res.stable) and st["floquet_overrides_hz"] == [round(float(res.freq_hz[k]), 6)]



def light_contacts(solver, force_dof=1):
    """Two unit masses in a chain (0, 1) and three light masses (1e-4) on unit springs: 2 from
    0 and 3 from 1 carry the Jenkins contacts, 4 (from 0) carries nothing.  The light masses'
    modes (16 Hz) are far above the window (modes 0.11 and 0.52 Hz), so two kept modes with
    the residual flexibility are nearly exact.  Modal damping: a stiffness-proportional one
    would damp the full model's light springs at every frequency, which the static residual
    term does not (1e-3 apart)."""
    K = np.zeros((5, 5))
    for a, b, k in ((0, 1, 5.0), (0, 2, 1.0), (1, 3, 1.0), (0, 4, 1.0)):
        K[np.ix_([a, b], [a, b])] += k * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[0, 0] += 1.0
    return case_from_dict({
        "model": {"mass": [1.0, 1.0, 1e-4, 1e-4, 1e-4], "stiffness": K.tolist(), "modal_damping": 0.01,
                  "solver": solver, "modes": 2, "residual_flexibility": solver == "condensed"},
        "element": [{"type": "jenkins", "dofs": [2], "kt": 0.6, "slip_force": 0.1},
                    {"type": "jenkins", "dofs": [3], "kt": 0.4, "slip_force": 0.08}],
        "excitation": {"dofs": [force_dof], "amplitude": [0.3]},
        "analysis": {"harmonics": 5, "time_samples": 64, "frequency_hz": [0.06, 0.25],
                     "outputs": {"x": 1, "c": 4}},
    })


def test_floquet_with_static_coordinates_matches_the_full_model():
    """Two modes kept plus the residual flexibility (static coordinates in the twin), the
    omitted modes far above the window: shooting converges next to the condensed balance
    point and its largest multiplier is the full model's at the same frequency.  (Without
    the static coordinates' treatment the recurrences of their velocities give a spurious
    multiplier 1 and shooting does not converge.)  Measured: 1e-4, 7e-6, 3e-4 apart."""
    cond, full = light_contacts("condensed"), light_contacts("full")
    rc = hbm.frf(cond, stability=False, error_estimate=False)
    assert rc.ok, rc.message
    problem = condensed_problem(cond, rc.basis)
    twin = time_twin(problem.linear)
    assert twin.n_modes == 2 and twin.n_dof == 4
    for f in (0.09, 0.11, 0.14):                       # slipping (stuck from about 0.17 Hz)
        i = int(np.argmin(np.abs(rc.freq_hz - f)))
        f = float(rc.freq_hz[i])
        b = check_point(cond, rc.basis, rc.X[i], f, steps=256, problem=problem)
        X, basis, _ = solve_at(full, f)
        a = check_point(full, basis, X, f, steps=256)
        assert a.converged and b.converged, (a.message, b.message)
        assert b.distance < 0.025
        assert b.largest < 0.99 and abs(a.largest - b.largest) < 1e-3 * a.largest, (f, a.largest, b.largest)


def test_twin_time_simulation_gives_the_full_models_outputs():
    """``timesim`` on the twin settles on the full model's response, outputs included: with
    the force on a light mass the output there is mostly the residual flexibility's direct
    response to the force (the twin's ``feed``), which the twin must add (without it: 0.634
    against 0.414 at 0.14 Hz; with it 1e-4 to 4.5e-4 from the full model)."""
    from hbm.timedomain.timesim import TimeSimOptions, timesim
    cond, full = light_contacts("condensed", force_dof=4), light_contacts("full", force_dof=4)
    rc = hbm.frf(cond, stability=False, error_estimate=False)
    problem = condensed_problem(cond, rc.basis)
    twin = time_twin(problem.linear, outputs=list(cond.analysis.outputs))
    assert abs(twin.analysis.feed["c"][0]) > 0.1 and twin.analysis.feed["c"][1] == 0.0
    opts = TimeSimOptions(steps=256)
    for f in (0.11, 0.14):
        a, b = timesim(full, f, opts), timesim(twin, f, opts)
        assert a.converged and b.converged
        for k in ("x", "c"):
            assert abs(b.h1[k] / a.h1[k] - 1) < 1e-3 and abs(b.max[k] / a.max[k] - 1) < 1e-3, (f, k, a.h1, b.h1)
        i = int(np.argmin(np.abs(rc.freq_hz - f)))
        assert abs(rc.outputs["c"].h1[i] / b.h1["c"] - 1) < 0.05


def test_timesim_cli_integrates_the_condensed_model(tmp_path, capsys):
    """``hbm timesim --condensed`` steps the twin and writes its outputs (direct part included);
    a full-solver case is refused in one line (exit status 2)."""
    import csv
    from hbm.interface.cli import main
    from hbm.timedomain.timesim import TimeSimOptions, timesim
    K = light_contacts("full", force_dof=4).structure.K
    rows = ", ".join("[" + ", ".join(f"{v:g}" for v in r) + "]" for r in K)
    text = f"""
element = [{{ type = "jenkins", dofs = [2], kt = 0.6, slip_force = 0.1 }},
           {{ type = "jenkins", dofs = [3], kt = 0.4, slip_force = 0.08 }}]
excitation = {{ dofs = [4], amplitude = [0.3] }}
analysis = {{ harmonics = 5, frequency_hz = [0.06, 0.25], outputs = {{ x = 1, c = 4 }} }}
[model]
mass = [1.0, 1.0, 1e-4, 1e-4, 1e-4]
stiffness = [{rows}]
modal_damping = 0.01
solver = "SOLVER"
modes = 2
residual_flexibility = true
"""
    for solver in ("condensed", "full"):
        (tmp_path / f"{solver}.toml").write_text(text.replace("SOLVER", solver))
    out = tmp_path / "out"
    assert main(["timesim", str(tmp_path / "condensed.toml"), "--freq-hz", "0.14", "--steps", "256",
                 "--condensed", "-q", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "2 modes + 2 static coordinates" in printed
    with open(out / "timesim.csv") as fh:
        row = next(csv.DictReader(fh))
    ref = timesim(light_contacts("full", force_dof=4), 0.14, TimeSimOptions(steps=256))
    assert ref.converged and abs(float(row["c_h1"]) / ref.h1["c"] - 1) < 1e-3
    assert main(["timesim", str(tmp_path / "full.toml"), "--freq-hz", "0.14", "--condensed", "-q",
                 "-o", str(out)]) == 2
    assert "solved on its full model" in capsys.readouterr().err


def test_runs_of_unstable_points_are_confirmed_by_their_middle(monkeypatch):
    """Runs are checked shortest first, each by its middle point (the stable islands 7-8 and
    10-11 between them too); a run whose middle Floquet calls stable is checked point by
    point; the cap leaves the rest to Hill, counted."""
    from hbm.timedomain import floquet_check as fc
    case = duffing_chain("full")
    freq = np.arange(20.0)
    stable = np.ones(20, dtype=bool)
    stable[[2, 3, 4, 5, 6, 9, 12, 13, 14]] = False             # runs 2-6, 9, 12-14
    truly_stable = {7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0}      # Floquet's verdicts
    asked = []

    def fake(case, basis, X, f, steps, problem):
        asked.append(f)
        return fc.FloquetCheck(f in truly_stable, 1.0, True, 0.0, "", {}, {}, 1)
    monkeypatch.setattr(fc, "check_point", fake)
    Xs = np.zeros((20, 3, case.n_dof))
    st = {}
    out = fc.confirm_unstable(case, None, Xs, freq, stable, st)
    assert asked == [9.0, 8.0, 11.0, 13.0, 12.0, 14.0, 4.0]    # shortest first; 12-14 turned, so all of it
    assert list(np.flatnonzero(~out)) == [2, 3, 4, 5, 6, 14]
    assert st == {"floquet_checked": 7, "floquet_steps": 256, "floquet_overrides_hz": [9.0, 12.0, 13.0]}
    monkeypatch.setattr(fc, "MAX_CONFIRM", 3)
    monkeypatch.setattr(fc, "CONFIRM_SECONDS", 0.0)
    asked.clear()
    st = {}
    out = fc.confirm_unstable(case, None, Xs, freq, stable, st)
    assert asked == [9.0, 8.0, 11.0] and st["floquet_unchecked"] == 3 + 5     # the runs 12-14 and 2-6


def test_stable_islands_between_unstable_points_are_checked_too(monkeypatch):
    """Short runs Hill calls stable between unstable points (the railcar's 36.00-36.06 Hz,
    largest multipliers 1.5) are checked by their middle in one queue with the unstable runs,
    shortest first; an island Floquet calls unstable is checked point by point, one it calls
    stable stays, and runs at the path's ends or longer than LONG_RUN are not islands."""
    from hbm.timedomain import floquet_check as fc
    case = duffing_chain("full")
    n = 40
    freq = np.arange(float(n))
    stable = np.zeros(n, dtype=bool)
    stable[[0, 5, 6, 7, 12, 13]] = True                         # end run 0, islands 5-7 and 12-13
    stable[20:20 + fc.LONG_RUN + 1] = True                      # too long for an island
    truly_unstable = set(range(n)) - {6, 7, 12, 13}             # Floquet: 5 unstable, 6-7 not
    asked = []

    def fake(case, basis, X, f, steps, problem):
        asked.append(int(f))
        return fc.FloquetCheck(int(f) not in truly_unstable, 1.0, True, 0.0, "", {}, {}, 1)
    monkeypatch.setattr(fc, "check_point", fake)
    monkeypatch.setattr(fc, "MAX_CONFIRM", 10 ** 6)
    st = {}
    out = fc.confirm_unstable(case, None, np.zeros((n, 3, case.n_dof)), freq, stable, st)
    assert asked[:2] == [13, 6]                                 # islands 12-13 and 5-7 by their middle
    assert asked[2:5] == [3, 10, 17]                            # then the unstable runs 1-4, 8-11, 14-19
    assert st["floquet_checked"] == len(asked) and "floquet_unstable_hz" not in st
    assert np.array_equal(out, stable)
    truly_unstable.add(6)                                       # now the middle of 5-7 is unstable
    asked.clear()
    st = {}
    out = fc.confirm_unstable(case, None, np.zeros((n, 3, case.n_dof)), freq, stable, st)
    assert asked[:4] == [13, 6, 5, 7] and st["floquet_unstable_hz"] == [5.0, 6.0]
    assert list(np.flatnonzero(out)) == [0, 7, 12, 13] + list(range(20, 20 + fc.LONG_RUN + 1))


def test_a_long_run_is_sampled_and_its_stable_window_bisected(monkeypatch):
    """A run longer than LONG_RUN (the railcar's Hill-unstable 35.8-37 Hz holds a window that
    Floquet calls stable) is checked at RUN_SAMPLES points; each change of verdict between two
    samples is bisected to neighbouring points, and the window between is turned stable."""
    from hbm.timedomain import floquet_check as fc
    case = duffing_chain("full")
    n = 60
    freq = np.arange(float(n))
    stable = np.ones(n, dtype=bool)
    stable[5:55] = False                                        # one run of 50 points
    truly_stable = set(range(21, 33))                           # Floquet's stable window
    asked = []

    def fake(case, basis, X, f, steps, problem):
        asked.append(int(f))
        return fc.FloquetCheck(int(f) in truly_stable, 1.0, True, 0.0, "", {}, {}, 1)
    monkeypatch.setattr(fc, "check_point", fake)
    st = {}
    out = fc.confirm_unstable(case, None, np.zeros((n, 3, case.n_dof)), freq, stable, st)
    assert list(np.flatnonzero(out[5:55]) + 5) == sorted(truly_stable)
    assert st["floquet_checked"] == len(asked) < 9 + 2 * 3     # samples + two bisections of <= 3 steps
    assert st["floquet_overrides_hz"] == [float(i) for i in sorted(truly_stable)]


def test_a_model_with_stiff_contacts_is_checked_at_finer_steps(monkeypatch):
    """Contacts at least 100 times stiffer than the structure along them (the railcar rig: 112
    and 338 times, where 256 steps per period gave the opposite verdict at 20 of 24 points)
    are checked at 1024 steps; the chain's soft Jenkins contact at 256."""
    from hbm.analyses.aft_retry import stiff_contacts
    from hbm.timedomain import floquet_check as fc
    soft = duffing_chain("full")
    stiff = chain_case("full", "all", [{"type": "cubic", "dofs": [7], "k3": 0.5},
                                       {"type": "jenkins", "dofs": [7], "kt": 1e6, "slip_force": 1e6}],
                       amplitude=0.02, window=(0.03, 0.09))
    assert not stiff_contacts(soft) and [i for i, _ in stiff_contacts(stiff)] == [1]
    stable = np.ones(4, dtype=bool)
    stable[2] = False
    for case, steps in ((soft, 256), (stiff, 1024)):
        asked = []

        def fake(case, basis, X, f, steps, problem):
            asked.append(steps)
            return fc.FloquetCheck(False, 1.2, True, 0.0, "", {}, {}, 1)
        monkeypatch.setattr(fc, "check_point", fake)
        st = {}
        fc.confirm_unstable(case, None, np.zeros((4, 3, case.n_dof)), np.arange(4.0), stable, st)
        assert asked == [steps] and st["floquet_steps"] == steps


def test_the_checks_may_take_a_quarter_of_hills_time_when_that_is_longer(monkeypatch):
    """The railcar's Hill spectra take 262 s: its Floquet checks may take a quarter of that,
    not only CONFIRM_SECONDS (which left 325 unstable points unchecked there)."""
    from hbm.timedomain import floquet_check as fc
    case = duffing_chain("full")
    seen = []
    real = fc._Budget

    def budget(seconds):
        seen.append(seconds)
        return real(seconds)
    monkeypatch.setattr(fc, "_Budget", budget)
    monkeypatch.setattr(fc, "check_point", lambda *a, **k: fc.FloquetCheck(False, 2.0, True, 0.0, "", {}, {}, 1))
    stable = np.array([True, False, True])
    for hill_seconds, allowed in ((10.0, fc.CONFIRM_SECONDS), (400.0, 100.0)):
        fc.confirm_unstable(case, None, np.zeros((3, 3, case.n_dof)), np.arange(3.0), stable,
                            {"stability_seconds": hill_seconds})
        assert seen[-1] == allowed
    b = real(0.0)
    assert all(b.take() for _ in range(fc.MAX_CONFIRM)) and b.spent() and not b.take()
