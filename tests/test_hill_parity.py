"""Hill's eigenproblem split by harmonic parity (:func:`hbm.analyses.stability_path.hill_blocks`).

A half-wave symmetric response couples a perturbation's even harmonics only to even ones and
its odd only to odd ones; the Hill matrix is then block diagonal on the two groups and its
spectrum is the union of the blocks' spectra.  The split must give the same eigenvalues,
margins and verdicts as the whole matrix, and must not be taken where the groups couple.
"""
import pathlib
import sys

import numpy as np
import pytest
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment

import hbm
import hbm.analyses.stability_path as spath
from hbm.analyses.hill_system import HillSystem
from hbm.analyses.problem_setup import build_problem
from hbm.interface.case import case_from_dict

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from bench_cases import target_case  # noqa: E402


def hill_systems(case, every):
    res = hbm.frf(case, error_estimate=False)
    problem, _ = build_problem(case, res.basis, "auto")
    hill = HillSystem(problem)
    for i in range(0, res.freq_hz.size, every):
        w = 2 * np.pi * res.freq_hz[i]
        J, M, C = hill.system(hill.jacobian(res.X[i], w), w)
        yield res.stable[i], J, M, C, hill.basis, w


def duffing():
    sys.path.insert(0, str(ROOT / "tests"))
    from test_duffing import duffing_case
    return duffing_case(5)


@pytest.mark.parametrize("make, every, unstable", [(target_case, 12, 0), (duffing, 3, 1)])
def test_symmetric_response_splits_with_the_same_spectrum_and_verdicts(make, every, unstable, monkeypatch):
    """The 3-DOF two-Jenkins chain of the benchmarks and a Duffing oscillator through its folds
    (symmetric laws, no offset): every point splits; the blocks' eigenvalues are the whole
    matrix's, and the verdicts are the FRF's (which include unstable ones on the Duffing)."""
    n_unstable = 0
    for stable, J, M, C, basis, w in hill_systems(make(), every):
        A = spath.hill_matrix(J, M, C, basis, w)
        blocks = spath.hill_blocks(J, M, C, basis, w)
        assert len(blocks) == 2
        assert sum(B.shape[0] for B in blocks) == A.shape[0]
        whole = sla.eigvals(A)
        split = np.concatenate([sla.eigvals(B) for B in blocks])
        dist = np.abs(whole[:, None] - split[None, :])
        rows, cols = linear_sum_assignment(dist)           # pair them one to one
        assert dist[rows, cols].max() <= 1e-9 * np.abs(whole).max()
        verdict, margin = spath.hill_margin(J, M, C, basis, w)
        monkeypatch.setattr(spath, "parity_split", lambda *args, **kwargs: None)
        whole_verdict, whole_margin = spath.hill_margin(J, M, C, basis, w)
        monkeypatch.undo()
        assert verdict == whole_verdict == stable
        assert margin == pytest.approx(whole_margin, abs=1e-12 * w)
        n_unstable += not verdict
    assert n_unstable >= unstable


def test_an_asymmetric_law_couples_the_parities_and_is_not_split():
    """A one-sided stop (unilateral spring with a gap) breaks the half-wave symmetry: its
    Jacobian couples even and odd harmonics, so the whole matrix is solved."""
    case = case_from_dict({
        "model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.05]]},
        "element": [{"type": "unilateral_spring", "dofs": [0], "k": 3.0, "gap": 0.5, "name": "stop"}],
        "excitation": {"dofs": [0], "amplitude": [0.2]},
        "analysis": {"harmonics": 5, "time_samples": 64, "frequency_hz": [0.14, 0.2],
                     "outputs": {"x": 0}}})
    for _, J, M, C, basis, w in hill_systems(case, 5):
        assert spath.parity_split(basis, M.shape[0]) is not None
        blocks = spath.hill_blocks(J, M, C, basis, w)
        assert len(blocks) == 1 and np.array_equal(blocks[0], spath.hill_matrix(J, M, C, basis, w))


@pytest.mark.parametrize("h", [[1, 3, 5], [0, 2, 4]])
def test_one_parity_only_is_not_split(h):
    from hbm.balance.fourier import FourierBasis
    basis = FourierBasis(h, 16)
    assert spath.parity_split(basis, 2) is None


def test_blocks_of_a_non_modal_mass_hold_the_whole_spectrum():
    """With a full mass matrix the coupling is ``M^{-1} J``'s; a Jacobian without even-odd
    coupling splits, and the blocks hold the whole matrix's eigenvalues; one coupling entry
    above the bound keeps it whole."""
    from hbm.balance.fourier import FourierBasis
    rng = np.random.default_rng(3)
    basis, n, w = FourierBasis([0, 1, 2, 3], 16), 2, 1.3
    B = rng.standard_normal((n, n))
    M, C = B @ B.T + n * np.eye(n), 0.1 * np.eye(n)
    odd = np.repeat(basis.h_of_row, n) % 2 == 1
    J = rng.standard_normal((odd.size, odd.size)) * (odd[:, None] == odd[None, :])
    blocks = spath.hill_blocks(J, M, C, basis, w)
    assert len(blocks) == 2
    whole = sla.eigvals(spath.hill_matrix(J, M, C, basis, w))
    split = np.concatenate([sla.eigvals(b) for b in blocks])
    dist = np.abs(whole[:, None] - split[None, :])
    rows, cols = linear_sum_assignment(dist)
    assert dist[rows, cols].max() <= 1e-9 * np.abs(whole).max()
    J[0, np.flatnonzero(odd)[0]] = 1e-6
    assert len(spath.hill_blocks(J, M, C, basis, w)) == 1


def test_one_harmonic_splits_into_the_mean_and_the_first_harmonic():
    """H = 1 (harmonics 0 and 1): the even block holds the mean alone; the two blocks hold the
    whole matrix's eigenvalues (the stress matrix's H = 1 cases raised here once)."""
    from hbm.balance.fourier import FourierBasis
    rng = np.random.default_rng(5)
    basis, n, w = FourierBasis([0, 1], 8), 3, 0.7
    odd = np.repeat(basis.h_of_row, n) % 2 == 1
    J = rng.standard_normal((odd.size, odd.size)) * (odd[:, None] == odd[None, :])
    M, C = np.eye(n), 0.05 * np.eye(n)
    blocks = spath.hill_blocks(J, M, C, basis, w)
    assert [b.shape[0] for b in blocks] == [2 * n, 4 * n]
    whole = np.sort_complex(sla.eigvals(spath.hill_matrix(J, M, C, basis, w)))
    split = np.sort_complex(np.concatenate([sla.eigvals(b) for b in blocks]))
    assert np.allclose(whole, split, rtol=0, atol=1e-10 * np.abs(whole).max())
