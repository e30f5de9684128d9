r"""Linear resonances of the two limits of a friction case, and the FRF step limit they set.

A contact that never slips adds its tangent stiffness :math:`K_s` (and the tangent damping of
velocity laws, :math:`C_s`) to the structure; one that slips freely adds nothing.  The
resonances of these two linear limits,

.. math::

    (K + K_s)\,\phi = \omega^2 M \phi, \qquad K \phi = \omega^2 M \phi, \qquad
    \zeta_r = \frac{\phi_r^T C \phi_r}{2\,\omega_r\,\phi_r^T M \phi_r},

are the narrowest features an FRF of the case can have: a contact that stays stuck (or
open) leaves the response linear, with the half-power half-width :math:`\zeta_r \omega_r`.  A
continuation step that is long against that width can land on the far side of such a peak,
where the path looks as straight as on the near side, and skip it without any sign.

The step limit keeps the parameter change of a step from :math:`\omega` below

.. math::

    \Delta\omega_{max}(\omega) = \min_{r\ \text{ahead}}
        \max\big(\beta\, \zeta_r \omega_r,\ \alpha\, |\omega_r - \omega|\big),

over the resonances ahead of :math:`\omega` (or within :math:`\zeta_r \omega_r` of it): a
step covers at most the fraction :math:`\alpha < 1` of the distance to the next resonance,
so it never jumps over it, and inside the half-power band it is at most
:math:`\beta \zeta_r \omega_r`.  From a distance :math:`D` this costs about
:math:`\ln(D / \zeta_r\omega_r) / \ln(1/(1-\alpha)) + 2/\beta` extra points per resonance.
Damping ratios below ``ZETA_FLOOR`` count as ``ZETA_FLOOR`` (an undamped peak has no width).

Both limits come from the problem's modes (``problem.modal_data()``, :mod:`hbm.analyses.modal_hill`):
the free frequencies and modal damping as they are, the stuck ones from the modal
eigenproblem with :math:`\Phi_c^T K_s \Phi_c` (and :math:`\Phi_c^T C_s \Phi_c`) added.  For
a full model every mode is kept, so this is the eigenproblem above in other coordinates; a
condensed model's residual flexibility is left out of this estimate.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla

ALPHA = 0.7
BETA = 0.5
ZETA_FLOOR = 1e-4


def _modes(K, M, C):
    """Angular frequencies (r,) and damping ratios (r,) of ``(K, M)`` with damping ``C``;
    rigid-body modes (zero frequency) are left out."""
    lam, phi = sla.eigh(K, M)
    keep = lam > 1e-12 * max(abs(lam).max(initial=0.0), 1e-300)
    om = np.sqrt(lam[keep])
    phi = phi[:, keep]
    c = np.einsum("ir,ij,jr->r", phi, C, phi)
    m = np.einsum("ir,ij,jr->r", phi, M, phi)
    return om, c / (2.0 * om * m)


def linear_resonances(modal, Ks=None, Cs=None):
    """Resonances of the free and the stuck linear limits, from a problem's modes.

    Parameters
    ----------
    modal : hbm.analyses.modal_hill.ModalData
        The problem's kept modes seen from its nonlinear coordinates (``problem.modal_data()``).
    Ks, Cs : ndarray, shape (n_c, n_c), optional
        Stuck tangent stiffness and damping of the elements on those coordinates.

    Returns
    -------
    omega : ndarray, shape (r,)
        Angular frequencies, rad/s, of both limits.
    zeta : ndarray, shape (r,)
        Their damping ratios.
    """
    om = np.asarray(modal.omega, dtype=float)
    Cm = np.asarray(modal.C_m, dtype=float)
    P = modal.phi_c
    Km = np.diag(om ** 2)
    o_f, z_f = _modes(Km, np.eye(om.size), Cm)
    Ks_m = Km if Ks is None else Km + P.T @ Ks @ P
    Cs_m = Cm if Cs is None else Cm + P.T @ Cs @ P
    o_s, z_s = _modes(Ks_m, np.eye(om.size), Cs_m)
    return np.r_[o_f, o_s], np.r_[z_f, z_s]


class ResonanceStepLimit:
    """``lam_step(w, direction)`` for :class:`continuation.Arclength` (module doc).

    Parameters
    ----------
    omega, zeta : ndarray, shape (r,)
        Resonances (rad/s) and damping ratios.
    window : (float, float), optional
        Parameter range of the path (rad/s): resonances whose band lies outside it are
        dropped (the path ends on the bound before it could pass them).
    alpha, beta : float
        Fraction of the distance to the next resonance, and of its half-width, a step may cover.
    """

    def __init__(self, omega, zeta, window=(0.0, math.inf), alpha: float = ALPHA, beta: float = BETA):
        omega = np.asarray(omega, dtype=float)
        zeta = np.maximum(np.asarray(zeta, dtype=float), ZETA_FLOOR)
        lo, hi = window
        ok = (np.isfinite(omega) & (omega > 0) & np.isfinite(zeta)
              & (omega * (1 + zeta) >= lo) & (omega * (1 - zeta) <= hi))
        self.omega = omega[ok]
        self.width = zeta[ok] * omega[ok]
        self.alpha = float(alpha)
        self.beta = float(beta)
        # plain floats: called once per continuation step on a handful of resonances, where
        # a loop costs a few us and NumPy's per-call overhead ten times that
        self._pairs = [(float(o), float(wd)) for o, wd in zip(self.omega, self.width)]

    def __call__(self, w: float, direction: int) -> float:
        cap = math.inf
        for om, width in self._pairs:
            d = (om - w) * direction          # > 0: ahead
            if d > -width:
                cap = min(cap, max(self.beta * width, self.alpha * abs(d)))
        return cap
