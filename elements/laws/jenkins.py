r"""Jenkins element: a spring ``kt`` in series with a Coulomb slider of limit ``fs``.

Incremental return mapping over one step (elastic predictor, return onto the slip limit):

.. math::

    f^{trial} = f_{prev} + k_t (u - u_{prev}), \qquad
    f = \begin{cases} f^{trial} & |f^{trial}| \le f_s \ \text{(stick)} \\
                      f_s \,\mathrm{sign}(f^{trial}) & \text{(slip)} \end{cases}

State ``s = [f, u_prev]``, input ``z = [u]``, parameters ``p = [kt, fs]``.  The rest state
at a displacement ``u0`` reached from ``q = 0`` without reversal is ``f = clip(kt u0, -fs, fs)``:
a motion that never slips keeps the slider where it started (``f = kt u``), which makes the
stuck state unique.
"""
from __future__ import annotations

import numba as nb


@nb.njit(cache=True, inline="always")
def jenkins_step(p, s, z, s_new, A, B):
    """One return-mapping step; writes ``s_new``, ``A = ds_new/ds`` (2, 2), ``B = ds_new/dz`` (2, 1)
    (every entry: no zeroing of A and B per sample)."""
    kt = p[0]
    fs = p[1]
    u = z[0]
    ft = s[0] + kt * (u - s[1])
    if abs(ft) <= fs:
        s_new[0] = ft
        A[0, 0] = 1.0
        A[0, 1] = -kt
        B[0, 0] = kt
    else:
        s_new[0] = fs if ft > 0.0 else -fs
        A[0, 0] = 0.0
        A[0, 1] = 0.0
        B[0, 0] = 0.0
    A[1, 0] = 0.0
    A[1, 1] = 0.0
    s_new[1] = u
    B[1, 0] = 1.0


@nb.njit(cache=True, inline="always")
def jenkins_init(p, z0, s0, C0):
    """Rest state reached at ``z0`` from ``q = 0``; ``C0 = ds0/dz0`` (2, 1)."""
    kt = p[0]
    fs = p[1]
    f = kt * z0[0]
    C0[:, :] = 0.0
    if abs(f) <= fs:
        s0[0] = f
        C0[0, 0] = kt
    else:
        s0[0] = fs if f > 0.0 else -fs
    s0[1] = z0[0]
    C0[1, 0] = 1.0


@nb.njit(cache=True, inline="always")
def jenkins_linear(p, z, K, f0):
    """True when the slider sticks at every sample from rest (``|kt u| <= fs``): ``f = kt u``."""
    kt = p[0]
    fs = p[1]
    for j in range(z.shape[0]):
        if abs(kt * z[j, 0]) > fs:
            return False
    K[0, 0] = kt
    f0[0] = 0.0
    return True
