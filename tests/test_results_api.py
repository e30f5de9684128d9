"""The result as a user handles it from Python: a short repr, the frf.csv columns as arrays,
and the elements' forces and hysteresis loops at a point."""
import pathlib

import numpy as np
import pytest

import hbm
from hbm.balance.energy import energy_balance
from hbm.analyses.response import build_problem

ROOT = pathlib.Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def traced():
    case = hbm.load_case(ROOT / "rigs" / "sdof_jenkins.toml")
    return case, hbm.frf(case, harmonics=5, stability=False)


def test_repr_is_short_and_table_matches_outputs(traced):
    case, res = traced
    text = repr(res)
    assert len(text) < 200 and "finished" in text and f"{res.freq_hz.size} points" in text
    t = res.table()
    assert list(t)[:3] == ["freq_hz", "x_h1", "x_max"] and np.isnan(t["stable"]).all()
    assert np.array_equal(t["x_h1"], res.outputs["x"].h1) and t["energy_error"].max() < 1e-9


def test_loop_work_is_the_dissipated_energy(traced):
    """The loop's enclosed area, sum f dz/dt over one period, equals the nonlinear work of the
    energy balance (Parseval on the retained harmonics): exact up to round-off, since z is a
    trigonometric polynomial of degree H < N/2 and so its sampled derivative is exact."""
    case, res = traced
    i = res.nearest(33.0)
    assert abs(res.freq_hz[i] - 33.0) < 1.0
    (loop,) = hbm.contact_loops(case, res, i)
    assert loop.name == case.elements[0].name and loop.displacement.shape == (res.basis.n_samples, 1)
    f, z = loop.force[:, 0], loop.displacement[:, 0]
    N, T = z.size, 1.0 / loop.freq_hz
    k = np.fft.rfftfreq(N, d=1.0 / N)
    zdot = np.fft.irfft(2j * np.pi * k / T * np.fft.rfft(z), n=N)
    loop_work = T / N * np.sum(f * zdot)
    problem, _ = build_problem(case, res.basis, res.settings["transform"])
    eb = energy_balance(problem, res.X[i], 2 * np.pi * res.freq_hz[i])
    assert loop_work > 0 and loop_work == pytest.approx(eb.nonlinear, rel=1e-9)
    # near resonance the contact slips: the force saturates at the slip force
    assert np.max(np.abs(f)) == pytest.approx(case.raw["element"][0]["slip_force"], rel=1e-9)
    with pytest.raises(IndexError):
        hbm.contact_loops(case, res, res.freq_hz.size)


def test_case_from_numpy_matrices():
    raw = {"model": {"mass": np.eye(1), "stiffness": np.array([[4e4]]), "damping": np.array([[2.0]])},
           "element": [{"type": "jenkins", "dofs": [0], "kt": 2.667e4, "slip_force": 2.0}],
           "excitation": {"dofs": [0], "amplitude": [5.0]},
           "analysis": {"harmonics": 3, "frequency_hz": [25.0, 40.0], "outputs": {"x": 0}}}
    res = hbm.frf(hbm.case_from_dict(raw), stability=False)
    assert res.ok and res.outputs["x"].h1.max() > 1e-3
