"""Tests of the pseudo-arclength solver on algebraic single-harmonic Duffing-type problems.

Unknowns (a, b): cos/sin amplitudes of the response, parameter w:
    R1 = (k - m w^2) a + c w b + g(A) a - F,   R2 = (k - m w^2) b - c w a + g(A) b,
with A^2 = a^2 + b^2 and g(A) = 0.75 k3 A^2 (Duffing) or a piecewise-linear stiffness.
"""
import numpy as np
import pytest
from scipy.optimize import brentq

from continuation import Arclength, ArclengthOptions, ContinuationPoint

C, K3, F = 0.02, 0.1, 0.05       # light damping, hardening: two folds in [0.5, 2]
BOUNDS = (0.5, 2.0)


def duffing(c=C, k3=K3, f=F, m=1.0, k=1.0):
    q = 0.75 * k3

    def fun(x):
        a, b, w = x
        D = k - m * w * w
        A2 = a * a + b * b
        R = np.array([D * a + c * w * b + q * A2 * a - f,
                      D * b - c * w * a + q * A2 * b])
        J = np.array([[D + q * (A2 + 2 * a * a), c * w + 2 * q * a * b, -2 * m * w * a + c * b],
                      [-c * w + 2 * q * a * b, D + q * (A2 + 2 * b * b), -2 * m * w * b - c * a]])
        return R, J
    return fun


def piecewise(c, f, kp, A0):
    """Stiffness 1 below amplitude A0, 1 + kp (1 - A0/A) above: Jacobian jumps at A = A0."""
    def fun(x):
        a, b, w = x
        A = np.hypot(a, b)
        D = 1.0 - w * w
        if A > A0:
            g, dg = kp * (1 - A0 / A), kp * A0 / A**3     # dg = (dg/dA) / A
        else:
            g, dg = 0.0, 0.0
        R = np.array([D * a + c * w * b + g * a - f, D * b - c * w * a + g * b])
        J = np.array([[D + g + dg * a * a, c * w + dg * a * b, -2 * w * a + c * b],
                      [-c * w + dg * a * b, D + g + dg * b * b, -2 * w * b - c * a]])
        return R, J
    return fun


def start(f=F, w0=BOUNDS[0]):
    return np.array([f / (1 - w0**2), 0.0, w0])


def amplitude(pts):
    return np.array([np.hypot(p.x[0], p.x[1]) for p in pts])


def peak_vertex(pts, scale):
    """Largest amplitude of a path, from the parabola (in scaled arclength) through its
    three samples around the largest one."""
    x = np.array([p.x / scale for p in pts])
    a = amplitude(pts)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    i = int(a.argmax())
    c = np.polyfit(s[i - 1:i + 2], a[i - 1:i + 2], 2)
    return c[2] - c[1] ** 2 / (4 * c[0])


def analytic_folds(c=C, k3=K3, f=F):
    """Zeros of the discriminant of the cubic in u = A^2 (where dw/dA = 0)."""
    q = 0.75 * k3

    def disc(w):
        D = 1 - w * w
        a3, a2, a1, a0 = q * q, 2 * q * D, D * D + c * c * w * w, -f * f
        return (18 * a3 * a2 * a1 * a0 - 4 * a2**3 * a0 + a2**2 * a1**2
                - 4 * a3 * a1**3 - 27 * a3**2 * a0**2)
    grid = np.linspace(*BOUNDS, 3001)
    d = np.array([disc(w) for w in grid])
    idx = np.nonzero(np.sign(d[:-1]) != np.sign(d[1:]))[0]
    return sorted(brentq(disc, grid[i], grid[i + 1], xtol=1e-14) for i in idx)


@pytest.fixture(scope="module")
def duffing_run():
    fun = duffing()
    solver = Arclength(fun, start(), None, lam_bounds=BOUNDS, direction=+1)
    return fun, solver, list(solver)


def test_duffing_passes_both_folds_and_finishes_on_bound(duffing_run):
    _, solver, pts = duffing_run
    assert solver.status == "finished", solver.message
    assert all(isinstance(p, ContinuationPoint) for p in pts)
    assert len(solver.folds) == 2
    assert sum(p.fold for p in pts) == 2
    lam = np.array([p.lam for p in pts])
    assert lam[0] == BOUNDS[0] and pts[-1].x[-1] == BOUNDS[1] and pts[-1].on_bound
    assert np.all((lam >= BOUNDS[0]) & (lam <= BOUNDS[1]))
    # parameter goes up, back down between the folds, then up again: two sign changes
    signs = np.sign(np.diff(lam))
    assert np.count_nonzero(signs[1:] != signs[:-1]) == 2
    assert solver.folds[0] > solver.folds[1]          # upper fold first, then the jump-up fold


def test_points_solve_the_equations_and_tangents_are_null_vectors(duffing_run):
    fun, solver, pts = duffing_run
    for p in pts:
        R, J = fun(p.x)
        assert np.abs(R).max() <= 1e-13, p        # polished to round-off, F = 0.05
        assert abs(np.linalg.norm(p.tangent) - 1) < 1e-12
        Js = J * solver.scale
        assert np.abs(Js @ p.tangent).max() <= 1e-8 * np.abs(Js).max()
    # tangents oriented along the path: consecutive chords agree with them
    for p, q in zip(pts[:-1], pts[1:]):
        chord = (q.x - p.x) / solver.scale
        assert chord @ p.tangent > 0 and chord @ q.tangent > 0


def test_peak_matches_light_damping_backbone(duffing_run):
    _, _, pts = duffing_run
    q = 0.75 * K3
    # A = F/(c w), w^2 = 1 + q A^2  ->  w^4 - w^2 - q F^2/c^2 = 0
    w2 = 0.5 * (1 + np.sqrt(1 + 4 * q * F**2 / C**2))
    A_peak = F / (C * np.sqrt(w2))
    A = amplitude(pts)
    assert abs(A.max() - A_peak) / A_peak < 0.01
    assert abs(pts[int(A.argmax())].lam - np.sqrt(w2)) / np.sqrt(w2) < 0.01


def test_fold_locations_match_discriminant(duffing_run):
    _, solver, _ = duffing_run
    expected = analytic_folds()
    assert len(expected) == 2
    # Hermite location: ~1e-8 here; linear interpolation of t_lam would give ~3e-5
    assert np.allclose(sorted(solver.folds), expected, rtol=1e-6, atol=0)


def test_linear_problem_gives_closed_form_receptance():
    fun = duffing(k3=0.0)
    solver = Arclength(fun, start(), None, lam_bounds=BOUNDS)
    pts = list(solver)
    assert solver.status == "finished" and not solver.folds
    for p in pts:
        w = p.lam
        D = 1 - w * w
        den = D * D + (C * w) ** 2
        assert np.allclose(p.x[:2], [F * D / den, F * C * w / den], rtol=1e-12, atol=1e-14)
    lam = np.array([p.lam for p in pts])
    assert np.all(np.diff(lam) > 0)
    assert amplitude(pts).max() == pytest.approx(F / C, rel=1e-3)   # resonance not skipped


def _narrow_peak(eps=5e-3, height=0.05, lam0=0.5):
    """``y = height eps^2 / ((lam - lam0)^2 + eps^2)``: linear in ``y`` (Newton converges at
    once, so the steps grow), with a peak of half-width ``eps`` at ``lam0``."""
    def fun(x):
        y, lam = x
        d = lam - lam0
        q = d * d + eps * eps
        return (np.array([y - height * eps * eps / q]),
                np.array([[1.0, 2 * height * eps * eps * d / (q * q)]]))
    return fun


def test_a_narrow_peak_is_skipped_without_a_step_limit_and_resolved_with_one():
    eps, height = 5e-3, 0.05
    fun = _narrow_peak(eps, height)
    free = Arclength(fun, [0.0, 0.0], [1.0, 1.0], lam_bounds=(0.0, 1.0))
    pts = free.run()
    assert free.status == "finished"
    # the hazard the limit exists for: nothing in the step control sees the peak
    assert max(p.x[0] for p in pts) < 0.01 * height
    calls = []

    def lam_step(lam, direction):
        calls.append(direction)
        d = (0.5 - lam) * direction
        return max(0.5 * eps, 0.7 * abs(d)) if d > -eps else np.inf

    lim = Arclength(fun, [0.0, 0.0], [1.0, 1.0], lam_bounds=(0.0, 1.0), lam_step=lam_step)
    pts = lim.run()
    assert lim.status == "finished" and calls and set(calls) == {1}
    lam = np.array([p.lam for p in pts])
    y = np.array([p.x[0] for p in pts])
    assert y.max() > 0.999 * height
    # before the peak no step passed the limit from its start (the hyperplane corrector
    # only shortens the parameter change when the path bends upwards)
    before = lam[1:] < 0.5 - eps
    allowed = np.array([lam_step(v, 1) for v in lam[:-1]])
    assert np.all(np.diff(lam)[before] <= allowed[before] * (1 + 1e-9))
    assert len(pts) < 60


def test_bad_start_fails_cleanly():
    fun = duffing(k3=1.0)
    solver = Arclength(fun, [1e6, -1e6, 1.0], None, lam_bounds=BOUNDS)
    pts = list(solver)
    assert pts == [] and solver.status == "failed"
    assert "starting point" in solver.message and "converge" in solver.message

    def nan_fun(x):
        return np.full(2, np.nan), np.full((2, 3), np.nan)
    solver = Arclength(nan_fun, start(), None, lam_bounds=BOUNDS)
    assert list(solver) == [] and solver.status == "failed" and solver.message


def test_failure_midway_reports_ds_min_without_nan():
    base = duffing()

    def fun(x):   # no solution beyond w = 0.8
        if x[-1] > 0.8:
            return np.full(2, np.nan), np.full((2, 3), np.nan)
        return base(x)
    solver = Arclength(fun, start(), None, lam_bounds=BOUNDS)
    pts = list(solver)
    assert solver.status == "failed"
    assert "ds_min" in solver.message and "lam=0.8" in solver.message
    assert solver.n_rejected > 0
    assert all(np.all(np.isfinite(p.x)) and p.lam <= 0.8 for p in pts)


def test_kink_traced_monotonically_with_defaults():
    c, f, kp, A0 = 0.3, 0.1, 0.5, 0.15
    # premise: for every w the amplitude equation has a single root, so w is monotone
    Ag = np.linspace(1e-4, 2, 20001)
    for w in np.linspace(*BOUNDS, 151):
        g = kp * np.maximum(0, 1 - A0 / Ag)
        h = ((1 + g - w * w) ** 2 + (c * w) ** 2) * Ag**2 - f * f
        assert np.count_nonzero(np.diff(np.sign(h))) == 1
    fun = piecewise(c, f, kp, A0)
    solver = Arclength(fun, start(f), None, lam_bounds=BOUNDS)
    pts = list(solver)
    assert solver.status == "finished", solver.message
    lam = np.array([p.lam for p in pts])
    assert np.all(np.diff(lam) > 0) and not solver.folds
    assert lam[-1] == BOUNDS[1]
    A = amplitude(pts)
    assert A.max() > A0 and A[0] < A0 and A[-1] < A0       # both kinks crossed
    assert max(np.abs(fun(p.x)[0]).max() for p in pts) < 1e-13


@pytest.mark.parametrize("c, f, kp, A0", [
    (0.1, 0.05, 0.5, 0.2),    # smooth folds on a kinked curve
    (0.5, 0.2, 3.0, 0.1),     # one fold sits on the kink (a corner of > 90 deg)
])
def test_kink_with_folds_is_traced_to_the_end(c, f, kp, A0):
    fun = piecewise(c, f, kp, A0)
    solver = Arclength(fun, start(f), None, lam_bounds=BOUNDS)
    pts = list(solver)
    assert solver.status == "finished", solver.message
    assert len(solver.folds) == 2 and pts[-1].lam == BOUNDS[1]
    assert max(np.abs(fun(p.x)[0]).max() for p in pts) < 1e-13


@pytest.mark.parametrize("explicit_scale", [False, True])
def test_scaled_formulation(duffing_run, explicit_scale):
    """Same Duffing problem with unknowns ~1e-6 and parameter ~1e3 (and residual ~1e-3)."""
    ys, ws, rs = 1e-6, 1e3, 1e-3
    base = duffing()

    def fun(x):
        R, J = base(np.array([x[0] / ys, x[1] / ys, x[2] / ws]))
        return rs * R, rs * J / np.array([ys, ys, ws])
    x0 = start() * np.array([ys, ys, ws])
    scale = np.array([ys, ys, ws]) if explicit_scale else None
    solver = Arclength(fun, x0, scale, lam_bounds=(500.0, 2000.0))
    pts = list(solver)
    assert solver.status == "finished", solver.message
    assert pts[-1].lam == 2000.0
    assert np.allclose(sorted(solver.folds), np.array(analytic_folds()) * ws, rtol=1e-3)
    ref = duffing_run[2]
    # the peak between the samples (parabola through the three around the largest, in
    # arclength): the two paths sample it at different points, the interpolated peaks agree
    assert peak_vertex(pts, np.array([ys, ys, ws])) / ys == pytest.approx(
        peak_vertex(ref, np.ones(3)), rel=1e-5)
    for p in pts:
        assert np.abs(base(p.x / np.array([ys, ys, ws]))[0]).max() < 1e-12


def test_direction_and_bounds():
    fun = duffing()
    solver = Arclength(fun, start(w0=2.0), None, lam_bounds=BOUNDS, direction=-1)
    pts = list(solver)
    assert solver.status == "finished", solver.message
    assert pts[-1].lam == BOUNDS[0] and len(solver.folds) == 2
    assert all(BOUNDS[0] <= p.lam <= BOUNDS[1] for p in pts)
    # starting on the bound and heading out: nothing beyond the first point
    solver = Arclength(fun, start(w0=2.0), None, lam_bounds=BOUNDS, direction=+1)
    assert len(list(solver)) == 1 and solver.status == "finished"


def test_max_steps_and_one_call_per_iteration():
    fun = duffing()
    calls = []

    def counted(x):
        calls.append(1)
        return fun(x)
    solver = Arclength(counted, start(), None, lam_bounds=BOUNDS,
                       options=ArclengthOptions(max_steps=5))
    pts = list(solver)
    assert solver.status == "max_steps" and len(pts) == 6
    assert solver.n_eval == len(calls)
    if solver.n_rejected == 0:   # one call per Newton iteration plus one per predictor
        assert len(calls) == sum(p.iterations + 1 for p in pts)


def test_options_are_frozen_and_validated():
    o = ArclengthOptions()
    with pytest.raises(Exception):
        o.tol = 1e-3
    with pytest.raises(ValueError):
        ArclengthOptions(ds_min=1.0, ds_max=0.1).step_lengths(1.0)
    with pytest.raises(ValueError):
        ArclengthOptions(max_angle_deg=120)
    ds0, ds_min, ds_max = o.step_lengths(3.0)
    assert ds0 == pytest.approx(0.03) and ds_min < ds0 < ds_max


def test_corrector_null_vector_is_the_tangent_system_solution():
    """The converged corrector's second solve gives null_tangent's vector (same matrix)."""
    from continuation.corrector import Evaluation, correct, linear_constraint
    from continuation.tangent import null_tangent
    rng = np.random.default_rng(3)
    A = rng.standard_normal((4, 5))

    def evaluate(xs):
        x = xs.copy()
        R = A @ x + 0.1 * x[:4] ** 3 - 1.0
        J = A.copy()
        J[:, :4] += np.diag(0.3 * x[:4] ** 2)
        return Evaluation(xs.copy(), R, J)
    t = np.ones(5) / np.sqrt(5)
    c = correct(evaluate, np.zeros(5), linear_constraint(t, 0.2), None, 1e-12, 20, 4)
    assert c.converged and c.null is not None
    v = c.null / np.linalg.norm(c.null)
    ref = null_tangent(c.ev.Js, t)
    assert np.abs(v - ref).max() < 1e-12
    assert abs(t @ c.null - 1.0) < 1e-12      # normalised by the constraint row


def test_corrector_gives_up_early_when_newton_stalls():
    """A residual that no update reduces (cycling at a kink) fails after 2 * stall_window
    iterations with the reason stated, instead of spending max_iter iterations on it."""
    from continuation.corrector import Evaluation, correct, linear_constraint
    calls = []

    def evaluate(xs):
        calls.append(xs)
        return Evaluation(xs.copy(), np.array([1e-3]), np.array([[1.0, 0.0]]))
    con = linear_constraint(np.array([0.0, 1.0]), 0.0)
    c = correct(evaluate, np.zeros(2), con, None, 1e-10, 12, 2, stall_window=3)
    assert not c.converged and "stalled" in c.reason
    assert len(calls) == 1 + 6 * 3          # 6 iterations of 1 + 2 backtracking calls
    calls.clear()
    c = correct(evaluate, np.zeros(2), con, None, 1e-10, 12, 2, stall_window=0)
    assert not c.converged and "no convergence in 12" in c.reason and len(calls) == 1 + 12 * 3
