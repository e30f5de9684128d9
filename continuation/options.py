r"""Options of the pseudo-arclength solver and the rule that fills in the derived defaults.

All step lengths are measured in *scaled* variables ``xs = x / scale``.  With the scaled
parameter range :math:`L = (\lambda_{hi} - \lambda_{lo}) / s_\lambda` (taken as 1 when a
bound is infinite), the defaults left as ``None`` are

.. math::

    ds_0 = L / 100, \qquad ds_{max} = \max(1, 20\, ds_0), \qquad ds_{min} = 10^{-4}\, ds_0 .

Step adaptation after an accepted step (``k`` corrector iterations, tangent turn
:math:`\alpha`):

.. math::

    ds \leftarrow ds \cdot \min\Big(\mathrm{clip}\big(\sqrt{k_{target}/\max(k,1)}, f_{min}, f_{max}\big),\;
    \max\big(f_{min}, 0.8\,\alpha_{max}/\alpha\big)\Big).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ArclengthOptions:
    """Settings of :class:`continuation.Arclength`; the defaults need no tuning.

    Parameters
    ----------
    ds0 : float or None
        First step length (scaled).  ``None``: 1/100 of the scaled parameter range.
    ds_min : float or None
        The solver stops with status ``'failed'`` when rejections push the step below this.
        ``None``: ``1e-4 * ds0``.
    ds_max : float or None
        Largest step length.  ``None``: ``max(1, 20 * ds0)``, i.e. a step
        changes the scaled variables by at most about one scale unit.
    max_steps : int
        Largest number of accepted steps after the starting point (status ``'max_steps'``).
    tol : float
        Newton tolerance on the scaled residual ``||R||_inf / rho`` (see
        :mod:`continuation.corrector`); ``1e-10`` lands near machine precision.
    max_iter : int
        Newton iterations allowed per corrector.
    target_iter : int
        Wished-for number of corrector iterations; steps grow when fewer are needed.
    max_angle_deg : float
        Largest angle between successive unit tangents; a larger turn rejects the step
        unless it is a kink (the turn does not shrink when the step is halved).
    grow_max : float
        Largest growth factor of the step between two accepted steps.
    shrink_min : float
        Smallest shrink factor of the step between two accepted steps.
    max_backtrack : int
        Halvings of a Newton update tried when the residual grows.
    max_correction : float
        A corrected point further than ``max_correction * ds`` from its predictor is
        rejected (a jump to another branch).
    """

    ds0: float | None = None
    ds_min: float | None = None
    ds_max: float | None = None
    max_steps: int = 2000
    tol: float = 1e-10
    max_iter: int = 12
    target_iter: int = 4
    max_angle_deg: float = 15.0
    grow_max: float = 2.0
    shrink_min: float = 0.5
    max_backtrack: int = 4
    max_correction: float = 1.0

    def __post_init__(self):
        for name in ("ds0", "ds_min", "ds_max"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a positive finite number or None, got {v}")
        if self.max_steps < 1 or self.max_iter < 1 or self.target_iter < 1:
            raise ValueError("max_steps, max_iter and target_iter must be at least 1")
        if not (0 < self.tol < 1):
            raise ValueError(f"tol must lie in (0, 1), got {self.tol}")
        if not (0 < self.max_angle_deg < 90):
            raise ValueError(f"max_angle_deg must lie in (0, 90), got {self.max_angle_deg}")
        if not (self.grow_max >= 1 and 0 < self.shrink_min <= 1):
            raise ValueError("need grow_max >= 1 and 0 < shrink_min <= 1")
        if self.max_backtrack < 0 or self.max_correction <= 0:
            raise ValueError("need max_backtrack >= 0 and max_correction > 0")

    def step_lengths(self, scaled_range: float) -> tuple[float, float, float]:
        """Resolve ``(ds0, ds_min, ds_max)`` for a scaled parameter range.

        Parameters
        ----------
        scaled_range : float
            ``(hi - lo) / scale_lam``; ``inf`` when a bound is open (then taken as 1).

        Returns
        -------
        ds0, ds_min, ds_max : float
            With ``ds_min <= ds0 <= ds_max``.
        """
        L = scaled_range if math.isfinite(scaled_range) and scaled_range > 0 else 1.0
        ds0 = self.ds0 if self.ds0 is not None else L / 100.0
        ds_max = self.ds_max if self.ds_max is not None else max(1.0, 20.0 * ds0)
        ds_min = self.ds_min if self.ds_min is not None else 1e-4 * ds0
        if ds_min > ds_max:
            raise ValueError(f"ds_min={ds_min:g} exceeds ds_max={ds_max:g}")
        return min(max(ds0, ds_min), ds_max), ds_min, ds_max


def default_scale(x0: np.ndarray, lam_bounds: tuple[float, float]) -> np.ndarray:
    """Per-unknown scales derived from the start (:mod:`continuation.arclength`, "Default scale").

    Parameters
    ----------
    x0 : ndarray, shape (n+1,)
        Starting point ``[y0, lam0]``.
    lam_bounds : (float, float)
        Parameter bounds.

    Returns
    -------
    ndarray, shape (n+1,)
        Positive scales.
    """
    y0 = np.abs(x0[:-1])
    ymax = float(y0.max(initial=0.0))
    s = np.empty_like(x0)
    s[:-1] = ymax if ymax > 0 else 1.0
    lo, hi = lam_bounds
    width = hi - lo if math.isfinite(hi - lo) else 1.0
    s[-1] = max(abs(float(x0[-1])), width)
    if s[-1] <= 0:
        s[-1] = 1.0
    return s
