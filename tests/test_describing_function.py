"""Jenkins first-harmonic describing function: HBM force coefficients against the closed form.

For ``u = A cos(theta)``, ``kt A > fs``: with ``cos(theta*) = 1 - 2 fs/(kt A)``,
``Fc = (kt A/pi)(theta* - sin(2 theta*)/2)`` ... derived in the test below as
``Fc = (2/pi)[(2 fs - kt A) sin(theta*) + kt A (theta*/2 + sin(2 theta*)/4)]`` and
``Fs = -(4 fs/pi)(1 - fs/(kt A))``; below the stick limit ``Fc = kt A``, ``Fs = 0``.
"""
import numpy as np

from elements import Jenkins
from hbm.balance.aft import NonlinearForces
from hbm.balance.fourier import FourierBasis
from hbm.balance.transforms import make_transform


def closed_form(A, kt, fs):
    if kt * A <= fs:
        return kt * A, 0.0
    th = np.arccos(1.0 - 2.0 * fs / (kt * A))
    Fc = (2.0 / np.pi) * ((2.0 * fs - kt * A) * np.sin(th) + kt * A * (th / 2.0 + np.sin(2.0 * th) / 4.0))
    Fs = -(4.0 * fs / np.pi) * (1.0 - fs / (kt * A))
    return Fc, Fs


def test_describing_function_against_closed_form():
    kt, fs = 3.0, 0.6
    b = FourierBasis(np.array([1, 3, 5]), 8192)
    nl = NonlinearForces(b, [Jenkins(np.array([[1.0]]), kt, fs)], 1, make_transform(b, "numpy"))
    A_stick = fs / kt
    for A in A_stick * np.array([0.3, 0.99, 1.5, 2.0, 5.0, 10.0, 30.0, 100.0]):
        X = np.zeros((b.n_coef, 1))
        X[0, 0] = A
        F = nl.forces(X, 1.0)
        Fc, Fs = closed_form(A, kt, fs)
        # the sampled march resolves the stick-slip instant to one sample: error ~ kt A / N^2
        tol = 1e-9 + 5e-6 * max(abs(Fc), fs)
        assert abs(F[0, 0] - Fc) < tol, (A, F[0, 0], Fc)
        assert abs(F[1, 0] - Fs) < tol, (A, F[1, 0], Fs)


def test_describing_function_converges_with_samples():
    kt, fs, A = 1.0, 0.3, 0.5
    Fc, Fs = closed_form(A, kt, fs)
    errs = []
    for N in (64, 256, 1024):
        b = FourierBasis(np.array([1]), N)
        nl = NonlinearForces(b, [Jenkins(np.array([[1.0]]), kt, fs)], 1, make_transform(b, "dft"))
        X = np.array([[A], [0.0]])
        F = nl.forces(X, 1.0)
        errs.append(np.hypot(F[0, 0] - Fc, F[1, 0] - Fs))
    assert errs[1] < errs[0] / 4 and errs[2] < errs[1] / 4
