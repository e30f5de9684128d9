r"""Path tangent from the null vector of the scaled Jacobian, and fold location.

Tangent: with the scaled Jacobian :math:`J_s = J\,\mathrm{diag}(s)` of shape (n, n+1) and a
reference direction :math:`t_r` (the previous tangent), solve the bordered system

.. math::

    \begin{bmatrix} J_s \\ \rho\, t_r^T \end{bmatrix} v = \begin{bmatrix} 0 \\ \rho \end{bmatrix},
    \qquad t = v / \|v\|,

where :math:`\rho = \|J_s\|_\infty` only balances the rows.  If the system is singular the
last right singular vector of :math:`J_s` is used instead.

Fold location: between two points a distance :math:`h = \|x_{s,1} - x_{s,0}\|` apart, the
parameter is interpolated by the cubic Hermite polynomial matching
:math:`\lambda_0, \lambda_1` and the slopes :math:`d\lambda/ds = t_{\lambda,0}, t_{\lambda,1}`,

.. math::

    p(\tau) = \lambda_0 + h t_0 \tau + (3\Delta - 2 h t_0 - h t_1)\tau^2
              + (h t_0 + h t_1 - 2\Delta)\tau^3, \qquad \Delta = \lambda_1 - \lambda_0,

and the fold is :math:`p(\tau^*)` with :math:`p'(\tau^*) = 0`, :math:`\tau^* \in [0, 1]`
(exact when :math:`\lambda(s)` is quadratic near the fold).
"""
from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgesv, dgetrf, dgetrs


def null_tangent(Js: np.ndarray, t_ref: np.ndarray, work: np.ndarray | None = None,
                 rho: float | None = None, linear_solve=None) -> np.ndarray:
    """Unit null vector of ``Js`` with a positive component along ``t_ref``.

    Parameters
    ----------
    Js : ndarray, shape (n, n+1)
        Scaled Jacobian ``dR/dxs``.
    t_ref : ndarray, shape (n+1,)
        Reference direction (unit), e.g. the previous tangent.
    work : ndarray, shape (n+1, n+1), optional
        C-ordered array whose first ``n`` rows are ``Js`` (the corrector's Newton matrix,
        :attr:`continuation.corrector.Correction.matrix`): the bordered system is built and
        factored in it, so ``Js`` is consumed and no ``(n+1)^2`` array is allocated.
    rho : float, optional
        ``||Js||_inf`` when the caller has it (:meth:`continuation.corrector.Evaluation.row_norm`);
        computed otherwise.
    linear_solve : callable, optional
        With ``work``: the path's solver of its Newton systems (:mod:`continuation.linsolve`),
        ``(A, B) -> A^{-1} B`` or None, used instead of a new LU of ``work`` (a large path's
        block preconditioner solves this system as it solves the corrector's).

    Returns
    -------
    t : ndarray, shape (n+1,), or None
        Unit tangent with ``t @ t_ref >= 0``; NaN-free whenever ``Js`` is finite.  With
        ``work``, None when the bordered system is singular (without it the last right singular
        vector of ``Js`` is returned then).
    """
    n = Js.shape[0]
    if rho is None:
        rho = float(np.abs(Js).sum(axis=1).max(initial=0.0))
    rho = max(rho, 1e-300)
    rhs = np.zeros(n + 1)
    rhs[-1] = rho
    if work is not None and linear_solve is not None:
        work[n] = rho * t_ref
        v = linear_solve(work, rhs[:, None])
        v = None if v is None else v[:, 0]
    elif work is not None:
        work[n] = rho * t_ref
        lu, piv, info = dgetrf(work.T, overwrite_a=True)     # work.T is Fortran-ordered
        v = dgetrs(lu, piv, rhs, trans=1)[0] if info == 0 else None
        del lu
    else:
        A = np.empty((n + 1, n + 1), order="F")     # factored in place: one (n+1)^2 array
        A[:n] = Js
        A[n] = rho * t_ref
        _, _, v, info = dgesv(A, rhs, overwrite_a=True, overwrite_b=False)
        del A
        v = v if info == 0 else None
    if v is None or not np.all(np.isfinite(v)) or not np.any(v):
        if work is not None:
            return None         # Js is consumed: the caller decides (a shorter step)
        v = np.linalg.svd(Js)[2][-1]
    t = v / np.linalg.norm(v)
    return -t if t @ t_ref < 0 else t


def fold_parameter(lam0: float, lam1: float, m0: float, m1: float, h: float) -> float:
    """Parameter value of a fold between two points (cubic Hermite, see module doc).

    Parameters
    ----------
    lam0, lam1 : float
        Scaled parameter at the two points.
    m0, m1 : float
        Parameter components of the unit tangents (opposite signs).
    h : float
        Scaled distance between the points.

    Returns
    -------
    float
        Scaled parameter at the fold; falls back to linear interpolation of the tangent
        component when the cubic has no stationary point in ``[0, 1]``.
    """
    d = lam1 - lam0
    b = 3.0 * d - 2.0 * h * m0 - h * m1
    c = h * m0 + h * m1 - 2.0 * d
    # p'(tau) = h m0 + 2 b tau + 3 c tau^2
    roots = np.roots([3.0 * c, 2.0 * b, h * m0]) if (c or b) else np.array([])
    tau_lin = m0 / (m0 - m1) if m0 != m1 else 0.5
    good = [r.real for r in np.atleast_1d(roots)
            if abs(r.imag) < 1e-12 and -1e-9 <= r.real <= 1.0 + 1e-9]
    if good:
        tau = min(good, key=lambda r: abs(r - tau_lin))
        return lam0 + h * m0 * tau + b * tau**2 + c * tau**3
    return lam0 + tau_lin * d
