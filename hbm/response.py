r"""Frequency response by harmonic balance and pseudo-arclength continuation.

The FRF is the branch of solutions of :math:`R(X, w) = 0` (:mod:`hbm.residual`) traced from
``fmin`` to ``fmax`` by :mod:`continuation` on ``x = [X.ravel(), w]`` with per-unknown
scaling.  The first point is solved by Newton from the linear response with the elements
stuck; failing that, from the response without elements; failing that, by ramping the
excitation.  Every converged point is checked by the energy balance (:mod:`hbm.energy`).
Outputs per point: first-harmonic amplitude ``h1 = sqrt(Xc1^2 + Xs1^2)`` and ``max`` of
``|x(t)|`` over a period on a fine grid.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from continuation import Arclength, ArclengthOptions

from .case import Case, CaseError
from .energy import energy_balance
from .fourier import FourierBasis, parse_harmonics, min_samples, default_samples, max_abs
from .newton import newton
from .residual import HarmonicBalance
from .transforms import make_transform


@dataclass(frozen=True)
class OutputSeries:
    """Per-point amplitudes of one output: ``h1`` and ``max`` (n_points,)."""

    h1: np.ndarray
    max: np.ndarray


@dataclass(frozen=True)
class FRFResult:
    """A traced FRF.

    Attributes
    ----------
    freq_hz : ndarray, shape (n_points,)
        Along the continuation path (folds appear as frequency reversals).
    outputs : dict of str -> OutputSeries
    X : ndarray, shape (n_points, n_coef, n)
        Harmonic coefficients of every point.
    stable : ndarray of bool or None
    folds_hz : list of float
    energy_error : ndarray, shape (n_points,)
        Relative energy-balance error per point.
    iterations : ndarray of int, shape (n_points,)
    status, message : str
        ``finished`` / ``failed`` / ``max_steps`` and a one-line explanation.
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

    @property
    def ok(self) -> bool:
        return self.status == "finished"


def resolve_settings(case: Case, harmonics=None, samples=None, fmin=None, fmax=None, transform=None):
    """Analysis settings with command-line / API overrides applied and validated."""
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
        N = a.time_samples if harmonics is None else max(a.time_samples, default_samples(h))
    else:
        N = int(samples)
    if N < min_samples(h):
        raise CaseError(f"time samples N={N} too small for harmonics up to {max(h)} (need >= {min_samples(h)})")
    lo = a.freq_hz[0] if fmin is None else float(fmin)
    hi = a.freq_hz[1] if fmax is None else float(fmax)
    if not (lo > 0 and hi > lo):
        raise CaseError(f"frequency range is empty or not positive ({lo} .. {hi} Hz)")
    tr = transform or a.transform
    return h, N, lo, hi, tr


def _stuck_stiffness(case: Case) -> np.ndarray:
    K = np.zeros((case.n_dof, case.n_dof))
    for e in case.elements:
        K += e.gather.T @ e.linear_stiffness() @ e.gather
    return K


def _unknown_scale(problem: HarmonicBalance, case: Case, w_lo: float, w_hi: float) -> np.ndarray:
    """Per-DOF amplitude scale: geometric mean of the stuck and free linear peak responses."""
    ws = np.linspace(w_lo, w_hi, 41)
    Ks = _stuck_stiffness(case)
    amp_free = np.zeros(case.n_dof)
    amp_stuck = np.zeros(case.n_dof)
    n = case.n_dof
    M, C, K, f = case.model.M, case.model.C, case.model.K, case.excitation.force
    for w in ws:
        for Kx, amp in ((K, amp_free), (K + Ks, amp_stuck)):
            Zc = Kx - w * w * M + 1j * w * C
            try:
                x = np.linalg.solve(Zc, f)
            except np.linalg.LinAlgError:
                continue
            np.maximum(amp, np.abs(x), out=amp)
    s = np.sqrt(np.maximum(amp_free, 1e-300) * np.maximum(amp_stuck, 1e-300))
    s = np.maximum(s, 1e-6 * s.max() if s.max() > 0 else 1.0)
    return np.tile(s, problem.basis.n_coef)


def _first_point(problem, case, w0, scale, r_scale):
    """Converged first point ``X`` (n_coef, n) at ``w0``, or raise RuntimeError with the reason."""
    fun = lambda X: problem.residual(X.reshape(problem.Fex.shape), w0)[:2]
    guesses = [problem.linear_solution(w0, _stuck_stiffness(case)), problem.linear_solution(w0)]
    last = None
    for g in guesses:
        res = newton(fun, g.ravel(), scale=scale, r_scale=r_scale)
        if res.converged:
            return res.x.reshape(problem.Fex.shape), res.iterations
        last = res
    # ramp the excitation from a small fraction
    Fex = problem.Fex
    X = guesses[0] * 0.1
    its = 0
    for lam in (0.1, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0):
        def fun_l(x, lam=lam):
            R, J = fun(x)
            return R + (1.0 - lam) * Fex.ravel(), J
        res = newton(fun_l, X.ravel(), scale=scale, r_scale=r_scale * lam, max_iter=60)
        its += res.iterations
        if not res.converged:
            raise RuntimeError(f"first point at {w0 / (2 * np.pi):.6g} Hz did not converge "
                               f"(linear starts: {last.message}; ramp stopped at {lam:.0%} of the force: {res.message})")
        X = res.x.reshape(Fex.shape)
    return X, its


POLISH_ENERGY = 1e-10


def _polish(problem, X, w, xscale, r_scale, err):
    """Newton at fixed ``w`` on a point whose energy balance is not closed.

    The continuation's tolerance is relative to the Jacobian's row norm, which a stiff
    contact (kt >> k) makes large against the excitation: such a point can be accepted with
    ``|R| / |F|`` ~ 1e-9 and an energy error ~ 1e-6.  Here the target is relative to ``|F|``.
    Returns the better of the two points and its relative energy error.
    """
    fun = lambda x: problem.residual(x.reshape(X.shape), w)[:2]
    res = newton(fun, X.ravel(), scale=xscale, r_scale=r_scale, tol=1e-13, max_iter=4)
    if np.all(np.isfinite(res.x)):
        Xp = res.x.reshape(X.shape)
        err_p = energy_balance(problem, Xp, w).relative_error
        if err_p < err:
            return Xp, err_p
    return X, err


def frf(case: Case, harmonics=None, samples=None, fmin=None, fmax=None, transform=None,
        progress=None, options: ArclengthOptions | None = None) -> FRFResult:
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
        Called as ``progress(n_points, freq_hz)`` after every converged point.
    options : ArclengthOptions, optional

    Returns
    -------
    FRFResult
        Always returned, also when the continuation fails (``status``/``message`` say why,
        with every point converged so far).
    """
    h, N, lo, hi, tr = resolve_settings(case, harmonics, samples, fmin, fmax, transform)
    basis = FourierBasis(h, N)
    problem = HarmonicBalance(case.model, case.elements, basis, case.excitation.force,
                              make_transform(basis, tr))
    w_lo, w_hi = 2 * np.pi * lo, 2 * np.pi * hi
    t0 = time.perf_counter()
    xscale = _unknown_scale(problem, case, w_lo, w_hi)
    r_scale = float(np.linalg.norm(case.excitation.force))
    settings = {"harmonics": [int(x) for x in h], "time_samples": int(N), "fmin_hz": lo, "fmax_hz": hi,
                "transform": problem.nl.transform.name}
    shape = problem.Fex.shape
    out_dofs = case.analysis.outputs
    pts_X, pts_w, its, eerr = [], [], [], []
    status, message, folds, n_rej = "failed", "", [], 0
    try:
        X0, it0 = _first_point(problem, case, w_lo, xscale, r_scale)
    except RuntimeError as exc:
        message = str(exc)
    else:
        scale = np.r_[xscale, w_hi - w_lo]
        opts = options or ArclengthOptions()
        solver = Arclength(problem, np.r_[X0.ravel(), w_lo], scale, lam_bounds=(w_lo, w_hi),
                           direction=+1, options=opts)
        for pt in solver:
            X = pt.x[:-1].reshape(shape)
            w = float(pt.x[-1])
            err = energy_balance(problem, X, w).relative_error
            if err > POLISH_ENERGY:
                X, err = _polish(problem, X, w, xscale, r_scale, err)
            pts_X.append(X)
            pts_w.append(w)
            its.append(pt.iterations if pts_w[1:] else it0 + pt.iterations)
            eerr.append(err)
            if progress is not None:
                progress(len(pts_w), w / (2 * np.pi))
            if len(pts_w) >= case.analysis.max_points:
                break
        status, message = solver.status, solver.message
        if status == "finished" and pts_w and pts_w[-1] < w_hi * (1 - 1e-9):
            # the arclength solver also ends on the lower bound: the path turned back
            status = "failed"
            message = (f"the path returned to {pts_w[-1] / (2 * np.pi):.6g} Hz after {len(pts_w)} points "
                       f"without reaching {hi:.6g} Hz ({message})")
        if len(pts_w) >= case.analysis.max_points and status not in ("finished", "failed"):
            status = "max_steps"
            message = f"stopped after max_points={case.analysis.max_points} points at {pts_w[-1] / (2 * np.pi):.6g} Hz"
        folds = [f / (2 * np.pi) for f in solver.folds]
        n_rej = solver.n_rejected
    secs = time.perf_counter() - t0
    Xs = np.array(pts_X) if pts_X else np.zeros((0,) + shape)
    outputs = {}
    for name, dof in out_dofs.items():
        xd = Xs[:, :, dof]
        if 1 in basis.harmonics and Xs.shape[0]:
            rc = basis.row_of(1, "c")
            h1 = np.hypot(xd[:, rc], xd[:, rc + 1])
        else:
            h1 = np.zeros(Xs.shape[0])
        mx = max_abs(basis, xd.T)
        outputs[name] = OutputSeries(h1, mx)
    return FRFResult(np.array(pts_w) / (2 * np.pi), outputs, Xs, basis, None, folds,
                     np.array(eerr), np.array(its, dtype=int), status, message, n_rej, secs, settings)


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
    problem = HarmonicBalance(case.model, case.elements, basis, case.excitation.force,
                              make_transform(basis, tr))
    w = 2 * np.pi * float(freq_hz)
    xscale = _unknown_scale(problem, case, w * 0.9, w * 1.1)
    X, _ = _first_point(problem, case, w, xscale, float(np.linalg.norm(case.excitation.force)))
    return X, basis, problem


def output_amplitudes(basis: FourierBasis, x: np.ndarray):
    """``(h1, max)`` of one DOF's coefficients ``x`` (n_coef,)."""
    rc = basis.row_of(1, "c")
    return float(np.hypot(x[rc], x[rc + 1])), float(max_abs(basis, x[:, None])[0])
