r"""Coulomb friction laws on one coordinate: static/kinetic (stick-slip) and regularised.

Static/kinetic (``COULOMB_STATIC_KINETIC``), seed 000: a spring ``kt`` (so that sticking is
well defined) in series with a slider whose break-loose limit ``mu_s N`` exceeds its sliding
limit ``mu_k N``.  Return mapping with a ``sliding`` flag:

.. math::

    f^{tr} = f_{prev} + k_t (u - u_{prev})

- sliding, and ``f^{tr}`` beyond ``mu_k N`` on the side of ``f_prev`` (the slip goes on in
  the same direction): keep sliding, ``f = mu_k N sign(f_prev)``;
- otherwise the contact is (or becomes) stuck: ``f = f^{tr}`` if ``|f^{tr}| <= mu_s N``,
  else it breaks loose: ``f = mu_k N sign(f^{tr})``, sliding.

So a sliding contact re-sticks when the slip reverses (the trial force moves back inside the
kinetic limit) and must reach ``mu_s N`` again to break loose.  State
``s = [f, u_prev, sliding]`` (sliding is 0.0 or 1.0), input ``z = [u]``, parameters
``p = [kt, N, mu_s, mu_k]``.

Regularised (``COULOMB_REGULARISED``), seed 001 eq. (2.2): memory-less in ``u``, reads the
velocity ``v = z[1]``:

.. math::

    f = F_{t0}\, \mathrm{sat}(v / v_r) \quad (\text{law } 0, \text{linear}), \qquad
    f = F_{t0}\, \tfrac{2}{\pi} \arctan(v / v_r) \quad (\text{law } 1, \text{arctan}), \qquad
    f = F_{t0} \tanh(v / v_r) \quad (\text{law } 2, \text{tanh, as in NLvib's examples})

State ``s = [f]``, input ``z = [u, v]``, parameters ``p = [Ft0, v_r, law]``.
"""
from __future__ import annotations

import math

import numba as nb

LINEAR = 0
ARCTAN = 1
TANH = 2


@nb.njit(cache=True, inline="always")
def coulomb_sk_step(p, s, z, s_new, A, B):
    """One stick/slide step; ``A`` (3, 3), ``B`` (3, 1)."""
    kt = p[0]
    Nload = p[1]
    fs = p[2] * Nload          # break-loose limit
    fk = p[3] * Nload          # sliding limit
    u = z[0]
    ft = s[0] + kt * (u - s[1])
    for i in range(A.shape[0]):      # explicit loops: a slice fill costs more per sample
        for k in range(A.shape[1]):
            A[i, k] = 0.0
    for i in range(B.shape[0]):      # explicit loops: a slice fill costs more per sample
        for k in range(B.shape[1]):
            B[i, k] = 0.0
    sliding = s[2] > 0.5
    if sliding and ft * s[0] > 0.0 and abs(ft) > fk:
        s_new[0] = fk if s[0] > 0.0 else -fk
        s_new[2] = 1.0
    elif abs(ft) <= fs:
        s_new[0] = ft
        s_new[2] = 0.0
        A[0, 0] = 1.0
        A[0, 1] = -kt
        B[0, 0] = kt
    else:
        s_new[0] = fk if ft > 0.0 else -fk
        s_new[2] = 1.0
    s_new[1] = u
    B[1, 0] = 1.0


@nb.njit(cache=True, inline="always")
def coulomb_sk_init(p, z0, s0, C0):
    """Rest state at ``z0`` reached from ``q = 0`` monotonically: stuck at ``kt u0`` unless that
    exceeds ``mu_s N``, in which case the contact broke loose and slides at ``mu_k N``."""
    kt = p[0]
    fs = p[2] * p[1]
    fk = p[3] * p[1]
    f = kt * z0[0]
    for i in range(C0.shape[0]):      # explicit loops: a slice fill costs more per sample
        for k in range(C0.shape[1]):
            C0[i, k] = 0.0
    if abs(f) <= fs:
        s0[0] = f
        s0[2] = 0.0
        C0[0, 0] = kt
    else:
        s0[0] = fk if f > 0.0 else -fk
        s0[2] = 1.0
    s0[1] = z0[0]
    C0[1, 0] = 1.0


@nb.njit(cache=True)
def _regularised(p, v):
    """Force and its derivative with respect to the velocity."""
    F0 = p[0]
    vr = p[1]
    x = v / vr
    if int(p[2]) == ARCTAN:
        return F0 * (2.0 / math.pi) * math.atan(x), F0 * (2.0 / math.pi) / (vr * (1.0 + x * x))
    if int(p[2]) == TANH:
        t = math.tanh(x)
        return F0 * t, F0 * (1.0 - t * t) / vr
    if x > 1.0:
        return F0, 0.0
    if x < -1.0:
        return -F0, 0.0
    return F0 * x, F0 / vr


@nb.njit(cache=True, inline="always")
def coulomb_reg_step(p, s, z, s_new, A, B):
    """``f = Ft0 g(v / v_r)``; ``A`` (1, 1) = 0, ``B`` (1, 2) = [0, df/dv]."""
    f, dfdv = _regularised(p, z[1])
    s_new[0] = f
    A[0, 0] = 0.0
    B[0, 0] = 0.0
    B[0, 1] = dfdv


@nb.njit(cache=True, inline="always")
def coulomb_reg_init(p, z0, s0, C0):
    f, dfdv = _regularised(p, z0[1])
    s0[0] = f
    C0[0, 0] = 0.0
    C0[0, 1] = dfdv
