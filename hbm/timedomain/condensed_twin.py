r"""The condensed model in the time domain: the same kept modes and residual flexibility that
the condensed harmonic balance solves (:mod:`hbm.balance.condensed`), as an ordinary
second-order model the time integrator and the period map (Floquet) can step.

The condensed model on its contact coordinates ``u`` (excitation ``F_e(t)``, element forces
``f`` on ``u``) is

.. math::

    \ddot\eta + C_m \dot\eta + \Omega^2 \eta = \Phi_c^T(-f) + \Phi_e^T F_e(t), \qquad
    u = \Phi_c \eta + R_{cc}(-f) + R_{ce} F_e(t) .

With ``R_cc = V diag(r) V^T`` (``r > 0``) and the static coordinates ``s = V^T(u - Phi_c eta)``
the second relation reads ``diag(1/r) s = V^T(-f) + diag(1/r) V^T R_ce F_e(t)`` (``R_ce``'s
columns lie in the range of ``R_cc``, ``R`` being positive semi-definite), so on
``y = [eta, s]``

.. math::

    M y'' + C y' + K y + B^T f(B y) = F(t), \quad
    M = \mathrm{diag}(I, 0),\; C = \mathrm{diag}(C_m, 0),\; K = \mathrm{diag}(\Omega^2, 1/r),\;
    B = [\Phi_c, V],

the elements reading ``u = B y``.  The static coordinates have no mass (their equations are
exact at every step; :func:`hbm.timedomain.shooting.static_dofs`).  Directions with ``r``
below ``RIGID`` of the largest flexibility at the contacts (residual or the kept modes'
static one) are taken as rigid (``u = Phi_c eta`` there): they change the contact motion
by less than that share (every mode kept: no static coordinates, only round-off).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hbm.balance.contact_coordinates import regathered

RIGID = 1e-9


@dataclass(frozen=True)
class _Model:
    M: np.ndarray
    C: np.ndarray
    K: np.ndarray


@dataclass(frozen=True)
class _Excitation:
    cos_sin: np.ndarray
    base: None = None


@dataclass(frozen=True)
class _Analysis:
    """Outputs ``y = g . q + d_c cos(w t) + d_s sin(w t)``: rows ``g`` (n,) by name in
    ``outputs``, the excitation's direct part ``(d_c, d_s)`` by name in ``feed``."""
    outputs: dict = field(default_factory=dict)
    feed: dict = field(default_factory=dict)


@dataclass(frozen=True)
class TimeTwin:
    """The condensed model ``y = [eta, s]`` as the time integrator takes a case (module doc).

    Attributes
    ----------
    model : object with ``M``, ``C``, ``K`` (n, n), ``n = m + n_s``
    elements : tuple of Element
        Gathers (n_local, n) over ``y``.
    excitation : object with ``cos_sin`` (2, n) and ``base = None``
    B : ndarray, shape (n_c, n)
        Contact coordinates ``u = B y``.
    V : ndarray, shape (n_c, n_s)
        Directions of the static coordinates.
    n_modes : int
    """

    name: str
    path: str
    model: _Model
    elements: tuple
    excitation: _Excitation
    B: np.ndarray
    V: np.ndarray
    n_modes: int
    analysis: _Analysis = _Analysis()

    @property
    def n_dof(self) -> int:
        return self.B.shape[1]


def time_twin(linear, name: str = "", path: str = "", outputs=()) -> TimeTwin:
    """The time-domain model of a condensed linear part with its elements.

    Parameters
    ----------
    linear : hbm.balance.condensed.CondensedLinear
    outputs : sequence of str
        Names of the linear part's output rows, in order (``[analysis] outputs``).  An output
        ``y = G_o q`` is ``Phi_o eta + R_oc(-f) + R_oe F_e(t)``, and ``R_oc(-f)`` depends only
        on ``V^T(-f) = diag(1/r)(s - V^T R_ce F_e(t))``: a row over ``y`` plus a direct part
        of the excitation.
    """
    cm, red = linear.condensed, linear.reduced
    R = red.residual
    phi_c, phi_e = cm.G_c @ red.phi, cm.G_e @ red.phi
    r, V = np.linalg.eigh(cm.G_c @ R @ cm.G_c.T)
    om = red.omega
    soft = om > 1e-8 * max(float(om.max(initial=0.0)), 1e-300)
    static = (phi_c[:, soft] ** 2 / om[soft] ** 2).sum(axis=1).max(initial=0.0)   # kept modes' flexibility
    keep = r > RIGID * max(float(r.max(initial=0.0)), float(static), 1e-300)
    r, V = r[keep], V[:, keep]
    R_ce = cm.G_c @ R @ cm.G_e.T                                   # (n_c, n_e)
    m, ns = red.n_modes, r.size
    n = m + ns
    M = np.zeros((n, n))
    M[:m, :m] = np.eye(m)
    C = np.zeros((n, n))
    C[:m, :m] = red.modal_c
    K = np.diag(np.concatenate([red.omega ** 2, 1.0 / r]))
    F2 = np.zeros((2, n))
    for k in range(phi_e.shape[0]):               # unit cosine coordinate, then unit sine
        F2[k, :m] = phi_e[k]
        F2[k, m:] = (V.T @ R_ce[:, k]) / r
    B = np.hstack([phi_c, V])
    elems = tuple(regathered(e, e.gather @ B) for e in linear.elements)
    R_oc, R_oe = cm.G_o @ R @ cm.G_c.T, cm.G_o @ R @ cm.G_e.T
    rows = np.hstack([cm.G_o @ red.phi, (R_oc @ V) / r])
    direct = R_oe - ((R_oc @ V) / r) @ (V.T @ R_ce)                  # (n_o, n_e): cosine, sine
    feed = np.zeros((rows.shape[0], 2))
    feed[:, :direct.shape[1]] = direct
    analysis = _Analysis({k: rows[i] for i, k in enumerate(outputs)}, {k: feed[i] for i, k in enumerate(outputs)})
    return TimeTwin(name, path, _Model(M, C, K), elems, _Excitation(F2), B, V, m, analysis)


def twin_coefficients(linear, twin: TimeTwin, X: np.ndarray, w: float) -> np.ndarray:
    """Coefficients (n_coef, n) of ``y = [eta, s]`` at the balance point ``X`` (n_coef, n_c) at
    ``w``: ``eta`` under the excitation and the contact forces the balance implies, ``s =
    V^T(u - Phi_c eta)``."""
    eta = linear.modal_coefficients(X, w)
    phi_c = twin.B[:, :twin.n_modes]
    return np.hstack([eta, (X - eta @ phi_c.T) @ twin.V])


def time_model(case, problem=None):
    """``(model, to_model)``: what the time integrator steps for the balance of ``case``, and
    the map ``to_model(X, w)`` of a balance point's coefficients onto its coordinates.

    For the full solver that is ``case`` itself (``X`` over every DOF); for a condensed
    ``problem`` (:class:`hbm.balance.residual.HarmonicBalance` on a condensed linear part) its
    kept modes and residual flexibility (:mod:`hbm.timedomain.condensed_twin`), ``X`` being
    the contact coordinates.
    """
    linear = getattr(problem, "linear", None)
    if linear is None or not hasattr(linear, "condensed"):
        return case, lambda X, w: X
    twin = time_twin(linear, case.name, case.path, list(case.analysis.outputs))
    return twin, lambda X, w: twin_coefficients(linear, twin, X, w)
