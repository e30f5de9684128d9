r"""Compiled kernels of the condensed linear part (:mod:`hbm.balance.condensed`), all harmonics in one call.

Modal receptances (proportional damping), for every ``W_k = h_k w``:

.. math::

    H(W) = \sum_r \frac{\phi_r \phi_r^T}{d_r(W)} + R, \qquad
    d_r = \omega_r^2 - W^2 + i W c_r, \qquad
    \frac{dH}{dW} = \sum_r \frac{2W - i c_r}{d_r^2}\, \phi_r \phi_r^T .

Condensed stiffness and its real block form on the unknown vector (:mod:`hbm.model.real_blocks`):

.. math::

    Z = H_{cc}^{-1}, \qquad Z' = -Z H_{cc}' Z, \qquad
    J_h = \begin{bmatrix} \mathrm{Re} Z & \mathrm{Im} Z \\ -\mathrm{Im} Z & \mathrm{Re} Z\end{bmatrix},
    \quad dJ_h = h \begin{bmatrix} \mathrm{Re} Z' & \mathrm{Im} Z' \\ -\mathrm{Im} Z' & \mathrm{Re} Z'\end{bmatrix},

(``J_0 = Re Z`` for the mean) and the equivalent load of a unit cosine force at harmonic 1,
``Fc - i Fs = Z H_ce``, ``d/dw = Z' H_ce + Z H_ce'``.  The inverse is Gauss-Jordan
elimination with partial pivoting.
"""
from __future__ import annotations

import numba as nb
import numpy as np


@nb.njit(cache=True)
def modal_receptances(Pu, ia, ib, p, om2, c, Ru, Ws):
    """``H(W)`` and ``dH/dW`` for proportional damping (module doc), from one product over the
    modes of the upper triangle (``H`` is symmetric).

    Parameters
    ----------
    Pu : ndarray, shape (m, n_t)
        Outer products ``phi_r[a] phi_r[b]`` of the modes for the ``n_t`` pairs ``a <= b``.
    ia, ib : ndarray of int, shape (n_t,)
        The pairs (row, column) of the upper triangle.
    p : int
        Number of coordinates.
    om2, c : ndarray, shape (m,)
        Squared natural frequencies and modal damping ``2 zeta_r omega_r``.
    Ru : ndarray, shape (n_t,)
        Residual flexibility on the pairs.
    Ws : ndarray, shape (n_W,)

    Returns
    -------
    H, dH : ndarray, complex, shape (n_W, p, p)
    """
    m = Pu.shape[0]
    nW = Ws.size
    A = np.empty((4 * nW, m))           # Re, Im of 1/d_r and of d(1/d_r)/dW, per W
    for k in range(nW):
        W = Ws[k]
        for r in range(m):
            inv = 1.0 / (om2[r] - W * W + 1j * W * c[r])
            dinv = (2.0 * W - 1j * c[r]) * inv * inv
            A[k, r] = inv.real
            A[nW + k, r] = inv.imag
            A[2 * nW + k, r] = dinv.real
            A[3 * nW + k, r] = dinv.imag
    S = A @ Pu
    H = np.empty((nW, p, p), dtype=np.complex128)
    dH = np.empty((nW, p, p), dtype=np.complex128)
    for k in range(nW):
        for j in range(ia.size):
            a, b = ia[j], ib[j]
            h = (S[k, j] + Ru[j]) + 1j * S[nW + k, j]
            dh = S[2 * nW + k, j] + 1j * S[3 * nW + k, j]
            H[k, a, b] = h
            H[k, b, a] = h
            dH[k, a, b] = dh
            dH[k, b, a] = dh
    return H, dH


@nb.njit(cache=True)
def _invert(A, out):
    """``out = A^{-1}`` (n, n) complex by Gauss-Jordan with partial pivoting (on ``|Re| + |Im|``,
    as LAPACK); False when a pivot is exactly zero (singular)."""
    n = A.shape[0]
    M = A.copy()
    for i in range(n):
        for j in range(n):
            out[i, j] = 1.0 if i == j else 0.0
    for col in range(n):
        piv = col
        best = abs(M[col, col].real) + abs(M[col, col].imag)
        for i in range(col + 1, n):
            v = abs(M[i, col].real) + abs(M[i, col].imag)
            if v > best:
                best, piv = v, i
        if best == 0.0:
            return False
        if piv != col:
            for j in range(n):
                M[col, j], M[piv, j] = M[piv, j], M[col, j]
                out[col, j], out[piv, j] = out[piv, j], out[col, j]
        d = 1.0 / M[col, col]
        for j in range(n):
            M[col, j] *= d
            out[col, j] *= d
        for i in range(n):
            if i != col:
                f = M[i, col]
                if f != 0.0:
                    for j in range(n):
                        M[i, j] -= f * M[col, j]
                        out[i, j] -= f * out[col, j]
    return True


@nb.njit(cache=True)
def condensed_linear(H, dH, hs, rows, nc, ie, i1):
    """Condensed stiffness per harmonic, its frequency derivative and the equivalent load.

    Parameters
    ----------
    H, dH : ndarray, complex, shape (n_h, p, p)
        Receptances at ``W = h w`` between the kept coordinates; the first ``nc`` are the
        contact coordinates.
    hs : ndarray, shape (n_h,)
        Harmonic numbers (float).
    rows : ndarray of int, shape (n_h,)
        Row of each harmonic's cosine (or mean) coefficient; the sine row follows it.
    nc : int
        Number of contact coordinates.
    ie : int
        Index of the excitation coordinate in ``H``.
    i1 : int
        Position of harmonic 1 in ``hs``.

    Returns
    -------
    ok : bool
        False when a contact receptance is singular.
    Z, hdZ : ndarray, complex, shape (n_h, nc, nc)
        ``H_cc^{-1}`` and ``h dZ/dW`` per harmonic.
    FF : ndarray, shape (2, n_coef nc)
        ``F_eq`` and ``dF_eq/dw``.
    """
    nh = hs.size
    nco = 0
    for k in range(nh):
        nco += 1 if hs[k] == 0.0 else 2
    Z = np.zeros((nh, nc, nc), dtype=np.complex128)
    dZ = np.zeros((nh, nc, nc), dtype=np.complex128)
    FF = np.zeros((2, nco * nc))
    F, dF = FF[0], FF[1]
    T = np.empty((nc, nc), dtype=np.complex128)
    for k in range(nh):
        if not _invert(H[k, :nc, :nc], Z[k]):
            return False, Z, dZ, FF
        for a in range(nc):                      # T = Z H'
            for b in range(nc):
                s = 0j
                for q in range(nc):
                    s += Z[k, a, q] * dH[k, q, b]
                T[a, b] = s
        for a in range(nc):                      # dZ = -T Z
            for b in range(nc):
                s = 0j
                for q in range(nc):
                    s += T[a, q] * Z[k, q, b]
                dZ[k, a, b] = -s
    c0 = rows[i1] * nc
    for a in range(nc):
        t = 0j
        dt = 0j
        for q in range(nc):
            t += Z[i1, a, q] * H[i1, q, ie]
            dt += dZ[i1, a, q] * H[i1, q, ie] + Z[i1, a, q] * dH[i1, q, ie]
        F[c0 + a] = t.real
        F[c0 + nc + a] = -t.imag
        dF[c0 + a] = dt.real
        dF[c0 + nc + a] = -dt.imag
    for k in range(nh):
        dZ[k] *= hs[k]
    return True, Z, dZ, FF


@nb.njit(cache=True)
def proportional_linear(Pu, ia, ib, p, om2, c, Ru, hs, w, rows, nc, ie, i1):
    """:func:`modal_receptances` at ``W = h w`` followed by :func:`condensed_linear`, one call.

    Returns
    -------
    ok, H, dH, Z, hdZ, FF
    """
    H, dH = modal_receptances(Pu, ia, ib, p, om2, c, Ru, hs * w)
    ok, Z, hdZ, FF = condensed_linear(H, dH, hs, rows, nc, ie, i1)
    return ok, H, dH, Z, hdZ, FF


@nb.njit(cache=True)
def assemble(Z, hs, rows, F0, dF0, x, Fn, dFw, J, R, dRw):
    """Residual ``R = Z U - F0 + Fn``, ``dR/dw = dFw - dF0`` (the caller adds ``h Z' U``) and ``J += J_Z``, written
    into ``R`` and ``dRw`` (n_u,) and added to ``J`` (n_u, n_u), which holds the nonlinear
    forces' Jacobian on entry (views allowed); ``J_Z`` is ``Z`` in real block form per harmonic
    (module doc).  No ``n_u x n_u`` matrix of the linear part is formed.

    Parameters
    ----------
    Z : ndarray, complex, shape (n_h, n_c, n_c)
        Condensed stiffness per harmonic.
    hs : ndarray, shape (n_h,)
    rows : ndarray of int, shape (n_h,)
        Cosine (or mean) row of each harmonic; the sine row follows it.
    F0, dF0 : ndarray, shape (n_u,)
        Equivalent load and its ``w``-derivative.
    x : ndarray, shape (n_u,)
        Unknowns (coefficient-major: ``x[row * n_c + a]``).
    Fn, dFw : ndarray, shape (n_u,)
        Nonlinear forces and their ``w``-derivative on all unknowns.
    """
    nh, nc = Z.shape[0], Z.shape[1]
    for i in range(x.size):
        R[i] = Fn[i] - F0[i]
        dRw[i] = dFw[i] - dF0[i]
    for k in range(nh):
        c0 = rows[k] * nc
        if hs[k] == 0.0:
            for a in range(nc):
                r = 0.0
                for b in range(nc):
                    z = Z[k, a, b].real
                    J[c0 + a, c0 + b] += z
                    r += z * x[c0 + b]
                R[c0 + a] += r
            continue
        s0 = c0 + nc
        for a in range(nc):
            rc, rs = 0.0, 0.0
            for b in range(nc):
                zr, zi = Z[k, a, b].real, Z[k, a, b].imag
                J[c0 + a, c0 + b] += zr
                J[c0 + a, s0 + b] += zi
                J[s0 + a, c0 + b] -= zi
                J[s0 + a, s0 + b] += zr
                xc, xs = x[c0 + b], x[s0 + b]
                rc += zr * xc + zi * xs
                rs += zr * xs - zi * xc
            R[c0 + a] += rc
            R[s0 + a] += rs
