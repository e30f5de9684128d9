r"""Linear solves of the Newton corrector: direct LU, or GMRES on an LU kept from an earlier matrix.

Every Newton update solves the bordered system :math:`A \delta = b` (:mod:`continuation.corrector`).
Between neighbouring iterations and steps of a path :math:`A` changes little (a few contacts
change between stick and slip), so for large systems an LU factorisation ``P L U = A_0`` of an
earlier matrix preconditions GMRES on the current one (right preconditioning):

.. math::

    A M^{-1} y = b, \qquad \delta = M^{-1} y, \qquad M = A_0 ,

stopped when :math:`\|b - A\delta\|_2 \le \epsilon \|b\|_2`.  Each Krylov iteration costs a
product with :math:`A` and a triangular solve, :math:`O(n^2)`, instead of the
:math:`O(n^3)` of a new factorisation.  When GMRES does not reach :math:`\epsilon` within
``max_krylov`` iterations the current matrix is factored and solved directly (exact), and
its LU becomes the new preconditioner.  An accepted point is still decided by the
corrector's residual test on the exact residual, so a Krylov update changes at most how
fast Newton converges, never what it converges to.

When the caller knows blocks of unknowns that are coupled only weakly (harmonic balance:
the linear part couples only the cosine and sine of one harmonic, and the harmonics meet
only through the nonlinear Jacobian of the contacts that slip), :class:`BlockPreconditioned`
first tries the block-diagonal part of the *current* matrix, with the border row and column
of a bordered system eliminated exactly:

.. math::

    M = \begin{bmatrix} J_b & c \\ r^T & d \end{bmatrix}, \quad
    M^{-1} v = \begin{bmatrix} y_1 - y_2 \xi \\ \xi \end{bmatrix}, \quad
    y_1 = J_b^{-1} v_{1:n},\ y_2 = J_b^{-1} c,\
    \xi = \frac{v_{n+1} - r^T y_1}{d - r^T y_2},

``J_b`` the diagonal blocks of ``J``, each factored by LU.  When the off-block entries are
zero (every contact stuck: the system is linear) ``M = A`` and GMRES stops after one
iteration; each slipping contact adds a few.  Factoring blocks of size ``n / n_b`` costs
about ``n_b^2`` times less than a full LU.

A caller that can apply an approximate inverse of its (unscaled) Jacobian without
factoring anything per iteration (:class:`Structure`; e.g. a condensed balance with every
contact stuck, :mod:`hbm.balance.stuck_inverse`) has it tried first in place of ``J_b^{-1}``,
``J_s^{-1} = diag(s)^{-1} J^{-1}`` for a matrix scaled by columns.  When it fails, the blocks
take over for :data:`APPROXIMATE_PAUSE` calls.  Measured on an FE patch (H = 3, 20 N):
64 contacts, FRF 8.6 -> 6.6 s (the block LUs were a quarter of it); 16 contacts 1.45 -> 1.34
s; 16 contacts all slipping (1 kN) 2.5 -> 3.0 s (9.4 GMRES iterations per solve against 8.3).
"""
from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np
from scipy.linalg import LinAlgWarning, lu_factor, lu_solve
from scipy.linalg.lapack import dgesv, dgetrs

REUSE_MIN_SIZE = 800      # below this a fresh LU is cheaper than a few Krylov iterations
BLOCK_MIN_SIZE = 250      # below this a fresh LU is cheaper than block LUs and a Krylov step
APPROXIMATE_PAUSE = 8     # calls that skip a caller's approximate inverse after it failed
# when the blocks pay (_blocks_pay): one block's solve costs about BLOCK_SECONDS whatever its
# size up to 100 rows (scipy's call, measured 11-15 us), a solve takes about KRYLOV_STEPS
# preconditioned steps, and LAPACK's dense LU solve runs at about DENSE_RATE n^3 per second
# on one thread (measured 3.1e10 at 306 unknowns, 3.6e10 at 500)
BLOCK_SECONDS = 15e-6
KRYLOV_STEPS = 8
DENSE_RATE = 3e10


def _usable(lu) -> bool:
    """An LU factor (``lu_factor``'s) that is finite and has no zero pivot."""
    return bool(np.all(np.isfinite(lu[0])) and not np.any(np.diag(lu[0]) == 0.0))


def direct_solve(A: np.ndarray, B: np.ndarray):
    """``A^{-1} B`` by LU (LAPACK ``dgesv``; ``A`` is overwritten when Fortran-ordered, ``B``
    is not), None if ``A`` is exactly singular.  ``np.linalg.solve`` costs about 20 us more
    per call in wrapping, a sizeable part of a small problem's continuation step."""
    _, _, x, info = dgesv(A, B, overwrite_a=True, overwrite_b=False)
    return x if info == 0 else None


direct_solve.order = "F"


class ReusedLU:
    """Solver of ``A X = B`` that keeps an LU for later matrices (module docstring).

    ``A`` may be C- or Fortran-ordered: a C-ordered ``A`` is factored as the Fortran-ordered
    ``A^T`` it is in memory (no transposed copy) and solved with ``trans = 1``, so callers
    fill it row by row (:attr:`order`).

    Parameters
    ----------
    rtol : float
        Relative residual at which GMRES stops (:math:`\\epsilon`).
    max_krylov : int
        Krylov iterations per right-hand side before a new factorisation.

    Attributes
    ----------
    factorisations, krylov_iterations : int
        Counts, for benchmarks.
    """

    order = "C"

    def __init__(self, rtol: float = 1e-7, max_krylov: int = 20):
        self.rtol, self.max_krylov = rtol, max_krylov
        self._lu = None
        self._trans = 0
        self.factorisations = 0
        self.krylov_iterations = 0

    def __call__(self, A: np.ndarray, B: np.ndarray):
        """``A^{-1} B`` for ``A`` (n, n) and ``B`` (n, k); None if ``A`` is singular.  ``A`` is not
        changed: the kept LU is a copy, since callers refill ``A`` for the next iteration."""
        if self._lu is not None and self._lu[0].shape == A.shape:
            lu, piv = self._lu
            X = self._krylov(A, B, lambda v: dgetrs(lu, piv, v, trans=self._trans)[0])
            if X is not None:
                return X
        return self._factor(A, B)

    def _krylov(self, A, B, pre):
        """Every column of ``A^{-1} B`` by :meth:`_gmres` on the preconditioner ``pre``; None
        as soon as one does not converge."""
        X = np.empty(B.shape)
        for j in range(B.shape[1]):
            x = self._gmres(A, B[:, j], pre)
            if x is None:
                return None
            X[:, j] = x
        return X

    def _factor(self, A, B):
        trans = 1 if A.flags.c_contiguous and not A.flags.f_contiguous else 0
        self._lu = None                      # not held while the next one is made
        try:
            with warnings.catch_warnings():      # a singular matrix is answered by None
                warnings.simplefilter("ignore", LinAlgWarning)
                lu = lu_factor(A.T if trans else A, overwrite_a=False, check_finite=False)
        except (ValueError, np.linalg.LinAlgError):
            return None
        if not _usable(lu):
            return None
        self._lu, self._trans = lu, trans
        self.factorisations += 1
        return lu_solve(lu, B, trans=trans, check_finite=False)

    def _gmres(self, A, b, pre):
        """Right-preconditioned GMRES from zero, ``pre(v) = M^{-1} v``; None when ``max_krylov``
        iterations do not reach the tolerance."""
        beta = np.linalg.norm(b)
        if beta == 0.0:
            return np.zeros_like(b)
        m = self.max_krylov
        V = np.empty((m + 1, b.size))
        Hh = np.zeros((m + 1, m))
        V[0] = b / beta
        g = np.zeros(m + 1)
        g[0] = beta
        cs, sn = np.zeros(m), np.zeros(m)
        Zs = np.empty((m, b.size))
        for k in range(m):
            Zs[k] = pre(V[k])
            w = A @ Zs[k]
            Vk = V[:k + 1]
            h = Vk @ w                               # classical Gram-Schmidt, twice (CGS2):
            w -= h @ Vk                              # as stable as modified Gram-Schmidt
            c = Vk @ w                               # twice, in matrix-vector products
            w -= c @ Vk
            Hh[:k + 1, k] = h + c
            Hh[k + 1, k] = np.linalg.norm(w)
            if Hh[k + 1, k] > 0.0:
                V[k + 1] = w / Hh[k + 1, k]
            for i in range(k):                       # previous Givens rotations
                t = cs[i] * Hh[i, k] + sn[i] * Hh[i + 1, k]
                Hh[i + 1, k] = -sn[i] * Hh[i, k] + cs[i] * Hh[i + 1, k]
                Hh[i, k] = t
            r = np.hypot(Hh[k, k], Hh[k + 1, k])
            if r == 0.0:
                return None
            cs[k], sn[k] = Hh[k, k] / r, Hh[k + 1, k] / r
            Hh[k, k], Hh[k + 1, k] = r, 0.0
            g[k + 1] = -sn[k] * g[k]
            g[k] = cs[k] * g[k]
            self.krylov_iterations += 1
            if abs(g[k + 1]) <= self.rtol * beta:
                y = np.linalg.solve(np.triu(Hh[:k + 1, :k + 1]), g[:k + 1])
                return y @ Zs[:k + 1]
        return None


class BlockPreconditioned(ReusedLU):
    """:class:`ReusedLU` that first tries GMRES preconditioned by the diagonal blocks of the
    current matrix (module docstring), then the kept LU, then a new factorisation.

    Parameters
    ----------
    blocks : sequence of (int, int) or (int, int, bool)
        ``(start, stop)`` of each block; together they cover ``0 .. n`` in order.  A matrix of
        size ``n + 1`` is taken as bordered (last row and column eliminated exactly).  A third
        entry True marks a *paired* block, ``[[A, B], [C, D]]`` on the real and imaginary parts
        of ``m`` complex unknowns (e.g. cosine and sine coefficients): it is preconditioned by
        the complex ``m x m`` matrix ``(A + D)/2 - i (B - C)/2``, exact when ``D = A`` and
        ``C = -B`` (an operator that does not vary over the period), at half the cost of a
        real LU of ``2m``.
    rtol, max_krylov
        As :class:`ReusedLU`.

    Attributes
    ----------
    block_solves : int
        Right-hand sides solved on the block preconditioner (for benchmarks).
    """

    def __init__(self, blocks, rtol: float = 1e-7, max_krylov: int = 20, approximate=None, scale=None):
        super().__init__(rtol, max_krylov)
        self.blocks = [(int(b[0]), int(b[1])) for b in blocks]
        self.paired = [len(b) > 2 and bool(b[2]) and (b[1] - b[0]) % 2 == 0 for b in blocks]
        if not self.blocks or self.blocks[0][0] != 0 or any(
                b0[1] != b1[0] or b1[1] <= b1[0] for b0, b1 in zip(self.blocks, self.blocks[1:])):
            raise ValueError("blocks must be consecutive, non-empty ranges from 0")
        self.n = self.blocks[-1][1]
        self.approximate = approximate
        self._unscale = None if scale is None else 1.0 / np.asarray(scale, dtype=float)[:self.n]
        self._skip = 0
        self.block_solves = 0
        self.approximate_solves = 0

    def __call__(self, A: np.ndarray, B: np.ndarray):
        square = A.shape[0] in (self.n, self.n + 1)
        if square and self.approximate is not None:
            X = self._on_approximate(A, B)
            if X is not None:
                self.approximate_solves += B.shape[1]
                return X
        pre = self._bordered(A, self._block_inverse(A)) if square else None
        X = None if pre is None else self._krylov(A, B, pre)
        if X is not None:
            self.block_solves += B.shape[1]
            return X
        return super().__call__(A, B)

    def _on_approximate(self, A, B):
        """GMRES on the caller's approximate inverse; after a failure it is skipped for
        :data:`APPROXIMATE_PAUSE` calls (a stretch of slipping contacts)."""
        if self._skip:
            self._skip -= 1
            return None
        inv = self.approximate()
        if inv is None:
            return None
        u = self._unscale
        pre = self._bordered(A, inv if u is None else (lambda v: inv(v) * u))
        X = None if pre is None else self._krylov(A, B, pre)
        if X is None:
            self._skip = APPROXIMATE_PAUSE
        return X

    def _block_inverse(self, A):
        """``v -> J_b^{-1} v`` for the diagonal blocks ``J_b`` of ``A``'s first ``n`` rows and
        columns, or None when a block is singular."""
        lus = []
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", LinAlgWarning)
            for (a, b), paired in zip(self.blocks, self.paired):
                Ab = A[a:b, a:b]
                if paired:
                    m = (b - a) // 2
                    Ab = 0.5 * (Ab[:m, :m] + Ab[m:, m:]) - 0.5j * (Ab[:m, m:] - Ab[m:, :m])
                lu = lu_factor(Ab, check_finite=False)
                if not _usable(lu):
                    return None
                lus.append(lu)

        def solve_blocks(v):
            y = np.empty(self.n)
            for (a, b), paired, (lu, piv) in zip(self.blocks, self.paired, lus):
                if paired:
                    m = (b - a) // 2
                    z = lu_solve((lu, piv), v[a:a + m] + 1j * v[a + m:b], check_finite=False)
                    y[a:a + m], y[a + m:b] = z.real, z.imag
                else:
                    y[a:b] = dgetrs(lu, piv, v[a:b])[0]
            return y

        return solve_blocks

    def _bordered(self, A, solve):
        """``v -> M^{-1} v`` from ``solve`` (``v -> J_b^{-1} v`` on the first ``n`` unknowns),
        with the border of a bordered ``A`` (``n + 1`` rows) eliminated exactly (module doc);
        None when ``solve`` is None or the border's pivot is singular."""
        n = self.n
        if solve is None or A.shape[0] == n:
            return solve
        r, d = A[n, :n], A[n, n]
        y2 = solve(np.ascontiguousarray(A[:n, n]))
        s = d - r @ y2
        if not np.isfinite(s) or abs(s) <= 1e-13 * (abs(d) + np.abs(r) @ np.abs(y2)):
            return None

        def solve_bordered(v):
            y1 = solve(v[:n])
            xi = (v[n] - r @ y1) / s
            return np.r_[y1 - y2 * xi, xi]

        return solve_bordered


class Structure(NamedTuple):
    """What a caller knows of its Jacobian beyond its size.

    Attributes
    ----------
    blocks : list of (int, int, bool)
        As :class:`BlockPreconditioned`'s.
    approximate : callable or None
        ``() -> (v (n,) -> y (n,))``: an approximate inverse of the unscaled Jacobian last
        evaluated (e.g. :class:`hbm.balance.stuck_inverse.StuckInverse`), or None when there
        is none yet; tried before the blocks.
    """

    blocks: list
    approximate: object = None


def make_solver(n: int, blocks=None, scale=None):
    """The linear solver for systems of ``n`` unknowns: :class:`BlockPreconditioned` on
    ``blocks`` (``(start, stop)`` ranges of the unknowns, or a :class:`Structure`, whose
    approximate inverse is then tried first on matrices scaled by columns by ``scale``)
    when given, ``n`` reaches :data:`BLOCK_MIN_SIZE` and the blocks pay (:func:`_blocks_pay`,
    or an approximate inverse is given), else :class:`ReusedLU` from
    :data:`REUSE_MIN_SIZE`, else :func:`direct_solve`.  (Measured on a 16-contact FE patch,
    336 unknowns: FRF 2.06 s direct, 1.66 s on the blocks; at 84 and 168 unknowns the direct
    LU is 20 % and 12 % faster.)"""
    approximate = None
    if isinstance(blocks, Structure):
        blocks, approximate = blocks
    if blocks and n >= BLOCK_MIN_SIZE and (approximate is not None or _blocks_pay(n, blocks)):
        return BlockPreconditioned(blocks, approximate=approximate, scale=scale)
    return ReusedLU() if n >= REUSE_MIN_SIZE else direct_solve


def _blocks_pay(n: int, blocks) -> bool:
    """Whether ``KRYLOV_STEPS`` steps preconditioned by one solve per block cost less than a
    dense LU solve of ``n`` unknowns.  Many small blocks do not pay: the railcar rig (6 DOFs,
    H = 25: 306 unknowns in 26 blocks) traced 36-40 Hz in 72.5 s on the blocks and in 38.8 s
    by dense LUs; a 16-contact patch at H = 3 (336 unknowns in 4 blocks) is faster on them."""
    return len(blocks) * BLOCK_SECONDS * KRYLOV_STEPS < n ** 3 / DENSE_RATE
