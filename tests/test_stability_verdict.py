"""The eigenvector-free stability verdict (hbm.analyses.stability.verdict_from_eigenvalues,
hill_is_stable, point_is_stable) against the full Hill filter."""
import numpy as np
import pytest

import hbm
import hbm.analyses.stability as stab
from hbm.balance.dense_part import dense_balance
from hbm.analyses.hill_system import point_is_stable, point_stability
from hbm.analyses.stability import hill_is_stable, hill_stability, select_exponents, verdict_from_eigenvalues
from hbm.balance.transforms import make_transform

from conftest import sdof_jenkins_case
from test_duffing import duffing_case

TOL = 1e-7


def filter_verdict(lam, mean_index, n, w):
    """HillResult.stable of the filter for given eigenvalues and mean indices."""
    keep = select_exponents(lam, mean_index, n, w)
    return bool(lam[keep].real.max() < TOL * w)


def verdicts_over_indices(lam, n, w, rng, trials=200):
    """The set of verdicts the filter gives over random mean-index assignments."""
    out = set()
    for _ in range(trials):
        out.add(filter_verdict(lam, rng.uniform(-3, 3, lam.size), n, w))
    # the extreme assignments: unstable ones most / least central
    bad = ~(lam.real < TOL * w)
    out.add(filter_verdict(lam, np.where(bad, 0.0, 1.0), n, w))
    out.add(filter_verdict(lam, np.where(bad, 1.0, 0.0), n, w))
    return out


def random_spectrum(rng, w, m_in, m_out, n_bad_in, n_bad_out):
    """Conjugate-free random eigenvalues: m_in in the strip, m_out outside, some unstable."""
    im_in = rng.uniform(-0.49, 0.49, m_in) * w
    im_out = np.sign(rng.uniform(-1, 1, m_out)) * rng.uniform(0.51, 4.0, m_out) * w
    re = -rng.uniform(0.01, 1.0, m_in + m_out) * w
    re[:n_bad_in] *= -1
    re[m_in:m_in + n_bad_out] *= -1
    lam = re + 1j * np.r_[im_in, im_out]
    return lam[rng.permutation(lam.size)]


@pytest.mark.parametrize("m_in", [1, 2, 3, 4, 5, 6, 8])
def test_verdict_matches_filter_for_every_choice_of_mean_index(m_in, rng):
    n, w = 2, 1.7
    decided = undecided = 0
    for trial in range(60):
        n_bad_in = rng.integers(0, m_in + 1)
        n_bad_out = rng.integers(0, 4)
        lam = random_spectrum(rng, w, m_in, 10, n_bad_in, n_bad_out)
        v = verdict_from_eigenvalues(lam, n, w, TOL)
        seen = verdicts_over_indices(lam, n, w, rng)
        if v is None:
            undecided += 1
            # only undecided when more than 2n sit in the strip and the choice can matter
            assert m_in > 2 * n and 0 < n_bad_in <= m_in - 2 * n
            assert seen == {True, False}
        else:
            decided += 1
            assert seen == {v}
    assert decided > 0
    if m_in > 2 * n:
        assert undecided > 0


def test_verdict_cases_by_hand():
    w = 1.0
    # fewer in the strip than 2n: the fill-in with the smallest |Im| decides
    lam = np.array([-0.1 + 0.2j, 0.3 + 0.7j, -0.2 + 1.2j])
    assert verdict_from_eigenvalues(lam, 1, w, TOL) is False         # fill 0.3+0.7j is unstable
    lam = np.array([-0.1 + 0.2j, -0.3 + 0.7j, 0.2 + 1.2j])
    assert verdict_from_eigenvalues(lam, 1, w, TOL) is True          # unstable one not a fill
    # a tie of |Im| at the fill-in boundary with mixed stability: undecided
    lam = np.array([-0.1 + 0.2j, 0.3 + 0.7j, -0.3 - 0.7j])
    assert verdict_from_eigenvalues(lam, 1, w, TOL) is None
    # a conjugate pair tie: both stable or both unstable, decided
    lam = np.array([-0.1 + 0.2j, 0.3 + 0.7j, 0.3 - 0.7j])
    assert verdict_from_eigenvalues(lam, 1, w, TOL) is False
    # a neutral exponent (Re = 0) counts as stable, Re = tol * w does not
    assert verdict_from_eigenvalues(np.array([0.0 + 0.1j, -1.0 + 3j]), 1, w, TOL) is True
    assert verdict_from_eigenvalues(np.array([TOL * w + 0.1j, -1.0 + 3j]), 1, w, TOL) is False
    # strip is half-open: +w/2 inside, -w/2 outside
    assert verdict_from_eigenvalues(np.array([1.0 + 0.5j, -1.0 + 0.1j]), 1, w, TOL) is False
    assert verdict_from_eigenvalues(np.array([1.0 - 0.5j, -1.0 + 0.1j, -1.0 - 0.1j]), 1, w, TOL) is True


@pytest.mark.parametrize("case, has_unstable", [(duffing_case(3), True), (duffing_case([0, 1, 2, 3]), True),
                                                (sdof_jenkins_case(F=1.0, H=5), False)],
                         ids=["duffing3", "duffing_h0", "jenkins"])
def test_point_is_stable_equals_full_filter_along_frf(case, has_unstable):
    res = hbm.frf(case, stability=False)
    prob = dense_balance(case.model, case.elements, res.basis, case.excitation.force,
                           make_transform(res.basis, "dft"))
    full = [point_stability(prob, X, 2 * np.pi * f).stable for X, f in zip(res.X, res.freq_hz)]
    fast = [point_is_stable(prob, X, 2 * np.pi * f) for X, f in zip(res.X, res.freq_hz)]
    assert fast == full
    assert any(full) and (not all(full)) == has_unstable


def test_undecided_verdict_falls_back_to_eigenvectors(monkeypatch):
    case = duffing_case(3)
    res = hbm.frf(case, stability=False)
    prob = dense_balance(case.model, case.elements, res.basis, case.excitation.force,
                           make_transform(res.basis, "dft"))
    calls = []
    real = stab.hill_stability

    def spy(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(stab, "verdict_from_eigenvalues", lambda *a: None)
    monkeypatch.setattr(stab, "hill_stability", spy)
    got = [point_is_stable(prob, X, 2 * np.pi * f) for X, f in zip(res.X, res.freq_hz)]
    assert len(calls) == len(res.X)
    monkeypatch.undo()
    assert got == [point_stability(prob, X, 2 * np.pi * f).stable for X, f in zip(res.X, res.freq_hz)]
    assert not all(got)


def test_non_finite_jacobian_raises_like_hill_stability():
    from hbm.balance.fourier import FourierBasis
    basis = FourierBasis([1, 2], 8)
    J = np.eye(4)
    J[1, 2] = np.nan
    with pytest.raises(ValueError):
        hill_stability(J, np.eye(1), np.zeros((1, 1)), basis, 1.0)
    with pytest.raises(ValueError):
        hill_is_stable(J, np.eye(1), np.zeros((1, 1)), basis, 1.0)
