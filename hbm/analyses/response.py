r"""Frequency response by harmonic balance and pseudo-arclength continuation.

The FRF is the branch of solutions of :math:`R(X, w) = 0` (:mod:`hbm.balance.residual`) traced from
``fmin`` to ``fmax`` by :mod:`continuation` on ``x = [X.ravel(), w]`` with per-unknown
scaling (:mod:`hbm.analyses.trace`).  The first point is solved by Newton from the linear
response with the elements stuck; failing that, from the response without elements; failing
that, by ramping the excitation; failing at ``fmin``, the window is traced from ``fmax`` down.
A window holding a resonance no friction can bound is refused (:mod:`hbm.analyses.bounded`).
Every converged point is checked by the energy balance (:mod:`hbm.balance.energy`)
and, unless switched off, by Hill's method (:mod:`hbm.analyses.stability`).
Outputs per point: first-harmonic amplitude ``h1 = sqrt(Xc1^2 + Xs1^2)`` and ``max`` of
``|x(t)|`` over a period on a fine grid.
"""
from __future__ import annotations

import time

import numpy as np

from continuation import ArclengthOptions

from hbm.interface.case import Case
from hbm.balance.element_outputs import element_output_series
from hbm.timedomain.floquet_check import confirm_unstable
from hbm.balance.fourier import FourierBasis, max_abs
from hbm.analyses.jumps import predict_jumps
from hbm.analyses.gap_bridge import bridge_gaps
from hbm.analyses.overhang import trace_overhangs
from hbm.analyses.curve_bends import fill_bends
from hbm.analyses.curve_fill import fill_long_steps
from hbm.analyses.peak_refine import refine_peaks
from hbm.analyses.problem_setup import (_first_point, _residual_scale, check_bounded,  # noqa: F401
                            _unknown_scale, build_problem, choose_solver, output_amplitudes,
                            recover_outputs, resolve_settings, setting_sources, solve_at)
from hbm.analyses.result import FRFResult, OutputSeries
from hbm.analyses.aft_retry import retry_with_events, stiff_sampled_contacts
from hbm.analyses.harmonics_retry import retry_with_harmonics
from hbm.analyses.stability import StabilityOptions
from hbm.analyses.stuck import stuck_contacts
from hbm.analyses.verdicts import landing_solver, path_verdicts
from hbm.analyses.trace import _step_limit, trace_window
from hbm.analyses.truncation import (MAX_UNKNOWNS, harmonics_note, largest_errors, richer_basis,
                                     truncation_errors, truncation_warning)

__all__ = ["frf", "FRFResult", "OutputSeries", "build_problem", "choose_solver", "output_amplitudes",
           "recover_outputs", "resolve_settings", "solve_at"]


# Hill exponents whose real part exceeds this fraction of w (growth by exp(0.3) per period)
# are flagged: measured on benchmarks/upd_like.toml, exponents of 0.88 w where a time
# integration at 248 Hz settles (modes above the retained harmonics, not the response)
IMPLAUSIBLE_GROWTH = 0.05


def _closure_warning(settings, unclosed, ws):
    """``settings["closure_warning"]`` when a point's element loops did not all close."""
    bad = [i for i, n in enumerate(unclosed) if n]
    settings["unclosed_loop_points"] = len(bad)
    if bad:
        settings["closure_warning"] = (
            f"at {len(bad)} of {len(ws)} points (first {ws[bad[0]] / (2 * np.pi):.6g} Hz) the hysteresis "
            f"loop of up to {max(unclosed)} contact(s) did not close within the element's max_passes "
            f"periods: their forces carry the closure error (a contact slipping very little per cycle)")


def frf(case: Case, harmonics=None, samples=None, fmin=None, fmax=None, transform=None,
        progress=None, options: ArclengthOptions | None = None, stability: bool = True,
        stability_options: StabilityOptions | None = None, error_estimate: bool = True) -> FRFResult:
    """Trace the FRF of ``case``; a run that stops or leaves gaps with stiff sampled contacts is
    traced again on their event-based AFT and the run covering more of the window is kept
    (:mod:`hbm.analyses.aft_retry`); one that still stops where its harmonics are inadequate,
    on richer harmonics (:mod:`hbm.analyses.harmonics_retry`).

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
    def trace(c, h=harmonics, n=samples):
        return _trace_frf(c, h, n, fmin, fmax, transform, progress, options, stability,
                          stability_options, error_estimate)

    def events_retried(h, n):
        return retry_with_events(case, trace(case, h, n), lambda c: trace(c, h, n))
    return retry_with_harmonics(case, events_retried(harmonics, samples), events_retried, samples, harmonics)


def _trace_frf(case, harmonics, samples, fmin, fmax, transform, progress, options, stability,
               stability_options, error_estimate) -> FRFResult:
    """One trace of the FRF of ``case`` (:func:`frf`'s parameters)."""
    h, N, lo, hi, tr = resolve_settings(case, harmonics, samples, fmin, fmax, transform)
    check_bounded(case, lo, hi)
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
    opts = options or ArclengthOptions()
    pts, segments, (status, message, folds, n_rej), xscale = trace_window(
        problem, case, (w_lo, w_hi), xscale, r_scale, opts, progress, settings)
    bridge_gaps(problem, case, pts, segments, settings, xscale, r_scale, progress)
    if len(segments) > 1:
        folds = folds + trace_overhangs(problem, case, pts, segments, settings, (w_lo, w_hi), xscale, r_scale,
                                        opts, _step_limit(problem, case, (w_lo, w_hi)))
    if status != "finished" or settings.get("gaps"):
        hint = stiff_contact_hint(case)
        if hint:
            settings["contact_hint"] = hint
    _add_points(problem, case, pts, segments, (w_lo, w_hi), xscale, r_scale, settings, progress)
    settings["trace_seconds"] = time.perf_counter() - t0      # what the retries judge (aft_retry)
    pts_X, pts_w, pts_Y, its, eerr = pts.X, pts.w, pts.Y, pts.its, pts.err
    settings["segments"] = segments
    _closure_warning(settings, pts.unclosed, pts.w)
    stable = _verdicts(problem, pts_X, pts_w, segments, stability_options, settings, progress) if stability else None
    secs = time.perf_counter() - t0
    Xs = np.array(pts_X) if pts_X else np.zeros((0,) + shape)
    n_out = len(case.analysis.outputs)
    Ys = np.array(pts_Y) if pts_Y else np.zeros((0, basis.n_coef, n_out))
    outputs = {name: OutputSeries(*_amplitudes(basis, Ys[:, :, i])) for i, name in enumerate(case.analysis.outputs)}
    freq_hz = np.array(pts_w) / (2 * np.pi)
    jumps = None
    if stable is not None:
        t1 = time.perf_counter()
        stable = confirm_unstable(case, basis, Xs, freq_hz, stable, settings, problem)
        jumps = _jumps(problem, case, Xs, freq_hz, outputs, stable, folds, xscale, r_scale, stability_options)
        settings["stability_seconds"] += time.perf_counter() - t1        # + Floquet checks, jumps
    eouts = element_output_series(problem, case.analysis.element_outputs, Xs, np.array(pts_w))
    stuck = stuck_contacts(problem, Xs, np.array(pts_w))
    if stuck is not None:
        settings["stuck_points"] = int(np.count_nonzero(stuck))
    if error_estimate and Xs.shape[0]:
        linear = None if stuck is None else stuck == len(problem.nl.elements)
        outputs = _with_errors(case, problem, outputs, Xs, np.array(pts_w), hi, settings, t0, linear)
    return FRFResult(freq_hz, outputs, Xs, basis, stable, folds,
                     np.array(eerr), np.array(its, dtype=int), status, message, n_rej, secs, settings,
                     jumps, eouts, Ys, stuck)


def _add_points(problem, case, pts, segments, window, xscale, r_scale, settings, progress=None) -> None:
    """Points solved into the traced path ``pts`` where its steps are long (over ``window``,
    rad/s), where its chords turn and on its peaks; their counts go to ``settings``.  Chords
    traced again report their points to ``progress``."""
    outputs_of = lambda X, w: recover_outputs(problem, case, X, w)      # noqa: E731
    if len(pts.w) >= 2:
        settings["fill_points_added"] = fill_long_steps(problem, case, pts, segments, outputs_of, window,
                                                        xscale, r_scale, progress)
    basis = problem.basis
    if len(pts.w) >= 3 and 1 in basis.harmonics:
        rc = basis.row_of(1, "c")
        h1 = lambda Y: np.hypot(Y[rc], Y[rc + 1])      # noqa: E731
        settings["bend_points_added"] = fill_bends(problem, case, pts, segments, h1, xscale, r_scale,
                                                   budget=max(50, len(pts.w)), progress=progress)
        settings["peak_points_added"] = refine_peaks(problem, pts, segments, outputs_of, h1, xscale, r_scale)


def stiff_contact_hint(case: Case) -> str:
    """What to try when the path stopped and sampled contacts that offer an event-based AFT
    are stiff (:func:`hbm.analyses.aft_retry.stiff_sampled_contacts`): their switches sit on
    the time grid, where Newton stalls, and ``aft = "events"`` locates them exactly.  Empty
    when there is none (or the model is not dense)."""
    stiff = [f"{case.elements[i].name}: kt = {r:.3g} x" for i, r in stiff_sampled_contacts(case)]
    if not stiff:
        return ""
    return (f"stiff contacts ({', '.join(stiff)} the structure's stiffness along them) are sampled "
            f"on the time grid, where Newton stalls at their switches: aft = \"events\" on them locates the "
            f"switches exactly (README, \"Stiff contacts\")")


def _verdicts(problem, Xs, ws, segments, stability_options, settings, progress):
    """Hill's verdict (n_points,) of every point (:func:`hbm.analyses.verdicts.path_verdicts`);
    ``settings`` gains the spectra count (and how many points at rest shared one), the largest
    growth, the seconds spent and, where implausible, a warning."""
    if progress is not None:
        progress(len(ws), None)
    t0 = time.perf_counter()
    stable, margin, reused = path_verdicts(problem, Xs, np.array(ws), segments, stability_options)
    settings["stability_seconds"] = time.perf_counter() - t0
    settings["stability_spectra"] = int(np.isfinite(margin).sum()) - reused
    settings["stability_spectra_reused"] = reused
    growth = margin / np.array(ws)
    settings["stability_max_growth"] = float(np.nanmax(growth)) if np.isfinite(margin).any() else None
    if np.nanmax(growth, initial=-np.inf) > IMPLAUSIBLE_GROWTH:
        settings["stability_warning"] = (
            f"Hill exponents grow by up to exp({2 * np.pi * np.nanmax(growth):.2g}) per period: "
            f"typical of modes above the retained harmonics, not of a friction-damped response; "
            f"check an unstable point with hbm timesim or raise the harmonics")
    return stable


def _amplitudes(basis: FourierBasis, Y: np.ndarray):
    """``(h1, max)`` of one output's coefficients at every point, ``Y`` (n_points, n_coef)."""
    if 1 in basis.harmonics and Y.shape[0]:
        rc = basis.row_of(1, "c")
        h1 = np.hypot(Y[:, rc], Y[:, rc + 1])
    else:
        h1 = np.zeros(Y.shape[0])
    return h1, max_abs(basis, Y.T)


def _jumps(problem, case, Xs, freq_hz, outputs, stable, folds, xscale, r_scale, stability_options) -> dict:
    """Per output, the jumps of slow up and down sweeps (:func:`hbm.analyses.jumps.predict_jumps`),
    each landing point solved where it can be (:func:`hbm.analyses.verdicts.landing_solver`)."""
    basis = problem.basis
    land = landing_solver(problem, Xs, freq_hz, xscale, r_scale, stability_options)
    jumps = {}
    for i, name in enumerate(case.analysis.outputs):
        def refine(i0, i1, f, i=i):
            X = land(i0, i1, f)
            if X is None:
                return None
            return output_amplitudes(basis, recover_outputs(problem, case, X, 2 * np.pi * f)[:, i])[0]
        jumps[name] = predict_jumps(freq_hz, outputs[name].h1, stable, folds, refine=refine)
    return jumps


def _with_errors(case, problem, outputs, Xs, ws, fmax_hz, settings, t_solve, linear=None) -> dict:
    """``outputs`` with the truncation error estimate of every point (:mod:`hbm.analyses.truncation`;
    ``linear`` (n_points,) marks the points with every contact stuck, where it may be 0 without a
    richer solve); ``settings`` gains ``error_estimate`` (computed, richer H, largest error per
    output, points estimated 0 without a solve) and,
    above ``WARN_ERROR``, a ``truncation_warning``, or far below it a ``harmonics_note`` (the FRF
    started at ``t_solve``, ``time.perf_counter``)."""
    t0 = time.perf_counter()
    rb = richer_basis(problem.basis)
    info = {"computed": False, "richer_harmonics": int(rb.harmonics.max())}
    n_richer = rb.n_coef * problem.n_unknowns // problem.basis.n_coef
    if n_richer > MAX_UNKNOWNS:      # decided before the richer problem is built
        info["reason"] = f"the richer problem would have {n_richer} unknowns (> {MAX_UNKNOWNS})"
        settings["error_estimate"] = info
        return outputs
    rp, _ = build_problem(case, rb, "auto", fmax_hz)
    E = truncation_errors(problem, rp, Xs, ws, linear)
    info.update(computed=True, seconds=round(time.perf_counter() - t0, 6))
    if linear is not None:
        info["nothing_added"] = int(np.count_nonzero(linear & np.all(E == 0.0, axis=1)))
    out = {name: OutputSeries(o.h1, o.max, E[:, i]) for i, (name, o) in enumerate(outputs.items())}
    worst = info["max"] = largest_errors(out, ws / (2 * np.pi))
    settings["error_estimate"] = info
    H = int(problem.basis.harmonics.max())
    top = max((v["error"] for v in worst.values()), default=0.0)
    note = harmonics_note(H, top, problem.n_unknowns, time.perf_counter() - t_solve)
    if note:
        settings["harmonics_note"] = note
    warning = truncation_warning(worst, f"H = {H}", ": raise harmonics")
    if warning:
        settings["truncation_warning"] = warning
    return out
