r"""Verdict on one stress case: converged and right, a stated failure, or bad.

A traced FRF passes when

* ``status == 'finished'``, the path runs from ``fmin`` to ``fmax``, every amplitude is
  finite, the energy balance closes at every point (relative error < ``ENERGY_TOL``), and
  the independent checks below hold; or
* ``status != 'finished'`` with a message (a stated failure), and every point it kept is
  finite and closes the energy balance.

Independent checks ("no silent wrong answer"), valid for the stress cases (``C = c I`` and
passive elements, whose work per period is >= 0):

* energy bound: with ``X_1`` the first-harmonic vector over all DOFs, the excitation's work
  :math:`\pi F \cdot X_{s,1} \le \pi |F| |X_1|` must exceed the viscous dissipation
  :math:`\pi c w \sum_h h^2 |X_h|^2 \ge \pi c w |X_1|^2`, so :math:`|X_1| \le |F| / (c w)`
  for the exact periodic solution; the answer may exceed it by its own stated truncation
  error (``outputs[...].err``; a contact that neither slips nor dissipates, at a resonance
  limited by the viscous damping alone, sits on the bound, and the harmonic truncation's
  error then shows as a small excess);
* stuck limit: when the linear system with every contact stuck (and closed) keeps each
  contact force inside its limit at every frequency of the path, that linear response *is*
  the solution: the first harmonic must equal it and the other harmonics must vanish.

* stuck peaks: when that also holds at the resonances of the stuck system inside the
  window (where the stuck response peaks), the path must pass them: its largest
  first-harmonic amplitude is at least ``PEAK_FRACTION`` of the stuck response's there (a
  path that steps over a narrow peak samples only its foot).

Anything else (NaN, energy not closed, an exception instead of a result, a bound violated)
is ``bad``.
"""
from __future__ import annotations

import numpy as np

from hbm.interface.case import case_from_dict
from hbm.analyses.response import frf

ENERGY_TOL = 1e-8
PEAK_FRACTION = 0.9


def _stuck_stiffness(case):
    """Stiffness of the structure with every contact stuck, (n, n)."""
    K = case.model.K.copy()
    for e in case.elements:
        K = K + e.gather.T @ e.linear_stiffness() @ e.gather
    return K


def _stuck_resonances(case, w_lo, w_hi):
    """Natural angular frequencies of the all-stuck linear system inside ``[w_lo, w_hi]``."""
    lam = np.linalg.eigvals(np.linalg.solve(case.model.M, _stuck_stiffness(case))).real
    w = np.sqrt(lam[lam > 0])
    return w[(w >= w_lo) & (w <= w_hi)]


def _stuck_linear(case, w):
    """First-harmonic response (complex, (n,)) of the all-stuck linear system at ``w``."""
    Z = _stuck_stiffness(case) - w * w * case.model.M + 1j * w * case.model.C
    return np.linalg.solve(Z, case.excitation.force)


def _stays_stuck(case, x):
    """Does the stuck linear response ``x`` (complex (n,)) keep every contact inside its limit?"""
    for e in case.elements:
        u = np.abs(e.gather @ x)
        kind = type(e).__name__
        if kind == "Jenkins":
            if not e.kt * u[0] < (1 - 1e-6) * e.slip_force:
                return False
        elif kind == "Friction3D":
            nt = e.n_tangential
            nmin = e.normal_preload - e.kn * u[nt]
            if not (nmin > 0 and e.kt * np.linalg.norm(u[:nt]) < (1 - 1e-6) * e.mu * nmin):
                return False
        else:
            return False
    return True


def assess(data: dict, **frf_kwargs) -> dict:
    """Run the FRF of the case tree ``data`` and judge it.

    Returns
    -------
    dict
        ``name``, ``verdict`` (``converged`` / ``gaps`` (finished past stated stops) / ``failed`` / ``bad``), ``detail`` (one line),
        ``points``, ``max_energy_error``, ``seconds``, ``stuck_checked`` (bool), ``middle_gaps``
        (stretches of a middle branch between two folds left untraced while every frequency
        of the window lies on a traced branch: :mod:`hbm.analyses.overhang`).
    """
    case = case_from_dict(data)
    rec = {"name": data["name"], "points": 0, "max_energy_error": float("nan"), "seconds": 0.0,
           "stuck_checked": False, "middle_gaps": 0}
    try:
        res = frf(case, **frf_kwargs)
    except Exception as exc:  # noqa: BLE001 - an exception instead of a result is itself a finding
        return {**rec, "verdict": "bad", "detail": f"raised {type(exc).__name__}: {exc}"}
    n = res.freq_hz.size
    rec.update(points=int(n), seconds=float(res.solve_seconds),
               max_energy_error=float(res.energy_error.max()) if n else float("nan"),
               middle_gaps=len(res.settings.get("middle_gaps", ())))
    problems = []
    if not np.all(np.isfinite(res.X)) or not all(np.all(np.isfinite(o.h1)) and np.all(np.isfinite(o.max))
                                                 for o in res.outputs.values()):
        problems.append("non-finite values")
    if n and not np.all(res.energy_error < ENERGY_TOL):
        i = int(np.nanargmax(res.energy_error))
        problems.append(f"energy balance error {res.energy_error[i]:.2e} at {res.freq_hz[i]:.6g} Hz")
    basis = res.basis
    rc = basis.row_of(1, "c")
    F = case.excitation.force
    c = float(case.model.C[0, 0])
    w = 2 * np.pi * res.freq_hz
    if n:
        X1 = np.sqrt(np.sum(res.X[:, rc, :] ** 2 + res.X[:, rc + 1, :] ** 2, axis=1))
        bound = np.linalg.norm(F) / (c * w)
        stated = np.nan_to_num(np.max([o.err for o in res.outputs.values()], axis=0)) \
            if all(o.err is not None for o in res.outputs.values()) else np.zeros(n)
        if np.any(X1 > bound * (1 + stated + 1e-9)):
            i = int(np.argmax(X1 / (bound * (1 + stated))))
            problems.append(f"|X1| = {X1[i]:.4g} exceeds the energy bound |F|/(c w) = {bound[i]:.4g} "
                            f"by more than the point's stated error {stated[i]:.2g} at {res.freq_hz[i]:.6g} Hz")
    if res.ok and n:
        lo, hi = res.settings["fmin_hz"], res.settings["fmax_hz"]
        if not (abs(res.freq_hz[0] - lo) <= 1e-9 * hi and abs(res.freq_hz[-1] - hi) <= 1e-9 * hi):
            problems.append(f"path covers {res.freq_hz[0]:.6g}..{res.freq_hz[-1]:.6g} Hz, "
                            f"not {lo:.6g}..{hi:.6g}")
        lin = [_stuck_linear(case, wi) for wi in w]
        if all(_stays_stuck(case, x) for x in lin):
            rec["stuck_checked"] = True
            ref = np.array([np.r_[x.real, -x.imag] for x in lin])      # Xc = Re, Xs = -Im
            got = np.concatenate([res.X[:, rc, :], res.X[:, rc + 1, :]], axis=1)
            scale = np.abs(ref).max()
            err1 = np.abs(got - ref).max() / scale
            other = np.delete(res.X, [rc, rc + 1], axis=1)
            err_h = np.abs(other).max() / scale if other.size else 0.0
            if err1 > 1e-7 or err_h > 1e-7:
                problems.append(f"stuck limit: first harmonic off by {err1:.2e}, other harmonics {err_h:.2e} "
                                f"(relative)")
            wr = _stuck_resonances(case, 2 * np.pi * lo, 2 * np.pi * hi)
            peaks = [_stuck_linear(case, x) for x in wr]
            if peaks and all(_stays_stuck(case, x) for x in peaks):
                top = max(float(np.linalg.norm(x)) for x in peaks)
                if not X1.max() >= PEAK_FRACTION * top:
                    problems.append(f"stuck peak |X1| = {top:.4g} missed: the path's largest is {X1.max():.4g}")
    if problems:
        return {**rec, "verdict": "bad", "detail": "; ".join(problems) + f" [status {res.status}: {res.message}]"}
    if res.ok and res.settings.get("gaps"):
        return {**rec, "verdict": "gaps", "detail": res.settings["gap_warning"]}
    if res.ok:
        return {**rec, "verdict": "converged", "detail": ""}
    if not res.message:
        return {**rec, "verdict": "bad", "detail": f"status {res.status} without a message"}
    return {**rec, "verdict": "failed", "detail": f"{res.status}: {res.message}"}
