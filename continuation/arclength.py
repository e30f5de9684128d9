r"""Pseudo-arclength continuation of :math:`R(y, \lambda) = 0` for any callable.

The caller gives ``fun(x) -> (R, J)`` with :math:`x = [y, \lambda]` of shape (n+1,),
:math:`R` of shape (n,) and :math:`J = dR/dx` of shape (n, n+1).  The solver works on scaled
variables :math:`x_s = x / s` (:math:`J_s = J\,\mathrm{diag}(s)`); arclength is measured there.

Step :math:`k \to k+1` with unit tangent :math:`t_k` and step :math:`ds`:

.. math::

    \text{predictor:}\quad x_{s,pred} = x_{s,k} + ds\, t_k, \qquad
    \text{corrector:}\quad R(s \odot x_s) = 0,\;\; t_k^T (x_s - x_{s,pred}) = 0,

then the new tangent :math:`t_{k+1}` spans the null space of :math:`J_s(x_{k+1})`
(:mod:`continuation.tangent`) with the sign of the chord,
:math:`t_{k+1}^T (x_{s,k+1} - x_{s,k}) > 0`.  A step is rejected (``ds`` halved) when Newton
fails, the chord points backwards (:math:`t_k^T (x_{s,k+1} - x_{s,k}) \le 0`), the
correction exceeds ``max_correction * ds``, the parameter moves against the sign of
:math:`t_\lambda` at both ends (no fold lies between, so the corrector found another part of
the path), or the tangents turn by more than
``max_angle_deg``; a turn that does not shrink when ``ds`` is halved is a kink of the path
(non-smooth Jacobian) and is accepted, so is any turn below 90 degrees once ``ds`` cannot be
halved without going under ``ds_min``.  Accepted steps adapt ``ds`` as in
:mod:`continuation.options`.

Bounds: when the predictor (or the corrected point) leaves :math:`[\lambda_{lo},
\lambda_{hi}]`, the last point is solved with :math:`\lambda` fixed on the bound, starting
from the chord's crossing of the bound, and the run ends with status ``'finished'``.  A
corrected point outside the bounds counts only if it lies within ``max_correction * ds`` of
its predictor and :math:`\lambda` moved along :math:`t_\lambda`: a long step's hyperplane can
cut the path again beyond the other bound (a branch jump, refused like any other).

Parameter-step limit (optional ``lam_step``): the caller may know where the path has
features narrower than the step control can see from two end points, e.g. the linear
resonances of a frequency response, which a step can jump over whole when the path is
nearly straight on both sides of the peak.  ``lam_step(lam, direction)`` gives the largest
parameter change :math:`\Delta\lambda_{max}` for a step from :math:`\lambda` moving in
``direction`` (the sign of :math:`t_\lambda`); the step is then shortened to
:math:`ds \le \Delta\lambda_{max} / (s_\lambda |t_\lambda|)`, i.e. the predictor moves the
parameter by at most that much.

Folds: a sign change of :math:`t_\lambda` between two accepted points marks a turning point,
located by cubic Hermite interpolation of :math:`\lambda(s)`.

Default scale (``scale=None``): one common scale :math:`s_i = \|y_0\|_\infty` for all the
unknowns (1 when :math:`y_0 = 0`), so that small unknowns (e.g. weak higher harmonics) are not
inflated in the arclength, and :math:`s_\lambda = \max(|\lambda_0|,
\lambda_{hi} - \lambda_{lo})` for the parameter (with infinite bounds
:math:`\max(|\lambda_0|, 1)`).
"""
from __future__ import annotations

import math
from typing import Callable, Iterator

import numpy as np

from .acceptance import Step, judge_step
from .corrector import Correction, Evaluation, correct, linear_constraint, sphere_constraint
from .linsolve import direct_solve, make_solver
from .options import ArclengthOptions, default_scale
from .point import ContinuationPoint
from .tangent import fold_parameter, null_tangent

Fun = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def _sign(v: float) -> int:
    """Sign of a number as -1, 0 or +1."""
    return 1 if v > 0 else -1 if v < 0 else 0


def _norm(v: np.ndarray) -> float:
    """Euclidean norm of a vector (``np.linalg.norm`` without its wrapping cost)."""
    return math.sqrt(float(v @ v))


class Arclength:
    """Pseudo-arclength continuation; iterate it to get :class:`ContinuationPoint` objects.

    Parameters
    ----------
    fun : callable
        ``fun(x) -> (R, J)`` with ``x`` shape (n+1,), ``R`` shape (n,), ``J`` shape (n, n+1)
        dense.  Called once per Newton iteration (plus once per predictor).
    x0 : array_like, shape (n+1,)
        Starting guess ``[y0, lam0]``; it is corrected with ``lam`` fixed at ``lam0``.
    scale : array_like, shape (n+1,), or None
        Positive scales, ``xs = x / scale``; ``None`` derives them from ``x0``
        (:func:`default_scale`).
    lam_bounds : (float, float)
        Parameter interval; leaving it ends the run with a point exactly on the bound.
    direction : {+1, -1}
        Sign of the parameter's motion along the first tangent.
    options : ArclengthOptions or None
        ``None`` uses the defaults.
    lam_step : callable or None
        ``lam_step(lam, direction) -> float``: the largest parameter change (unscaled, > 0)
        of a step from ``lam`` whose parameter moves in ``direction`` (+1 or -1); ``None``:
        no limit (module doc).
    overwrite_jacobian : bool
        ``fun`` returns a new ``J`` on every call, which the solver may scale in place (saves
        one ``n x (n+1)`` array per evaluation on large systems).
    fun_into : callable, optional
        ``fun_into(x, out) -> R``: ``fun`` writing ``J`` into ``out`` (n, n+1), a C-ordered
        view of the rows of a Newton matrix.  Large systems then keep the Jacobian inside
        the corrector's Newton matrix (:func:`continuation.corrector.correct`): with the kept
        LU, two ``n x n`` arrays in all while a step is corrected.
    describe_lam : callable, optional
        ``lam -> str`` naming a parameter value in messages (default ``"lam=<value>"``).
    blocks : sequence of (int, int[, bool]), optional
        Ranges of unknowns coupled mainly among themselves: large systems precondition their
        Newton solves by these diagonal blocks (:class:`continuation.linsolve.BlockPreconditioned`).

    Attributes
    ----------
    status : str
        ``'running'`` until iteration ends, then ``'finished'`` (left the bounds),
        ``'max_steps'`` or ``'failed'``.
    message : str
        One-line explanation of ``status``.
    n_rejected : int
        Rejected steps.
    folds : list of float
        Parameter values of the folds passed.
    n_eval : int
        Calls of ``fun``.
    points : list of ContinuationPoint
        Points produced so far.
    ds0, ds_min, ds_max : float
        Resolved step lengths (scaled).
    """

    def __init__(self, fun: Fun, x0, scale=None, lam_bounds=(-np.inf, np.inf),
                 direction: int = +1, options: ArclengthOptions | None = None, lam_step=None,
                 overwrite_jacobian: bool = False, describe_lam=None, fun_into=None, blocks=None):
        x0 = np.array(x0, dtype=float).ravel()
        if x0.size < 2 or not np.all(np.isfinite(x0)):
            raise ValueError("x0 must be a finite vector [y, lam] with at least one unknown")
        lo, hi = (float(v) for v in lam_bounds)
        if not lo < hi:
            raise ValueError(f"lam_bounds must satisfy lo < hi, got {lam_bounds}")
        if not lo <= x0[-1] <= hi:
            raise ValueError(f"starting parameter {x0[-1]:g} lies outside {lam_bounds}")
        if direction not in (1, -1):
            raise ValueError(f"direction must be +1 or -1, got {direction}")
        if scale is None:
            scale = default_scale(x0, (lo, hi))
        scale = np.array(scale, dtype=float).ravel()
        if scale.shape != x0.shape or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
            raise ValueError(f"scale must be {x0.size} positive finite numbers")
        self.fun = fun
        self.fun_into = fun_into
        self.x0 = x0
        self.scale = scale
        self.lam_bounds = (lo, hi)
        self.direction = direction
        self.options = options if options is not None else ArclengthOptions()
        self.lam_step = lam_step
        self._overwrite = bool(overwrite_jacobian)
        # how messages name a parameter value (e.g. in Hz for a caller whose lam is rad/s)
        self._lam = describe_lam or (lambda lam: f"lam={lam:.6g}")
        self.ds0, self.ds_min, self.ds_max = self.options.step_lengths((hi - lo) / scale[-1])
        self.status = "running"
        self.message = ""
        self.n_rejected = 0
        self.folds: list[float] = []
        self.n_eval = 0
        self.points: list[ContinuationPoint] = []
        self._started = False
        self._rho0: float | None = None
        # large systems keep an LU across Newton iterations and steps (continuation.linsolve);
        # callers may solve their own (n+1, n+1) systems with it (a fixed-parameter polish)
        self.linear_solve = make_solver(x0.size, blocks, scale=self.scale)
        # tangents on the same solver when iterative (else null_tangent's in-place LU)
        self._tangent_solve = None if self.linear_solve is direct_solve else self.linear_solve

    # ------------------------------------------------------------------ evaluation
    def _evaluate(self, xs: np.ndarray) -> Evaluation:
        """One call of ``fun`` (inside :meth:`_correct`'s ``errstate``: NaN/inf are results)."""
        self.n_eval += 1
        n = xs.size - 1
        R, J = self.fun(xs * self.scale)
        R = np.ascontiguousarray(R, dtype=float).reshape(-1)
        J = np.ascontiguousarray(J, dtype=float)
        if R.shape != (n,) or J.shape != (n, n + 1):
            raise ValueError(f"fun must return R shape ({n},) and J shape ({n}, {n + 1}), "
                             f"got {R.shape} and {J.shape}")
        return Evaluation.scaled(xs.copy(), R, J, self.scale, out=J if self._overwrite else None)

    def _evaluate_into(self, xs: np.ndarray, out: np.ndarray) -> Evaluation:
        """One call of ``fun_into``, ``J`` written and scaled in ``out`` (n, n+1)."""
        self.n_eval += 1
        R = np.ascontiguousarray(self.fun_into(xs * self.scale, out), dtype=float).reshape(-1)
        if R.shape != (out.shape[0],):
            raise ValueError(f"fun_into must return R shape ({out.shape[0]},), got {R.shape}")
        return Evaluation.scaled(xs.copy(), R, out, self.scale, out=out)

    def _correct(self, xs0, constraint) -> Correction:
        o = self.options
        into = self._evaluate_into if self.fun_into is not None else None
        with np.errstate(all="ignore"):
            return correct(self._evaluate, xs0, constraint, self._rho0, o.tol, o.max_iter,
                           o.max_backtrack, linear_solve=self.linear_solve, evaluate_into=into)

    def _fixed_lam(self, xs0: np.ndarray, lam_s: float) -> Correction:
        e = np.zeros_like(xs0)
        e[-1] = 1.0
        start = xs0.copy()
        start[-1] = lam_s
        c = self._correct(start, linear_constraint(e, lam_s))
        c.xs[-1] = lam_s  # exactly on the requested value despite round-off in the update
        return c

    # ------------------------------------------------------------------ iteration
    def __iter__(self) -> Iterator[ContinuationPoint]:
        if self._started:
            yield from list(self.points)
            return
        self._started = True
        yield from self._run()

    def run(self) -> list[ContinuationPoint]:
        """Trace the whole path and return its points (same as ``list(self)``)."""
        return list(self)

    def _point(self, c: Correction, t, ds, fold, on_bound=False) -> ContinuationPoint:
        pt = ContinuationPoint(x=c.xs * self.scale, tangent=t.copy(), iterations=c.iterations,
                               ds=float(ds), fold=bool(fold), residual_norm=float(c.residual),
                               on_bound=on_bound)
        self.points.append(pt)
        return pt

    def _run(self) -> Iterator[ContinuationPoint]:
        o = self.options
        s_lam = self.scale[-1]
        lo_s, hi_s = self.lam_bounds[0] / s_lam, self.lam_bounds[1] / s_lam
        c, t = self._start(self.x0 / self.scale)
        if c is None:
            return
        xs = c.xs
        pt = self._point(c, t, 0.0, False, on_bound=xs[-1] in (lo_s, hi_s))
        c = None            # no Jacobian held while the caller works on the point
        yield pt
        lam_prev_sign = _sign(t[-1])
        ds = self.ds0
        steps = 0
        consecutive = 0
        angle_reject = None   # (ds, angle) of the last rejection for the angle
        while True:
            if steps >= o.max_steps:
                self.status = "max_steps"
                self.message = (f"stopped after max_steps={o.max_steps} steps at "
                                f"{self._lam(xs[-1] * s_lam)}")
                return
            if (xs[-1] >= hi_s and t[-1] > 0) or (xs[-1] <= lo_s and t[-1] < 0):
                self.status = "finished"
                self.message = f"parameter reached the bound {self._lam(xs[-1] * s_lam)}"
                return
            ds = self._limited(xs, t, ds)
            c = out = None      # the last step's Jacobians are not needed any more
            out = self._attempt(xs, t, ds, angle_reject, consecutive)
            c, t_new, angle, reason, on_bound = out[:5]
            if reason is not None:
                self.n_rejected += 1
                consecutive += 1
                if out.turned:
                    angle_reject = (ds, angle)
                # other reasons keep the memory of a turn: at a corner the hyperplane
                # corrector fails (branch jump) at every ds, only the sphere sees the turn
                ds *= 0.5
                if ds < self.ds_min:
                    self._fail(f"step size fell below ds_min={self.ds_min:.3g} at "
                               f"{self._lam(xs[-1] * s_lam)} after {consecutive} rejections: "
                               f"{reason}")
                    return
                continue
            # --- accept
            steps += 1
            sign_new = _sign(t_new[-1])
            fold = lam_prev_sign != 0 and sign_new != 0 and sign_new != lam_prev_sign
            if fold:
                lam_f = fold_parameter(xs[-1], c.xs[-1], t[-1], t_new[-1], _norm(c.xs - xs))
                self.folds.append(float(lam_f * s_lam))
            lam_prev_sign = sign_new or lam_prev_sign
            pt = self._point(c, t_new, ds, fold, on_bound=on_bound)
            c_xs, c_its = c.xs, c.iterations
            c = out = None      # no Jacobian held while the caller works on the point
            yield pt
            if on_bound:
                self.status = "finished"
                self.message = (f"parameter left the bounds; last point solved on "
                                f"{self._lam(c_xs[-1] * s_lam)} after {steps} steps, "
                                f"{len(self.folds)} folds, {self.n_rejected} rejections")
                return
            xs, t = c_xs, t_new
            # a step shorter than the last rejected turn approaches a corner: keep the
            # memory, so that the same turn at a smaller ds is recognised as a kink
            # (otherwise the path creeps towards the corner in ever shorter steps)
            if angle_reject is not None and not ds < angle_reject[0]:
                angle_reject = None
            ds = self._next_ds(ds, c_its, angle, consecutive)
            consecutive = 0

    def _start(self, xs):
        """The starting point, solved with the parameter fixed (its Jacobian's row norm becomes
        ``rho0``), and its tangent along ``direction``: ``(c, t)``, or ``(None, None)`` after
        :meth:`_fail`."""
        self._rho0 = None
        c = self._fixed_lam(xs, xs[-1])
        self._rho0 = c.ev.row_norm() or 1.0
        if not c.converged:
            self._fail(f"starting point not solved at {self._lam(self.x0[-1])}: {c.reason}")
            return None, None
        e = np.zeros_like(xs)
        e[-1] = self.direction
        t = null_tangent(c.ev.Js, e, c.matrix, c.ev.row_norm(), self._tangent_solve)
        if t is None:
            self._fail(f"the path's tangent at the starting point {self._lam(self.x0[-1])} is "
                       f"undefined (singular bordered system)")
            return None, None
        return c, (-t if t[-1] * self.direction < 0 else t)

    def _attempt(self, xs, t, ds, angle_reject, consecutive) -> Step:
        """One step on the hyperplane; after a rejection at this point, also on the sphere."""
        out = self._step(xs, t, ds, angle_reject, False)
        if out.reason is not None and consecutive >= 1 and not out.on_bound:
            # repeated trouble at this point: maybe a sharp corner of the path, which a
            # hyperplane normal to t cannot cross; try a sphere around the last point
            # (the refused step's correction, and its Newton matrix, are let go first)
            out = out._replace(c=None)
            out2 = self._step(xs, t, ds, angle_reject, True)
            if out2.reason is None or out2.turned:
                return out2
        return out

    def _next_ds(self, ds: float, iterations: int, angle: float, consecutive: int) -> float:
        """The step after an accepted one (:mod:`continuation.options`): Newton's iterations
        against ``target_iter``, the turn against ``max_angle_deg``, no growth right after a
        rejection."""
        o = self.options
        factor = min(max(math.sqrt(o.target_iter / max(iterations, 1)), o.shrink_min), o.grow_max)
        if angle > 0:
            factor = min(factor, max(o.shrink_min, 0.8 * math.radians(o.max_angle_deg) / angle))
        if consecutive:
            factor = min(factor, 1.0)
        return min(max(ds * factor, self.ds_min), self.ds_max)

    def _limited(self, xs, t, ds):
        """``ds`` shortened so that the predictor moves the parameter by at most
        ``lam_step`` (module doc), never below ``ds_min``."""
        if self.lam_step is None or t[-1] == 0.0:
            return ds
        s_lam = self.scale[-1]
        cap = float(self.lam_step(xs[-1] * s_lam, 1 if t[-1] > 0 else -1))
        if not cap > 0:
            return self.ds_min
        return max(min(ds, cap / (s_lam * abs(t[-1]))), self.ds_min)

    def _step(self, xs, t, ds, angle_reject, sphere) -> Step:
        """Predict and correct one step (:mod:`continuation.acceptance` decides it).

        ``sphere`` replaces the hyperplane ``t @ (xs' - pred) = 0`` by the sphere
        ``|xs' - xs| = ds``, which may turn by more than 90 degrees (a corner of the path);
        only a turn back onto the incoming direction is refused then.
        """
        o = self.options
        s_lam = self.scale[-1]
        lo_s, hi_s = self.lam_bounds[0] / s_lam, self.lam_bounds[1] / s_lam
        pred = xs + ds * t
        start = pred
        on_bound = False
        bound = hi_s if pred[-1] > hi_s else lo_s if pred[-1] < lo_s else None
        if bound is not None:
            start = xs + ((bound - xs[-1]) / (pred[-1] - xs[-1])) * (pred - xs)
            c = self._fixed_lam(start, bound)
            on_bound = True
        else:
            con = sphere_constraint(xs, ds) if sphere else linear_constraint(t, float(t @ pred))
            c = self._correct(pred, con)
            if c.converged and not lo_s <= c.xs[-1] <= hi_s:
                # the hyperplane may cut the path again far away (a scaled tangent made of
                # amplitudes meets the same amplitudes at the other end of the window):
                # leave the window only from a point found near the predictor, moving on
                jump = _norm(c.xs - pred)
                if jump > o.max_correction * ds or (c.xs[-1] - xs[-1]) * t[-1] < 0:
                    return Step(c, None, 0.0, f"the corrector left the window {jump / ds:.2g} "
                                f"step lengths from the predictor (branch jump)", False)
                bound = hi_s if c.xs[-1] > hi_s else lo_s
                start = xs + ((bound - xs[-1]) / (c.xs[-1] - xs[-1])) * (c.xs - xs)
                c = self._fixed_lam(start, bound)
                on_bound = True
        if not c.converged:
            return Step(c, None, 0.0, f"Newton did not converge ({c.reason})", on_bound)
        return judge_step(c, xs, t, start, ds, sphere, on_bound, o, angle_reject, self.ds_min,
                          self._tangent_solve)

    def _fail(self, message: str) -> None:
        self.status = "failed"
        self.message = message
