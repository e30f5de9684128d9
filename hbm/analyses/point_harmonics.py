r"""Harmonics chosen point by point for a tolerance: ``hbm frf --tol``.

The FRF is traced on the case's harmonics :math:`\mathcal H_0` and every point's truncation
error :math:`e_i` is estimated (:mod:`hbm.analyses.truncation`).  A point with
:math:`e_i > tol` is solved again on the next, richer set :math:`\mathcal H_{k+1}`
(:func:`hbm.analyses.adaptive.next_harmonics`), where the richer path crosses the plane
through the point normal to the path,

.. math::

    R_{k+1}(X, \omega) = 0, \qquad
    t_i^T S^{-1} \big([X; \omega] - [X_i; \omega_i]\big) = 0,

with :math:`X_i` embedded (zero on the new harmonics), :math:`t_i` the unit secant of its
neighbours along the path in the scaled unknowns :math:`S^{-1} x`: a fixed-frequency solve
where the path runs along :math:`\omega`, and still well posed at a fold.  Its error is then
estimated on :math:`\mathcal H_{k+1}`; the ladder stops at ``tol`` or at
:data:`hbm.analyses.adaptive.H_MAX`.  Points that need it pay for the harmonics; the rest of
the path keeps the cheap ones.

A refined point is post-processed with its own problem: outputs, error estimate, energy
balance, element outputs, stuck contacts and (when computed) Hill's verdict; a point on a
bound of the window is solved there (the plane of fixed frequency).  The predicted jumps stay
those of the traced path (their amplitudes within its estimated errors).  The result's
basis holds every harmonic used, every point's coefficients embedded in it (zero on the
harmonics it did not carry), and ``FRFResult.point_harmonics`` holds each point's highest
harmonic.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np

from hbm.analyses.adaptive import H_MAX, next_harmonics
from hbm.analyses.hill_system import point_is_stable
from hbm.analyses.problem_setup import _residual_scale, _unknown_scale, build_problem, output_amplitudes
from hbm.analyses.result import OutputSeries
from hbm.analyses.stuck import stuck_contacts
from hbm.analyses.truncation import MAX_UNKNOWNS, richer_basis, embed, truncation_errors
from hbm.balance.element_outputs import element_output_series
from hbm.balance.fourier import FourierBasis, default_samples
from hbm.balance.newton import newton


def over_tolerance(res, tol: float) -> np.ndarray:
    """Points (bool, n_points) whose largest estimated error over the outputs exceeds ``tol``."""
    errs = [o.err for o in res.outputs.values() if o.err is not None]
    if not errs:
        return np.zeros(res.freq_hz.size, dtype=bool)
    return np.nanmax(np.vstack(errs), axis=0, initial=0.0) > tol


def path_direction(xs: np.ndarray, i: int, segments) -> np.ndarray:
    """Unit secant (n+1,) of the path ``xs`` (n_points, n+1, scaled) at point ``i``: from its
    neighbours in its segment (one-sided at a segment's end; the frequency axis when alone)."""
    a, b = next(((a, b) for a, b in segments if a <= i < b), (i, i + 1))
    lo, hi = max(i - 1, a), min(i + 1, b - 1)
    d = xs[hi] - xs[lo]
    n = np.linalg.norm(d)
    if n == 0.0:
        d = np.zeros(xs.shape[1])
        d[-1], n = 1.0, 1.0
    return d / n


def _normal(xs, i, segments, f_hz, window_hz) -> np.ndarray:
    """The plane's normal at point ``i``: the path's direction, or the frequency axis for a
    point on a bound of the window (it stays there)."""
    if min(abs(f_hz - window_hz[0]), abs(f_hz - window_hz[1])) <= 1e-12 * abs(window_hz[1]):
        t = np.zeros(xs.shape[1])
        t[-1] = 1.0
        return t
    return path_direction(xs, i, segments)


def solve_on_plane(problem, x0: np.ndarray, t: np.ndarray, scale: np.ndarray, r_scale: float,
                   tol: float = 1e-10):
    """``[unknowns, w]`` (n+1,) solving ``R(x) = 0`` on the plane ``t . (x - x0) / scale = 0``,
    or None when Newton fails.

    Parameters
    ----------
    problem : HarmonicBalance
    x0 : ndarray, shape (n+1,)
        A point of the plane (the start).
    t : ndarray, shape (n+1,)
        Unit normal in the scaled unknowns ``x / scale``.
    scale : ndarray, shape (n+1,)
    r_scale : float
        Typical residual (the load): weights the plane's row like the others.
    """
    a = t / scale

    def fun(x):
        R, J = problem(x)
        return np.r_[R, r_scale * (a @ (x - x0))], np.vstack([J, r_scale * a])

    res = newton(fun, x0, scale=scale, r_scale=r_scale, tol=tol)
    return res.x if res.converged else None


@dataclasses.dataclass
class _Level:
    """One rung of the ladder: its problem, the richer one for the estimate, scales."""

    basis: FourierBasis
    problem: object
    richer: object
    scale: np.ndarray
    r_scale: float


def _level(case, basis, window_hz, transform):
    """:class:`_Level` on ``basis``, or None when its error estimate would exceed
    :data:`hbm.analyses.truncation.MAX_UNKNOWNS`."""
    problem, _ = build_problem(case, basis, transform, window_hz[1])
    rb = richer_basis(basis)
    if rb.n_coef * problem.n_unknowns // basis.n_coef > MAX_UNKNOWNS:
        return None
    richer, _ = build_problem(case, rb, "auto", window_hz[1])
    w_lo, w_hi = 2 * np.pi * window_hz[0], 2 * np.pi * window_hz[1]
    scale = np.r_[_unknown_scale(problem, case, w_lo, w_hi), w_hi - w_lo]
    return _Level(basis, problem, richer, scale, _residual_scale(problem, w_lo))


def _point_record(case, lv: _Level, X, w, stability_options, with_stability: bool) -> dict:
    """Everything the FRF reports of the point ``(X, w)`` on ``lv``'s harmonics."""
    p = lv.problem
    rec = {"X": X, "w": w, "Y": p.recover_outputs(X, w),
           "err": truncation_errors(p, lv.richer, X[None], np.array([w]))[0],
           "energy": p.energy_balance(X, w).relative_error,
           "elements": {k: v[0] for k, v in element_output_series(
               p, case.analysis.element_outputs, X[None], np.array([w])).items()},
           "basis": lv.basis}
    st = stuck_contacts(p, X[None], np.array([w]))
    rec["stuck"] = None if st is None else int(st[0])
    if with_stability:
        rec["stable"] = bool(point_is_stable(p, X, w, stability_options))
    return rec


def refine_points(case, res, tol: float, window_hz, transform="auto", stability_options=None, start=None,
                  progress=None, deadline=None):
    """``res`` with every point whose estimated error exceeds ``tol`` solved again on richer
    harmonics until within it (module doc).  Returns ``(result, info)``; ``info`` lists the
    levels (highest harmonic, samples, points solved there), the points left above ``tol``, the
    failed solves and the time taken.  ``start``: the harmonics whose richer sets are tried
    (default: the result's; :func:`hbm.analyses.adaptive.carried_harmonics` leaves out those that
    carry nothing).  ``progress.refining(done, total, H)`` is called per point when ``progress``
    has it (:class:`hbm.interface.progress.FRFProgress`).  Past ``deadline`` (a
    ``time.perf_counter()`` value) no level and no point is started: ``info["stopped_hz"]`` is
    then ``[frequency of the first point not solved, H]``, else None."""
    t0 = time.perf_counter()
    todo = [int(i) for i in np.flatnonzero(over_tolerance(res, tol))]
    info = {"levels": [], "left_above": 0, "failed": 0, "failed_hz": [], "stopped_hz": None}
    segments = res.settings.get("segments") or [(0, res.freq_hz.size)]
    current = {i: (res.X[i], 2 * np.pi * res.freq_hz[i], res.basis) for i in todo}
    records, h, stuck_above = {}, list(start if start is not None else res.basis.harmonics), []
    while todo and max(h) < H_MAX:
        h = next_harmonics(h)
        N = max(res.basis.n_samples, default_samples(h, case.analysis.samples_factor))
        lv = _level(case, FourierBasis(h, N), window_hz, transform)
        if lv is None:
            break
        xs = _scaled_path(lv, res, current)
        info["levels"].append({"H": int(max(h)), "samples": int(N), "points": 0})
        left = []
        tell = getattr(progress, "refining", None)
        for done, i in enumerate(todo):
            if deadline is not None and time.perf_counter() > deadline:
                info["stopped_hz"] = [round(float(res.freq_hz[i]), 6), int(max(h))]
                left += todo[done:]
                break
            if tell is not None:
                tell(done, len(todo), int(max(h)))
            X0, w0, b0 = current[i]
            x0 = np.r_[lv.problem.unknowns(embed(X0, b0, lv.basis)), w0]
            x = solve_on_plane(lv.problem, x0, _normal(xs, i, segments, res.freq_hz[i], window_hz),
                               lv.scale, lv.r_scale)
            if x is None:           # kept as last solved, with its estimate: still above tol
                info["failed"] += 1
                info["failed_hz"].append([round(float(w0) / (2 * np.pi), 6), int(max(h))])
                stuck_above.append(i)
                continue
            X, w = lv.problem.expand(x[:-1]), float(x[-1])
            records[i] = _point_record(case, lv, X, w, stability_options, res.stable is not None)
            current[i] = (X, w, lv.basis)
            info["levels"][-1]["points"] += 1
            if np.nanmax(records[i]["err"], initial=0.0) > tol:
                left.append(i)
        todo = left
        if info["stopped_hz"] is not None:
            break
    info["left_above"] = len(todo) + len(stuck_above)
    out = _merged(res, records) if records else res
    return out, dict(info, seconds=round(time.perf_counter() - t0, 4))


def _scaled_path(lv: _Level, res, current) -> np.ndarray:
    """The path's points as scaled ``[unknowns, w]`` (n_points, n+1) on ``lv``'s harmonics
    (the refined ones at their current solution), for the planes' normals."""
    p = lv.problem
    rows = []
    for k in range(res.freq_hz.size):
        X, w, b = current.get(k, (res.X[k], 2 * np.pi * res.freq_hz[k], res.basis))
        rows.append(np.r_[p.unknowns(embed(X, b, lv.basis)), w] / lv.scale)
    return np.array(rows)


def _merged(res, records: dict):
    """``res`` on a basis holding its harmonics and those of ``records``, their points replacing its own."""
    bases = [r["basis"] for r in records.values()]
    h = np.unique(np.concatenate([res.basis.harmonics] + [b.harmonics for b in bases]))
    rb = FourierBasis(h, max(b.n_samples for b in bases))
    n = res.freq_hz.size
    X, Y = embed(res.X, res.basis, rb, axis=1), embed(res.Y, res.basis, rb, axis=1)
    freq = res.freq_hz.copy()
    energy = np.array(res.energy_error, dtype=float)
    H = np.full(n, int(res.basis.harmonics.max()))
    eouts = {k: np.array(v, dtype=float) for k, v in res.element_outputs.items()}
    stable = None if res.stable is None else np.array(res.stable, dtype=bool)
    stuck = None if res.stuck is None else np.array(res.stuck)
    amps = {name: [o.h1.copy(), o.max.copy(), np.array(o.err, dtype=float)] for name, o in res.outputs.items()}
    for k, r in records.items():
        X[k], Y[k] = embed(r["X"], r["basis"], rb), embed(r["Y"], r["basis"], rb)
        freq[k], energy[k], H[k] = r["w"] / (2 * np.pi), r["energy"], int(r["basis"].harmonics.max())
        for j, a in enumerate(amps.values()):
            (a[0][k], a[1][k]), a[2][k] = output_amplitudes(r["basis"], r["Y"][:, j]), r["err"][j]
        for name, v in r["elements"].items():
            eouts[name][k] = v
        if stable is not None:
            stable[k] = r["stable"]
        if stuck is not None and r["stuck"] is not None:
            stuck[k] = r["stuck"]
    outputs = {name: OutputSeries(*a) for name, a in amps.items()}
    return dataclasses.replace(res, freq_hz=freq, outputs=outputs, X=X, basis=rb, stable=stable,
                               energy_error=energy, element_outputs=eouts, Y=Y, stuck=stuck, point_harmonics=H)
