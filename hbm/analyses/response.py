r"""Frequency response by harmonic balance and pseudo-arclength continuation.

The FRF is the branch of solutions of :math:`R(X, w) = 0` (:mod:`hbm.balance.residual`) traced from
``fmin`` to ``fmax`` by :mod:`continuation` on ``x = [X.ravel(), w]`` with per-unknown
scaling.  The first point is solved by Newton from the linear response with the elements
stuck; failing that, from the response without elements; failing that, by ramping the
excitation.  Every converged point is checked by the energy balance (:mod:`hbm.balance.energy`)
and, unless switched off, by Hill's method (:mod:`hbm.analyses.stability`).
Outputs per point: first-harmonic amplitude ``h1 = sqrt(Xc1^2 + Xs1^2)`` and ``max`` of
``|x(t)|`` over a period on a fine grid.
"""
from __future__ import annotations

import time

import numpy as np

from continuation import Arclength, ArclengthOptions
from continuation.linsolve import REUSE_MIN_SIZE, ReusedLU

from hbm.interface.case import Case
from hbm.balance.element_outputs import element_output_series
from hbm.balance.energy import energy_balance
from hbm.timedomain.floquet_check import confirm_unstable
from hbm.balance.fourier import FourierBasis, max_abs
from hbm.analyses.jumps import predict_jumps
from hbm.balance.newton import newton
from hbm.analyses.curve_fill import fill_long_steps
from hbm.analyses.peak_refine import refine_peaks
from hbm.analyses.problem_setup import (_first_point, _residual_scale,  # noqa: F401
                            _unknown_scale, build_problem, choose_solver, output_amplitudes,
                            recover_outputs, resolve_settings, setting_sources, solve_at)
from hbm.analyses.result import FRFResult, OutputSeries
from hbm.analyses.resonances import ResonanceStepLimit, linear_resonances
from hbm.analyses.stability import StabilityOptions
from hbm.analyses.stuck import stuck_contacts
from hbm.analyses.verdicts import landing_solver, path_verdicts
from hbm.analyses.truncation import MAX_UNKNOWNS, SMALL_ERROR, WARN_ERROR, richer_basis, truncation_errors

__all__ = ["frf", "FRFResult", "OutputSeries", "build_problem", "choose_solver", "output_amplitudes",
           "recover_outputs", "resolve_settings", "solve_at"]


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
    Newton's linear solver (:func:`hbm.balance.newton.newton`), one kept LU shared by a path's polishes.
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
    (:mod:`hbm.analyses.resonances`) inside ``window`` (rad/s)."""
    d = np.ix_(problem.modal_rows(), problem.modal_rows())
    om, z = linear_resonances(problem.modal_data(), problem.stuck_stiffness()[d], problem.stuck_damping()[d])
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
                       direction=direction, options=opts, lam_step=lam_step, overwrite_jacobian=True,
                       describe_lam=lambda lam: f"{lam / (2 * np.pi):.6g} Hz")
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


GAP_FIRST = 1e-3        # first restart this share of the window past a stop, doubled per try
GAP_TRIES = 8
MAX_GAPS = 10


def _restart_past_stops(problem, case, pts, segments, window, xscale, r_scale, opts, progress, lam_step,
                        outcome, settings):
    """Where the continuation stopped inside the window, solve a fresh point a little further
    (``GAP_FIRST`` of the window, doubled up to ``GAP_TRIES`` times) and trace on from it.

    A stop at a stick-slip discontinuity (static above kinetic friction) or a corner the
    corrector cannot turn leaves the rest of the window untraced; restarting past it gives the
    user the rest, and every skipped stretch is stated: ``settings["gaps"]`` (from, to, why)
    and a ``gap_warning``.  Returns the last segment's ``(status, message, folds, n_rejected)``.
    """
    status, message, folds, n_rej = outcome
    w_lo, w_hi = window
    gaps = []
    while (status == "failed" and pts.w and pts.w[-1] < w_hi * (1 - 1e-9) and len(gaps) < MAX_GAPS
           and len(pts.w) < case.analysis.max_points):
        w_from, restart = pts.w[-1], None
        for k in range(GAP_TRIES):
            w_r = min(w_from + GAP_FIRST * 2 ** k * (w_hi - w_lo), w_hi)
            try:
                Xr, itr = _first_point(problem, case, w_r, xscale, r_scale)
            except RuntimeError:
                if w_r == w_hi:
                    break
                continue
            if energy_balance(problem, Xr, w_r).relative_error <= ENERGY_LIMIT:
                restart = (Xr, itr, w_r)
                break
            if w_r == w_hi:
                break
        if restart is None:
            message += "; no restart past it converged"
            break
        gaps.append({"from_hz": w_from / (2 * np.pi), "to_hz": restart[2] / (2 * np.pi), "reason": message})
        start = len(pts.w)
        status, message, f2, r2 = _trace(problem, case, pts, restart[0], restart[1], restart[2], (w_lo, w_hi), +1,
                                         xscale, r_scale, opts, progress, offset=0, lam_step=lam_step)
        folds, n_rej = folds + f2, n_rej + r2
        segments.append([start, len(pts.w)])
    if gaps:
        settings["gaps"] = gaps
        where = ", ".join(f"{g['from_hz']:.6g}..{g['to_hz']:.6g} Hz" for g in gaps)
        settings["gap_warning"] = (f"the continuation stopped {len(gaps)} time(s) and was restarted further on; "
                                   f"not traced: {where} (first stop: {gaps[0]['reason']})")
    return status, message, folds, n_rej


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
        Estimate every point's truncation error (``outputs[name].err``, :mod:`hbm.analyses.truncation`).

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
        status, message, folds, n_rej = _restart_past_stops(
            problem, case, pts, segments, (w_lo, w_hi), xscale, r_scale, opts, progress, lam_step,
            (status, message, folds, n_rej), settings)
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
    def outputs_of(X, w):
        return recover_outputs(problem, case, X, w)
    if len(pts.w) >= 2:
        settings["fill_points_added"] = fill_long_steps(problem, pts, segments, outputs_of, (w_lo, w_hi),
                                                        xscale, r_scale)
    if len(pts.w) >= 3 and 1 in basis.harmonics:
        rc = basis.row_of(1, "c")
        settings["peak_points_added"] = refine_peaks(problem, pts, segments, outputs_of,
                                                     lambda Y: np.hypot(Y[rc], Y[rc + 1]), xscale, r_scale)
    pts_X, pts_w, pts_Y, its, eerr = pts.X, pts.w, pts.Y, pts.its, pts.err
    settings["segments"] = segments
    _closure_warning(settings, pts.unclosed, pts.w)
    stable = None
    if stability:
        if progress is not None:
            progress(len(pts_w), None)
        stable, margin = path_verdicts(problem, pts_X, np.array(pts_w), segments, stability_options)
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
        if choose_solver(case) == "full":
            stable = confirm_unstable(case, basis, Xs, freq_hz, stable, settings)
        land = landing_solver(problem, Xs, freq_hz, xscale, r_scale, stability_options)
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
    """``outputs`` with the truncation error estimate of every point (:mod:`hbm.analyses.truncation`);
    ``settings`` gains ``error_estimate`` (computed, richer H, largest error per output) and,
    above ``WARN_ERROR``, a ``truncation_warning``."""
    t0 = time.perf_counter()
    rb = richer_basis(problem.basis)
    info = {"computed": False, "richer_harmonics": int(rb.harmonics.max())}
    n_richer = rb.n_coef * problem.n_unknowns // problem.basis.n_coef
    if n_richer > MAX_UNKNOWNS:      # decided before the richer problem is built
        info["reason"] = f"the richer problem would have {n_richer} unknowns (> {MAX_UNKNOWNS})"
        settings["error_estimate"] = info
        return outputs
    rp, _ = build_problem(case, rb, "auto", fmax_hz)
    E = truncation_errors(problem, rp, Xs, ws)
    info.update(computed=True, seconds=round(time.perf_counter() - t0, 6))
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
