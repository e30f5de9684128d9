r"""Per-element quantities of one harmonic-balance solution (for reports and checks).

For a solution ``X`` (n_coef, n) at ``w`` every element's inputs are sampled as in the AFT,
``z = E X G^T``, its forces marched over the closed period, and its ``summary(f, z)`` taken
(normal loads, slip and open fractions, dissipation).  Elements with internal DOFs (a
``damper_index`` attribute, e.g. the wedge damper) also receive the sampled internal DOFs,
``summary(f, z, E X[:, damper_index])``.
"""
from __future__ import annotations

import numpy as np


def element_summaries(problem, X: np.ndarray, w: float) -> list:
    """Summaries of every element that has a ``summary`` method.

    Parameters
    ----------
    problem : hbm.balance.residual.HarmonicBalance
    X : ndarray, shape (n_coef, n)
    w : float
        rad/s.

    Returns
    -------
    list of dict
        ``{"name", "type", **summary}`` in element order (elements without ``summary`` skipped).
    """
    nl = problem.nl
    Xnl = np.ascontiguousarray(X[:, nl.dofs])
    out = []
    for e, (z, f) in zip(nl.elements, nl.element_forces(Xnl, w)):
        if not hasattr(e, "summary"):
            continue
        u = z[:, :e.n_local]
        idx = getattr(e, "damper_index", None)
        if idx is not None:
            s = e.report(f, u, problem.basis.E @ X[:, idx])
        else:
            s = e.summary(f, u)
        out.append({"name": e.name, "type": type(e).__name__, **s})
    return out
