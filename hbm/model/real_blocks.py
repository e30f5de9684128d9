r"""Real block form of complex receptances (the conventions of :mod:`hbm.balance.fourier` and :mod:`hbm.model.linear`).

With ``x(t) = Xc cos(h w t) + Xs sin(h w t) = Re[(Xc - i Xs) e^{i h w t}]`` and likewise for
the force, the harmonic-``h`` balance ``Z_h [Xc; Xs] = [Fc; Fs]`` with
``Z_h = [[A, B], [-B, A]]``, ``A = K - (hw)^2 M``, ``B = hw C`` is the complex equation
``(A + i B)(Xc - i Xs) = Fc - i Fs``.  Hence ``Xc - i Xs = H(hw) (Fc - i Fs)`` and

.. math::

    Z_h^{-1} = \begin{bmatrix} \mathrm{Re}\,H & \mathrm{Im}\,H \\ -\mathrm{Im}\,H & \mathrm{Re}\,H
    \end{bmatrix}_{W = h w}, \qquad
    \frac{d Z_h^{-1}}{dw} = h \begin{bmatrix} \mathrm{Re}\,H' & \mathrm{Im}\,H' \\
    -\mathrm{Im}\,H' & \mathrm{Re}\,H' \end{bmatrix}, \qquad H' = dH/dW,

acting on ``[Xc_h, Xs_h]`` (:func:`real_block`).  The map ``a + i b -> [[a, b], [-b, a]]``
is a ring homomorphism, so products and inverses may be done in complex arithmetic and
converted at the end.  For ``h = 0`` the block is the static flexibility ``H(0)`` (real).
"""
from __future__ import annotations

import numpy as np

from hbm.balance.fourier import FourierBasis


def real_block(Hc: np.ndarray) -> np.ndarray:
    """Real form ``[[Re H, Im H], [-Im H, Re H]]`` of a complex matrix, acting on ``[Xc, Xs]``.

    Parameters
    ----------
    Hc : ndarray, complex, shape (p, q)

    Returns
    -------
    ndarray, shape (2p, 2q)
    """
    a, b = Hc.real, Hc.imag
    p, q = a.shape
    out = np.empty((2 * p, 2 * q))
    out[:p, :q] = a
    out[:p, q:] = b
    out[p:, :q] = -b
    out[p:, q:] = a
    return out


def apply_blocks(blocks, basis: FourierBasis, X: np.ndarray) -> np.ndarray:
    """Apply per-harmonic blocks to coefficients ``X`` (n_coef, q) -> (n_coef, p).

    Parameters
    ----------
    blocks : list of ndarray
        One per harmonic of ``basis``: (p, q) for h = 0, (2p, 2q) otherwise.
    basis : FourierBasis
    X : ndarray, shape (n_coef, q)
    """
    X = np.asarray(X, dtype=float)
    if X.ndim != 2 or X.shape[0] != basis.n_coef:
        raise ValueError(f"coefficients must have shape (n_coef={basis.n_coef}, q), got {X.shape}")
    out, k = [], 0
    for h, B in zip(basis.harmonics, blocks):
        if h == 0:
            out.append((B @ X[k])[None, :])
            k += 1
        else:
            p = B.shape[0] // 2
            y = B @ X[k:k + 2].reshape(-1)
            out.append(y.reshape(2, p))
            k += 2
    return np.vstack(out)


def real_blocks_of(fun, basis: FourierBasis, w: float):
    """Real blocks of ``fun(W) -> (H, dH/dW)`` for each harmonic, and their w-derivatives."""
    blocks, dblocks = [], []
    for h in basis.harmonics:
        H, dH = fun(h * w)
        if h == 0:
            blocks.append(np.ascontiguousarray(H.real))
            dblocks.append(np.zeros(H.shape))
        else:
            blocks.append(real_block(H))
            dblocks.append(h * real_block(dH))
    return blocks, dblocks
