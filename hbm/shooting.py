r"""Periodic steady state by shooting, and Floquet multipliers, on the discrete period map.

With the integrator state ``y = [q, v, a, S]`` at the start of a period and ``Phi`` the map
of one period of time steps, a periodic solution solves ``Phi(y) = y``.  Newton's method on
it uses the monodromy matrix ``Y = dPhi/dy``, built step by step from the laws' exact
tangents (:mod:`hbm.time_sensitivity`):

.. math::

    (Y - I)\, \delta = -(\Phi(y_k) - y_k), \qquad y_{k+1} = y_k + \delta ,

solved in least squares on scaled unknowns: a contact stuck all period leaves a neutral
direction (a constant slider offset gives another periodic solution, multiplier exactly 1),
so ``Y - I`` is singular there and the minimum-norm step keeps the nearest orbit.  The map
is only piecewise smooth (stick/slip and contact transitions): a step that raises the
residual to more than ``GROWTH`` times the best so far is shortened (by 4, down to 1/64)
from the best point.

The eigenvalues ``mu`` of ``Y`` at the periodic solution are its Floquet multipliers: the
solution is asymptotically stable when every ``|mu| < 1`` apart from the neutral ones;
:func:`floquet_verdict` calls it unstable when some ``|mu| > 1 + FLOQUET_MARGIN``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .time_kernels import element_forces

FLOQUET_MARGIN = 1e-6      # |mu| above 1 + this is growth (round-off of the product ~1e-10)
MAX_NEWTON = 12            # shooting iterations before giving up (quadratic: 3-5 usually)
MIN_DAMPING = 1.0 / 64     # shortest Newton step tried (a quarter at each worse residual)
GROWTH = 10.0              # a residual this many times the best so far shortens the step


@dataclass(frozen=True)
class ShootingResult:
    """Outcome of :func:`shoot`.

    Attributes
    ----------
    converged : bool
        ``max|q(T) - q(0)|`` within ``tol`` of the period's largest ``|q|``.
    iterations : int
        Periods integrated with sensitivities.
    residuals : tuple of float
        The relative periodicity residual before each Newton step.
    multipliers : ndarray, shape (m,)
        Eigenvalues of the last monodromy matrix (complex).
    message : str
    """

    converged: bool
    iterations: int
    residuals: tuple
    multipliers: np.ndarray
    message: str


def state_vector(state) -> np.ndarray:
    """``y = [q, v, a, S]`` of an integrator state (:class:`hbm.timesim._State`)."""
    return np.concatenate([state.q, state.v, state.a, state.S])


def set_state(state, y: np.ndarray, laws) -> None:
    """Write ``y`` into ``state`` and its element forces ``fnl`` from the law states."""
    n = state.q.size
    state.q[:] = y[:n]
    state.v[:] = y[n:2 * n]
    state.a[:] = y[2 * n:3 * n]
    state.S[:] = y[3 * n:]
    element_forces(laws, state.S, state.fnl)


def start_sensitivity(n: int, n_s: int, fixed: np.ndarray) -> np.ndarray:
    """``dy/dy`` at the period's start: the identity, without the support DOFs (prescribed)."""
    Y = np.eye(3 * n + n_s)
    for b in range(3):
        idx = b * n + np.flatnonzero(fixed)
        Y[idx, idx] = 0.0
    return Y


def _scales(y0, y1, Y, n, w, q_peak):
    """Magnitudes of the unknowns: ``q_peak``, ``w q_peak``, ``w^2 q_peak`` for the motion;
    for each law state the larger of its end values and of its response to the motion over
    the period (``q_peak max|dS/dq0|``, ``w q_peak max|dS/dv0|``), 1 if all are zero.  A state
    scaled by its own value alone (a force that happens to pass near zero at the period's
    start) would swamp the least-squares step."""
    s = np.empty_like(y0)
    s[:n] = q_peak
    s[n:2 * n] = w * q_peak
    s[2 * n:3 * n] = w * w * q_peak
    st = np.maximum(np.abs(y0[3 * n:]), np.abs(y1[3 * n:]))
    if n:
        st = np.maximum(st, q_peak * np.abs(Y[3 * n:, :n]).max(axis=1))
        st = np.maximum(st, w * q_peak * np.abs(Y[3 * n:, n:2 * n]).max(axis=1))
    s[3 * n:] = np.where(st > 0, st, 1.0)
    return s


def floquet_verdict(multipliers: np.ndarray) -> tuple:
    """``(stable, largest |mu|)``: unstable when some ``|mu| > 1 + FLOQUET_MARGIN``."""
    big = float(np.abs(multipliers).max()) if multipliers.size else 0.0
    return big <= 1.0 + FLOQUET_MARGIN, big


def shoot(one_period, state, laws, n: int, w: float, fixed: np.ndarray, tol: float,
          max_iter: int = MAX_NEWTON) -> ShootingResult:
    """Newton on the period map from ``state`` (updated in place to the last iterate).

    Parameters
    ----------
    one_period : callable
        ``one_period(state, Y) -> q_history (N + 1, n)``: integrates one period in place,
        carrying ``Y`` (m, m) through every step.
    state : hbm.timesim._State
    laws : tuple
        The packed law parts (:attr:`hbm.time_parts.Packed.laws`).
    n : int
        DOFs.
    w : float
        Angular frequency, rad/s.
    fixed : ndarray of int, shape (n,)
        Support flags.
    tol : float
        Periodicity tolerance, relative to the period's largest ``|q|``.
    """
    n_s = state.S.size
    residuals = []
    best = None                  # (residual, y, Newton step) of the best point so far
    lam = 1.0
    mult = np.zeros(0, dtype=complex)
    for it in range(1, max_iter + 1):
        y0 = state_vector(state)
        Y = start_sensitivity(n, n_s, fixed)
        q_hist = one_period(state, Y)
        y1 = state_vector(state)
        q_peak = max(float(np.abs(q_hist).max()), 1e-300)
        res = float(np.abs(y1[:n] - y0[:n]).max() / q_peak)
        residuals.append(res)
        mult = np.linalg.eigvals(Y)
        if res <= tol:
            return ShootingResult(True, it, tuple(residuals), mult, f"periodic after {it} shooting periods")
        if best is None or res <= GROWTH * best[0]:
            d = _scales(y0, y1, Y, n, w, q_peak)
            A = (Y - np.eye(Y.shape[0])) * d[None, :] / d[:, None]
            step = np.linalg.lstsq(A, -(y1 - y0) / d, rcond=1e-12)[0] * d
            if best is None or res < best[0]:
                best = (res, y0, step)
            lam = 1.0
            set_state(state, y0 + step, laws)
            continue
        lam *= 0.25              # far worse than the best: a shorter step from it
        if lam < MIN_DAMPING:
            set_state(state, best[1], laws)
            return ShootingResult(False, it, tuple(residuals), mult,
                                  f"shooting stalled at residual {best[0]:.3g} (steps shortened to "
                                  f"{MIN_DAMPING:g} of Newton's did not reduce it)")
        set_state(state, best[1] + lam * best[2], laws)
    set_state(state, best[1], laws)
    return ShootingResult(False, max_iter, tuple(residuals), mult,
                          f"shooting did not reach {tol:g} in {max_iter} periods (best {best[0]:.3g})")
