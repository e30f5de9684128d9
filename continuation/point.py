r"""One converged point of a continuation path.

A point is a solution :math:`R(x) = 0` with :math:`x = [y, \lambda]` together with the unit
tangent :math:`t` of the path in scaled variables, :math:`J_s t = 0`, :math:`\|t\| = 1`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ContinuationPoint:
    """A converged point and how it was reached.

    Parameters
    ----------
    x : ndarray, shape (n+1,)
        Solution ``[y, lam]`` in the caller's (unscaled) variables.
    tangent : ndarray, shape (n+1,)
        Unit tangent in scaled variables ``x / scale``, oriented along the path.
    iterations : int
        Newton iterations of the corrector that produced the point.
    ds : float
        Scaled step length used to reach it (0 for the starting point; for the final point
        on a bound, the step of the predictor that crossed the bound).
    fold : bool
        The parameter component of the tangent changed sign since the previous point.
    residual_norm : float
        ``||R(x)||_inf / rho``, the scaled residual of the convergence test.
    on_bound : bool
        The point was solved with the parameter fixed on a bound.
    """

    x: np.ndarray
    tangent: np.ndarray
    iterations: int
    ds: float
    fold: bool
    residual_norm: float
    on_bound: bool = False

    @property
    def lam(self) -> float:
        """The parameter, ``x[-1]``."""
        return float(self.x[-1])

    @property
    def y(self) -> np.ndarray:
        """The unknowns, ``x[:-1]``, shape (n,)."""
        return self.x[:-1]
