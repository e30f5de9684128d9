r"""Per-period element outputs along an FRF (``[analysis] outputs = { n = "contact.slip_fraction" }``).

At every converged point :math:`(X, w)` the elements are marched once over the closed
period, :math:`z = E\,(X_{nl} G^T)` and :math:`f = \mathrm{march}(z)`
(:meth:`hbm.balance.aft.NonlinearForces.element_forces`), and each requested element reduces its
samples to scalars, :math:`q = \mathrm{summary}(f, z)[\text{quantity}]` (e.g. the normal
load's minimum over the period, the slip fraction, the dissipation per cycle).
"""
from __future__ import annotations

import numpy as np


def element_output_series(problem, spec: dict, Xs: np.ndarray, ws: np.ndarray) -> dict:
    """Element outputs at every point of a path.

    Parameters
    ----------
    problem : HarmonicBalance
        Its ``nl`` holds the elements in case order.
    spec : dict of str -> (int, str)
        Output name -> (element index, quantity), as in ``Analysis.element_outputs``.
    Xs : ndarray, shape (n_points, n_coef, n)
        Harmonic coefficients of the points.
    ws : ndarray, shape (n_points,)
        Angular frequencies, rad/s.

    Returns
    -------
    dict of str -> ndarray, shape (n_points,)
    """
    out = {name: np.empty(len(ws)) for name in spec}
    if not spec:
        return out
    nl = problem.nl
    for p, (X, w) in enumerate(zip(Xs, ws)):
        marched = nl.element_forces(np.ascontiguousarray(X[:, nl.dofs]), float(w))
        cache = {}
        for name, (i, qty) in spec.items():
            if i not in cache:
                z, f = marched[i]
                cache[i] = nl.elements[i].summary(f, z)
            out[name][p] = cache[i][qty]
    return out
