r"""Stability verdicts along a traced path with Hill spectra only where a change can hide.

Hill's test (:mod:`hbm.analyses.stability`) costs a dense eigenvalue problem of size ``2 n_u`` per
point, several times the cost of solving the point.  Along a path the Floquet exponents move
continuously, so the verdict can change only where the largest real part of the kept
exponents, the *margin* :math:`\mu_i = \max \mathrm{Re}\,\lambda - \tau w`, crosses zero:

* at a fold (a real exponent through 0, where the path's frequency reverses), and
* where :math:`\mu` drifts through zero between points (a complex pair: Neimark-Sacker).

The walk (:func:`path_stability`) decides the verdict by the full Hill spectrum at probe
points.  From a probe ``i`` it skips ahead by ``s`` points, where ``s`` is half the number of
points that the margin's rate of change between the last two probes needs to reach zero
(``s = 1`` while no rate is known, at most ``max_skip``), and never skips a frequency
reversal: the points on either side of every fold are probes.  When two consecutive probes
disagree, every point between them is tested.  Points between two agreeing probes take
their verdict.  The margin used to pick ``s`` is an upper bound of the kept exponents' (all
in-strip eigenvalues and the fill-ins), so the walk is conservative.

What it can miss: an island of instability narrower than the skip between two probes whose
margins lie away from zero and change slowly there, e.g. a Neimark-Sacker pair that crosses
and returns within the skip.  Measured on a Duffing chain (``tests/test_condensed_stability.py``):
the margin sat at -3.5e-3 w for 20 points, then crossed to +4e-3 w within one step, and a
three-point island was missed at ``max_skip = 6``.  So the default, ``max_skip = 1``, tests
every point; a larger skip is an explicit trade of certainty for time.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as sla

from hbm.analyses.stability import (StabilityOptions, hill_matrix, hill_stability, is_identity,
                                   verdict_from_eigenvalues)

PARITY_TOL = 1e-11      # even-odd couplings below this (relative to A) are round-off


def hill_margin(J, M, C, basis, w: float, options: StabilityOptions | None = None):
    """Verdict and an upper bound of ``max Re`` of the kept exponents at one point.

    Parameters
    ----------
    J : ndarray, shape (n_u, n_u)
    M, C : ndarray, shape (n, n)
    basis : FourierBasis
    w : float
    options : StabilityOptions, optional

    Returns
    -------
    stable : bool
        :func:`hbm.analyses.stability.hill_stability`'s verdict.
    margin : float
        ``max Re(lambda) - rel_tol w`` over the in-strip eigenvalues and the fill-ins (an
        upper bound of the kept exponents'); negative when stable.
    """
    opts = options or StabilityOptions()
    if M.shape[0] == 0:
        return True, -np.inf
    if not np.all(np.isfinite(J)):
        raise ValueError("Hill matrix is not finite (a non-finite Jacobian at a converged point)")
    n = M.shape[0]
    lam = np.concatenate([eigenvalues(A) for A in hill_blocks(J, M, C, basis, w)])
    verdict = verdict_from_eigenvalues(lam, n, w, opts.rel_tol)
    if verdict is None:
        res = hill_stability(J, M, C, basis, w, opts)
        return res.stable, res.max_real - opts.rel_tol * w
    inside = (lam.imag > -0.5 * w) & (lam.imag <= 0.5 * w)
    cand = lam[inside]
    if cand.size < 2 * n:
        out = lam[~inside]
        cand = np.r_[cand, out[np.argsort(np.abs(out.imag), kind="stable")[:2 * n - cand.size]]]
    return bool(verdict), float(cand.real.max()) - opts.rel_tol * w


def eigenvalues(A: np.ndarray) -> np.ndarray:
    """Eigenvalues of the C-ordered square ``A`` (overwritten), by LAPACK's ``geev`` on
    ``A^T`` (the same spectrum, Fortran-ordered without a copy, no eigenvectors): a Hill
    matrix of 45 rows in 0.66 ms instead of scipy's 0.74 ms wrapper."""
    wr, wi, _, _, info = _geev(A.T, compute_vl=0, compute_vr=0, overwrite_a=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"the eigenvalues of a Hill matrix did not converge (geev info {info})")
    return wr + 1j * wi


_geev = sla.get_lapack_funcs("geev", dtype=np.float64)


def hill_blocks(J, M, C, basis, w: float, rel_tol: float = PARITY_TOL) -> list:
    """Hill's matrix (:func:`hbm.analyses.stability.hill_matrix`) as the blocks whose spectra
    make up its spectrum: its even and its odd harmonics when they do not couple, else whole.

    A half-wave symmetric response (``q(t + T/2) = -q(t)``: symmetric laws, no static
    offset) has a Jacobian with period ``T/2``, which couples a perturbation's harmonic ``j``
    only to harmonics ``j +- 2k``: the Hill matrix is block diagonal on the even and the odd
    rows (two eigenproblems of about half the size, about a quarter of the work).  ``M`` and
    ``D1`` act within a harmonic, so the coupling is ``M^{-1} J``'s between the parities; the
    blocks are used when every coupling entry is below ``rel_tol`` times the largest entry of
    the Hill matrix.  Each block is built from its own rows of ``J`` on the basis of its
    harmonics (the whole matrix is never formed).

    Parameters
    ----------
    J : ndarray, shape (n_u, n_u)
    M, C : ndarray, shape (n, n)
    basis : FourierBasis
    w : float

    Returns
    -------
    list of ndarray
        One (2 n_u, 2 n_u) matrix, or the even and the odd block.
    """
    n = M.shape[0]
    split = parity_split(basis, n)
    if split is None:
        return [hill_matrix(J, M, C, basis, w)]
    perm, ne, bases = split
    Jp = J[np.ix_(perm, perm)]
    if is_identity(M):
        MJ, MC = Jp, C
    else:
        Minv = np.linalg.inv(M)
        MJ = np.einsum("ab,kbl->kal", Minv, Jp.reshape(-1, n, Jp.shape[1])).reshape(Jp.shape)
        MC = Minv @ C
    largest = max(1.0, np.abs(MJ).max(initial=0.0), np.abs(MC).max(initial=0.0), 2.0 * w * max(basis.harmonics))
    bound = rel_tol * largest
    if np.abs(MJ[:ne, ne:]).max() > bound or np.abs(MJ[ne:, :ne]).max() > bound:
        return [hill_matrix(J, M, C, basis, w)]
    return [hill_matrix(Jp[:ne, :ne], M, C, bases[0], w), hill_matrix(Jp[ne:, ne:], M, C, bases[1], w)]


_SPLITS: dict = {}


@dataclasses.dataclass(frozen=True)
class _Rows:
    """The coefficient rows of one parity, as :func:`hill_matrix` reads a basis (the even
    ones may hold the mean alone, which no :class:`FourierBasis` does)."""
    h_of_row: np.ndarray

    @property
    def n_coef(self) -> int:
        return int(self.h_of_row.size)


def parity_split(basis, n: int):
    """The even and odd harmonics of ``basis`` as a permutation of the Jacobian's rows.

    Returns
    -------
    tuple or None
        ``(perm, n_even, (even_rows, odd_rows))``: ``perm`` (n_u,) lists the rows of the
        even harmonics (harmonic-major, ``n`` per coefficient) and then the odd ones,
        ``n_even`` of them even; None when the basis has one parity only.
    """
    key = (tuple(int(h) for h in basis.harmonics), int(basis.n_samples), int(n))
    if key not in _SPLITS:
        odd = (np.repeat(basis.h_of_row, n) % 2).astype(bool)
        if odd.all() or not odd.any():
            _SPLITS[key] = None
        else:
            ev, od = np.flatnonzero(~odd), np.flatnonzero(odd)
            hr = basis.h_of_row
            bases = (_Rows(hr[hr % 2 == 0]), _Rows(hr[hr % 2 == 1]))
            _SPLITS[key] = (np.r_[ev, od], ev.size, bases)
    return _SPLITS[key]


def _skip(margins: dict, i: int, max_skip: int) -> int:
    """Points to skip ahead of probe ``i``: half the steps the margin's trend needs to reach 0."""
    probes = sorted(k for k in margins if k < i)
    if not probes:
        return 1
    p = probes[-1]
    rate = abs(margins[i] - margins[p]) / (i - p)
    if rate == 0.0:
        return max_skip
    return int(min(max(0.5 * abs(margins[i]) / rate, 1), max_skip))


def path_stability(test, freq: np.ndarray, max_skip: int = 1):
    """Verdicts at every point of a path, by Hill spectra at probe points (module doc).

    Parameters
    ----------
    test : callable
        ``test(i) -> (stable, margin)`` for point ``i`` (e.g. :func:`hill_margin`).
    freq : ndarray, shape (n,)
        The path's frequencies, in path order.
    max_skip : int
        Largest number of points between two probes (1: test every point).

    Returns
    -------
    stable : ndarray of bool, shape (n,)
    margin : ndarray, shape (n,)
        :func:`hill_margin`'s margin at the points whose verdict comes from their own Hill
        spectrum, NaN elsewhere.
    """
    n = freq.size
    stable = np.ones(n, dtype=bool)
    tested = np.zeros(n, dtype=bool)
    if n == 0:
        return stable, np.zeros(0)
    d = np.sign(np.diff(freq))
    # both sides of every frequency reversal are probes
    must = np.zeros(n, dtype=bool)
    rev = np.flatnonzero(d[1:] * d[:-1] < 0) + 1
    must[rev] = must[np.maximum(rev - 1, 0)] = must[np.minimum(rev + 1, n - 1)] = True
    must[[0, n - 1]] = True
    margins = {}

    def probe(k):
        if not tested[k]:
            stable[k], margins[k] = test(k)
            tested[k] = True

    i = 0
    probe(0)
    while i < n - 1:
        j = min(i + _skip(margins, i, max(int(max_skip), 1)), n - 1)
        forced = np.flatnonzero(must[i + 1:j + 1])
        if forced.size:
            j = i + 1 + int(forced[0])
        probe(j)
        if stable[j] != stable[i]:
            for k in range(i + 1, j):
                probe(k)
        else:
            stable[i + 1:j] = stable[i]
        i = j
    margin = np.full(n, np.nan)
    for k, m in margins.items():
        margin[k] = m
    return stable, margin
