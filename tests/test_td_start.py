"""A fresh point past a stop from a time integration's periodic response (issue 17): where Newton
from the linear responses fails, the integration's last period, fitted onto the harmonics, is a
start Newton converges from.  (On rigs/railcar_wedge.toml this carries the FRF from 28.18 Hz,
where it stopped, to 30.33 Hz; that run takes a minute and a half.)"""
import pathlib

import numpy as np
import pytest

import hbm
import hbm.analyses.trace as trace
from hbm.analyses.problem_setup import _residual_scale, _unknown_scale, build_problem, resolve_settings
from hbm.analyses.td_start import fit_harmonics, time_domain_start
from hbm.analyses.traced_points import TracedPoints
from hbm.balance.fourier import FourierBasis

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_fit_is_exact_on_the_basis():
    basis = FourierBasis([0, 1, 3], 32)
    w = 2.5
    t = 0.7 + np.linspace(0, 2 * np.pi / w, 65)
    X = np.random.default_rng(1).normal(size=(basis.n_coef, 2))
    q = np.column_stack([X[0, j] + X[1, j] * np.cos(w * (t - t[0])) + X[2, j] * np.sin(w * (t - t[0]))
                         + X[3, j] * np.cos(3 * w * (t - t[0])) + X[4, j] * np.sin(3 * w * (t - t[0]))
                         for j in range(2)])
    assert fit_harmonics(basis, w, t, q) == pytest.approx(X, abs=1e-12)


@pytest.fixture(scope="module")
def sdof():
    case = hbm.load_case(ROOT / "rigs" / "sdof_jenkins.toml")
    h, N, lo, hi, tr = resolve_settings(case, None, None, None, None, None)
    problem, _ = build_problem(case, FourierBasis(h, N), tr)
    w_lo, w_hi = 2 * np.pi * lo, 2 * np.pi * hi
    return case, problem, _unknown_scale(problem, case, w_lo, w_hi), _residual_scale(problem, w_lo), (w_lo, w_hi)


def test_time_domain_start_is_the_frf_point(sdof):
    case, problem, xscale, r_scale, _ = sdof
    f = 33.0                           # slipping, near resonance
    X, its = time_domain_start(problem, case, 2 * np.pi * f, xscale, r_scale)
    assert its <= 4
    from hbm.analyses.response import solve_at
    Xref = solve_at(case, f)[0]
    assert np.abs(X - Xref).max() <= 1e-8 * np.abs(Xref).max()


def test_a_run_not_yet_periodic_still_gives_a_start(sdof, monkeypatch):
    """Four periods from rest are far from periodic; Newton from the last one still lands on
    the FRF point (the railcar rig at 40 Hz: its stuck contacts ring undamped for hundreds of
    periods, and Newton from the last of 100 converges in 9 iterations)."""
    import hbm.analyses.td_start as td
    case, problem, xscale, r_scale, _ = sdof
    monkeypatch.setattr(td, "PERIODS", 4)
    f = 33.0
    X, _ = td.time_domain_start(problem, case, 2 * np.pi * f, xscale, r_scale)
    from hbm.analyses.response import solve_at
    Xref = solve_at(case, f)[0]
    assert np.abs(X - Xref).max() <= 1e-8 * np.abs(Xref).max()


def test_restart_falls_back_on_the_time_domain(sdof, monkeypatch):
    case, problem, xscale, r_scale, window = sdof

    def no_newton(*args, **kwargs):
        raise RuntimeError("linear starts fail")
    monkeypatch.setattr(trace, "_first_point", no_newton)
    w_from = 2 * np.pi * 33.0
    X, its, w = trace._fresh_point_past(problem, case, w_from, window, xscale, r_scale, TracedPoints())
    assert w == pytest.approx(w_from + trace.GAP_FIRST * (window[1] - window[0]))
    R = problem.residual(X, w)[0]
    assert np.abs(R).max() < 1e-8 * np.abs(problem.residual(np.zeros_like(X), w)[0]).max()

    def no_period(*args, **kwargs):
        raise RuntimeError("a time integration from rest found no periodic response in 600 periods")
    monkeypatch.setattr(trace, "time_domain_start", no_period)
    why = trace._fresh_point_past(problem, case, w_from, window, xscale, r_scale, TracedPoints())
    assert why == "a time integration from rest found no periodic response in 600 periods"
