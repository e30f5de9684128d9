"""The harmonic balance: Fourier conventions, the AFT of the elements, the one residual and its linear parts."""
