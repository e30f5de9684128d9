"""Condensed harmonic balance (contact coordinates only) against the full model, through the solver.

Chains of masses and springs clamped at one end are small enough for the full solver and
still have interior contacts, excitation and outputs at different DOFs.
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.linalg as sla
import scipy.sparse as sp

from hbm.interface.case import CaseError, case_from_dict, load_case
from hbm.balance.energy import energy_balance
from hbm.model.op4 import write_op4
from hbm.analyses.response import choose_solver, frf, recover_outputs, solve_at

ROOT = Path(__file__).resolve().parents[1]


def chain(n, seed=0):
    rng = np.random.default_rng(seed)
    m = rng.uniform(0.5, 1.5, n)
    k = rng.uniform(800.0, 1200.0, n)
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += k[i]
        if i > 0:
            K[i - 1, i - 1] += k[i]
            K[i - 1, i] -= k[i]
            K[i, i - 1] -= k[i]
    return np.diag(m), K


M12, K12 = chain(12)
C12 = 1e-4 * K12 + 0.02 * M12
C12[5, 5] += 0.4                       # non-proportional

JENKINS = [{"type": "jenkins", "dofs": [11, 10], "kt": 500.0, "slip_force": 0.3}]
FRICTION3D = [{"type": "friction3d", "dofs": {"t1": 5, "t2": [8, 9], "n": 6}, "kt": 800.0, "kn": 900.0,
               "mu": 0.3, "normal_preload": 5.0}]
BOTH = JENKINS + FRICTION3D
DAMPING = {"modal": {"modal_damping": 0.01}, "rayleigh": {"rayleigh": [0.05, 1e-4]},
           "matrix": {"damping": C12.tolist()}}


def chain_case(model, elements, *, harmonics=3, f_hz=(0.5, 3.0), outputs=None):
    return case_from_dict({
        "model": model,
        "element": elements,
        "excitation": {"dofs": [11], "amplitude": [1.0]},
        "analysis": {"harmonics": harmonics, "time_samples": 32, "frequency_hz": list(f_hz),
                     "outputs": outputs or {"tip": 11, "mid": 4}},
    })


def inline(solver, damping="modal", **keys):
    return {"mass": M12.tolist(), "stiffness": K12.tolist(), "solver": solver, **DAMPING[damping], **keys}


def outputs_at(case, freqs):
    Y, E = [], []
    for f in freqs:
        X, _, p = solve_at(case, f)
        w = 2 * np.pi * f
        Y.append(recover_outputs(p, case, X, w))
        E.append(energy_balance(p, X, w).relative_error)
    return np.array(Y), np.array(E)


@pytest.mark.parametrize("elements, damping", [
    ([], "modal"), (JENKINS, "modal"), (FRICTION3D, "rayleigh"), (BOTH, "matrix")])
def test_all_modes_condensed_equals_full(elements, damping):
    full = chain_case(inline("full", damping), elements)
    cond = chain_case(inline("condensed", damping, modes="all"), elements)
    assert choose_solver(full) == "full" and choose_solver(cond) == "condensed"
    freqs = [0.45, 0.6, 0.8, 1.3, 1.9]
    Yf, Ef = outputs_at(full, freqs)
    Yc, Ec = outputs_at(cond, freqs)
    err = np.abs(Yc - Yf).max() / np.abs(Yf).max()
    print(f"{len(elements)} elements, {damping}: condensed vs full {err:.2e}, energy {Ec.max():.1e}")
    assert err <= 1e-8
    assert Ec.max() <= 1e-8 and Ef.max() <= 1e-8


def test_condensed_frf_points_are_full_solutions():
    """Points traced by continuation on the condensed problem solve the full problem."""
    cond = chain_case(inline("condensed", modes="all"), JENKINS, f_hz=(1.2, 2.2))
    full = chain_case(inline("full"), JENKINS, f_hz=(1.2, 2.2))
    res = frf(cond)
    assert res.ok and res.settings["solver"] == "condensed" and res.settings["modes"] == 12
    assert res.settings["contact_coordinates"] == 1 and res.X.shape[2] == 1
    assert res.energy_error.max() <= 1e-8
    idx = np.linspace(0, res.freq_hz.size - 1, 5).astype(int)
    Yf, _ = outputs_at(full, res.freq_hz[idx])
    err = np.abs(res.Y[idx] - Yf).max() / np.abs(Yf).max()
    assert err <= 1e-8, err
    h1 = np.hypot(Yf[:, 0, 0], Yf[:, 1, 0])          # harmonics [1, 2, 3]: rows 0, 1 are h1
    assert np.allclose(res.outputs["tip"].h1[idx], h1, rtol=1e-8, atol=0)


def test_residual_flexibility_cuts_truncation_error_through_the_solver():
    M, K = chain(40, 3)
    om = np.sqrt(sla.eigh(K, M, eigvals_only=True)) / (2 * np.pi)

    def case(solver, modes, rf):
        return case_from_dict({
            "model": {"mass": M.tolist(), "stiffness": K.tolist(), "modal_damping": 0.01,
                      "solver": solver, "modes": modes, "residual_flexibility": rf},
            "element": [{"type": "jenkins", "dofs": [17, 16], "kt": 300.0, "slip_force": 0.05}],
            "excitation": {"dofs": [39], "amplitude": [1.0]},
            "analysis": {"harmonics": 3, "time_samples": 32, "frequency_hz": [0.1, 3.0],
                         "outputs": {"tip": 39, "mid": 17}},
        })

    freqs = np.r_[np.array([0.9, 1.0, 1.1]) * om[0], np.array([0.9, 1.0, 1.1]) * om[1]]
    Yf, _ = outputs_at(case("full", "all", True), freqs)
    errs = []
    for rf in (False, True):
        Yc, E = outputs_at(case("condensed", 6, rf), freqs)
        assert E.max() <= 1e-8          # exact balance of the reduced model, truncated or not
        errs.append(np.abs(Yc - Yf).max() / np.abs(Yf).max())
    print(f"6 of 40 modes: plain truncation {errs[0]:.2e}, with residual flexibility {errs[1]:.2e}, "
          f"ratio {errs[0] / errs[1]:.1f}")
    assert errs[0] / errs[1] >= 10.0


def test_same_frf_from_inline_npz_matrix_market_op4(tmp_path):
    """The same FRF (same continuation path, same points) whichever way the matrices come in;
    the condensed solver on a file model caches its reduction next to the case."""
    np.savez(tmp_path / "chain.npz", M=M12, K=K12, C=C12)
    scipy.io.mmwrite(str(tmp_path / "chain_M.mtx"), sp.csr_matrix(M12))
    scipy.io.mmwrite(str(tmp_path / "chain_K.mtx"), sp.csr_matrix(K12))
    scipy.io.mmwrite(str(tmp_path / "chain_C.mtx"), C12)
    write_op4(tmp_path / "chain.op4", {"MAA": M12, "KAA": K12, "BAA": C12}, sparse=True)
    tail = """
[[element]]
type = "jenkins"
dofs = [11, 10]
kt = 500.0
slip_force = 0.3
[excitation]
dofs = [11]
amplitude = [1.0]
[analysis]
harmonics = 3
time_samples = 32
frequency_hz = [1.2, 1.6]
outputs = { tip = 11, mid = 4 }
"""

    def run(model, solver, label):
        p = tmp_path / f"{label}_{solver}.toml"
        p.write_text(f'[model]\n{model}\nsolver = "{solver}"\n' + tail)
        return frf(load_case(p))

    ref = frf(ref_case_full())
    assert ref.ok and ref.settings["solver"] == "full" and ref.freq_hz.size > 5
    for label, model in [("npz", 'file = "chain.npz"'), ("mtx", 'file = "chain_K.mtx"'),
                         ("op4", 'file = "chain.op4"')]:
        res = run(model, "full", label)
        assert res.ok and res.freq_hz.size == ref.freq_hz.size, label
        for name in ("tip", "mid"):
            assert np.allclose(res.outputs[name].h1, ref.outputs[name].h1, rtol=1e-9, atol=0), label
    res = run('file = "chain.op4"', "condensed", "op4")     # OP4 matrices come back sparse
    assert res.ok and res.settings["reduction_cached"] is False and res.settings["modes"] == 12
    assert (tmp_path / "op4_condensed.reduction.npz").is_file()
    again = run('file = "chain.op4"', "condensed", "op4")
    assert again.settings["reduction_cached"] is True and again.settings["reduction_seconds"] == 0.0
    assert np.array_equal(again.outputs["tip"].h1, res.outputs["tip"].h1)
    idx = np.linspace(0, res.freq_hz.size - 1, 3).astype(int)
    Yf, _ = outputs_at(ref_case_full(), res.freq_hz[idx])
    assert np.abs(res.Y[idx] - Yf).max() <= 1e-8 * np.abs(Yf).max()


def ref_case_full():
    return chain_case({"mass": M12.tolist(), "stiffness": K12.tolist(), "damping": C12.tolist(),
                       "solver": "full"}, JENKINS, f_hz=(1.2, 1.6))


BEAM_CASE = """
name = "blade with a platform contact"
[model]
builder = "beam"
modal_damping = 0.005
modes = 12
[model.beam]
length = 0.1
n_elements = 12
E = 2.1e11
rho = 7800.0
width = 0.02
height = 0.004
axis = [0.0, 0.0, 1.0]
up = [0.0, 1.0, 0.0]
points = { platform = { node = 8, offset = [0.01, 0.0, 0.0] } }
[[element]]
type = "friction3d"
dofs = { t1 = "platform.y", t2 = "platform.z", n = "platform.x" }
kt = 2.0e5
kn = 2.0e5
mu = 0.5
normal_preload = 10.0
[excitation]
dofs = ["n10.uy"]
amplitude = [2.0]
[analysis]
harmonics = 3
time_samples = 32
frequency_hz = [300.0, 600.0]
outputs = { tip = "n10.uy", platform = "platform.y" }
"""


def test_beam_builder_case_runs_from_the_cli(tmp_path):
    case = tmp_path / "blade.toml"
    case.write_text(BEAM_CASE)
    out = tmp_path / "out"
    r = subprocess.run([sys.executable, "-m", "hbm", "frf", str(case), "-o", str(out), "-q"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    s = json.loads((out / "summary.json").read_text())
    st = s["settings"]
    assert st["solver"] == "condensed" and st["modes"] == 12 and st["n_dof"] == 72
    assert st["contact_coordinates"] == 3 and st["reduction_cached"] is False
    assert st["reduction_seconds"] > 0 and s["max_energy_error"] <= 1e-8
    assert (tmp_path / "blade.reduction.npz").is_file()
    header = (out / "frf.csv").read_text().splitlines()[0]
    # at H = 3 a few points are estimated above the default 1 %: solved again at H = 5 and 8 (column H)
    assert header == "freq_hz,tip_h1,tip_max,tip_err,platform_h1,platform_max,platform_err,stuck_contacts,H,stable"
    a = st["adaptive"]
    assert a["met"] and a["tol"] == 0.01 and a["tried"][0]["max_error"] > 0.01 and a["points"]["levels"]
    r = subprocess.run([sys.executable, "-m", "hbm", "frf", str(case), "-o", str(out), "-q"],
                       capture_output=True, text=True)
    assert r.returncode == 0 and json.loads((out / "summary.json").read_text())["settings"]["reduction_cached"]


def test_point_coordinates_are_rigid_offset_rows():
    case = case_from_dict(__import__("tomllib").loads(BEAM_CASE))
    st = case.structure
    row = case.analysis.output_rows(st.n_dof)[1]          # platform.y = uy + rz * 0.01 ... of node 8
    q = np.zeros(st.n_dof)
    q[st.dof_index["n8.uy"]] = 1.0
    q[st.dof_index["n8.rz"]] = 2.0                        # theta_z x (0.01, 0, 0) -> +0.02 along y
    assert np.isclose(row @ q, 1.0 + 0.02)
    e = case.elements[0]
    assert e.gather.shape == (3, st.n_dof) and np.allclose(e.gather[1] @ q, 0.0)


def test_energy_balance_every_point_general_damping():
    """Non-proportional damping: viscous work from the coupled modal coordinates."""
    cond = chain_case(inline("condensed", "matrix", modes="all"), BOTH, f_hz=(1.0, 1.6))
    res = frf(cond)
    assert res.ok and res.freq_hz.size > 5
    print(f"{res.freq_hz.size} points, largest energy error {res.energy_error.max():.1e}")
    assert res.energy_error.max() <= 1e-8


def test_energy_check_detects_a_wrong_solution():
    cond = chain_case(inline("condensed", modes="all"), JENKINS)
    X, _, p = solve_at(cond, 1.5)
    w = 2 * np.pi * 1.5
    assert energy_balance(p, X, w).relative_error < 1e-10
    assert energy_balance(p, 1.05 * X, w).relative_error > 1e-3


def test_two_beams_with_a_coupling_spring():
    """Identical beams coupled at the tips: in-phase mode unchanged, out-of-phase mode stiffer."""
    from hbm.builders.assembly import build_assembly
    beam = {"length": 0.2, "n_elements": 8, "E": 7e10, "rho": 2700.0, "width": 0.02, "height": 0.005}
    single = build_assembly([beam], sparse=False)
    pair = build_assembly([{**beam, "name": "a"}, {**beam, "name": "b", "origin": [0.0, 0.1, 0.0]}],
                          springs=[{"between": ["a.n8", "b.n8"], "k": 1e4}], sparse=False)
    f1 = np.sqrt(sla.eigh(single.K, single.M, eigvals_only=True)[:2])     # weak and strong plane
    f2 = np.sqrt(sla.eigh(pair.K, pair.M, eigvals_only=True)[:6])
    for f in f1:       # in-phase modes do not stretch the spring: exactly the single beam's
        assert np.min(np.abs(f2 / f - 1.0)) < 1e-9
    assert f2[0] == pytest.approx(f1[0], rel=1e-9) and f2[1] > 1.01 * f1[0]   # out-of-phase: stiffer
    assert "a.n8.uy" in pair.dof_names and pair.n_dof == 2 * single.n_dof


@pytest.mark.parametrize("mutate, needle", [
    (lambda t: t.replace("n_elements = 12", "n_elements = 12\nlenght = 2.0"), "lenght"),
    (lambda t: t.replace('builder = "beam"', 'builder = "bean"'), "bean"),
    (lambda t: t.replace("node = 8,", "node = 8, nod = 3,"), "nod"),
    (lambda t: t.replace("modes = 12", "modes = 12\nmodez = 3"), "modez"),
    (lambda t: t.replace("modes = 12", 'modes = 12\nsolver = "fast"'), "solver"),
    (lambda t: t.replace('"platform.x"', '"platform.w"'), "platform.w"),
    (lambda t: t + '\n[[model.spring]]\nbetween = ["platform"]\nk = 1.0\nkk = 2.0\n', "kk"),
    (lambda t: t + '\n[[model.spring]]\nbetween = ["nowhere"]\nk = 1.0\n', "nowhere"),
    (lambda t: t.replace('builder = "beam"', 'builder = "beam"\nfile = "x.npz"'), "exactly one"),
])
def test_bad_builder_keys_are_rejected_by_name(tmp_path, mutate, needle):
    text = mutate(BEAM_CASE)
    # [[model.spring]] appended after [analysis] belongs to [model] only when placed under it
    if "[[model.spring]]" in text:
        head, spring = text.split("\n[[model.spring]]", 1)
        text = head.replace("[[element]]", "[[model.spring]]" + spring.rstrip() + "\n[[element]]", 1)
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(CaseError, match=needle.replace(".", r"\.")) as exc:
        load_case(p)
    assert "\n" not in str(exc.value)


def test_case_without_a_file_is_reduced_once_per_run():
    """A case built in Python has no file to cache its reduction beside: the FRF's error
    estimate (a second problem on more harmonics) reuses the reduction in memory, and any
    change of the reduction's inputs recomputes it."""
    case = chain_case(inline("condensed", modes=6), JENKINS, f_hz=(1.2, 1.3))
    res = frf(case, stability=False)
    assert res.ok and res.settings["error_estimate"]["computed"]
    assert res.settings["reduction_cached"] in (False, True)       # an earlier test may have made it
    again = frf(case, stability=False)
    assert again.settings["reduction_cached"] is True and again.settings["reduction_seconds"] == 0.0
    assert np.array_equal(again.outputs["tip"].h1, res.outputs["tip"].h1)
    other = frf(chain_case(inline("condensed", modes=7), JENKINS, f_hz=(1.2, 1.3)), stability=False)
    assert other.settings["reduction_cached"] is False and other.settings["modes"] == 7
