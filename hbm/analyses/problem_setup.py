r"""Setting up a harmonic-balance problem from a case, and solving one point of it.

:func:`resolve_settings` applies overrides of H, N, the window and the transform (and checks
the memory the run needs, :mod:`hbm.analyses.budget`); :func:`build_problem` builds the full
(:mod:`hbm.balance.residual`) or condensed (:mod:`hbm.balance.condensed`) problem; :func:`first_point`
solves a first point by Newton from the stuck, then the free linear response, then by
ramping the excitation; :func:`solve_at` does that at one frequency.
"""
from __future__ import annotations

import numpy as np

from continuation import Arclength, ArclengthOptions
from hbm.analyses.bounded import unbounded_modes
from hbm.analyses.budget import check_memory
from hbm.interface.case import Case, CaseError
from hbm.balance.condensed import condensed_balance
from hbm.balance.dense_part import dense_balance
from hbm.balance.fourier import FourierBasis, default_samples, max_abs, min_samples, parse_harmonics
from hbm.model.mode_cover import reduce_covering
from hbm.balance.newton import newton
from hbm.model.reduction_cache import cache_path
from hbm.model.structure import AUTO_CONDENSE_DOF
from hbm.balance.transforms import fftw_available, make_transform


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
    (the case file) or ``"default"`` (the elements' defaults, :func:`hbm.interface.case.element_defaults`).
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


def check_bounded(case: Case, lo_hz: float, hi_hz: float) -> None:
    """Raise :class:`CaseError` when the window ``[lo_hz, hi_hz]`` holds a resonance that the
    friction cannot bound (:mod:`hbm.analyses.bounded`): the FRF would be infinite there.
    Made for the full solver without support motion (the test needs the whole model)."""
    if choose_solver(case) != "full" or case.excitation.base is not None:
        return
    for m in unbounded_modes(case.model, case.elements, case.excitation.force, case.excitation.force_sine):
        if lo_hz <= m.freq_hz <= hi_hz:
            raise CaseError(f"{case.path}: {m.describe()}")


def build_problem(case: Case, basis: FourierBasis, transform: str, fmax_hz: float | None = None):
    """The harmonic-balance problem of ``case`` on ``basis`` and what was chosen.

    ``fmax_hz`` (default: the case's window) is the frequency the condensed solver's kept
    modes must cover (:mod:`hbm.model.mode_cover`).

    Returns
    -------
    problem : HarmonicBalance
        On a dense or a condensed linear part.
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
        problem = dense_balance(case.model, case.elements, basis, case.excitation.cos_sin, tr,
                                base=case.excitation.base, output_rows=case.analysis.output_rows(st.n_dof))
        info.update(modes=None, reduction_seconds=0.0)
    elif case.excitation.base is not None:
        raise CaseError(f"{case.path}: [excitation] base (support motion) needs the full solver: "
                        f"set [model] solver = \"full\"")
    else:
        G_o = case.analysis.output_rows(st.n_dof)
        force = case.excitation.cos_sin
        rows = np.vstack([e.gather for e in case.elements] + [force, G_o])
        keep = np.flatnonzero(np.any(rows != 0.0, axis=0))
        modes = case.reduction.modes or st.default_modes()
        try:
            cr, cover = reduce_covering(st, keep, modes, case.reduction.residual_flexibility, cache_path(case.path),
                                        fmax_hz, basis.harmonics)
            problem = condensed_balance(cr.reduced, case.elements, basis, force, tr, G_o)
        except ValueError as exc:
            raise CaseError(f"{case.path}: [model] condensed solver: {exc}") from exc
        info.update(**cover, residual_flexibility=case.reduction.residual_flexibility,
                    contact_coordinates=int(problem.n_dof),
                    reduction_seconds=round(cr.seconds, 6), reduction_cached=cr.from_cache)
    info["n_unknowns"] = int(problem.basis.n_coef * problem.n_dof)
    return problem, info


def condensed_time_model(case: Case, basis: FourierBasis | None = None, transform: str | None = None,
                         fmax_hz: float | None = None, problem=None):
    """The model the condensed solver's balance of ``case`` solves (kept modes and residual
    flexibility) as the time integrator steps it (:mod:`hbm.timedomain.condensed_twin`), for
    the harmonics ``basis`` up to ``fmax_hz`` (default: the case's settings; they decide the
    modes kept), or of the balance ``problem`` already built for them.

    Raises
    ------
    CaseError
        The case is solved on the full model, or a law reads velocities (the twin's static
        coordinates have none).
    """
    from hbm.timedomain.condensed_twin import time_model
    from hbm.timedomain.time_parts import pack_elements
    if choose_solver(case) != "condensed":
        raise CaseError(f"{case.path}: --condensed integrates the condensed solver's model, but this case is "
                        f"solved on its full model (set [model] solver = \"condensed\")")
    if problem is None:
        if basis is None:
            h, N, _, fmax_hz, transform = resolve_settings(case)
            basis = FourierBasis(h, N)
        problem = build_problem(case, basis, transform, fmax_hz)[0]
    model, _ = time_model(case, problem)
    if np.any(pack_elements(model.elements, model.n_dof).laws[6]):
        raise CaseError(f"{case.path}: a condensed model with a velocity-dependent law is not integrated in "
                        f"time (the residual flexibility's coordinates have no velocity)")
    return model


def recover_outputs(problem, case: Case, X: np.ndarray, w: float) -> np.ndarray:
    """Output coefficients (n_coef, n_outputs) of a point ``X`` (n_coef, n) at ``w``
    (``problem.recover_outputs``: the problem was built with ``case``'s outputs)."""
    return problem.recover_outputs(X, w)


def _unknown_scale(problem, case: Case, w_lo: float, w_hi: float) -> np.ndarray:
    """Per-unknown scale: geometric mean of the stuck and free linear peak responses per DOF
    (the stuck one alone where the free system leaves the DOF at rest).  "Stuck" adds every
    element's tangent at rest: ``linear_stiffness`` and, for velocity laws, ``linear_damping``.

    A coordinate without any linear response takes the largest scale of the model, the
    coordinates the unknowns do not hold included (a condensed model's excitation and
    outputs), so that full and condensed models weigh it alike.  Such a coordinate moves
    only through the elements; where they all slip its mean is held by little more than
    anchor springs (a damper's out-of-plane position): Newton leaves it anywhere within
    ``tol / k_anchor``, and a small scale would turn that wander into step rejections.

    The linear responses include the supports' imposed motion (base excitation).
    """
    ws = np.linspace(w_lo, w_hi, 41)
    n = problem.n_unknowns // problem.basis.n_coef
    amp_free, amp_stuck = problem.linear_peak_amplitudes(ws, problem.stuck_stiffness(), problem.stuck_damping(),
                                                         observed=True)
    s_all = np.sqrt(amp_free * amp_stuck)
    amp_free, amp_stuck = amp_free[:n], amp_stuck[:n]
    # a DOF that only the elements couple to the force (free response nil) takes its stuck
    # amplitude, and one without any linear response (round-off) the largest scale: a
    # geometric mean with nil or the 1e-6 floor inflates it in the arclength (the path creeps)
    top = max(amp_free.max(), amp_stuck.max())
    nil = 1e-9 * top if top > 0 else 1.0
    af, ast = amp_free > nil, amp_stuck > nil
    s = np.where(af & ast, np.sqrt(amp_free * amp_stuck), np.where(af, amp_free, amp_stuck))
    smax = max(s.max(), s_all.max())
    smax = smax if smax > 0 else 1.0
    s = np.where(af | ast, np.maximum(s, SCALE_FLOOR * s.max()), smax)
    return np.tile(s, problem.basis.n_coef)


def _first_point(problem, case, w0, scale, r_scale, arclength_ramp=True, avoid=None):
    """Converged first point ``X`` (n_coef, n) at ``w0``, or raise RuntimeError with the reason.

    Newton from the linear response with the elements stuck, then without them; failing
    both, the Newton homotopy ``H(x, lam) = R(x) - (1 - lam) R(0)`` from ``lam = 0`` (solved
    by ``x = 0``) to ``lam = 1``: first in fixed steps of ``lam``, then, if a step fails (the
    homotopy path folds back in ``lam``: a contact that closes or a jump up the resonance),
    traced by pseudo-arclength continuation through its folds (:func:`_homotopy_path`) unless
    ``arclength_ramp`` is False (a restart past a stop, which tries several frequencies: there
    the traced ramp cost half the run on the cross beam and found nothing the next try did not).
    A solution for which ``avoid(X)`` is true (a branch already traced) is passed over.
    """
    avoid = avoid if avoid is not None else (lambda X: False)
    fun = lambda x: problem.residual(problem.expand(x), w0)[:2]
    blocks = problem.solver_structure()
    guesses = [problem.linear_solution(w0, problem.stuck_stiffness()), problem.linear_solution(w0)]
    linear = ""
    for g in guesses:
        res = newton(fun, problem.unknowns(g), scale=scale, r_scale=r_scale, overwrite_jacobian=True,
                     blocks=blocks)
        if res.converged and not avoid(problem.expand(res.x)):
            return problem.expand(res.x), res.iterations
        linear = "converged on the branch already traced" if res.converged else res.message
    x = np.zeros(problem.n_unknowns)
    R0 = fun(x)[0]
    its = 0
    for lam in (0.1, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0):
        def fun_l(x, lam=lam):
            R, J = fun(x)
            return R - (1.0 - lam) * R0, J
        res = newton(fun_l, x, scale=scale, r_scale=r_scale, max_iter=60, overwrite_jacobian=True,
                     blocks=blocks)
        its += res.iterations
        if not res.converged:
            ramp = f"ramp stopped at {lam:.0%} of the excitation: {res.message}"
            break
        x = res.x
    else:
        if not avoid(problem.expand(x)):
            return problem.expand(x), its
        ramp = "the ramp converged on the branch already traced"
    x, its_h, why = _homotopy_path(fun, R0, scale, r_scale, blocks) if arclength_ramp else (None, 0, "no arclength ramp")
    if x is None or avoid(problem.expand(x)):
        why = why if x is None else "the traced ramp reached the branch already traced"
        raise RuntimeError(f"first point at {w0 / (2 * np.pi):.6g} Hz did not converge "
                           f"(linear starts: {linear}; {ramp}; {why})")
    return problem.expand(x), its + its_h


def _homotopy_path(fun, R0, scale, r_scale, blocks=None, max_steps=400):
    """Solve ``R(x) = 0`` by tracing ``H(x, lam) = R(x) - (1 - lam) R0`` from ``(0, 0)`` to
    ``lam = 1`` with :class:`continuation.Arclength` (``dH/dlam = R0``), then Newton on ``R``
    from the point on ``lam = 1``.

    Returns
    -------
    x : ndarray, shape (n_u,), or None
        The solution, or ``None`` when the path did not reach ``lam = 1``.
    iterations : int
        Residual evaluations spent.
    why : str
        ``""``, or how the path ended.
    """
    def fun_h(xl):
        R, J = fun(xl[:-1])
        return R - (1.0 - xl[-1]) * R0, np.hstack([J, R0[:, None]])

    path = Arclength(fun_h, np.zeros(scale.size + 1), scale=np.r_[scale, 1.0], lam_bounds=(-1.0, 1.0),
                     options=ArclengthOptions(max_steps=max_steps, ds0=0.05), overwrite_jacobian=True,
                     describe_lam=lambda lam: f"{lam:.0%} of the excitation", blocks=blocks)
    end = None
    for pt in path:
        end = pt
        if pt.on_bound:
            break
    if end is None or not end.on_bound or end.lam < 1.0:
        return None, path.n_eval, f"arclength ramp: {path.message or 'left at ' + path.status}"
    res = newton(fun, end.y, scale=scale, r_scale=r_scale, blocks=blocks)
    if not res.converged:
        return None, path.n_eval + res.iterations, f"arclength ramp reached 100 %, then {res.message}"
    return res.x, path.n_eval + res.iterations, ""


def _residual_scale(problem, w) -> float:
    """Typical force of the problem: the norm of the residual at zero unknowns (the load)."""
    R = problem.residual(problem.expand(np.zeros(problem.n_unknowns)), w)[0]
    return float(max(np.linalg.norm(R), 1e-300))


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
