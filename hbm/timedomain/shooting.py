r"""Periodic steady state by shooting, and Floquet multipliers, on the discrete period map.

With the integrator state ``y = [q, v, a, S]`` at the start of a period and ``Phi`` the map
of one period of time steps, a periodic solution solves ``Phi(y) = y``.  Newton's method on
it uses the monodromy matrix ``Y = dPhi/dy``, built step by step from the laws' exact
tangents (:mod:`hbm.timedomain.time_sensitivity`):

.. math::

    (Y - I)\, \delta = -(\Phi(y_k) - y_k), \qquad y_{k+1} = y_k + \delta ,

on the unknowns ``[q, v, S]``: the acceleration is not one, since at every step end the
equations of motion fix it, ``a = M^{-1}(F - C v - K q - G^T P S)`` (exactly for Newmark,
``alpha = 0``), so ``dPhi/d[q, v, S] = Y_{:, qvS} + Y_{:, a}\, da/d[q, v, S]`` (keeping ``a``
as an unknown made the system as badly scaled as ``w_max^2 / w^2`` of the model's stiffest
mode).  The step is solved in least squares on scaled unknowns: a contact stuck all period
leaves a neutral
direction (a constant slider offset gives another periodic solution, multiplier exactly 1),
so ``Y - I`` is singular there and the minimum-norm step keeps the nearest orbit.  The map
is only piecewise smooth (stick/slip and contact transitions): a step that raises the
residual to more than ``GROWTH`` times the best so far is shortened (by 4, down to 1/64)
from the best point, and the steps after it grow back by 2 (a trust region on the step).

The eigenvalues ``mu`` of ``Y`` at the periodic solution are its Floquet multipliers: the
solution is asymptotically stable when every ``|mu| < 1`` apart from the neutral ones;
:func:`floquet_verdict` calls it unstable when some ``|mu| > 1 + FLOQUET_MARGIN``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from hbm.timedomain.time_kernels import element_forces

FLOQUET_MARGIN = 1e-6      # |mu| above 1 + this is growth (round-off of the product ~1e-10)
MAX_NEWTON = 12            # shooting iterations before giving up (quadratic: 3-5 usually)
MIN_DAMPING = 1.0 / 64     # shortest Newton step tried (a quarter at each worse residual)
GROWTH = 10.0              # a residual this many times the best so far shortens the step
OUT_OF_RANGE = 0.5         # share of the residual the least-squares step leaves: no progress
NEUTRAL = 1e-6             # |mu| this close to 1: a neutral direction


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
    """``y = [q, v, a, S]`` of an integrator state (:class:`hbm.timedomain.time_state.TimeState`)."""
    return np.concatenate([state.q, state.v, state.a, state.S])


def set_state(state, y: np.ndarray, laws) -> None:
    """Write ``y`` into ``state`` and its element forces ``fnl`` from the law states."""
    n = state.q.size
    state.q[:] = y[:n]
    state.v[:] = y[n:2 * n]
    state.a[:] = y[2 * n:3 * n]
    state.S[:] = y[3 * n:]
    element_forces(laws, state.S, state.fnl)


def static_dofs(model) -> np.ndarray:
    """Flags (n,) of the DOFs without mass and damping (rows of ``M`` and ``C`` zero): their
    equations are static, so their velocities and accelerations are by-products of the scheme
    that nothing reads (the condensed model's residual flexibility,
    :mod:`hbm.timedomain.condensed_twin`)."""
    M, C = model[0], model[1]
    return ~np.any(M != 0.0, axis=1) & ~np.any(C != 0.0, axis=1)


def start_sensitivity(n: int, n_s: int, fixed: np.ndarray, static: np.ndarray | None = None) -> np.ndarray:
    """``dy/dy`` at the period's start: the identity, without the support DOFs (prescribed)
    and without the velocities and accelerations of ``static`` DOFs (:func:`static_dofs`;
    their trapezoidal recurrences would add multipliers of exactly 1 that no motion has)."""
    Y = np.eye(3 * n + n_s)
    for b in range(3):
        idx = b * n + np.flatnonzero(fixed)
        Y[idx, idx] = 0.0
    if static is not None:
        for b in (1, 2):
            idx = b * n + np.flatnonzero(static)
            Y[idx, idx] = 0.0
    return Y


def force_map(laws, n: int) -> np.ndarray:
    """``G^T P`` (n, n_S): element forces ``fnl = G^T P S`` from the law states."""
    s_off, g_all, g_off = laws[3], laws[4], laws[5]
    GP = np.zeros((n, int(s_off[-1])))
    for p in range(g_off.size - 1):
        for i in range(g_off[p + 1] - g_off[p]):
            GP[:, s_off[p] + i] = g_all[g_off[p] + i]
    return GP


class Balance:
    """The acceleration at phase 0 from the equations of motion, and its derivative.

    ``a_f = M_ff^{-1}(F_c - C v - K q - G^T P S - M_fs a_s)_f`` on the free DOFs, ``a_s =
    -w^2 y_b`` on the supports; ``da/d[q, v, S]`` (n, 2 n + n_S) is zero on support rows.
    Static DOFs (:func:`static_dofs`, flags ``static``) have no acceleration: zero, like their
    rows of ``J``.
    """

    def __init__(self, model, laws, w):
        M, C, K, F2, fixed, ybase = model
        self.static = static_dofs(model)
        self.fr = np.flatnonzero((fixed == 0) & ~self.static)
        self.fx = np.flatnonzero(fixed)
        self.M, self.C, self.K, self.F0 = M, C, K, F2[0]
        self.a_fixed = -w * w * ybase[self.fx]
        self.GP = force_map(laws, M.shape[0])
        self.Minv = np.linalg.inv(M[np.ix_(self.fr, self.fr)])

    @cached_property
    def J(self) -> np.ndarray:
        """``da/d[q, v, S]`` (n, 2 n + n_S), zero on support rows."""
        J = np.zeros((self.M.shape[0], 2 * self.M.shape[0] + self.GP.shape[1]))
        J[self.fr] = -self.Minv @ np.hstack([self.K, self.C, self.GP])[self.fr]
        return J

    def acceleration(self, q, v, S):
        """``a`` (n,) that balances the equations at phase 0 for ``q``, ``v``, ``S``."""
        a = np.zeros_like(q)
        a[self.fx] = self.a_fixed
        rhs = self.F0 - self.C @ v - self.K @ q - self.GP @ S - self.M[:, self.fx] @ a[self.fx]
        a[self.fr] = self.Minv @ rhs[self.fr]
        return a


def reduced_monodromy(Y: np.ndarray, balance: Balance, n: int) -> np.ndarray:
    """``dPhi_r/dr`` (2 n + n_S, 2 n + n_S) for ``r = [q, v, S]`` (module docstring)."""
    keep = np.r_[0:2 * n, 3 * n:Y.shape[0]]
    return Y[np.ix_(keep, keep)] + Y[keep, 2 * n:3 * n] @ balance.J


def _reduced(y, n):
    return np.concatenate([y[:2 * n], y[3 * n:]])


def _set_reduced(state, r, laws, balance, n):
    q, v, S = r[:n], r[n:2 * n], r[2 * n:]
    set_state(state, np.concatenate([q, v, balance.acceleration(q, v, S), S]), laws)


def _scales(r0, r1, Yr, n, w, q_peak):
    """Magnitudes of the unknowns ``[q, v, S]``: ``q_peak`` and ``w q_peak`` for the motion;
    for each law state the larger of its end values and of its response to the motion over
    the period (``q_peak max|dS/dq0|``, ``w q_peak max|dS/dv0|``), 1 if all are zero.  A state
    scaled by its own value alone (a force that happens to pass near zero at the period's
    start) would swamp the least-squares step."""
    s = np.empty_like(r0)
    s[:n] = q_peak
    s[n:2 * n] = w * q_peak
    st = np.maximum(np.abs(r0[2 * n:]), np.abs(r1[2 * n:]))
    if n:
        st = np.maximum(st, q_peak * np.abs(Yr[2 * n:, :n]).max(axis=1))
        st = np.maximum(st, w * q_peak * np.abs(Yr[2 * n:, n:2 * n]).max(axis=1))
    s[2 * n:] = np.where(st > 0, st, 1.0)
    return s


def floquet_verdict(multipliers: np.ndarray) -> tuple:
    """``(stable, largest |mu|)``: unstable when some ``|mu| > 1 + FLOQUET_MARGIN``."""
    big = float(np.abs(multipliers).max()) if multipliers.size else 0.0
    return big <= 1.0 + FLOQUET_MARGIN, big


def _neutral_message(res, mult) -> str:
    k = int(np.count_nonzero(np.abs(np.abs(mult) - 1.0) < NEUTRAL))
    return (f"shooting stopped at residual {res:.3g}: what remains lies along directions Newton cannot "
            f"correct, {k} multiplier(s) within {NEUTRAL:g} of 1 (modes the time step leaves undamped, "
            f"e.g. stiff FE modes far above it, or contacts stuck all period); raise --tol above it, or "
            f"damp unresolved modes with --alpha -0.01")


def shoot(one_period, state, model, laws, w: float, tol: float,
          max_iter: int = MAX_NEWTON) -> ShootingResult:
    """Newton on the period map from ``state`` (updated in place to the last iterate).

    Parameters
    ----------
    one_period : callable
        ``one_period(state, Y) -> q_history (N + 1, n)``: integrates one period in place,
        carrying ``Y`` (m, m) through every step.
    state : hbm.timedomain.time_state.TimeState
    model : tuple
        ``(M, C, K, F2, fixed, ybase)`` as the kernels take it (:mod:`hbm.timedomain.time_kernels`).
    laws : tuple
        The packed law parts (:attr:`hbm.timedomain.time_parts.Packed.laws`).
    w : float
        Angular frequency, rad/s.
    tol : float
        Periodicity tolerance, relative to the period's largest ``|q|``.
    """
    n = model[0].shape[0]
    n_s = state.S.size
    balance = Balance(model, laws, w)
    residuals = []
    best = None                  # (residual, r, Newton step) of the best point so far
    lam = 1.0
    mult = np.zeros(0, dtype=complex)
    _set_reduced(state, _reduced(state_vector(state), n), laws, balance, n)
    for it in range(1, max_iter + 1):
        r0 = _reduced(state_vector(state), n)
        Y = start_sensitivity(n, n_s, model[4], balance.static)
        q_hist = one_period(state, Y)
        r1 = _reduced(state_vector(state), n)
        Yr = reduced_monodromy(Y, balance, n)
        q_peak = max(float(np.abs(q_hist).max()), 1e-300)
        res = float(np.abs(r1[:n] - r0[:n]).max() / q_peak)
        residuals.append(res)
        mult = np.linalg.eigvals(Yr)
        if res <= tol:
            return ShootingResult(True, it, tuple(residuals), mult, f"periodic after {it} shooting periods")
        if best is None or res <= GROWTH * best[0]:
            d = _scales(r0, r1, Yr, n, w, q_peak)
            A = (Yr - np.eye(Yr.shape[0])) * d[None, :] / d[:, None]
            b = -(r1 - r0) / d
            sol = np.linalg.lstsq(A, b, rcond=1e-12)[0]
            if np.abs(A @ sol - b).max() > OUT_OF_RANGE * np.abs(b).max():
                return ShootingResult(False, it, tuple(residuals), mult, _neutral_message(res, mult))
            step = sol * d
            if best is None or res < best[0]:
                best = (res, r0, step)
            lam = min(1.0, 2.0 * lam)
            _set_reduced(state, r0 + lam * step, laws, balance, n)
            continue
        lam *= 0.25              # far worse than the best: a shorter step from it
        if lam < MIN_DAMPING:
            _set_reduced(state, best[1], laws, balance, n)
            return ShootingResult(False, it, tuple(residuals), mult,
                                  f"shooting stalled at residual {best[0]:.3g} (steps shortened to "
                                  f"{MIN_DAMPING:g} of Newton's did not reduce it)")
        _set_reduced(state, best[1] + lam * best[2], laws, balance, n)
    _set_reduced(state, best[1], laws, balance, n)
    return ShootingResult(False, max_iter, tuple(residuals), mult,
                          f"shooting did not reach {tol:g} in {max_iter} periods (best {best[0]:.3g})")
