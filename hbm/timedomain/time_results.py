"""Results and settings of the time-domain reference (:mod:`hbm.timedomain.timesim`): the options, a
sampled history, one run at ``n`` steps per period and the ``n`` / ``2 n`` result."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hbm.interface.case import CaseError


@dataclass(frozen=True)
class TimeSimOptions:
    """Settings of the time integration.

    Attributes
    ----------
    steps : int
        Steps per excitation period ``n`` (the error estimate also runs ``2 n``).
    tol : float
        Periodicity tolerance: relative max change of ``q`` between successive periods.
    max_periods : int
        Most periods integrated per run (steady-state mode).
    alpha : float
        HHT parameter in [-1/3, 0]; 0 is Newmark average acceleration.
    max_level : int
        Finest sub-step ``dt / 2**max_level`` for locating element transitions.
    jump_tol : float
        Relative tangent jump that counts as an element status change.
    newton_tol : float
        Newton tolerance on the residual, relative to its largest term (which includes the
        inertia term's round-off, ``c0 |M| |q|``).  Each step's displacement error is about
        ``newton_tol |q|``; it enters every period as noise, which a lightly damped mode
        (multiplier ``|mu|`` near 1) accumulates to about ``noise / sqrt(1 - |mu|^2)``: at
        1e-10 the beam-damper-beam rig at 536 Hz (``|mu| = 0.9989``) beat at 1e-6 for 5000
        periods, hence 1e-12 (a few hundred times the round-off).
    max_iter : int
        Newton iterations per (sub-)step before the step is halved.
    shoot_after : int
        Plain periods integrated before the steady state is sought by shooting (Newton on
        the period map, :mod:`hbm.timedomain.shooting`) when the periods have not yet repeated.
    floquet : bool
        Also compute the Floquet multipliers of the final periodic solution (one more
        period with sensitivities).
    """

    steps: int = 512
    tol: float = 1e-8
    max_periods: int = 5000
    alpha: float = 0.0
    max_level: int = 6
    jump_tol: float = 0.3
    newton_tol: float = 1e-12
    max_iter: int = 30
    shoot_after: int = 200
    floquet: bool = False

    def validate(self):
        _whole("steps per period", self.steps, 8)
        if not (self.tol > 0 and math.isfinite(self.tol)):
            raise CaseError(f"periodicity tolerance must be > 0, got {self.tol!r}")
        _whole("max periods", self.max_periods, 2)
        if not -1.0 / 3.0 - 1e-12 <= self.alpha <= 0.0:
            raise CaseError(f"HHT alpha must be in [-1/3, 0], got {self.alpha!r}")
        _whole("shoot_after", self.shoot_after, 1)
        if not 0 <= self.max_level <= 20:
            raise CaseError(f"max_level must be in 0..20, got {self.max_level!r}")


def _whole(name, value, low):
    if not (isinstance(value, (int, np.integer)) and value >= low):
        raise CaseError(f"{name} must be an integer >= {low}, got {value!r}")


@dataclass(frozen=True)
class History:
    """Sampled time history.

    Attributes
    ----------
    t : ndarray, shape (n_rows,)
        Time, s.
    q : ndarray, shape (n_rows, n_dof)
    forces : ndarray, shape (n_rows, n_forces)
        Element forces (every element's ``n_local`` components, in case order).
    disp : ndarray, shape (n_rows, n_forces)
        The matching element coordinates ``G q``.
    force_names : tuple of str
    vel : ndarray, shape (n_rows, n_forces)
        The element coordinates' velocities ``G v`` (e.g. the relative sliding velocity).
    """

    t: np.ndarray
    q: np.ndarray
    forces: np.ndarray
    disp: np.ndarray
    force_names: tuple
    vel: np.ndarray | None = None


@dataclass(frozen=True)
class Run:
    """One integration at ``steps`` steps per period.

    ``h1``/``max`` (per output name) are of the last period on the step grid.  ``converged``
    is whether the periodicity test passed (steady mode; always False in transient mode, where
    ``change`` is -1).  ``history`` is the last period (steady) or the whole run (transient).
    ``shooting`` is the :class:`hbm.timedomain.shooting.ShootingResult` when the run needed shooting.
    """

    freq_hz: float
    steps: int
    periods: int
    converged: bool
    change: float
    h1: dict
    max: dict
    history: History
    stats: dict
    seconds: float
    shooting: object = None

    @property
    def shot_unstable(self) -> float | None:
        """Largest ``|multiplier|`` when this run's steady state was found by shooting and its
        monodromy matrix calls it unstable, else None.  Newton on the period map converges to
        unstable periodic solutions too: a motion from rest leaves such a one (its plain
        periods had not repeated), so it is not what the structure would show.  (The
        multipliers are the last shooting iteration's, free with the orbit.)"""
        from hbm.timedomain.shooting import floquet_verdict
        if self.shooting is None or not self.shooting.converged:
            return None
        stable, big = floquet_verdict(self.shooting.multipliers)
        return None if stable else big


@dataclass(frozen=True)
class TimeSimResult:
    """Result of :func:`timesim`: the ``2 n`` run's values with the ``n`` vs ``2 n`` estimate.

    Attributes
    ----------
    h1, max : dict of str -> float
        Per output, from the fine run.
    error_estimate : float
        Largest relative change of any output's ``h1`` or ``max`` between ``n`` and ``2 n``.
    errors : dict of str -> (float, float)
        Relative changes of ``(h1, max)`` per output.
    periods : int
        Periods integrated in total (both runs).
    converged : bool
        Both runs periodic to ``tol`` (steady mode); True in transient mode.
    mode : str
        ``"steady"`` or ``"transient"``.
    floquet : tuple or None
        ``(stable, largest |multiplier|, multipliers)`` of the fine run's periodic solution
        (with ``options.floquet``).
    """

    freq_hz: float
    h1: dict
    max: dict
    error_estimate: float
    errors: dict
    periods: int
    converged: bool
    mode: str
    coarse: Run
    fine: Run
    seconds: float
    switch_off_at: float | None = None
    floquet: tuple | None = None

    @property
    def history(self) -> History:
        return self.fine.history

    @property
    def shot_unstable(self) -> float | None:
        """:attr:`Run.shot_unstable` of the fine run, else of the coarse one."""
        return next((r.shot_unstable for r in (self.fine, self.coarse)
                     if r.shooting is not None and r.shooting.converged), None)


def output_series(case, q: np.ndarray, t: np.ndarray, w: float) -> dict:
    """Each output's values ``y = q g`` (n_rows,) at the rows of ``q`` (n_rows, n), times ``t``;
    with the excitation's direct part ``d_c cos(w t) + d_s sin(w t)`` of a condensed model's
    time twin (``analysis.feed``, :mod:`hbm.timedomain.condensed_twin`)."""
    feed = getattr(case.analysis, "feed", {})
    out = {}
    for name, g in case.analysis.outputs.items():
        y = q @ g
        if name in feed:
            y = y + feed[name][0] * np.cos(w * t) + feed[name][1] * np.sin(w * t)
        out[name] = y
    return out


def period_amplitudes(case, q: np.ndarray, t: np.ndarray, w: float):
    """``(h1, max)`` per output of one period sampled at ``N + 1`` rows ``q`` (N + 1, n) and
    times ``t`` (N + 1,) from its start to its end: ``h1 = sqrt(a^2 + b^2)`` with
    ``a, b = 2/N sum y_j (cos, sin)(2 pi j / N)`` over samples ``1 .. N`` and ``max = max |y_j|``."""
    N = q.shape[0] - 1
    th = 2.0 * np.pi * np.arange(1, N + 1) / N
    h1, mx = {}, {}
    for name, xo in output_series(case, q, t, w).items():
        x = xo[1:]
        h1[name] = float(np.hypot(2.0 / N * np.dot(x, np.cos(th)), 2.0 / N * np.dot(x, np.sin(th))))
        mx[name] = float(np.abs(xo).max())
    return h1, mx
