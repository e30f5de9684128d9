import numpy as np
import pytest

from hbm.balance.fourier import FourierBasis, parse_harmonics, min_samples


@pytest.mark.parametrize("h", [[0, 1, 2, 3], [1, 3, 5, 7], [1, 2], [0, 1, 4]])
def test_synthesis_analysis_inverse(h, rng):
    b = FourierBasis(np.array(h), 32)
    X = rng.standard_normal((b.n_coef, 3))
    assert np.allclose(b.P @ (b.E @ X), X, atol=1e-13)


def test_layout_and_derivative(rng):
    b = FourierBasis(np.array([0, 1, 3]), 64)
    assert list(b.h_of_row) == [0, 1, 1, 3, 3]
    w = 2.5
    X = rng.standard_normal((b.n_coef, 2))
    t = 2 * np.pi * np.arange(64) / 64 / w
    x = X[0] + X[1] * np.cos(w * t)[:, None] + X[2] * np.sin(w * t)[:, None] \
        + X[3] * np.cos(3 * w * t)[:, None] + X[4] * np.sin(3 * w * t)[:, None]
    assert np.allclose(b.E @ X, x)
    xdot = -w * X[1] * np.sin(w * t)[:, None] + w * X[2] * np.cos(w * t)[:, None] \
        - 3 * w * X[3] * np.sin(3 * w * t)[:, None] + 3 * w * X[4] * np.cos(3 * w * t)[:, None]
    assert np.allclose(b.E @ (w * b.D @ X), xdot)
    assert np.allclose(w * b.dE @ X, xdot)


def test_aliasing_guard():
    with pytest.raises(ValueError, match="too small"):
        FourierBasis(np.array([1, 2, 5]), 10)
    assert min_samples([1, 5]) == 11
    FourierBasis(np.array([1, 2, 5]), 11)


def test_parse_harmonics():
    assert list(parse_harmonics(3)) == [1, 2, 3]
    assert list(parse_harmonics(2, include_zero=True)) == [0, 1, 2]
    assert list(parse_harmonics([5, 1, 3])) == [1, 3, 5]
    for bad in (0, -1, [], [0], True):
        with pytest.raises(ValueError):
            parse_harmonics(bad)
