"""The time integrator's model and state tuples, and the state it starts from.

The kernels (:mod:`hbm.timedomain.time_kernels`) take ``model = (M, C, K, F2, fixed, ybase)`` and
``state = (q, v, a, fnl, S, D, Dref)``: displacements, velocities, accelerations and element
forces of the ``n`` DOFs, the laws' states ``S`` and tangent data ``D``, ``Dref``.  At the
start the acceleration balances the equations of motion at phase 0,
``M a = F(0) - C v - K q - f_nl`` (:class:`hbm.timedomain.shooting.Balance`).
"""
from __future__ import annotations

import numpy as np

from elements.base import rest_tangents

from hbm.interface.case import Case
from hbm.timedomain.shooting import Balance
from hbm.timedomain.time_kernels import element_forces, init_states
from hbm.timedomain.time_parts import Packed


def _support(case: Case):
    """``fixed`` (n,) int64 flags of the support DOFs and ``ybase`` (n,) their amplitudes."""
    n = case.n_dof
    fixed = np.zeros(n, dtype=np.int64)
    ybase = np.zeros(n)
    if case.excitation.base is not None:
        bd, ba = case.excitation.base
        fixed[np.asarray(bd, dtype=int)] = 1
        ybase[np.asarray(bd, dtype=int)] = np.asarray(ba, dtype=float)
    return fixed, ybase


class TimeState:
    """The integrator state carried between chunks (and from the n run to the 2n run).

    Start: at rest, except that support DOFs start at their prescribed position ``A`` (cosine
    at ``t = 0``, velocity 0, acceleration ``-A w^2``) and the free DOFs at the quasi-static
    position that follows it, ``K_ff q_f = -K_fs A`` with ``K`` including the elements'
    stuck stiffness (a rigid translation when the supports carry the structure), so that the
    run does not begin with a jolt.
    """

    def __init__(self, case: Case, packed: Packed, w: float = 0.0):
        n = case.n_dof
        K = case.model.K
        fixed, ybase = _support(case)
        fx = np.flatnonzero(fixed)
        fr = np.flatnonzero(fixed == 0)
        self.q = np.zeros(n)
        self.v = np.zeros(n)
        if fx.size:
            self.q[fx] = ybase[fx]
            Ks = K + rest_tangents(case.elements, n)[0]
            self.q[fr] = -np.linalg.lstsq(Ks[np.ix_(fr, fr)], Ks[np.ix_(fr, fx)] @ ybase[fx], rcond=None)[0]
        self.S = np.zeros(packed.n_states)
        self.D = np.zeros(packed.n_tangents)
        self.Dref = np.zeros(packed.n_parts)
        init_states(packed.laws, self.q, self.v, self.S, self.D, self.Dref)
        self.fnl = np.zeros(n)
        element_forces(packed.laws, self.S, self.fnl)
        # the acceleration that balances the equations at phase 0
        self.a = Balance(kernel_model(case), packed.laws, w).acceleration(self.q, self.v, self.S)

    def arrays(self) -> tuple:
        """``(q, v, a, fnl, S, D, Dref)``, the kernels' state tuple (updated in place)."""
        return self.q, self.v, self.a, self.fnl, self.S, self.D, self.Dref

    def copy(self):
        other = object.__new__(TimeState)
        for k, val in self.__dict__.items():
            setattr(other, k, val.copy())
        return other


def kernel_model(case: Case) -> tuple:
    """``(M, C, K, F2, fixed, ybase)``, the kernels' model tuple (:mod:`hbm.timedomain.time_kernels`)."""
    fixed, ybase = _support(case)
    return (np.ascontiguousarray(case.model.M, dtype=float), np.ascontiguousarray(case.model.C, dtype=float),
            np.ascontiguousarray(case.model.K, dtype=float),
            np.ascontiguousarray(case.excitation.cos_sin, dtype=float), fixed, ybase)
