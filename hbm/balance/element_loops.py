r"""Contact forces and hysteresis loops of the elements at one point of a traced FRF.

At the point's harmonic coefficients :math:`X` and frequency :math:`\omega` every element's
inputs are sampled over one period as in the AFT, :math:`z(t_k) = (E X G^T)_k` at
:math:`t_k = 2\pi k / (N \omega)`, and its law marched over the closed period to the forces
:math:`f(t_k)`.  Plotting :math:`f` against :math:`z` gives the element's hysteresis loop; the
area enclosed is the energy it dissipates per period.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ElementLoop:
    """One element over one period of a solution.

    Attributes
    ----------
    name, kind : str
        The element's name and class name.
    freq_hz : float
    time : ndarray, shape (N,)
        Sample times over one period, s.
    displacement : ndarray, shape (N, n_local)
        The element's local inputs (relative displacements: tangential, then normal).
    force : ndarray, shape (N, n_local)
        The element's local forces at those samples.
    """

    name: str
    kind: str
    freq_hz: float
    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray


def contact_loops(case, result, point: int) -> list:
    """Forces and loops of every element at point ``point`` of ``result``.

    Parameters
    ----------
    case : Case
        The case the FRF was traced for.
    result : FRFResult
    point : int
        Index along the path (``result.nearest(freq_hz)`` finds one by frequency).

    Returns
    -------
    list of ElementLoop
        In the case's element order.
    """
    from hbm.analyses.response import build_problem
    n = result.freq_hz.size
    if not -n <= point < n:
        raise IndexError(f"point {point} is outside the {n} points of the FRF")
    problem, _ = build_problem(case, result.basis, result.settings.get("transform", "auto"))
    X, f = result.X[point], float(result.freq_hz[point])
    w = 2 * np.pi * f
    nl = problem.nl
    marched = nl.element_forces(np.ascontiguousarray(X[:, nl.dofs]), w)
    t = np.arange(result.basis.n_samples) / (result.basis.n_samples * f)
    return [ElementLoop(e.name, type(e).__name__, f, t, z[:, :e.n_local].copy(), fe.copy())
            for e, (z, fe) in zip(nl.elements, marched)]
