r"""Unilateral spring with a gap: a contact that pushes back only once it is closed.

.. math::

    f = k \max(u - g, 0), \qquad \frac{df}{du} = k\,[u > g]

for the coordinate ``u`` (a DOF, or a relative motion) and the gap ``g``: ``g > 0`` is open at
rest, ``g < 0`` an interference (preloaded at rest, ``f = -k g``).  Memoryless: state
``s = [f]``, input ``z = [u]``, parameters ``p = [k, g]``.  NLvib's ``unilateralSpring`` is this
law (its examples 03 and 07).

Describing function (first harmonic of ``f`` for ``u = a cos(theta)``, ``|g| < a``, with
``cos(beta) = g / a``): ``f_1 = (k a / pi) (beta - sin(beta) cos(beta))`` and the mean
``f_0 = (k a / pi) (sin(beta) - beta cos(beta))``.
"""
from __future__ import annotations

import numba as nb
import numpy as np

from .record import LawRecord


@nb.njit(cache=True, inline="always")
def unilateral_step(p, s, z, s_new, A, B):
    """``f = k max(u - g, 0)``; writes ``s_new`` (1,), ``A`` (1, 1) = 0, ``B`` (1, 1)."""
    d = z[0] - p[1]
    if d > 0.0:
        s_new[0] = p[0] * d
        B[0, 0] = p[0]
    else:
        s_new[0] = 0.0
        B[0, 0] = 0.0
    A[0, 0] = 0.0


@nb.njit(cache=True, inline="always")
def unilateral_init(p, z0, s0, C0):
    """Rest state at ``z0`` (memoryless: the law itself); ``C0 = df/dz0`` (1, 1)."""
    d = z0[0] - p[1]
    s0[0] = p[0] * d if d > 0.0 else 0.0
    C0[0, 0] = p[0] if d > 0.0 else 0.0


@nb.njit(cache=True, inline="always")
def unilateral_linear(p, z, K, f0):
    """True when every sample is on one side of the gap: ``f = f0 + K u`` with ``K = k``,
    ``f0 = -k g`` (closed) or ``K = 0``, ``f0 = 0`` (open)."""
    n_closed = 0
    for j in range(z.shape[0]):
        if z[j, 0] > p[1]:
            n_closed += 1
    if n_closed == 0:
        K[0, 0] = 0.0
        f0[0] = 0.0
        return True
    if n_closed == z.shape[0]:
        K[0, 0] = p[0]
        f0[0] = -p[0] * p[1]
        return True
    return False


def _rest_tangent(p: np.ndarray):
    """Closed at rest (``g < 0``): ``k``; open or touching: 0."""
    return (float(p[0]) if p[1] < 0.0 else 0.0), 0.0


LAW = LawRecord(
    name="unilateral_spring",
    params=(("k", "positive", "contact stiffness once closed, N/m"),
            ("gap", "finite", "gap at rest, m: > 0 open, < 0 interference (f = k max(u - gap, 0))")),
    n_state=1, rest_tangent=_rest_tangent, needs_mean=True,
    default_harmonics=7, default_samples_factor=2,     # as Jenkins (piecewise linear); not measured
    summary="One-sided spring with a gap, f = k max(u - gap, 0)")
