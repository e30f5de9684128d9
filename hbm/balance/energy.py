r"""Energy balance over one period of a harmonic-balance solution.

With velocity coefficients :math:`V = w D X` (:mod:`hbm.balance.fourier`) and period :math:`T = 2\pi/w`,
the work of a periodic force ``F`` on the velocity over one period is (Parseval)

.. math::

    W[F] = \int_0^T F \cdot \dot q \, dt = \frac{T}{2} \sum_{r:\,h_r > 0} F_r \cdot V_r .

At a converged point the excitation's work equals the viscous plus the friction dissipation,
:math:`W[F_{ex}] = \frac{T}{2}\sum_r V_r^T C V_r + W[F_{nl}]` (stiffness and mass forces do
no work over a period).  Supports with imposed motion (base excitation) add the work of
the force that drives them, ``W[R_b]`` on their velocities, to the input.

The relative error is the imbalance over the largest of the three works and of a round-off
floor ``ROUNDOFF_SHARE * S``, with ``S = (T/2) |F_ex| |V|`` the most work the excitation
could do at this motion (Cauchy-Schwarz).  Without the floor a point that dissipates nothing
(an undamped structure with its contacts stuck: every work is zero up to round-off) had a
"relative error" of 1 and was refused; with it, such a point passes when its imbalance is
at round-off level against ``S``, and a dissipating point is judged as before.
The linear part supplies the excitation and viscous work (:meth:`work` of
:class:`hbm.balance.dense_part.DenseLinear` and :class:`hbm.balance.condensed.CondensedLinear`, the latter
from modal coordinates); :meth:`hbm.balance.residual.HarmonicBalance.energy_balance` adds the
nonlinear forces' work.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


ROUNDOFF_SHARE = 1e-6     # floor of the reference work, as a share of the bound S


@dataclass(frozen=True)
class EnergyBalance:
    """Work per period (J): excitation input, viscous and nonlinear dissipation, relative error.

    ``bound`` is ``S``, the largest work the excitation could do at this motion (module doc).
    """

    excitation: float
    viscous: float
    nonlinear: float
    bound: float = 0.0

    @property
    def relative_error(self) -> float:
        ref = max(abs(self.excitation), abs(self.viscous) + abs(self.nonlinear),
                  ROUNDOFF_SHARE * self.bound, 1e-300)
        return abs(self.excitation - self.viscous - self.nonlinear) / ref


def work(basis, F: np.ndarray, V: np.ndarray, w: float) -> float:
    """Work per period of forces ``F`` (n_coef, n) on velocities ``V`` (n_coef, n)."""
    s = 1 if basis.has_zero else 0          # harmonic 0 is the first row when present
    return float(np.pi / w * np.vdot(F[s:], V[s:]))


def energy_balance(problem, X: np.ndarray, w: float) -> EnergyBalance:
    """Energy balance of ``problem`` (a :class:`hbm.balance.residual.HarmonicBalance`) at ``(X, w)``."""
    return problem.energy_balance(X, w)
