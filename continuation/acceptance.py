r"""Acceptance of one corrected continuation step (pure: nothing is changed in place).

A step from :math:`x_{s,k}` with unit tangent :math:`t_k` and length :math:`ds` was corrected
to :math:`x_{s,k+1}` from the start :math:`x_{s,start}` (the predictor, or its crossing of a
parameter bound).  With the chord :math:`c = x_{s,k+1} - x_{s,k}` and the new unit tangent
:math:`t_{k+1}` (oriented so that :math:`t_{k+1}^T c > 0`) the step is refused when

- :math:`c = 0` (the corrector returned to the last point);
- :math:`t_k^T c \le 0` on the hyperplane, or :math:`t_k^T c \le -\cos\alpha_{max} |c|` on the
  sphere (the corrector went back along the path);
- :math:`|x_{s,k+1} - x_{s,start}| > \texttt{max\_correction}\; ds` on the hyperplane (branch
  jump);
- :math:`\lambda` moved against the sign of :math:`t_\lambda` at both ends (no fold between:
  another part of the path);
- :math:`t_k^T t_{k+1} \le 0` on the hyperplane, :math:`\le -\cos\alpha_{max}` on the sphere
  (the tangent reversed);
- the turn :math:`\arccos(t_k^T t_{k+1})` exceeds :math:`\alpha_{max}` =
  ``max_angle_deg``, unless it is a kink (the same turn, within 70 %, was refused at a longer
  step: it does not shrink with ``ds``) or ``ds`` cannot be halved above ``ds_min``.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .corrector import Correction
from .kernels import step_geometry
from .tangent import null_tangent


class Step(NamedTuple):
    """Outcome of one predictor-corrector step.

    Parameters
    ----------
    c : Correction or None
        The corrector's result (None in a refused step whose correction was let go).
    t_new : ndarray, shape (n+1,), or None
        New unit tangent (None when the step failed before it was computed).
    angle : float
        Turn between the old and the new tangent (rad; 0 when not computed).
    reason : str or None
        Why the step is refused (one line); None when accepted.
    on_bound : bool
        The point was solved with the parameter fixed on a bound.
    turned : bool
        Refused only for turning by more than ``max_angle_deg`` (a shorter step may pass).
    """

    c: Correction | None
    t_new: np.ndarray | None
    angle: float
    reason: str | None
    on_bound: bool
    turned: bool = False


def judge_step(c: Correction, xs, t, start, ds: float, sphere: bool, on_bound: bool, options,
               angle_reject, ds_min: float, linear_solve=None) -> Step:
    """Decide a converged correction ``c`` of the step from ``xs`` (module doc).

    Parameters
    ----------
    c : Correction
        Converged; ``c.null`` is the corrector's null vector when the constraint was the
        hyperplane normal to ``t``.
    xs, t, start : ndarray, shape (n+1,)
        Last point, its unit tangent, and the corrector's start.
    ds : float
    sphere, on_bound : bool
        Constraint used; parameter fixed on a bound.
    options : ArclengthOptions
    angle_reject : tuple (ds, angle) or None
        The last step refused for its turn.
    ds_min : float
    linear_solve : callable, optional
        The path's iterative solver, for the new tangent (:func:`continuation.tangent.null_tangent`).

    Returns
    -------
    Step
    """
    max_angle = math.radians(options.max_angle_deg)
    # the hyperplane's a is t: the corrector's null vector solves the tangent system
    # (finite, and t @ null = 1, so not zero)
    fast = c.null is not None and not sphere and not on_bound
    chord_len, along, jump, cosang, f = step_geometry(xs, t, c.xs, start, c.null if fast else t)
    if not chord_len > 0:
        return Step(c, None, 0.0, "the corrector returned to the last point", on_bound)
    if along <= (-math.cos(max_angle) * chord_len if sphere else 0.0):
        return Step(c, None, 0.0, "the corrector went back along the path", on_bound)
    if not sphere and not on_bound and jump > options.max_correction * ds:
        return Step(c, None, 0.0, f"the corrector moved {jump / ds:.2g} step lengths (branch jump)",
                    on_bound)
    if fast:
        t_new = c.null * f
    else:
        u = null_tangent(c.ev.Js, t, c.matrix, c.ev.row_norm(), linear_solve)     # consumes c.ev.Js
        if u is None:
            return Step(c, None, 0.0, "the tangent system is singular", on_bound)
        _, _, _, cosang, f = step_geometry(xs, t, c.xs, start, u)
        t_new = u * f
    cosang = min(1.0, max(-1.0, cosang))
    dlam = c.xs[-1] - xs[-1]
    if (not on_bound and t[-1] * t_new[-1] > 0 and dlam * t[-1] < 0
            and abs(dlam) > 1e-3 * ds * abs(t[-1])):
        # the parameter moved against both end tangents: no fold can lie between, so the
        # corrector landed on another part of the path (one that passes close by, e.g.
        # the start of a resonance loop seen from its end)
        return Step(c, None, 0.0, "the parameter went back without a fold (branch jump)", on_bound)
    angle = math.acos(cosang)
    if cosang <= (-math.cos(max_angle) if sphere else 0.0):
        return Step(c, t_new, angle, "the tangent reversed", on_bound)
    if angle > max_angle:
        kink = (angle_reject is not None and angle_reject[0] > ds
                and angle > 0.7 * angle_reject[1])
        if not kink and 0.5 * ds >= ds_min:
            return Step(c, t_new, angle, f"the tangent turned {math.degrees(angle):.1f} deg "
                        f"> max_angle_deg={options.max_angle_deg:g}", on_bound, turned=True)
    return Step(c, t_new, angle, None, on_bound)
