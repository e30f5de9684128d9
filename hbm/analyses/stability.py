r"""Stability of a harmonic-balance solution by Hill's method.

Perturb a periodic solution :math:`q^*(t)` by :math:`y(t) = e^{\lambda t} p(t)` with
:math:`p` periodic and expanded on the same real Fourier basis, :math:`p = E P`
(:mod:`hbm.balance.fourier`).  With :math:`\dot y = e^{\lambda t} (\lambda p + \dot p)` and
:math:`\ddot y = e^{\lambda t} (\lambda^2 p + 2 \lambda \dot p + \ddot p)` the linearised
equation of motion :math:`M \ddot y + C \dot y + K y + \partial f_{nl} / \partial q\, y = 0`
becomes, harmonic by harmonic, the quadratic eigenvalue problem

.. math::

    \left(\lambda^2 \Delta_2 + \lambda \Delta_1 + J\right) P = 0, \qquad
    J = \frac{\partial R}{\partial X}(X^*, w),

with block-diagonal :math:`\Delta_2 = I \otimes M` and, per harmonic :math:`h` acting on
:math:`[P^c_h, P^s_h]` (the derivative operator :math:`d/dt [P^c_h, P^s_h] = h w [P^s_h, -P^c_h]`),

.. math::

    \Delta_{1,0} = C, \qquad
    \Delta_{1,h} = \begin{bmatrix} C & 2 h w M \\ -2 h w M & C \end{bmatrix}.

For a rate-independent (hysteretic) law the dependence of the nonlinear force on
:math:`\lambda` is neglected: :math:`J` already holds its stiffness-like part (standard in
AFT-Hill).  Since :math:`M` is positive definite, the QEP is linearised to the standard
eigenproblem of size :math:`2 n_u`,

.. math::

    \begin{bmatrix} 0 & I \\ -\Delta_2^{-1} J & -\Delta_2^{-1} \Delta_1 \end{bmatrix}
    \begin{bmatrix} P \\ \lambda P \end{bmatrix}
    = \lambda \begin{bmatrix} P \\ \lambda P \end{bmatrix},

where :math:`\Delta_2^{-1} = I \otimes M^{-1}` is applied block by block (no Kronecker product).

**Filter.**  In the exact (infinite) Hill problem every Floquet exponent :math:`\lambda`
appears as a family of eigenvalues :math:`\lambda - i j w` (:math:`j \in \mathbb Z`) whose
eigenvectors are :math:`e^{i j w t} p(t)`.  Exactly one member of each family has
:math:`\mathrm{Im} \in (-w/2, w/2]`: the *slow* member, a modulation of the periodic
response on a time scale longer than the period.  The filter keeps the ``2n`` eigenvalues

1. inside the strip :math:`-w/2 < \mathrm{Im}\,\lambda \le w/2`, and among those (when the
   truncation adds spurious ones) the most *central*, i.e. with the smallest
   :math:`|\bar\jmath|`, the mean complex harmonic index of the eigenvector: the real
   coefficients of harmonic :math:`h` give :math:`c_{\pm h} = (P^c_h \mp i P^s_h)/2`
   (:math:`c_0 = P_0`), weights :math:`\omega_j = \sum_{dofs}|c_j|^2` normalised to unit sum, and
   :math:`\bar\jmath = \sum_j j\,\omega_j`;
2. when fewer than ``2n`` lie in the strip (a basis without harmonic 0 cannot hold the slow
   member of a free vibration much slower than :math:`w/2`), the remaining ones with the
   smallest :math:`|\mathrm{Im}\,\lambda|`, folded into the strip modulo :math:`i w`.

The strip, rather than eigenvector centrality alone, is what makes the neglect of the
:math:`\lambda`-dependence of hysteretic forces consistent: the friction's damping enters
:math:`J` only as an antisymmetric coupling :math:`\pm d_h` of the cosine and sine blocks
(not in :math:`\Delta_1`), like a structural (complex-stiffness) damping; the members of a family are then no longer exact shifted copies,
and only the slow member carries the friction damping with the right sign (the fast members
of one root are spuriously unstable, a known defect of hysteretic damping in the time domain).

The solution is asymptotically stable when :math:`\max \mathrm{Re}\,\lambda < \tau w`
with a small relative tolerance :math:`\tau` (:class:`StabilityOptions`).

**Verdict without eigenvectors** (:func:`hill_is_stable`, used along an FRF).  Only the
choice among more than ``2n`` in-strip eigenvalues needs the eigenvectors; with ``m``
eigenvalues in the strip of which ``b`` are unstable, the verdict is *stable* when ``b = 0``
and *unstable* when ``b > m - 2n`` (some unstable one must be kept), whatever the choice;
with ``m < 2n`` the fill-ins are chosen by ``|Im|`` alone.  Only ``0 < b <= m - 2n`` needs
the vectors (the full :func:`hill_stability`).  The eigenvalues come from the same LAPACK
``geev`` reduction and QR iteration with and without vectors, so the verdict is the same.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from hbm.balance.fourier import FourierBasis


@dataclass(frozen=True)
class StabilityOptions:
    """Settings of the Hill stability test.

    Parameters
    ----------
    rel_tol : float
        A point is stable when ``max Re(lambda) < rel_tol * w`` (``w`` the excitation's
        angular frequency); a neutral exponent (e.g. a floating friction slider) counts as
        stable.
    max_skip : int
        Along an FRF, the most points between two whose Hill spectra are computed
        (:mod:`hbm.analyses.stability_path`).  The default, 1, computes every point's: a larger skip
        is cheaper and can miss an island of instability narrower than the skip (a
        three-point Neimark-Sacker island of a Duffing chain is missed at 6, found at 3).
    """

    rel_tol: float = 1e-7
    max_skip: int = 1

    def __post_init__(self):
        if not (np.isfinite(self.rel_tol) and self.rel_tol >= 0):
            raise ValueError(f"rel_tol must be a finite number >= 0, got {self.rel_tol}")
        if int(self.max_skip) != self.max_skip or self.max_skip < 1:
            raise ValueError(f"max_skip must be a whole number >= 1, got {self.max_skip}")


@dataclass(frozen=True)
class HillResult:
    """Floquet exponents of one periodic solution.

    Attributes
    ----------
    exponents : ndarray of complex, shape (2 n,)
        The kept Floquet exponents, imaginary parts folded into ``(-w/2, w/2]``, sorted by
        decreasing real part.
    hill_eigenvalues : ndarray of complex, shape (2 n_u,)
        All eigenvalues of the truncated Hill problem (before filtering).
    mean_index : ndarray of float, shape (2 n_u,)
        Mean complex harmonic index of each eigenvector (see the module doc).
    max_real : float
        ``max Re(exponents)``.
    stable : bool
    """

    exponents: np.ndarray
    hill_eigenvalues: np.ndarray
    mean_index: np.ndarray
    max_real: float
    stable: bool


def _pair_rows(basis: FourierBasis):
    """Cosine rows ``rc`` (k,) of the harmonics ``h > 0`` (sine row ``rc + 1``), their
    harmonics ``h`` (k,), and the row of harmonic 0 (``None`` if absent)."""
    hr = basis.h_of_row
    rc = np.flatnonzero(hr > 0)[::2]
    return rc, hr[rc], (0 if hr[0] == 0 else None)


def hill_matrix(J: np.ndarray, M: np.ndarray, C: np.ndarray, basis: FourierBasis, w: float) -> np.ndarray:
    r"""Companion matrix of the Hill QEP (module doc), shape (2 n_u, 2 n_u).

    Parameters
    ----------
    J : ndarray, shape (n_u, n_u)
        ``dR/dX`` at the solution, harmonic-major layout (``n_u = n_coef * n``).
    M, C : ndarray, shape (n, n)
        Mass and damping matrices.
    basis : FourierBasis
    w : float
        Excitation angular frequency, rad/s.

    Returns
    -------
    A : ndarray, shape (2 n_u, 2 n_u)
        ``[[0, I], [-D2^{-1} J, -D2^{-1} D1]]``, filled by blocks and index arrays (no loop
        over harmonics).
    """
    n = M.shape[0]
    nc = basis.n_coef
    nu = nc * n
    if J.shape != (nu, nu):
        raise ValueError(f"J must be ({nu}, {nu}) for {nc} coefficients x {n} dofs, got {J.shape}")
    A = np.zeros((2 * nu, 2 * nu))
    A[:nu, nu:].flat[::nu + 1] = 1.0
    if is_identity(M):                        # modal Hill systems: no inverse, no product
        A[nu:, :nu] = -J
        MinvC = C
    else:
        # -D2^{-1} J: M^{-1} applied to every coefficient row-block of J
        Minv = np.linalg.inv(M)
        MinvC = Minv @ C
        A[nu:, :nu] = -np.einsum("ab,kbl->kal", Minv, J.reshape(nc, n, nu)).reshape(nu, nu)
    # -D2^{-1} D1, block diagonal per harmonic: -M^{-1} C on the diagonal, -+2 h w I coupling
    r = np.arange(nc)
    A.reshape(2, nc, n, 2, nc, n)[1, r, :, 1, r, :] = -MinvC
    rc, h, _ = _pair_rows(basis)
    if rc.size:
        D1 = A[nu:, nu:]
        rows = (rc[:, None] * n + np.arange(n)).ravel()
        g = np.repeat(2.0 * w * h, n)
        D1[rows, rows + n] = -g
        D1[rows + n, rows] = g
    return A


def is_identity(M: np.ndarray) -> bool:
    """Whether the mass matrix ``M`` (n, n) is exactly the identity (mass-normalised modes)."""
    return bool(np.array_equal(M, np.eye(M.shape[0])))


def complex_index_weights(P: np.ndarray, basis: FourierBasis, n: int):
    """Complex harmonic indices and normalised weights of eigenvectors.

    Parameters
    ----------
    P : ndarray of complex, shape (n_u, m)
        Eigenvectors (real Fourier coefficients, harmonic-major).
    basis : FourierBasis
    n : int
        Number of DOFs.

    Returns
    -------
    j : ndarray of int, shape (n_j,)
        Complex harmonic indices ``[0?, h1, -h1, h2, -h2, ...]``.
    weights : ndarray, shape (n_j, m)
        ``sum over dofs |c_j|^2``, normalised to unit sum per eigenvector.
    """
    m = P.shape[1]
    Pr = P.reshape(basis.n_coef, n, m)
    rc, h, r0 = _pair_rows(basis)
    cp = 0.5 * (Pr[rc] - 1j * Pr[rc + 1])              # (k, n, m): c_{+h}
    cm = 0.5 * (Pr[rc] + 1j * Pr[rc + 1])              # c_{-h}
    pairs = np.stack([np.sum(np.abs(cp) ** 2, axis=1), np.sum(np.abs(cm) ** 2, axis=1)], axis=1)
    W = pairs.reshape(2 * rc.size, m)
    idx = np.stack([h, -h], axis=1).reshape(-1)
    if r0 is not None:
        W = np.concatenate([np.sum(np.abs(Pr[r0]) ** 2, axis=0)[None], W])
        idx = np.r_[0, idx]
    tot = W.sum(axis=0)
    W = W / np.where(tot > 0, tot, 1.0)
    return idx.astype(np.int64), W


def fold_exponents(lam: np.ndarray, w: float) -> np.ndarray:
    """Floquet exponents with the imaginary part folded into ``(-w/2, w/2]`` (modulo ``i w``)."""
    lam = np.asarray(lam, dtype=complex)
    k = np.ceil(lam.imag / w - 0.5)          # Im - k w lies in (-w/2, w/2]
    return lam - 1j * k * w


def select_exponents(hill_eigenvalues: np.ndarray, mean_index: np.ndarray, n: int, w: float) -> np.ndarray:
    """Indices of the ``2 n`` kept Hill eigenvalues (filter of the module doc).

    Parameters
    ----------
    hill_eigenvalues : ndarray of complex, shape (m,)
    mean_index : ndarray of float, shape (m,)
        Mean complex harmonic index of each eigenvector.
    n : int
        Number of DOFs (``2 n`` exponents are kept).
    w : float
        Excitation angular frequency.

    Returns
    -------
    ndarray of int, shape (min(2 n, m),)
        In-strip eigenvalues first, most central first; then out-of-strip ones by ``|Im|``.
        Ties are broken by position, so the choice is deterministic.
    """
    im = hill_eigenvalues.imag
    inside = (im > -0.5 * w) & (im <= 0.5 * w)
    second = np.where(inside, np.abs(mean_index), np.abs(im) / w)
    order = np.lexsort((np.arange(im.size), np.round(second, 9), ~inside))
    return order[:2 * n]


def hill_stability(J: np.ndarray, M: np.ndarray, C: np.ndarray, basis: FourierBasis, w: float,
                   options: StabilityOptions | None = None) -> HillResult:
    """Floquet exponents and stability of a converged harmonic-balance point.

    Parameters
    ----------
    J : ndarray, shape (n_u, n_u)
        ``dR/dX`` at the solution (from :meth:`hbm.balance.residual.HarmonicBalance.residual`).
    M, C : ndarray, shape (n, n)
    basis : FourierBasis
    w : float
        Angular frequency of the solution, rad/s (> 0).
    options : StabilityOptions, optional

    Returns
    -------
    HillResult
    """
    opts = options or StabilityOptions()
    n = M.shape[0]
    nu = basis.n_coef * n
    if n == 0:              # no dynamic mode left (all static): nothing can lose stability
        empty = np.zeros(0, dtype=complex)
        return HillResult(empty, empty, np.zeros(0), -np.inf, True)
    A = hill_matrix(J, M, C, basis, w)
    lam, V = sla.eig(A, check_finite=True)
    j, W = complex_index_weights(V[:nu], basis, n)
    mean_index = j @ W
    keep = select_exponents(lam, mean_index, n, w)
    # in-strip members are unchanged; out-of-strip fill-ins are folded modulo i w
    ex = fold_exponents(lam[keep], w)
    ex = ex[np.argsort(-ex.real, kind="stable")]
    max_real = float(ex.real.max())
    return HillResult(ex, lam, mean_index, max_real, bool(max_real < opts.rel_tol * w))


def verdict_from_eigenvalues(hill_eigenvalues: np.ndarray, n: int, w: float, rel_tol: float):
    """The verdict of :func:`hill_stability` decided from the Hill eigenvalues alone.

    The filter (:func:`select_exponents`) needs eigenvectors only to choose among more than
    ``2 n`` in-strip eigenvalues; the verdict does not depend on that choice when no in-strip
    eigenvalue is unstable (``Re >= rel_tol * w``), or when there are more unstable ones
    than can be left out.  With fewer than ``2 n`` in the strip every in-strip eigenvalue is
    kept and the fill-ins are chosen by ``|Im|`` alone.

    Parameters
    ----------
    hill_eigenvalues : ndarray of complex, shape (m,)
        All eigenvalues of the truncated Hill problem, in the order LAPACK returns them
        (it breaks ties of the fill-in order, as in :func:`select_exponents`).
    n : int
        Number of DOFs.
    w : float
        Angular frequency, rad/s.
    rel_tol : float
        :attr:`StabilityOptions.rel_tol`.

    Returns
    -------
    bool or None
        ``HillResult.stable`` of the same eigenvalues, or ``None`` when it depends on the
        eigenvectors (or on how a tie in the fill-in order is broken).
    """
    lam = hill_eigenvalues
    k = min(2 * n, lam.size)
    im = lam.imag
    inside = (im > -0.5 * w) & (im <= 0.5 * w)
    bad = ~(lam.real < rel_tol * w)                  # fails max_real < rel_tol * w
    m_in = int(inside.sum())
    bad_in = int((bad & inside).sum())
    if m_in >= k:
        # the kept ones are k of the m_in in-strip eigenvalues
        if bad_in == 0:
            return True
        return False if bad_in > m_in - k else None
    if bad_in:
        return False
    # every in-strip one is kept, plus the first k - m_in outside in select_exponents' order
    out = np.flatnonzero(~inside)
    key = np.round(np.abs(im[out]) / w, 9)
    order = np.lexsort((out, key))
    n_fill = k - m_in
    last = key[order[n_fill - 1]]
    tie = key == last
    if np.any(bad[out[tie]]) and not np.all(bad[out[tie]]):
        return None                                  # the choice inside a tie decides
    return not np.any(bad[out[order[:n_fill]]])


def hill_is_stable(J: np.ndarray, M: np.ndarray, C: np.ndarray, basis: FourierBasis, w: float,
                   options: StabilityOptions | None = None) -> bool:
    """``hill_stability(J, M, C, basis, w, options).stable``, computed without eigenvectors
    whenever :func:`verdict_from_eigenvalues` can decide it (parameters as there).

    LAPACK's ``geev`` runs the same reduction and QR iteration with and without vectors, so
    the eigenvalues are those :func:`hill_stability` filters; when the verdict depends on
    the eigenvectors this falls back to :func:`hill_stability`.
    """
    opts = options or StabilityOptions()
    if M.shape[0] == 0:
        return True
    A = hill_matrix(J, M, C, basis, w)
    if not np.all(np.isfinite(A)):
        return hill_stability(J, M, C, basis, w, opts).stable      # raises as eig does
    lam = sla.eigvals(A, overwrite_a=True, check_finite=False)
    verdict = verdict_from_eigenvalues(lam, M.shape[0], w, opts.rel_tol)
    if verdict is None:
        return hill_stability(J, M, C, basis, w, opts).stable
    return verdict
