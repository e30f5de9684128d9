r"""Cubic (Duffing) spring, ``f = k3 u^3``: a smooth, memory-less law for fold tests.

State ``s = [f]``, input ``z = [u]``, parameters ``p = [k3]``.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from .record import LawRecord


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


def _rest_tangent(p: np.ndarray):
    """``df/du = 3 k3 u^2 = 0`` at rest."""
    return 0.0, 0.0


LAW = LawRecord(
    name="cubic",
    params=(("k3", "finite", "cubic stiffness, N/m^3: f = k3 x^3"),),
    n_state=1, rest_tangent=_rest_tangent, needs_mean=False,
    default_harmonics=3, default_samples_factor=1,      # benchmarks/default_harmonics.py
    summary="Cubic (Duffing) spring, f = k3 u^3")
