r"""Cubic (Duffing) spring, ``f = k3 u^3``: a smooth, memory-less law for fold tests.

State ``s = [f]``, input ``z = [u]``, parameters ``p = [k3]``.
"""
from __future__ import annotations

import numba as nb


@nb.njit(cache=True, inline="always")
def cubic_step(p, s, z, s_new, A, B):
    """``f = k3 u^3``; writes ``s_new`` (1,), ``A`` (1, 1) = 0, ``B`` (1, 1) = 3 k3 u^2."""
    u = z[0]
    s_new[0] = p[0] * u * u * u
    A[0, 0] = 0.0
    B[0, 0] = 3.0 * p[0] * u * u


@nb.njit(cache=True, inline="always")
def cubic_init(p, z0, s0, C0):
    u = z0[0]
    s0[0] = p[0] * u * u * u
    C0[0, 0] = 3.0 * p[0] * u * u
