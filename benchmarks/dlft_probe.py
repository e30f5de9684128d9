r"""Would a dynamic Lagrangian (DLFT) contact finish the stiff cases, and would it be right?

Issue 17 names the dynamic Lagrangian frequency-time method (Nacivet et al. 2003) as a
rigid-contact option.  This probe builds it for the one case that still stops, the SDOF
oscillator ``m = k = 1`` with a rigid Coulomb contact (slip force ``s``) under ``F cos w t``,
and measures convergence and accuracy before anything is built into the solver.

DLFT writes the contact force as a Lagrange multiplier: with the force the balance asks of
the contact, :math:`\Lambda_{eq} = F - Z(w) X`, and a numerical penalty :math:`\epsilon`,

.. math::

    \lambda_u(t) = \lambda_{eq}(t) + \epsilon\, x(t), \qquad
    \lambda_k = \mathrm{proj}_{[-s, s]}\big(\lambda_u(t_k) - \epsilon\, x_{c,k-1}\big), \qquad
    x_{c,k} = (\lambda_u(t_k) - \lambda_k) / \epsilon ,

(stick keeps the contact displacement :math:`x_c`, slip moves it), and the balance
:math:`Z X + P\lambda - F = \epsilon\,(X - P x_c) = 0`: the harmonics of the displacement
equal those of a contact displacement that is exactly flat while it sticks.  Newton uses a
finite-difference Jacobian (a probe: 31 unknowns).

Two measurements, printed:

1. den Hartog's closed form (viscous ``c = 0.1`` + Coulomb ``s = 0.3``, continuous motion),
   H = 15, N = 256: the largest error of ``max |x|`` for ``epsilon = 1, 10, 100`` (k = 1).
2. The undamped case of issue 17 (``s = 0.9``, H = 15), traced down from 0.3 Hz by Newton
   from the previous point, against the time domain (``hbm timesim`` on the penalty law at
   ``kt = 1e5``, whose stick range is 1.8e-5): the first harmonic at 0.0852 and 0.149 Hz.

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/dlft_probe.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import numba as nb
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import hbm                                          # noqa: E402
from den_hartog import den_hartog                   # noqa: E402
from hbm.balance.fourier import FourierBasis        # noqa: E402
from hbm.interface.case import case_from_dict       # noqa: E402

H, N = 15, 256
BASIS = FourierBasis(list(range(H + 1)), N)


@nb.njit(cache=True)
def contact_march(lam_u, s, eps):
    """``x_c`` (N,) of the periodic DLFT march (three passes from ``x_c = 0``)."""
    xc, out = 0.0, np.zeros(lam_u.size)
    for _ in range(3):
        for k in range(lam_u.size):
            pred = lam_u[k] - eps * xc
            if abs(pred) > s:
                xc = (lam_u[k] - np.sign(pred) * s) / eps
            out[k] = xc
    return out


def dynamic_stiffness(w, c):
    """``Z(w)`` (2H+1, 2H+1) of ``m = k = 1`` with damping ``c`` on the real basis."""
    Z = np.zeros((BASIS.n_coef, BASIS.n_coef))
    for r, h in enumerate(BASIS.h_of_row):
        Z[r, r] = 1.0 - (h * w) ** 2
    Z += c * w * BASIS.D
    return Z


def residual(X, w, c, s, eps, F):
    lam_u = BASIS.E @ (F - dynamic_stiffness(w, c) @ X + eps * X)
    return eps * (X - BASIS.P @ contact_march(lam_u, s, eps))


def solve(X, w, c, s, eps, F, tol=1e-10, max_iter=60):
    """Newton with a finite-difference Jacobian and halving; ``(X, converged)``."""
    for _ in range(max_iter):
        r = residual(X, w, c, s, eps, F)
        if np.abs(r).max() < tol:
            return X, True
        J = np.column_stack([(residual(X + 1e-7 * e, w, c, s, eps, F) - r) / 1e-7 for e in np.eye(X.size)])
        dx = np.linalg.lstsq(J, -r, rcond=None)[0]
        a = 1.0
        while a > 1e-3 and np.abs(residual(X + a * dx, w, c, s, eps, F)).max() >= np.abs(r).max():
            a /= 2
        X = X + a * dx
    return X, False


def force(F):
    Fv = np.zeros(BASIS.n_coef)
    Fv[BASIS.row_of(1, "c")] = F
    return Fv


def den_hartog_errors(eps, c=0.1, s=0.3):
    X, errs, failed = np.zeros(BASIS.n_coef), [], 0
    for f in np.geomspace(0.3, 0.1, 21):
        w = 2 * np.pi * f
        X, ok = solve(X, w, c, s, eps, force(1.0))
        failed += not ok
        A, _ = den_hartog(1.0, c, 1.0, s, 1.0, w)
        errs.append(np.abs(BASIS.E @ X).max() / A - 1)
    return float(np.max(np.abs(errs))), failed


def undamped(freqs, eps=1.0, s=0.9):
    """DLFT first harmonics at ``freqs`` (traced down from 0.3 Hz) and the time domain's."""
    case = case_from_dict({"model": {"mass": [[1.0]], "stiffness": [[1.0]], "damping": [[0.0]]},
                           "element": [{"type": "jenkins", "dofs": [0], "kt": 1e5, "slip_force": s}],
                           "excitation": {"dofs": [0], "amplitude": [1.0]},
                           "analysis": {"frequency_hz": [0.08, 0.3], "outputs": {"x": 0}}})
    rc = BASIS.row_of(1, "c")
    X, out, failed = np.zeros(BASIS.n_coef), {}, 0
    for f in np.r_[np.geomspace(0.3, 0.15, 12), 0.149, np.geomspace(0.145, 0.0852, 20)]:
        X, ok = solve(X, 2 * np.pi * f, 0.0, s, eps, force(1.0))
        failed += not ok
        if any(abs(f - g) < 1e-9 for g in freqs):
            out[f] = (float(np.hypot(X[rc], X[rc + 1])), hbm.timesim(case, float(f)).h1["x"])
    return out, failed


def main():
    print(f"1. den Hartog (c = 0.1, s = 0.3, F = 1), H = {H}, N = {N}: largest error of max|x| over 0.1-0.3 Hz")
    for eps in (1.0, 10.0, 100.0):
        err, failed = den_hartog_errors(eps)
        print(f"   epsilon = {eps:5g}: {100 * err:.2f} %   ({failed} of 21 points did not converge)")
    print("2. undamped, s = 0.9, F = 1, H = 15, epsilon = 1: first harmonic, DLFT against the time domain")
    out, failed = undamped((0.149, 0.0852))
    for f, (a, ref) in sorted(out.items()):
        print(f"   {f:.4f} Hz: DLFT {a:.4f}, time domain {ref:.4f} ({100 * (a / ref - 1):+.0f} %)")
    print(f"   {failed} of 33 points on the way did not converge")


if __name__ == "__main__":
    main()
