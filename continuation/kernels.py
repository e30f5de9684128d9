r"""Compiled arithmetic of one corrector iteration and one accepted step.

Scaled Jacobian and its measures (:mod:`continuation.corrector`):

.. math::

    J_s = J\,\mathrm{diag}(s), \qquad \|J_s\|_\infty = \max_i \sum_j |J_{s,ij}|, \qquad
    \|R\|_\infty,

and the bordered Newton system with one or two right-hand sides,

.. math::

    A = \begin{bmatrix} J_s \\ \rho\, a^T \end{bmatrix}, \qquad
    B = \begin{bmatrix} -R & 0 \\ -\rho\, g & \rho \end{bmatrix}.

These are a handful of small array operations each; done one NumPy call at a time they cost
more than the arithmetic (about 1 us per call against a few ns per entry), which for a
problem of 50 unknowns made the continuation's own work as large as the residual's.
"""
from __future__ import annotations

import math

import numba as nb


@nb.njit(cache=True)
def scale_jacobian(R, J, scale, Js):
    """``Js = J * scale`` and the norms of the convergence test, in one pass.

    Parameters
    ----------
    R : ndarray, shape (n,)
    J : ndarray, shape (n, n+1)
    scale : ndarray, shape (n+1,)
    Js : ndarray, shape (n, n+1)
        Written.

    Returns
    -------
    row_norm : float
        ``||Js||_inf``.
    r_max : float
        ``||R||_inf``.
    finite : bool
        No NaN or inf in ``R`` and ``Js`` (nor an overflowing row sum).
    """
    n, m = J.shape
    finite = True
    norm = 0.0
    for i in range(n):
        s = 0.0
        for j in range(m):
            v = J[i, j] * scale[j]
            Js[i, j] = v
            s += abs(v)
        if not math.isfinite(s):
            finite = False
        elif s > norm:
            norm = s
    r_max = 0.0
    for i in range(R.size):
        v = abs(R[i])
        if not math.isfinite(v):
            finite = False
        elif v > r_max:
            r_max = v
    return norm, r_max, finite


@nb.njit(cache=True)
def bordered_system(Js, R, a, rho, g, A, B):
    """Fill the Newton matrix ``A`` (n+1, n+1) and right-hand sides ``B`` (n+1, k), k = 1 or 2
    (the second column gives the null vector of ``Js``; module doc)."""
    n, m = Js.shape
    for i in range(n):                  # row by row: Js is C-ordered (A is either)
        for j in range(m):
            A[i, j] = Js[i, j]
    border_rows(R, a, rho, g, A, B)


@nb.njit(cache=True)
def border_rows(R, a, rho, g, A, B):
    """The constraint row of ``A`` (n+1, n+1) (whose first ``n`` rows already hold ``Js``) and
    the right-hand sides ``B`` (n+1, k) of :func:`bordered_system`."""
    n = R.size
    k = B.shape[1]
    for j in range(n + 1):
        A[n, j] = rho * a[j]
    for i in range(n):
        B[i, 0] = -R[i]
    B[n, 0] = -rho * g
    if k > 1:
        for i in range(n):
            B[i, 1] = 0.0
        B[n, 1] = rho


@nb.njit(cache=True)
def inf_norm(x):
    """``max |x_i|``; NaN when ``x`` holds a NaN or inf."""
    r = 0.0
    for v in x:
        a = abs(v)
        if not math.isfinite(a):
            return math.nan
        if a > r:
            r = a
    return r


@nb.njit(cache=True)
def step_geometry(xs, t, new, start, u):
    """Measures of a corrected step from ``xs`` with unit tangent ``t`` to ``new``, predicted
    at ``start``, and of a candidate new tangent direction ``u``; all shape (n+1,).

    Returns
    -------
    chord_len, along, jump : float
        ``|new - xs|``, ``(new - xs) . t``, ``|new - start|``.
    cos_turn : float
        ``t_new . t`` for the unit tangent ``t_new = f u`` oriented along the chord.
    f : float
        ``+-1 / |u|`` (0 when ``u`` is zero or not finite; then ``cos_turn`` is NaN).
    """
    cl = 0.0
    along = 0.0
    jump = 0.0
    uu = 0.0
    u_chord = 0.0
    u_t = 0.0
    for i in range(xs.size):
        c = new[i] - xs[i]
        cl += c * c
        along += c * t[i]
        d = new[i] - start[i]
        jump += d * d
        v = u[i]
        uu += v * v
        u_chord += v * c
        u_t += v * t[i]
    un = math.sqrt(uu)
    if not (un > 0 and math.isfinite(un)):
        return math.sqrt(cl), along, math.sqrt(jump), math.nan, 0.0
    f = 1.0 / un if u_chord >= 0 else -1.0 / un
    return math.sqrt(cl), along, math.sqrt(jump), u_t * f, f
