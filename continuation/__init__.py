"""Pseudo-arclength continuation on any callable ``x -> (R, dR/dx)``; knows nothing of HBM.

The path :math:`R(y, \\lambda) = 0`, :math:`R: \\mathbb{R}^{n+1} \\to \\mathbb{R}^n`, is traced
by a tangent predictor and a Newton corrector on the bordered pseudo-arclength system, in
scaled variables ``x / scale`` (see :mod:`continuation.arclength`).

Public names: :class:`Arclength` (the solver, iterate it), :class:`ArclengthOptions`
(frozen settings) and :class:`ContinuationPoint` (one converged point).
"""
from .arclength import Arclength, default_scale
from .options import ArclengthOptions
from .point import ContinuationPoint

__all__ = ["Arclength", "ArclengthOptions", "ContinuationPoint", "default_scale"]
