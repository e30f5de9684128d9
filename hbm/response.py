r"""Frequency response by harmonic balance and pseudo-arclength continuation.

The FRF is the branch of solutions of :math:`R(X, w) = 0` (:mod:`hbm.residual`) traced from
``fmin`` to ``fmax`` by :mod:`continuation` on ``x = [X.ravel(), w]`` with per-unknown
scaling.  The first point is solved by Newton from the linear response with the elements
stuck; failing that, from the response without elements; failing that, by ramping the
excitation.  Every converged point is checked by the energy balance (:mod:`hbm.energy`)
and, unless switched off, by Hill's method (:mod:`hbm.stability`).
Outputs per point: first-harmonic amplitude ``h1 = sqrt(Xc1^2 + Xs1^2)`` and ``max`` of
``|x(t)|`` over a period on a fine grid.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from continuation import Arclength, ArclengthOptions
from continuation.linsolve import REUSE_MIN_SIZE, ReusedLU

from .case import Case, CaseError
from .condensed import CondensedHarmonicBalance
from .element_outputs import element_output_series
from .energy import energy_balance
from .fourier import FourierBasis, parse_harmonics, min_samples, default_samples, max_abs
from .jumps import predict_jumps
from .newton import newton
from .mode_cover import reduce_covering
from .stuck import stuck_contacts
from .truncation import MAX_UNKNOWNS, SMALL_ERROR, WARN_ERROR, richer_basis, truncation_errors
from .reduction_cache import cache_path
from .residual import HarmonicBalance
from .resonances import ResonanceStepLimit, linear_resonances
from .stability import HillSystem, StabilityOptions, point_is_stable
from .stability_path import hill_margin, path_stability
from .structure import AUTO_CONDENSE_DOF
from .budget import check_memory
from .transforms import fftw_available, make_transform


@dataclass(frozen=True)
class OutputSeries:
    """Per-point amplitudes of one output: ``h1`` and ``max`` (n_points,), and ``err``, the
    estimated relative error of ``h1`` from the harmonic truncation (:mod:`hbm.truncation`;
    None when not computed)."""

    h1: np.ndarray
    max: np.ndarray
    err: np.ndarray | None = None


@dataclass(frozen=True)
class FRFResult:
    """A traced FRF.

    Attributes
    ----------
    freq_hz : ndarray, shape (n_points,)
        Along the continuation path (folds appear as frequency reversals).
    outputs : dict of str -> OutputSeries
    X : ndarray, shape (n_points, n_coef, n)
        Harmonic coefficients of every point's unknowns: all DOFs (full solver, supports
        included) or the contact coordinates (condensed solver).
    stable : ndarray of bool, shape (n_points,), or None
        Hill stability of every point (``None`` when not computed).
    folds_hz : list of float
    energy_error : ndarray, shape (n_points,)
        Relative energy-balance error per point.
    iterations : ndarray of int, shape (n_points,)
    element_outputs : dict of str -> ndarray, shape (n_points,)
        Per-period element quantities (``"ELEMENT.QUANTITY"`` outputs), :mod:`hbm.element_outputs`.
    status, message : str
        ``finished`` / ``failed`` / ``max_steps`` and a one-line explanation.
    jumps : dict or None
        Per output, the predicted jumps of slow up and down sweeps
        (:func:`hbm.jumps.predict_jumps`, landing amplitudes solved exactly); ``None`` when
        the stability was not computed.
    """

    freq_hz: np.ndarray
    outputs: dict
    X: np.ndarray
    basis: FourierBasis
    stable: np.ndarray | None
    folds_hz: list
    energy_error: np.ndarray
    iterations: np.ndarray
    status: str
    message: str
    n_rejected: int
    solve_seconds: float
    settings: dict = field(default_factory=dict)
    jumps: dict | None = None
    element_outputs: dict = field(default_factory=dict)
    Y: np.ndarray | None = None
    """Output coefficients of every point, (n_points, n_coef, n_outputs), in ``outputs`` order."""
    stuck: np.ndarray | None = None
    """Hysteretic contacts stuck for the whole period at every point (:mod:`hbm.stuck`; a
    point with one has a family of periodic solutions), None without such contacts."""

    @property
    def ok(self) -> bool:
        return self.status == "finished"

    def __repr__(self) -> str:
        f = self.freq_hz
        span = f"{f.min():.6g}..{f.max():.6g} Hz" if f.size else "no points"
        h = self.settings.get("harmonics", [])
        return (f"FRFResult({self.status}, {f.size} points, {span}, H={h[-1] if h else '?'}, "
                f"outputs={list(self.outputs)}, stable={'computed' if self.stable is not None else 'not computed'})")

    def nearest(self, freq_hz: float) -> int:
        """Index of the point nearest to ``freq_hz`` along the path (the first, at a fold)."""
        return int(np.argmin(np.abs(self.freq_hz - float(freq_hz))))

    def table(self) -> dict:
        """The ``frf.csv`` columns as arrays (name -> ndarray (n_points,)), in file order, plus
        ``energy_error``; ``stable`` is float (1/0, NaN when not computed)."""
        cols = {"freq_hz": self.freq_hz}
        for name, o in self.outputs.items():
            cols[f"{name}_h1"], cols[f"{name}_max"] = o.h1, o.max
            if o.err is not None:
                cols[f"{name}_err"] = o.err
        cols.update(self.element_outputs)
        if self.stuck is not None:
            cols["stuck_contacts"] = self.stuck
        cols["stable"] = (np.full(self.freq_hz.size, np.nan) if self.stable is None
                          else np.asarray(self.stable, dtype=float))
        cols["energy_error"] = self.energy_error
        return cols

    def to_frame(self):
        """:meth:`table` as a pandas DataFrame (needs pandas: ``pip install 'hbm-friction[pandas]'``)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("FRFResult.to_frame needs pandas (pip install 'hbm-friction[pandas]'); "
                              "FRFResult.table() gives the same columns as arrays") from None
        return pd.DataFrame(self.table())


def resolve_settings(case: Case, harmonics=None, samples=None, fmin=None, fmax=None, transform=None):
    """Analysis settings with command-line / API overrides applied and validated.

    An override of H without one of N gives ``N = factor * default_samples(H)`` (``factor``
    the elements' ``default_samples_factor``), or the case's N if that is larger and was
    given in the case.
    """
    a = case.analysis
    if harmonics is None:
        h = a.harmonics
    else:
        try:
            h = parse_harmonics(harmonics, include_zero=any(e.needs_mean for e in case.elements))
        except (ValueError, TypeError) as exc:
            raise CaseError(f"--harmonics: {exc}") from None
        if 1 not in h:
            raise CaseError(f"--harmonics must include 1 (the excitation's harmonic), got {list(map(int, h))}")
    if samples is None:
        N_case = a.time_samples if a.samples_source == "case" else 0
        N = a.time_samples if harmonics is None else max(N_case, default_samples(h, a.samples_factor))
    else:
        N = int(samples)
    if N < min_samples(h):
        raise CaseError(f"time samples N={N} too small for harmonics up to {max(h)} (need >= {min_samples(h)})")
    lo = a.freq_hz[0] if fmin is None else float(fmin)
    hi = a.freq_hz[1] if fmax is None else float(fmax)
    if not (lo > 0 and hi > lo):
        raise CaseError(f"frequency range is empty or not positive ({lo} .. {hi} Hz)")
    tr = transform or a.transform
    n_coef = (2 * int(np.count_nonzero(h)) + int(np.count_nonzero(h == 0)))
    check_memory(case, n_coef, int(N), choose_solver(case) == "condensed")
    if tr == "fftw" and not fftw_available():
        raise CaseError("transform 'fftw' needs pyFFTW, which is not installed: "
                        "pip install 'hbm-friction[fftw]', or choose transform = 'numpy' or 'auto'")
    return h, N, lo, hi, tr


def setting_sources(case: Case, harmonics, samples, N: int) -> dict:
    """Where H and N came from, for the FRF settings: ``harmonics_source`` and
    ``time_samples_source``, each ``"argument"`` (API / command-line override), ``"case"``
    (the case file) or ``"default"`` (the elements' defaults, :func:`hbm.case.element_defaults`).
    ``N`` is the resolved sample count (:func:`resolve_settings`)."""
    a = case.analysis
    if samples is not None:
        ns = "argument"
    elif harmonics is None:
        ns = a.samples_source
    else:
        ns = "case" if a.samples_source == "case" and N == a.time_samples else "default"
    return {"harmonics_source": "argument" if harmonics is not None else a.harmonics_source,
            "time_samples_source": ns}


# Smallest per-DOF unknown scale, relative to the largest.  DOFs that the linear responses
# leave at rest (by symmetry, e.g. the radial motion of a wedge damper in the in-phase mode)
# still move through nonlinear effects (mean shifts from normal-load variation); with a floor
# of 1e-6 the continuation measured those small motions as huge scaled steps and stalled.
SCALE_FLOOR = 1e-2


def choose_solver(case: Case) -> str:
    """``full`` or ``condensed`` for ``case`` (``[model] solver``, ``auto`` by size)."""
    s = case.reduction.solver
    if s != "auto":
        return s
    st = case.structure
    return "condensed" if st.sparse or st.n_dof > AUTO_CONDENSE_DOF else "full"


def build_problem(case: Case, basis: FourierBasis, transform: str, fmax_hz: float | None = None):
    """The harmonic-balance problem of ``case`` on ``basis`` and what was chosen.

    ``fmax_hz`` (default: the case's window) is the frequency the condensed solver's kept
    modes must cover (:mod:`hbm.mode_cover`).

    Returns
    -------
    problem : HarmonicBalance or CondensedHarmonicBalance
    info : dict
        ``solver``, ``n_dof`` (model), ``n_unknowns``, and for the condensed solver ``modes``,
        ``residual_flexibility``, ``contact_coordinates``, ``reduction_seconds``,
        ``reduction_cached``.
    """
    solver = choose_solver(case)
    tr = make_transform(basis, transform)
    fmax_hz = case.analysis.freq_hz[1] if fmax_hz is None else float(fmax_hz)
    st = case.structure
    info = {"solver": solver, "n_dof": st.n_dof}
    if solver == "full":
        ex = case.excitation
        problem = HarmonicBalance(case.model, case.elements, basis, np.vstack([ex.force, ex.force_sine]), tr,
                                  base=case.excitation.base, output_rows=case.analysis.output_rows(st.n_dof))
        info.update(modes=None, reduction_seconds=0.0)
    elif case.excitation.base is not None:
        raise CaseError(f"{case.path}: [excitation] base (support motion) needs the full solver: "
                        f"set [model] solver = \"full\"")
    else:
        G_o = case.analysis.output_rows(st.n_dof)
        force = np.vstack([case.excitation.force, case.excitation.force_sine])
        rows = np.vstack([e.gather for e in case.elements] + [force, G_o])
        keep = np.flatnonzero(np.any(rows != 0.0, axis=0))
        modes = case.reduction.modes or st.default_modes()
        try:
            cr, cover = reduce_covering(st, keep, modes, case.reduction.residual_flexibility, cache_path(case.path),
                                        fmax_hz, basis.harmonics)
            problem = CondensedHarmonicBalance(cr.reduced, case.elements, basis, force, tr, G_o)
        except ValueError as exc:
            raise CaseError(f"{case.path}: [model] condensed solver: {exc}") from exc
        info.update(**cover, residual_flexibility=case.reduction.residual_flexibility,
                    contact_coordinates=int(problem.n_dof),
                    reduction_seconds=round(cr.seconds, 6), reduction_cached=cr.from_cache)
    info["n_unknowns"] = int(problem.basis.n_coef * problem.n_dof)
    return problem, info


def _stuck_stiffness(problem) -> np.ndarray:
    """Stiffness of the elements at rest over the problem's unknowns, (n, n)."""
    K = np.zeros((problem.n_dof, problem.n_dof))
    for e in problem.nl.elements:
        K += e.gather.T @ e.linear_stiffness() @ e.gather
    return K


def recover_outputs(problem, case: Case, X: np.ndarray, w: float) -> np.ndarray:
    """Output coefficients (n_coef, n_outputs) of a point ``X`` (n_coef, n) at ``w``
    (``problem.recover_outputs``: the problem was built with ``case``'s outputs)."""
    return problem.recover_outputs(X, w)


def _stuck_damping(problem) -> np.ndarray:
    """Viscous tangent at rest of velocity-dependent elements (``linear_damping``), (n, n)."""
    C = np.zeros((problem.n_dof, problem.n_dof))
    for e in problem.nl.elements:
        cd = getattr(e, "linear_damping", None)
        if cd is not None:
            C += e.gather.T @ cd() @ e.gather
    return C


def _unknown_scale(problem, case: Case, w_lo: float, w_hi: float) -> np.ndarray:
    """Per-unknown scale: geometric mean of the stuck and free linear peak responses per DOF
    (the stuck one alone where the free system leaves the DOF at rest).  "Stuck" adds every
    element's tangent at rest: ``linear_stiffness`` and, for velocity laws, ``linear_damping``.

    The linear responses include the supports' imposed motion (base excitation).
    """
    ws = np.linspace(w_lo, w_hi, 41)
    amp_free, amp_stuck = problem.linear_peak_amplitudes(ws, _stuck_stiffness(problem), _stuck_damping(problem))
    # a DOF that only the elements couple to the force (free response nil) takes its stuck
    # amplitude, and one without any linear response (round-off) the largest scale: a
    # geometric mean with nil or the 1e-6 floor inflates it in the arclength (the path creeps)
    top = max(amp_free.max(), amp_stuck.max())
    nil = 1e-9 * top if top > 0 else 1.0
    af, ast = amp_free > nil, amp_stuck > nil
    s = np.where(af & ast, np.sqrt(amp_free * amp_stuck), np.where(af, amp_free, amp_stuck))
    smax = s.max() if s.max() > 0 else 1.0
    s = np.where(af | ast, np.maximum(s, SCALE_FLOOR * smax), smax)
    return np.tile(s, problem.basis.n_coef)


def _first_point(problem, case, w0, scale, r_scale):
    """Converged first point ``X`` (n_coef, n) at ``w0``, or raise RuntimeError with the reason.

    Newton from the linear response with the elements stuck, then without them; failing
    both, the Newton homotopy ``R(x) - (1 - lam) R(0)`` from ``lam = 0`` (solved by ``x = 0``)
    to ``lam = 1``.
    """
    fun = lambda x: problem.residual(problem.expand(x), w0)[:2]
    guesses = [problem.linear_solution(w0, _stuck_stiffness(problem)), problem.linear_solution(w0)]
    last = None
    for g in guesses:
        res = newton(fun, problem.unknowns(g), scale=scale, r_scale=r_scale)
        if res.converged:
            return problem.expand(res.x), res.iterations
        last = res
    x = np.zeros(problem.n_unknowns)
    R0 = fun(x)[0]
    its = 0
    for lam in (0.1, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0):
        def fun_l(x, lam=lam):
            R, J = fun(x)
            return R - (1.0 - lam) * R0, J
        res = newton(fun_l, x, scale=scale, r_scale=r_scale, max_iter=60)
        its += res.iterations
        if not res.converged:
            raise RuntimeError(f"first point at {w0 / (2 * np.pi):.6g} Hz did not converge "
                               f"(linear starts: {last.message}; ramp stopped at {lam:.0%} of the excitation: "
                               f"{res.message})")
        x = res.x
    return problem.expand(x), its


def _residual_scale(problem, w) -> float:
    """Typical force of the problem: the norm of the residual at zero unknowns (the load)."""
    R = problem.residual(problem.expand(np.zeros(problem.n_unknowns)), w)[0]
    return float(max(np.linalg.norm(R), 1e-300))


POLISH_ENERGY = 1e-10
# a point whose energy balance stays looser than this after polishing is not a solution
# the FRF can report: the path ends before it (status failed, the point named)
ENERGY_LIMIT = 1e-8
# Hill exponents whose real part exceeds this fraction of w (growth by exp(0.3) per period)
# are flagged: measured on benchmarks/upd_like.toml, exponents of 0.88 w where a time
# integration at 248 Hz settles (modes above the retained harmonics, not the response)
IMPLAUSIBLE_GROWTH = 0.05


def _polish(problem, X, w, xscale, r_scale, err, linear_solve=None):
    """Newton at fixed ``w`` on a point whose energy balance is not closed.

    The continuation's tolerance is relative to the Jacobian's row norm, which a stiff
    contact (kt >> k) makes large against the excitation: such a point can be accepted with
    ``|R| / |F|`` ~ 1e-9 and an energy error ~ 1e-6.  Here the target is relative to ``|F|``.
    Returns the better of the two points and its relative energy error.  ``linear_solve``:
    Newton's linear solver (:func:`hbm.newton.newton`), one kept LU shared by a path's polishes.
    """
    fun = lambda u: problem.residual(problem.expand(u), w)[:2]
    res = newton(fun, problem.unknowns(X), scale=xscale, r_scale=r_scale, tol=1e-13, max_iter=4,
                 linear_solve=linear_solve)
    if np.all(np.isfinite(res.x)):
        Xp = problem.expand(res.x)
        err_p = energy_balance(problem, Xp, w).relative_error
        if err_p < err:
            return Xp, err_p
    return X, err


def _closure_warning(settings, unclosed, ws):
    """``settings["closure_warning"]`` when a point's element loops did not all close."""
    bad = [i for i, n in enumerate(unclosed) if n]
    settings["unclosed_loop_points"] = len(bad)
    if bad:
        settings["closure_warning"] = (
            f"at {len(bad)} of {len(ws)} points (first {ws[bad[0]] / (2 * np.pi):.6g} Hz) the hysteresis "
            f"loop of up to {max(unclosed)} contact(s) did not close within the element's max_passes "
            f"periods: their forces carry the closure error (a contact slipping very little per cycle)")


class _Path:
    """Converged points of a traced path: coefficients, frequencies, outputs, iterations, errors."""

    def __init__(self):
        self.X, self.w, self.Y, self.its, self.err, self.unclosed = [], [], [], [], [], []

    def extend_reversed(self, other: "_Path") -> None:
        for name in ("X", "w", "Y", "its", "err", "unclosed"):
            getattr(self, name).extend(getattr(other, name)[::-1])


def _step_limit(problem, case, window) -> ResonanceStepLimit:
    """The FRF's parameter-step limit at the linear resonances of the free and stuck limits
    (:mod:`hbm.resonances`) inside ``window`` (rad/s)."""
    d = np.ix_(problem.modal_rows(), problem.modal_rows())
    om, z = linear_resonances(problem.modal_data(), _stuck_stiffness(problem)[d], _stuck_damping(problem)[d])
    return ResonanceStepLimit(om, z, window)


def _trace(problem, case, pts, X0, it0, w0, bounds, direction, xscale, r_scale, opts, progress, offset=0,
           lam_step=None):
    """One continuation from ``(X0, w0)`` in ``direction``; appends to ``pts``.

    Returns ``(status, message, folds_hz, n_rejected)``.  Points whose energy balance is
    looser than ``POLISH_ENERGY`` are polished by a fixed-frequency Newton solve; a point
    still looser than ``ENERGY_LIMIT`` ends the path (status ``failed``, not kept).
    """
    scale = np.r_[xscale, bounds[1] - bounds[0]]
    solver = Arclength(problem, np.r_[problem.unknowns(X0), w0], scale, lam_bounds=bounds,
                       direction=direction, options=opts, lam_step=lam_step, overwrite_jacobian=True)
    polish_solve = ReusedLU() if problem.n_unknowns >= REUSE_MIN_SIZE else None
    for pt in solver:
        X = problem.expand(pt.x[:-1])
        w = float(pt.x[-1])
        err = energy_balance(problem, X, w).relative_error
        if err > POLISH_ENERGY:
            X, err = _polish(problem, X, w, xscale, r_scale, err, polish_solve)
        if err > ENERGY_LIMIT:
            return ("failed", f"stopped at {w / (2 * np.pi):.6g} Hz: the energy balance of the "
                    f"converged point does not close (relative error {err:.1e} > {ENERGY_LIMIT:g} "
                    f"after polishing); the {len(pts.w)} points before it are kept",
                    [f / (2 * np.pi) for f in solver.folds], solver.n_rejected)
        pts.X.append(X)
        pts.w.append(w)
        pts.Y.append(recover_outputs(problem, case, X, w))
        pts.its.append(pt.iterations if pts.w[1:] else it0 + pt.iterations)
        pts.err.append(err)
        pts.unclosed.append(problem.nl.last_unclosed)    # of the energy balance's force call at X
        if progress is not None:
            progress(offset + len(pts.w), w / (2 * np.pi))
        if offset + len(pts.w) >= case.analysis.max_points:
            break
    return solver.status, solver.message, [f / (2 * np.pi) for f in solver.folds], solver.n_rejected


def frf(case: Case, harmonics=None, samples=None, fmin=None, fmax=None, transform=None,
        progress=None, options: ArclengthOptions | None = None, stability: bool = True,
        stability_options: StabilityOptions | None = None, error_estimate: bool = True) -> FRFResult:
    """Trace the FRF of ``case``.

    Parameters
    ----------
    case : Case
    harmonics : int or list of int, optional
        Overrides ``[analysis] harmonics``.
    samples : int, optional
        Overrides ``[analysis] time_samples``.
    fmin, fmax : float, optional
        Override the frequency range (Hz).
    transform : str, optional
        ``auto``, ``dft``, ``numpy`` or ``fftw``.
    progress : callable, optional
        Called as ``progress(n_points, freq_hz)`` after every converged point, and as
        ``progress(n_points, None)`` when the stability pass starts.
    options : ArclengthOptions, optional
    stability : bool
        Decide the stability of every point by Hill's method (``FRFResult.stable``);
        ``False`` leaves ``stable`` as ``None``.
    stability_options : StabilityOptions, optional
    error_estimate : bool
        Estimate every point's truncation error (``outputs[name].err``, :mod:`hbm.truncation`).

    Returns
    -------
    FRFResult
        Always returned, also when the continuation fails (``status``/``message`` say why,
        with every point converged so far).
    """
    h, N, lo, hi, tr = resolve_settings(case, harmonics, samples, fmin, fmax, transform)
    basis = FourierBasis(h, N)
    problem, info = build_problem(case, basis, tr, hi)
    stability = bool(stability)
    w_lo, w_hi = 2 * np.pi * lo, 2 * np.pi * hi
    t0 = time.perf_counter()
    xscale = _unknown_scale(problem, case, w_lo, w_hi)
    r_scale = _residual_scale(problem, w_lo)
    settings = {"harmonics": [int(x) for x in h], "time_samples": int(N), "fmin_hz": lo, "fmax_hz": hi,
                "transform": problem.nl.transform.name, "stability": stability,
                **setting_sources(case, harmonics, samples, N), **info}
    shape = (basis.n_coef, problem.n_dof)
    pts = _Path()
    status, message, folds, n_rej = "failed", "", [], 0
    segments = []
    try:
        X0, it0 = _first_point(problem, case, w_lo, xscale, r_scale)
    except RuntimeError as exc:
        message = str(exc)
    else:
        opts = options or ArclengthOptions()
        lam_step = _step_limit(problem, case, (w_lo, w_hi))
        seg = _trace(problem, case, pts, X0, it0, w_lo, (w_lo, w_hi), +1, xscale, r_scale, opts, progress,
                     lam_step=lam_step)
        status, message, folds, n_rej = seg
        segments.append([0, len(pts.w)])
        if status == "finished" and pts.w and pts.w[-1] < w_hi * (1 - 1e-9):
            # the branch folded back out of the window at fmin (e.g. a softening upper branch):
            # the rest of the window lies on another branch, traced from fmax downwards
            first_msg = (f"the branch from {lo:.6g} Hz folded back to {pts.w[-1] / (2 * np.pi):.6g} Hz; "
                         f"traced the rest from {hi:.6g} Hz down")
            part = _Path()
            try:
                Xh, ith = _first_point(problem, case, w_hi, xscale, r_scale)
            except RuntimeError as exc:
                status, message = "failed", f"{first_msg}, but: {exc}"
            else:
                st2, msg2, f2, r2 = _trace(problem, case, part, Xh, ith, w_hi, (w_lo, w_hi), -1, xscale,
                                           r_scale, opts, progress, offset=len(pts.w), lam_step=lam_step)
                folds, n_rej = folds + f2, n_rej + r2
                if st2 == "finished" and part.w and part.w[-1] > w_lo * (1 + 1e-9):
                    st2 = "failed"
                    msg2 = (f"the FRF between {part.w[-1] / (2 * np.pi):.6g} Hz and the first branch is not "
                            f"traced: the branch from {hi:.6g} Hz folded back too")
                status, message = st2, f"{first_msg}: {msg2}"
                segments.append([len(pts.w), len(pts.w) + len(part.w)])
                pts.extend_reversed(part)
        if len(pts.w) >= case.analysis.max_points and status not in ("finished", "failed"):
            status = "max_steps"
            message = f"stopped after max_points={case.analysis.max_points} points at {pts.w[-1] / (2 * np.pi):.6g} Hz"
    pts_X, pts_w, pts_Y, its, eerr = pts.X, pts.w, pts.Y, pts.its, pts.err
    settings["segments"] = segments
    _closure_warning(settings, pts.unclosed, pts.w)
    stable = None
    if stability:
        if progress is not None:
            progress(len(pts_w), None)
        stable, margin = _path_verdicts(problem, pts_X, np.array(pts_w), segments, stability_options)
        settings["stability_spectra"] = int(np.isfinite(margin).sum())
        growth = margin / np.array(pts_w)
        settings["stability_max_growth"] = float(np.nanmax(growth)) if np.isfinite(margin).any() else None
        if np.nanmax(growth, initial=-np.inf) > IMPLAUSIBLE_GROWTH:
            settings["stability_warning"] = (
                f"Hill exponents grow by up to exp({2 * np.pi * np.nanmax(growth):.2g}) per period: "
                f"typical of modes above the retained harmonics, not of a friction-damped response; "
                f"check an unstable point with hbm timesim or raise the harmonics")
    secs = time.perf_counter() - t0
    Xs = np.array(pts_X) if pts_X else np.zeros((0,) + shape)
    n_out = len(case.analysis.outputs)
    Ys = np.array(pts_Y) if pts_Y else np.zeros((0, basis.n_coef, n_out))
    outputs = {}
    for i, name in enumerate(case.analysis.outputs):
        yd = Ys[:, :, i]
        if 1 in basis.harmonics and Ys.shape[0]:
            rc = basis.row_of(1, "c")
            h1 = np.hypot(yd[:, rc], yd[:, rc + 1])
        else:
            h1 = np.zeros(Ys.shape[0])
        mx = max_abs(basis, yd.T)
        outputs[name] = OutputSeries(h1, mx)
    freq_hz = np.array(pts_w) / (2 * np.pi)
    jumps = None
    if stable is not None:
        land = _landing_solver(problem, Xs, freq_hz, xscale, r_scale, stability_options)
        jumps = {}
        for i, name in enumerate(case.analysis.outputs):
            def refine(i0, i1, f, i=i):
                X = land(i0, i1, f)
                if X is None:
                    return None
                return output_amplitudes(basis, recover_outputs(problem, case, X, 2 * np.pi * f)[:, i])[0]
            jumps[name] = predict_jumps(freq_hz, outputs[name].h1, stable, folds, refine=refine)
    eouts = element_output_series(problem, case.analysis.element_outputs, Xs, np.array(pts_w))
    if error_estimate and Xs.shape[0]:
        outputs = _with_errors(case, problem, outputs, Xs, np.array(pts_w), hi, settings)
    stuck = stuck_contacts(problem, Xs, np.array(pts_w))
    if stuck is not None:
        settings["stuck_points"] = int(np.count_nonzero(stuck))
    return FRFResult(freq_hz, outputs, Xs, basis, stable, folds,
                     np.array(eerr), np.array(its, dtype=int), status, message, n_rej, secs, settings,
                     jumps, eouts, Ys, stuck)


def _with_errors(case, problem, outputs, Xs, ws, fmax_hz, settings) -> dict:
    """``outputs`` with the truncation error estimate of every point (:mod:`hbm.truncation`);
    ``settings`` gains ``error_estimate`` (computed, richer H, largest error per output) and,
    above ``WARN_ERROR``, a ``truncation_warning``."""
    t0 = time.perf_counter()
    rb = richer_basis(problem.basis)
    rp, _ = build_problem(case, rb, "auto", fmax_hz)
    E = truncation_errors(problem, rp, Xs, ws)
    info = {"computed": E is not None, "richer_harmonics": int(rb.harmonics.max()),
            "seconds": round(time.perf_counter() - t0, 6)}
    if E is None:
        info["reason"] = f"the richer problem has {rp.n_unknowns} unknowns (> {MAX_UNKNOWNS})"
        settings["error_estimate"] = info
        return outputs
    out, worst = {}, {}
    for i, (name, o) in enumerate(outputs.items()):
        out[name] = OutputSeries(o.h1, o.max, E[:, i])
        k = int(np.nanargmax(E[:, i])) if np.isfinite(E[:, i]).any() else 0
        worst[name] = {"error": float(E[k, i]), "freq_hz": float(ws[k] / (2 * np.pi))}
    info["max"] = worst
    settings["error_estimate"] = info
    H = int(problem.basis.harmonics.max())
    top = max((v["error"] for v in worst.values()), default=0.0)
    if H >= 5 and top < SMALL_ERROR:
        settings["harmonics_note"] = (
            f"estimated errors stay below {SMALL_ERROR:g} at every point: H = {H} is more than this response "
            f"needs (the Newton systems grow as H^2 and their factorisations as H^3); try harmonics = {max(3, H // 2)}")
    bad = {n: v for n, v in worst.items() if v["error"] > WARN_ERROR}
    if bad:
        n, v = max(bad.items(), key=lambda kv: kv[1]["error"])
        settings["truncation_warning"] = (
            f"estimated error of {n} up to {v['error']:.1%} at {v['freq_hz']:.6g} Hz from the harmonic "
            f"truncation (H = {int(problem.basis.harmonics.max())}): raise harmonics")
    return out


def _path_verdicts(problem, Xs, ws, segments, options):
    """Hill verdicts of every point, segment by segment (:func:`hbm.stability_path.path_stability`).

    Returns
    -------
    stable : ndarray of bool, shape (n_points,)
    margin : ndarray, shape (n_points,)
        ``max Re(lambda) - tol w`` where a spectrum was computed, NaN elsewhere.
    """
    opts = options or StabilityOptions()
    hill = HillSystem(problem)
    stable = np.ones(ws.size, dtype=bool)
    margin = np.full(ws.size, np.nan)
    for a, b in segments:
        def test(k, a=a):
            w = float(ws[a + k])
            return hill_margin(*hill(Xs[a + k], w), hill.basis, w, opts)
        stable[a:b], margin[a:b] = path_stability(test, ws[a:b], opts.max_skip)
    return stable, margin


def _landing_solver(problem, Xs, freq_hz, xscale, r_scale, stability_options):
    """``land(i0, i1, f_hz) -> X`` (n_coef, n) or ``None``: the stable solution at ``f_hz``
    by Newton from the path interpolated linearly between points ``i0`` and ``i1``.

    Results are cached (one solve per landing, shared by all outputs); ``None`` when Newton
    fails or lands on an unstable solution.
    """
    cache = {}

    def land(i0, i1, f_hz):
        key = (i0, i1, float(f_hz))
        if key not in cache:
            w = 2 * np.pi * f_hz
            df = freq_hz[i1] - freq_hz[i0]
            t = 0.0 if df == 0 else min(max((f_hz - freq_hz[i0]) / df, 0.0), 1.0)
            X0 = Xs[i0] + t * (Xs[i1] - Xs[i0])
            fun = lambda x: problem.residual(problem.expand(x), w)[:2]
            res = newton(fun, problem.unknowns(X0), scale=xscale, r_scale=r_scale)
            X = problem.expand(res.x) if res.converged else None
            if X is not None and not point_is_stable(problem, X, w, stability_options):
                X = None
            cache[key] = X
        return cache[key]

    return land


def solve_at(case: Case, freq_hz: float, harmonics=None, samples=None, transform=None):
    """Harmonic-balance solution at one frequency (no continuation).

    Returns
    -------
    X : ndarray, shape (n_coef, n)
    basis : FourierBasis
    problem : HarmonicBalance

    Raises
    ------
    RuntimeError
        If Newton does not converge (the message says why).
    """
    h, N, _, _, tr = resolve_settings(case, harmonics, samples, None, None, transform)
    basis = FourierBasis(h, N)
    problem, _ = build_problem(case, basis, tr, max(float(freq_hz), case.analysis.freq_hz[1]))
    w = 2 * np.pi * float(freq_hz)
    xscale = _unknown_scale(problem, case, w * 0.9, w * 1.1)
    X, _ = _first_point(problem, case, w, xscale, _residual_scale(problem, w))
    return X, basis, problem


def output_amplitudes(basis: FourierBasis, x: np.ndarray):
    """``(h1, max)`` of one output's coefficients ``x`` (n_coef,) (e.g. ``X @ g`` or ``X[:, dof]``)."""
    rc = basis.row_of(1, "c")
    return float(np.hypot(x[rc], x[rc + 1])), float(max_abs(basis, x[:, None])[0])
