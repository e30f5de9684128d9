r"""The registered laws: one id each, and the compiled dispatch on it.

Every law is an incremental update ``s_new = Phi(p, s, z)`` (:mod:`elements.kernels`) with a
rest state and, optionally, a linear shortcut (:mod:`elements.law_march`).  The id of a law is
its position in :data:`KERNELS`; :func:`_law_step`, :func:`_law_init` and :func:`_law_linear`
switch on it (numba needs the branches written out: a constant id lets it prune the other
laws when one march is compiled for one law).

Adding a law is two files: its module in ``elements/laws/`` (kernels and, for a law on one
coordinate, a :class:`~elements.laws.record.LawRecord`) and this one (its id, its three
branches, its step, rest state and linear test in :data:`STEPS`, :data:`INITS` and
:data:`LINEARS`, and its record in
:data:`CASE_LAWS` to make it a case type).
"""
from __future__ import annotations

from . import cubic, unilateral
from .coulomb import coulomb_reg_init, coulomb_reg_step, coulomb_sk_init, coulomb_sk_step
from .cubic import cubic_init, cubic_step
from .friction3d import friction3d_init, friction3d_linear, friction3d_step
from .jenkins import jenkins_init, jenkins_linear, jenkins_step
from .unilateral import unilateral_init, unilateral_linear, unilateral_step

KERNELS = ("jenkins", "cubic", "friction3d", "coulomb_stick_slip", "coulomb_regularised", "unilateral_spring")
JENKINS, CUBIC, FRICTION3D, COULOMB_STATIC_KINETIC, COULOMB_REGULARISED, UNILATERAL = range(len(KERNELS))

# each law's step and rest state by id, for the marches that compile one law
# (elements.kernels.law_step_inline): the same order as KERNELS and the branches below
STEPS = (jenkins_step, cubic_step, friction3d_step, coulomb_sk_step, coulomb_reg_step, unilateral_step)
INITS = (jenkins_init, cubic_init, friction3d_init, coulomb_sk_init, coulomb_reg_init, unilateral_init)
# each law's linear test by id (None: it has none), for the AFT kernel of one law
LINEARS = (jenkins_linear, None, friction3d_linear, None, None, unilateral_linear)
assert len(STEPS) == len(INITS) == len(LINEARS) == len(KERNELS)

# laws on one coordinate that are case types by their record alone (elements.law_element)
CASE_LAWS = {CUBIC: cubic.LAW, UNILATERAL: unilateral.LAW}


def _law_step(kind, p, s, z, s_new, A, B):
    """One incremental update of law ``kind``: writes ``s_new``, ``A = ds_new/ds``, ``B = ds_new/dz``."""
    if kind == JENKINS:
        jenkins_step(p, s, z, s_new, A, B)
    elif kind == CUBIC:
        cubic_step(p, s, z, s_new, A, B)
    elif kind == FRICTION3D:
        friction3d_step(p, s, z, s_new, A, B)
    elif kind == COULOMB_STATIC_KINETIC:
        coulomb_sk_step(p, s, z, s_new, A, B)
    elif kind == COULOMB_REGULARISED:
        coulomb_reg_step(p, s, z, s_new, A, B)
    elif kind == UNILATERAL:
        unilateral_step(p, s, z, s_new, A, B)
    else:
        raise ValueError("unknown law kind")


def _law_init(kind, p, z0, s0, C0):
    """Rest state ``s0`` of law ``kind`` at input ``z0`` reached from ``q = 0``, and ``C0 = ds0/dz0``."""
    if kind == JENKINS:
        jenkins_init(p, z0, s0, C0)
    elif kind == CUBIC:
        cubic_init(p, z0, s0, C0)
    elif kind == FRICTION3D:
        friction3d_init(p, z0, s0, C0)
    elif kind == COULOMB_STATIC_KINETIC:
        coulomb_sk_init(p, z0, s0, C0)
    elif kind == COULOMB_REGULARISED:
        coulomb_reg_init(p, z0, s0, C0)
    elif kind == UNILATERAL:
        unilateral_init(p, z0, s0, C0)
    else:
        raise ValueError("unknown law kind")


def _law_linear(kind, p, z, K, f0):
    """True if law ``kind`` is linear, ``f = f0 + K z``, at every sample of ``z`` (N, nz)
    (then ``K`` (n_local, nz) and ``f0`` (n_local,) are written); False if it is not, or has
    no such test."""
    if kind == JENKINS:
        return jenkins_linear(p, z, K, f0)
    if kind == FRICTION3D:
        return friction3d_linear(p, z, K, f0)
    if kind == UNILATERAL:
        return unilateral_linear(p, z, K, f0)
    return False
