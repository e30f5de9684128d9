r"""Contacts that stick for the whole period: where the periodic solution is not unique.

A hysteretic contact (Jenkins, friction3d, Coulomb stick-slip, brush, wedge flanks) that
sticks at every sample of the period carries a slider position that no balance fixes: any
constant offset of it gives the same forces' harmonics above the mean, so the periodic
solution is a family.  The harmonic balance returns one member (the one its start and the
continuation lead to); a time simulation from rest settles on another, chosen by its
transient.  The first harmonic hardly differs, but the mean and so ``max |y(t)|`` can (by
30-40 % on a stuck chain).  Per point this module counts the contacts that stick the whole
period (``slip_fraction = 0`` and ``open_fraction = 0``), so that the FRF can say where.
"""
from __future__ import annotations

import numpy as np


def _hysteretic(e) -> bool:
    return "slip_fraction" in getattr(e, "quantities", ()) and not getattr(e, "velocity", False)


def stuck_contacts(problem, Xs, ws) -> np.ndarray | None:
    """Number of hysteretic contacts stuck for the whole period at each point.

    Parameters
    ----------
    problem
        The FRF's problem (full or condensed).
    Xs : ndarray, shape (n_points, n_coef, n)
    ws : ndarray, shape (n_points,)
        rad/s.

    Returns
    -------
    ndarray of int, shape (n_points,), or None when the case has no hysteretic contact.
    """
    nl = problem.nl
    which = [i for i, e in enumerate(nl.elements) if _hysteretic(e)]
    if not which:
        return None
    out = np.zeros(len(ws), dtype=int)
    for k, (X, w) in enumerate(zip(Xs, ws)):
        marched = nl.element_forces(np.ascontiguousarray(X[:, nl.dofs]), float(w))
        for i in which:
            z, f = marched[i]
            s = nl.elements[i].summary(f, z)
            if s.get("slip_fraction", 1.0) == 0.0 and s.get("open_fraction", 0.0) == 0.0:
                out[k] += 1
    return out
