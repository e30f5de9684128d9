r"""Time <-> frequency transforms of the AFT, three interchangeable backends behind one interface.

With the layout of :mod:`hbm.balance.fourier`, synthesis and analysis of ``m`` signals are

.. math::

    x = E X \quad (N \times m), \qquad X = P x \quad (n_{coef} \times m).

The FFT backends use the real FFT :math:`\hat x_h = \sum_j x_j e^{-2\pi i h j / N}`:
``X0 = Re(x_0)/N``, ``Xc_h = 2 Re(x_h)/N``, ``Xs_h = -2 Im(x_h)/N``, and the inverse
spectrum ``x_h = N/2 (Xc_h - i Xs_h)``.  All three give the same numbers to round-off:

- :class:`DFTMatrix`: precomputed ``E`` and ``P`` (cheapest for few harmonics and signals),
- :class:`NumpyFFT`: ``numpy.fft.rfft / irfft``,
- :class:`FFTWTransform`: pyFFTW plans, built once per signal count and reused.
"""
from __future__ import annotations

import numpy as np

from hbm.balance.fourier import FourierBasis


class DFTMatrix:
    """Synthesis and analysis by the precomputed matrices ``E`` (N, n_coef) and ``P`` (n_coef, N)."""

    name = "dft"

    def __init__(self, basis: FourierBasis):
        self.basis = basis

    def synthesize(self, X: np.ndarray) -> np.ndarray:
        """(n_coef, m) -> (N, m)."""
        return self.basis.E @ X

    def analyse(self, x: np.ndarray) -> np.ndarray:
        """(N, m) -> (n_coef, m)."""
        return self.basis.P @ x


class _RealFFT:
    """Shared index bookkeeping of the FFT backends."""

    def __init__(self, basis: FourierBasis):
        self.basis = basis
        h = basis.h_of_row
        self._rows0 = np.flatnonzero(h == 0)
        cos_rows = [r for r in range(h.size) if h[r] > 0 and (r == 0 or h[r - 1] != h[r])]
        self._rows_c = np.array(cos_rows, dtype=np.int64)
        self._rows_s = self._rows_c + 1
        self._h = h[self._rows_c]
        self._n = basis.n_samples

    def _to_coef(self, F: np.ndarray) -> np.ndarray:
        N = self._n
        X = np.empty((self.basis.n_coef, F.shape[1]))
        if self._rows0.size:
            X[self._rows0] = F[0].real / N
        Fh = F[self._h]
        X[self._rows_c] = (2.0 / N) * Fh.real
        X[self._rows_s] = (-2.0 / N) * Fh.imag
        return X

    def _to_spectrum(self, X: np.ndarray, out: np.ndarray) -> np.ndarray:
        N = self._n
        out[...] = 0.0
        if self._rows0.size:
            out[0] = N * X[self._rows0[0]]
        out[self._h] = (0.5 * N) * (X[self._rows_c] - 1j * X[self._rows_s])
        return out


class NumpyFFT(_RealFFT):
    """Synthesis and analysis with ``numpy.fft``."""

    name = "numpy"

    def synthesize(self, X):
        S = self._to_spectrum(X, np.empty((self._n // 2 + 1, X.shape[1]), dtype=complex))
        return np.fft.irfft(S, n=self._n, axis=0)

    def analyse(self, x):
        return self._to_coef(np.fft.rfft(x, axis=0))


class FFTWTransform(_RealFFT):
    """Synthesis and analysis with pyFFTW; one plan per (direction, signal count), reused."""

    name = "fftw"

    def __init__(self, basis: FourierBasis):
        super().__init__(basis)
        if not fftw_available():
            raise ValueError("transform 'fftw' needs pyFFTW: pip install 'hbm-friction[fftw]' "
                             "(or choose transform = 'numpy')")
        self._plans = {}

    def _plan(self, direction: str, m: int):
        key = (direction, m)
        plan = self._plans.get(key)
        if plan is None:
            import pyfftw
            N = self._n
            if direction == "r2c":
                a = pyfftw.empty_aligned((N, m), dtype="float64")
                b = pyfftw.empty_aligned((N // 2 + 1, m), dtype="complex128")
                plan = pyfftw.FFTW(a, b, axes=(0,), direction="FFTW_FORWARD",
                                   flags=("FFTW_ESTIMATE",), threads=1)
            else:
                a = pyfftw.empty_aligned((N // 2 + 1, m), dtype="complex128")
                b = pyfftw.empty_aligned((N, m), dtype="float64")
                plan = pyfftw.FFTW(a, b, axes=(0,), direction="FFTW_BACKWARD",
                                   flags=("FFTW_ESTIMATE", "FFTW_DESTROY_INPUT"), threads=1)
            self._plans[key] = plan
        return plan

    def synthesize(self, X):
        plan = self._plan("c2r", X.shape[1])
        self._to_spectrum(X, plan.input_array)
        plan.execute()
        return plan.output_array / self._n   # FFTW's backward transform is unnormalised

    def analyse(self, x):
        plan = self._plan("r2c", x.shape[1])
        plan.input_array[...] = x
        plan.execute()
        return self._to_coef(plan.output_array)


TRANSFORMS = {"dft": DFTMatrix, "numpy": NumpyFFT, "fftw": FFTWTransform}


def fftw_available() -> bool:
    try:
        import pyfftw  # noqa: F401
    except ImportError:
        return False
    return True


def make_transform(basis: FourierBasis, name: str = "auto"):
    """Transform by name (``dft``, ``numpy``, ``fftw``) or ``auto``.

    ``auto`` takes the DFT matrices while ``n_coef`` is small (a matrix product of
    ``n_coef x N`` beats an FFT of ``N log N`` plus its bookkeeping there) and FFTW (NumPy
    when pyFFTW is missing) above.  Measured by ``benchmarks/time_vs_error.py`` (section 2):
    the DFT still wins at H = 25 (n_coef = 51, N = 256: 73 us against 97 us NumPy, 110 us
    FFTW), so the crossover is set at n_coef = 64.
    """
    if name == "auto":
        if basis.n_coef <= 64:
            name = "dft"
        else:
            name = "fftw" if fftw_available() else "numpy"
    if name not in TRANSFORMS:
        raise ValueError(f"unknown transform {name!r} (choose from {', '.join(TRANSFORMS)} or auto)")
    return TRANSFORMS[name](basis)
