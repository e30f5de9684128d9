r"""Error of the harmonic truncation at every FRF point, by one Newton step in a richer basis.

A point :math:`X` solves the balance on the harmonics :math:`\mathcal H` (highest :math:`H`)
with :math:`N` samples.  Embedded in the richer basis :math:`\mathcal H'` (the same pattern
up to :math:`H' = 2H + 1`, :math:`N' \ge 4N`) with zero coefficients on the new harmonics,
its residual :math:`R'(X)` holds what the truncation left out: the element forces on the
harmonics above :math:`H` and the aliasing of :math:`N` samples.  One Newton step

.. math::

    J'(X)\, \delta = -R'(X)

gives the richer solution to first order, :math:`X' \approx X + \delta`, and the estimated
relative error of each output's first harmonic is

.. math::

    e = \frac{\big|\, |y_1(X + \delta)| - |y_1(X)| \,\big|}{|y_1(X + \delta)|}.

Where the richer basis adds nothing, :math:`R'(X)` is the embedded balance residual itself
and :math:`\delta` only Newton's last correction: when the element forces on :math:`N'`
samples equal those on :math:`N` embedded (to ``SAME_FORCES`` of their size) and the load has
no harmonic above :math:`H`, e.g. every contact stuck for the whole period (a linear law) or
no element loaded, the estimate is 0 and the point costs two force evaluations (no seeds),
not the richer Jacobian and solve.  The FRF tries this where every contact sticks for the
whole period (:mod:`hbm.analyses.stuck`).

Otherwise it costs one residual, Jacobian and linear solve of the richer problem per point (solved
like the continuation's: :func:`continuation.linsolve.make_solver` on its harmonic blocks, so a
contact patch costs block LUs and a few Krylov steps, not a dense LU), and the FRF computes it
when that problem has at most ``MAX_UNKNOWNS`` unknowns (its settings say so otherwise): the
richer Jacobian is still formed densely, ``8 n^2`` bytes.
"""
from __future__ import annotations

import numpy as np

from continuation.linsolve import make_solver
from hbm.balance.fourier import FourierBasis

MAX_UNKNOWNS = 6000       # a richer Jacobian of 290 MB
WARN_ERROR = 1e-2        # a point estimated worse than this is named in a warning
NOTE_SHARE = 1e-2        # every point better than this share of WARN_ERROR: H far beyond need
DECAY = 2.0              # friction's first-harmonic truncation error falls about as H^-DECAY
SAME_FORCES = 1e-12      # richer forces within this share of their size of the embedded ones: nothing added


def harmonics_note(H: int, top: float, n_unknowns: int, seconds: float) -> str | None:
    """A note when every point's estimate (largest ``top``) lies far within :data:`WARN_ERROR`:
    the harmonics that would bring it near a tenth of it, by the decay ``e ~ H^-DECAY``
    (measured on the SDOF Jenkins rig: 9.3e-4, 7.4e-5, 1.2e-5 at H = 7, 17, 40), and what this
    run paid (``n_unknowns`` per point, ``seconds``); None otherwise."""
    if H < 5 or not top < NOTE_SHARE * WARN_ERROR:
        return None
    target = 0.1 * WARN_ERROR
    need = max(3, int(np.ceil(H * (max(top, 1e-300) / target) ** (1.0 / DECAY))))
    if need >= H:
        return None
    return (f"estimated errors stay below {top:.1e} at every point: H = {H} is more than this response needs; "
            f"about H = {need} would keep them near {target:g} (they fall about as 1/H^{DECAY:g}) with about "
            f"{need / H:.2g} x the {n_unknowns} unknowns per point of this run ({seconds:.2g} s; the Newton "
            f"systems grow as their square, their factorisations as their cube)")


def largest_errors(outputs: dict, freq_hz: np.ndarray) -> dict:
    """Per output (``OutputSeries`` with ``err``), its largest estimated error and where:
    ``{name: {"error": e, "freq_hz": f}}``; ``freq_hz`` (n_points,)."""
    out = {}
    for name, o in outputs.items():
        k = int(np.nanargmax(o.err)) if np.isfinite(o.err).any() else 0
        out[name] = {"error": float(o.err[k]), "freq_hz": float(freq_hz[k])}
    return out


def truncation_warning(worst: dict, harmonics: str, advice: str = "") -> str | None:
    """The warning for the largest of :func:`largest_errors`'s ``worst`` above
    :data:`WARN_ERROR`, naming the ``harmonics`` it was computed with; None when none is."""
    bad = {n: v for n, v in worst.items() if v["error"] > WARN_ERROR}
    if not bad:
        return None
    n, v = max(bad.items(), key=lambda kv: kv[1]["error"])
    return (f"estimated error of {n} up to {v['error']:.1%} at {v['freq_hz']:.6g} Hz from the harmonic "
            f"truncation ({harmonics}){advice}")


def richer_basis(basis: FourierBasis) -> FourierBasis:
    """The harmonics of ``basis`` continued to ``2 H + 1`` in the same pattern (odd only when
    ``basis`` has odd harmonics only), mean kept when present, on ``N' >= 4 N`` samples."""
    h = np.asarray(basis.harmonics)
    top = 2 * int(h.max()) + 1
    pos = h[h > 0]
    step = 2 if np.all(pos % 2 == 1) and pos.size > 1 else 1
    more = np.arange(int(h.max()) + step, top + 1, step)
    hr = np.unique(np.concatenate([h, more]))
    n = max(4 * basis.n_samples, 4 * top + 2)
    return FourierBasis(hr, int(n))


def embed(X: np.ndarray, basis: FourierBasis, other: FourierBasis, axis: int = 0) -> np.ndarray:
    """Coefficients ``X`` of ``basis`` (its rows along ``axis``, e.g. (n_coef, n)) as those of
    ``other``: zero on the harmonics ``basis`` lacks, and those ``other`` lacks left out."""
    hb, ho = basis.h_of_row, other.h_of_row
    keep = np.isin(hb, ho)
    rows = (np.searchsorted(ho, hb) + (np.arange(hb.size) - np.searchsorted(hb, hb)))[keep]
    shape = list(X.shape)
    shape[axis] = other.n_coef
    out = np.zeros(shape)
    into, take = [slice(None)] * X.ndim, [slice(None)] * X.ndim
    into[axis], take[axis] = rows, np.flatnonzero(keep)
    out[tuple(into)] = X[tuple(take)]
    return out


def _h1(basis: FourierBasis, Y: np.ndarray) -> np.ndarray:
    r = basis.row_of(1, "c")
    return np.hypot(Y[r], Y[r + 1])


def truncation_errors(problem, richer_problem, Xs, ws, linear=None) -> np.ndarray:
    """Estimated relative error of every output's first harmonic at every point.

    Parameters
    ----------
    problem, richer_problem
        The FRF's problem and the same case on :func:`richer_basis`.
    Xs : ndarray, shape (n_points, n_coef, n)
    ws : ndarray, shape (n_points,)
        rad/s.
    linear : ndarray of bool, shape (n_points,), optional
        Points where the richer basis may add nothing (e.g. every contact stuck): there
        :func:`adds_nothing` is tried first (it costs as much as the estimate at a point where
        it fails, so it is not tried elsewhere).

    Returns
    -------
    ndarray, shape (n_points, n_outputs)
        NaN where the richer Jacobian is singular; 0 where the richer basis adds nothing
        (:func:`adds_nothing`).
    """
    rp = richer_problem
    out = np.full((len(ws), rp.linear.output_rows.shape[0]), np.nan)
    solve = make_solver(rp.n_unknowns, rp.solver_structure())
    new_rows = ~np.isin(rp.basis.h_of_row, problem.basis.h_of_row)
    try_first = np.zeros(len(ws), dtype=bool) if linear is None else np.asarray(linear, dtype=bool)
    if try_first.any() and np.any(rp.load(float(ws[0]))[new_rows] != 0.0):
        try_first[:] = False                    # a load above H: the richer basis adds it
    for k, (X, w) in enumerate(zip(Xs, ws)):
        Xr = embed(X, problem.basis, rp.basis)
        if try_first[k] and adds_nothing(problem, rp, X, Xr, float(w)):
            out[k] = 0.0
            continue
        R, J = rp.residual(Xr, float(w))[:2]
        d = solve(J, -R[:, None])
        if d is None or not np.all(np.isfinite(d)):
            continue
        d = d[:, 0]
        y0 = _h1(rp.basis, rp.recover_outputs(Xr, float(w)))
        y1 = _h1(rp.basis, rp.recover_outputs(rp.expand(rp.unknowns(Xr) + d), float(w)))
        out[k] = np.abs(y1 - y0) / np.maximum(y1, 1e-300)
    return out


def adds_nothing(problem, richer_problem, X: np.ndarray, Xr: np.ndarray, w: float) -> bool:
    """True when the element forces of ``Xr`` (``X`` (n_coef, n) embedded) on the richer basis
    equal those of ``X`` embedded, to ``SAME_FORCES`` of the larger force coefficient: no
    harmonic above ``H``, no aliasing of ``N`` samples (module doc).  Two force evaluations."""
    Fr = richer_problem.nonlinear_forces(Xr, w)
    F = embed(problem.nonlinear_forces(X, w), problem.basis, richer_problem.basis)
    return float(np.abs(Fr - F).max(initial=0.0)) <= SAME_FORCES * float(np.abs(Fr).max(initial=0.0))
