r"""Real Fourier basis for a list of harmonics: the project's conventions, fixed once.

A periodic signal of fundamental angular frequency ``w`` is written

.. math::

    x(t) = X_0 + \sum_{h \in \mathcal{H},\, h>0} \left( X^c_h \cos(h w t) + X^s_h \sin(h w t) \right)

for a harmonic list :math:`\mathcal{H}` (sorted, unique, non-negative; 0 optional, gaps
allowed, e.g. odd harmonics only).  The coefficient rows are ordered harmonic-major::

    [X0 (if 0 in H), Xc_h1, Xs_h1, Xc_h2, Xs_h2, ...]

so that for ``n`` degrees of freedom the unknown vector is ``X.reshape(-1)`` of an array
``X`` of shape ``(n_coef, n)``.  Time is sampled on ``N`` equidistant points of one
period, :math:`\theta_j = w t_j = 2 \pi j / N`.

Synthesis ``x = E @ X`` and analysis ``X = P @ x`` use

.. math::

    E_{j,\cdot} = [1, \cos h\theta_j, \sin h\theta_j, \dots], \qquad
    P = \tfrac{2}{N} E^T \ (\text{row of } X_0: \tfrac{1}{N})

which are exact inverses on band-limited signals when ``N > 2 max(H)`` (no aliasing of
the retained harmonics onto each other).  The time derivative acts per harmonic as
:math:`d/dt\,[X^c_h, X^s_h] = h w\,[X^s_h, -X^c_h]`.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def parse_harmonics(spec, include_zero: bool = False) -> np.ndarray:
    """Harmonic list from an int ``H`` (1..H, plus 0 if asked) or an explicit list.

    Parameters
    ----------
    spec : int or sequence of int
        ``H`` or an explicit list of harmonics.
    include_zero : bool
        With an int ``H``, prepend harmonic 0.

    Returns
    -------
    ndarray of int, shape (n_h,)
        Sorted unique harmonics.
    """
    if isinstance(spec, (bool, np.bool_)):
        raise ValueError("harmonics must be an integer H or a list of integers")
    if isinstance(spec, (int, np.integer)):
        if spec < 1:
            raise ValueError(f"harmonics must be >= 1, got {spec}")
        h = np.arange(0 if include_zero else 1, int(spec) + 1)
    else:
        h = np.asarray(list(spec))
        if h.size == 0 or h.dtype.kind not in "iu":
            raise ValueError("harmonics list must be a non-empty list of integers")
        if np.any(h < 0):
            raise ValueError("harmonics must be non-negative")
        h = np.unique(h)
        if not np.any(h > 0):
            raise ValueError("harmonics list must contain at least one harmonic > 0")
    return h.astype(np.int64)


def min_samples(harmonics) -> int:
    """Smallest N for which the retained harmonics do not alias onto each other (2 Hmax + 1)."""
    return 2 * int(np.max(harmonics)) + 1


def default_samples(harmonics, factor: int = 1) -> int:
    """``factor`` times a power of two with at least 8 samples per period of the highest
    harmonic (and at least 64); ``factor`` (an integer >= 1) is the elements'
    ``default_samples_factor`` (friction laws need more samples than harmonics)."""
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"samples factor must be an integer >= 1, got {factor!r}")
    need = 8 * int(np.max(harmonics))
    return int(factor) * int(max(64, 1 << int(np.ceil(np.log2(max(need, 2))))))


@dataclass(frozen=True)
class FourierBasis:
    """Real Fourier basis on ``N`` time samples for a harmonic list.

    Parameters
    ----------
    harmonics : array_like of int, shape (n_h,)
        Sorted unique non-negative harmonics.
    n_samples : int
        Samples per period ``N``; must be >= 2 max(H) + 1.

    Attributes
    ----------
    n_coef : int
        Number of real coefficients per DOF (``2 n_h`` minus one if 0 is included).
    h_of_row : ndarray of int, shape (n_coef,)
        Harmonic number of each coefficient row.
    E : ndarray, shape (N, n_coef)
        Synthesis matrix, ``x = E @ X``.
    dE : ndarray, shape (N, n_coef)
        Derivative of ``E`` with respect to ``theta = w t`` (so ``xdot = w dE @ X``).
    P : ndarray, shape (n_coef, N)
        Analysis matrix, ``X = P @ x`` (exact inverse of ``E`` on the retained harmonics).
    D : ndarray, shape (n_coef, n_coef)
        Derivative operator in coefficient space for ``w = 1``: ``Xdot = w D @ X``.
    """

    harmonics: np.ndarray
    n_samples: int
    h_of_row: np.ndarray = field(init=False, repr=False)
    E: np.ndarray = field(init=False, repr=False)
    dE: np.ndarray = field(init=False, repr=False)
    P: np.ndarray = field(init=False, repr=False)
    D: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        h = parse_harmonics(list(np.asarray(self.harmonics)))
        N = int(self.n_samples)
        if N < min_samples(h):
            raise ValueError(
                f"time_samples N={N} is too small for harmonics up to {h.max()}: "
                f"need N >= {min_samples(h)} (2 Hmax + 1) to avoid aliasing")
        rows = []
        for hh in h:
            rows += [hh] if hh == 0 else [hh, hh]
        h_of_row = np.array(rows, dtype=np.int64)
        is_cos = np.zeros(h_of_row.size, dtype=bool)
        is_sin = np.zeros(h_of_row.size, dtype=bool)
        k = 0
        for hh in h:
            if hh == 0:
                k += 1
            else:
                is_cos[k] = True
                is_sin[k + 1] = True
                k += 2
        theta = 2.0 * np.pi * np.arange(N) / N
        ht = np.outer(theta, h_of_row)
        E = np.where(is_cos, np.cos(ht), np.where(is_sin, np.sin(ht), 1.0))
        dE = np.where(is_cos, -h_of_row * np.sin(ht), np.where(is_sin, h_of_row * np.cos(ht), 0.0))
        P = (2.0 / N) * E.T.copy()
        P[h_of_row == 0] = 1.0 / N
        D = np.zeros((h_of_row.size, h_of_row.size))
        for r in np.flatnonzero(is_cos):
            hh = h_of_row[r]
            D[r, r + 1] = hh      # d/dt of Xs sin -> h Xs cos
            D[r + 1, r] = -hh     # d/dt of Xc cos -> -h Xc sin
        for name, val in (("harmonics", h), ("n_samples", N), ("h_of_row", h_of_row),
                          ("E", E), ("dE", dE), ("P", P), ("D", D)):
            if isinstance(val, np.ndarray):
                val.setflags(write=False)
            object.__setattr__(self, name, val)

    @property
    def n_coef(self) -> int:
        return int(self.h_of_row.size)

    @property
    def has_zero(self) -> bool:
        return bool(self.harmonics[0] == 0)

    def row_of(self, h: int, part: str = "c") -> int:
        """Row index of harmonic ``h``'s cosine (``part='c'``), sine (``'s'``) or mean (``h=0``)."""
        idx = np.flatnonzero(self.h_of_row == h)
        if idx.size == 0:
            raise KeyError(f"harmonic {h} is not in the basis")
        return int(idx[0] if (h == 0 or part == "c") else idx[1])

def basis_matrix(h_of_row: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Synthesis matrix at arbitrary phases ``theta`` (n_t,), shape (n_t, n_coef)."""
    out = np.empty((theta.size, h_of_row.size))
    k = 0
    while k < h_of_row.size:
        h = h_of_row[k]
        if h == 0:
            out[:, k] = 1.0
            k += 1
        else:
            out[:, k] = np.cos(h * theta)
            out[:, k + 1] = np.sin(h * theta)
            k += 2
    return out


def max_abs(basis: FourierBasis, X: np.ndarray, n_fine: int | None = None) -> np.ndarray:
    """Maximum over one period of ``|x(t)|`` for each column of ``X`` (n_coef, m) -> (m,).

    The maximum is bracketed on a fine grid and then refined by Newton iterations on
    ``dx/dtheta = 0`` of the trigonometric polynomial, so it is exact to round-off rather
    than to the grid spacing.
    """
    X = np.atleast_2d(X)
    if X.shape[1] == 0:
        return np.zeros(0)
    n_fine = n_fine or max(256, 16 * int(basis.harmonics.max()))
    theta_grid = 2.0 * np.pi * np.arange(n_fine) / n_fine
    x = basis_matrix(basis.h_of_row, theta_grid) @ X
    j = np.argmax(np.abs(x), axis=0)
    th = theta_grid[j]
    h = basis.h_of_row.astype(float)
    is_c = np.zeros(h.size, dtype=bool)
    is_c[[r for r in range(h.size) if h[r] > 0 and (r == 0 or h[r - 1] != h[r])]] = True
    is_s = np.roll(is_c, 1) & (h > 0)
    cols = np.arange(X.shape[1])
    for _ in range(4):
        ht = np.outer(th, h)                      # (m, n_coef)
        c, s = np.cos(ht), np.sin(ht)
        d1 = np.where(is_c, -h * s, np.where(is_s, h * c, 0.0))
        d2 = np.where(is_c, -h * h * c, np.where(is_s, -h * h * s, 0.0))
        g1 = np.einsum("mk,km->m", d1, X)
        g2 = np.einsum("mk,km->m", d2, X)
        step = np.where(np.abs(g2) > 1e-300, g1 / np.where(g2 == 0, 1.0, g2), 0.0)
        step = np.clip(step, -np.pi / n_fine, np.pi / n_fine)
        th = th - step
    vals = np.abs(np.einsum("mk,km->m", basis_matrix(basis.h_of_row, th), X))
    return np.maximum(vals, np.abs(x[j, cols]))
