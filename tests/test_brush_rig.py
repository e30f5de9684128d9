"""brush on a rig and in time: the rig's damper acts on the out-of-phase mode, the time-domain
parts of the law give the march's forces, timesim agrees with the balance, and the summary
quantities in microslip and gross slip."""
import numpy as np
import pytest

from elements.loops import harmonic_motion, loop_forces
from test_brush import line_brush, rolling_brush


def test_rig_damper_acts_on_out_of_phase_mode():
    """rigs/beam_damper_beam.toml (coarse: 8 bristles per contact, H = 1): the damper leaves the
    in-phase peak nearly as it is and removes most of the out-of-phase response."""
    import tomllib
    from pathlib import Path
    import hbm
    from hbm.interface.case import case_from_dict
    path = Path(__file__).resolve().parents[1] / "rigs" / "beam_damper_beam.toml"
    data = tomllib.loads(path.read_text())
    for el in data["element"]:
        el.update(nx=8, lx=14e-6)
    data["analysis"].update(harmonics=1, time_samples=32)
    damped = hbm.frf(case_from_dict(data, str(path), path.parent), fmin=520, fmax=900)
    free = hbm.frf(case_from_dict({k: v for k, v in data.items() if k != "element"}, str(path), path.parent),
                   fmin=520, fmax=900)
    assert damped.ok and free.ok
    assert np.abs(damped.energy_error).max() < 1e-6

    def peak(res, name, lo, hi):
        m = (res.freq_hz >= lo) & (res.freq_hz <= hi)
        return res.outputs[name].h1[m].max()

    ip_ratio = peak(damped, "tip_A", 525, 541) / peak(free, "tip_A", 525, 541)
    oop_ratio = peak(damped, "tips_relative", 541, 900) / peak(free, "tips_relative", 541, 900)
    assert ip_ratio > 0.75, ip_ratio          # measured 0.86
    assert oop_ratio < 0.15, oop_ratio        # measured 0.08
    # the damped out-of-phase resonance moved up (stiffened by the damper), well above 544 Hz
    m = damped.freq_hz > 560
    f_oop = damped.freq_hz[m][np.argmax(damped.outputs["tips_relative"].h1[m])]
    assert 650 < f_oop < 800, f_oop


def _stepped_forces(el, z, periods=3):
    """Element forces of the last of ``periods`` repetitions of the motion ``z`` (N, n_local),
    from the time integrator's law parts stepped sample by sample from rest."""
    from elements.kernels import law_init, law_step
    N = z.shape[0]
    f = np.zeros_like(z)
    for R, spec in el.time_parts():
        ns, nin = spec.n_state, R.shape[0]
        s, s_new = np.zeros(ns), np.zeros(ns)
        law_init(spec.kind, spec.params, np.zeros(nin), s, np.zeros((ns, nin)))
        A, B = np.zeros((ns, ns)), np.zeros((ns, nin))
        zp = np.tile(z, (periods, 1)) @ R.T
        out = np.empty((zp.shape[0], nin))
        for j in range(zp.shape[0]):
            law_step(spec.kind, spec.params, s, np.ascontiguousarray(zp[j]), s_new, A, B)
            s[:] = s_new
            out[j] = s[:nin]
        f += out[-N:] @ R
    return f


@pytest.mark.parametrize("which", ["rolling_pivot", "line_separating"])
def test_time_parts_give_the_forces_of_the_march(which):
    """The time integrator's bristles (friction3d parts with weighted parameters, reading
    ``[u_t, c_b . T z]``) reproduce the harmonic march's element forces on a closed periodic
    motion, including bristles clear of the indenter at rest that touch during the period
    (their normal force is zero at rest) and the pivot's rotation-slip coupling."""
    N = 256
    t = 2 * np.pi * np.arange(N) / N
    if which == "rolling_pivot":
        el = rolling_brush(nt=2, pivot=0.4)
        amp = np.array([0.9, 0.5, 0.8, 0.15, 0.2])
    else:
        el = line_brush(nx=40)
        kt_tot = el.kt * np.count_nonzero(el.delta0 > el.h)
        kn_tot = el.kn * np.count_nonzero(el.delta0 > el.h)
        amp = np.array([0.5 * 0.14 * 50.0 / kt_tot, 1.5 * 50.0 / kn_tot])   # lifts off part of the period
    assert np.any(el._pre < 0)       # some bristles clear at rest
    z = amp[None, :] * np.cos(t[:, None] + 0.7 * np.arange(amp.size)[None, :])
    f_march, _ = el.march(z, np.zeros(z.shape + (1,)))
    f_time = _stepped_forces(el, z)
    np.testing.assert_allclose(f_time, f_march, rtol=0, atol=1e-10 * np.abs(f_march).max())
    assert np.abs(f_march[:, el.coord_names.index("n")]).max() > 0.1 * np.abs(f_march).max()


def test_timesim_on_the_brush_rig_agrees_with_the_balance():
    """rigs/beam_damper_beam.toml, coarse brushes (8 bristles each): the time-domain steady
    state at 700 Hz (damper slipping, out-of-phase peak region) matches the H = 7 balance
    within 1 % on the tips (measured 0.3 and 0.4 % at 512 steps per period, 0.8 % at 256)."""
    import tomllib
    from pathlib import Path
    from hbm.interface.case import case_from_dict
    from hbm.analyses.problem_setup import output_amplitudes
    from hbm.analyses.response import solve_at
    from hbm.timedomain.timesim import TimeSimOptions, steady_state
    path = Path(__file__).resolve().parents[1] / "rigs" / "beam_damper_beam.toml"
    data = tomllib.loads(path.read_text())
    for el in data["element"]:
        el.update(nx=8, lx=14e-6)
    data["analysis"].update(harmonics=7, time_samples=128)
    case = case_from_dict(data, str(path), path.parent)
    f = 700.0
    run = steady_state(case, f, TimeSimOptions(steps=512, tol=1e-7))
    assert run.converged
    X, basis, problem = solve_at(case, f)
    Y = problem.recover_outputs(X, 2 * np.pi * f)
    names = list(case.analysis.outputs)
    for name in ("tip_A", "tip_B"):
        hb = output_amplitudes(basis, Y[:, names.index(name)])[0]
        assert abs(run.h1[name] - hb) < 0.01 * hb, (name, run.h1[name], hb)
    # the recorded element forces are the brushes' resultants (t1, n), not per bristle
    assert run.history.force_names == ("contact_A_f_t1", "contact_A_f_n", "contact_B_f_t1", "contact_B_f_n")


def test_summary_quantities_in_microslip_and_gross_slip():
    """The scalar outputs: dissipation equals the exact bristle sum, slip fraction rises from
    a partial value in microslip to most of the period in gross slip, normal load constant."""
    br = line_brush()
    Nb = br.kn * np.maximum(br.delta0 - br.h, 0.0)
    kt_total = br.kt * np.count_nonzero(Nb)
    a_gross = 0.14 * 50.0 / kt_total
    fracs = []
    for a in (0.2 * a_gross, 3.0 * a_gross):
        z = harmonic_motion(1024, [a, 0.0])
        s = br.summary(loop_forces(br, z), z)
        W_exact = np.sum(4 * 0.14 * Nb * np.maximum(a - 0.14 * Nb / br.kt, 0.0))
        assert s["dissipation"] == pytest.approx(W_exact, rel=2e-2)
        assert s["normal_load_min"] == pytest.approx(50.0) and s["normal_load_max"] == pytest.approx(50.0)
        fracs.append(s["slip_fraction"])
    assert 0.0 < fracs[0] < fracs[1] <= 1.0
    # stuck: tiny motion well inside every bristle's limit
    z = harmonic_motion(256, [1e-6 * a_gross, 0.0])
    s = br.summary(loop_forces(br, z), z)
    assert s["slip_fraction"] == 0.0 and abs(s["dissipation"]) < 1e-12


def test_table2_partial_contact_case():
    """Seed 002's Table 2 re-analysis at N = 20 N (2 mm of contact, k_w = 33 N/um): the
    out-of-phase resonance as benchmarks/beam_damper_beam_table2.py measured it (583.5 Hz,
    0.489 um), well below the whole-length contact's 677 Hz."""
    import sys
    import tempfile
    from pathlib import Path
    import hbm
    root = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(root / "benchmarks"))
    from beam_damper_beam_table2 import TABLE2, case_for, model_with_kw, peak_in
    length, k_w = TABLE2[20.0][:2]
    with tempfile.TemporaryDirectory() as tmp:
        res = hbm.frf(case_for(20.0, length, model_with_kw(k_w, Path(tmp))), fmin=550, fmax=650,
                      stability=False)
    assert res.ok, res.message
    f, a = peak_in(res.freq_hz, res.outputs["tip_A"].h1, 560, 650)
    assert f == pytest.approx(583.5, abs=1.0) and a * 1e6 == pytest.approx(0.4885, rel=0.02)
