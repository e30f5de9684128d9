r"""Unbounded resonances: den Hartog's condition for modes without viscous damping.

When every element is a friction element with a fixed slip force :math:`F_{s,i}` (its
``slip_limit``: Jenkins, Coulomb) and a mode :math:`\phi_r` of the structure (``K phi = w_r^2 M phi``, the elements
slipping add no stiffness) has no viscous damping (:math:`C \phi_r = 0`), then at a large
modal amplitude :math:`a` the elements slip almost all the time and, per period at
:math:`w_r`,

.. math::

    W_{in} = \pi\, |\phi_r^T \hat F|\, a, \qquad
    W_{fr} \le 4 \sum_i F_{s,i}\, |g_i \phi_r|\, a,

(:math:`\hat F` the complex force amplitude, :math:`g_i` the element's gather row).  Both grow
linearly with :math:`a`; when :math:`W_{in} > W_{fr}` nothing limits the amplitude and the
response at :math:`w_r` is unbounded.  For one mass this is den Hartog's (1931) condition,
slip force below :math:`\pi/4` of the force amplitude.  The test is only made where it is
sound: a dense model, no imposed support motion, friction elements only.  Modes of a
repeated frequency are tested one by one as the eigensolver returns them, so a combination
of them that the friction does not see can be missed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

@dataclass(frozen=True)
class UnboundedMode:
    """A mode whose resonance the friction cannot bound: frequency (Hz), the work the force
    puts in and the most the friction can take out, per period and unit modal amplitude."""

    index: int
    freq_hz: float
    work_in: float
    friction_bound: float

    def describe(self) -> str:
        ratio = self.work_in / self.friction_bound if self.friction_bound > 0 else np.inf
        raise_by = "" if not np.isfinite(ratio) else f", raise the slip forces more than {ratio:.3g}x"
        return (f"unbounded response at {self.freq_hz:.6g} Hz: mode {self.index + 1} has no viscous damping, "
                f"and per period its friction can dissipate at most {self.friction_bound:.4g} x amplitude "
                f"while the force puts in {self.work_in:.4g} x amplitude (den Hartog's condition; for one "
                f"mass: slip force below pi/4 of the force). Add damping{raise_by}, "
                f"or end the window before {self.freq_hz:.6g} Hz")


def unbounded_modes(model, elements, force: np.ndarray, force_sine: np.ndarray) -> list[UnboundedMode]:
    """The modes of ``model`` (a :class:`hbm.model.linear.LinearModel`) that the friction
    ``elements`` cannot bound under the force ``force cos + force_sine sin`` (n,) each;
    empty when the test does not apply (module doc)."""
    limits = [e.slip_limit for e in elements]
    if any(fs is None for fs in limits):
        return []
    lam, phi = sla.eigh(model.K, model.M)
    F = np.asarray(force, dtype=float) - 1j * np.asarray(force_sine, dtype=float)
    out = []
    c_max = np.abs(model.C).max()
    for r in np.flatnonzero(lam > 1e-12 * max(lam.max(), 1e-300)):
        p = phi[:, r]
        if np.abs(model.C @ p).max() > 1e-12 * c_max * np.abs(p).max():
            continue                    # viscous damping bounds this mode
        work_in = np.pi * abs(p @ F)
        bound = 4.0 * sum(fs * np.abs(e.gather @ p).sum() for e, fs in zip(elements, limits))
        if work_in > bound * (1 + 1e-9):
            out.append(UnboundedMode(int(r), float(np.sqrt(lam[r]) / (2 * np.pi)), float(work_in), float(bound)))
    return out
