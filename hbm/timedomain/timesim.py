r"""Time-domain reference: implicit integration of a case to its periodic steady state.

Equations of motion (the same model, elements and excitation as the harmonic balance):

.. math::

    M \ddot q + C \dot q + K q + \sum_e G_e^T f_e = F_c \cos(w t) + F_s \sin(w t) \quad (t \le t_{off}),
    \qquad F = 0 \ \text{after} \ t_{off}.

Base (support) excitation (``[excitation] base``): the support DOFs ``b`` follow the prescribed
motion ``q_b(t) = A_b cos(w t)`` with ``v_b = -w A_b sin(w t)``, ``a_b = -w^2 A_b cos(w t)``
exactly at every (sub-)step end; only the free DOFs are unknowns (their rows of the equations
above), and the supports drive them through the coupling terms of ``M``, ``C``, ``K`` and
through every element attached to them (the elements see ``G q`` with the supports' motion).
The support reactions are not computed.  The run starts with the supports at ``A_b`` and the
free DOFs at the quasi-static position ``K_ff q_f = -K_fb A_b`` (elements stuck).

Scheme
------
HHT-alpha (Hilber-Hughes-Taylor) with ``alpha`` in [-1/3, 0]; ``alpha = 0`` (the default) is
Newmark's average-acceleration (trapezoidal) rule, ``gamma = 1/2``, ``beta = 1/4``.  In general
``gamma = 1/2 - alpha``, ``beta = (1 - alpha)^2 / 4`` and each step of size ``h`` solves

.. math::

    M a_{n+1} + (1+\alpha)(C v_{n+1} + K q_{n+1} + f_{n+1})
              - \alpha (C v_n + K q_n + f_n) = (1+\alpha) F_{n+1} - \alpha F_n

for ``q_{n+1}``, with ``a_{n+1} = (q_{n+1} - q_n - h v_n)/(\beta h^2) - (1/(2\beta) - 1) a_n``
and ``v_{n+1} = v_n + h((1-\gamma) a_n + \gamma a_{n+1})``, by Newton's method.  The element
forces come from the law's incremental return mapping (:func:`elements.kernels.law_step`),
always from the *last committed* state to the trial coordinates, so a Newton iterate never
pollutes the history; the states are committed only when the step has converged.  The
consistent tangent is ``df/du + gamma/(beta h) df/dv`` read from the law's ``B = ds_new/dz``
(``df/du = B[:n_local, :n_local]``, ``df/dv = B[:n_local, n_local:]`` for velocity laws).

Transitions (stick/slip, open/closed, static -> kinetic)
--------------------------------------------------------
Generic, law-agnostic: the integrator compares every element's tangent block
``D = B[:n_local, :]`` at the end of a trial step with the tangent committed at its start.
A jump ``max|D_new - D_old| > jump_tol * D_ref`` (``D_ref`` the largest tangent magnitude the
element has shown) means the element changed status inside the step (e.g. Jenkins stick ->
slip: ``kt -> 0``; a static -> kinetic Coulomb law also drops its stick stiffness).  Such a
step is rejected and retried as two halves, recursively (dyadic sub-steps), down to
``dt / 2**max_level``: the transition is located to within that sub-step, the sub-steps
around it grow back to ``dt`` as soon as they are aligned.  A step whose Newton iteration
fails is halved the same way; failure at the finest level stops the run with the time.
Smooth laws (cubic spring, a mildly regularised Coulomb law) do not trigger it except when
their tangent changes by a large fraction within a step.  The output grid is always the
``steps`` equal steps per period.

Periodic steady state
---------------------
From rest (``q = 0``, ``q' = 0``, element rest states from :func:`elements.kernels.law_init`
at zero coordinates), whole periods are integrated until the relative change of ``q`` (all
DOFs, all samples of the step grid) between successive periods,
``max|q_p - q_{p-1}| / max|q_p|``, is at most ``tol`` (default 1e-8), or ``max_periods``.
When the periods have not repeated after ``shoot_after`` (default 200), the periodic solution
is sought by shooting, Newton's method on the period map with its exact monodromy matrix
(:mod:`hbm.timedomain.shooting`, :mod:`hbm.timedomain.time_sensitivity`); plain periods then confirm the test.
Outputs per case output: ``h1 = sqrt(a^2 + b^2)`` with ``a, b = 2/N sum q_j (cos, sin)(2 pi j/N)``
over the last period's step grid, and ``max = max |q_j|`` over the same samples.

Error estimate by step halving: :func:`timesim` runs with ``steps = n``, then continues from
that steady state with ``2 n`` steps per period to steady state again, and reports the results
of the ``2 n`` run with the relative change ``|y_2n - y_n| / |y_2n|`` (largest over the
outputs' ``h1`` and ``max``) as its error estimate.  The scheme is second order, so this
overestimates the error of the ``2 n`` result (by about 3x for smooth motion).

Everything per time step runs in one numba kernel (:func:`hbm.timedomain.time_march.march`); Python
only loops over chunks of whole periods (for progress output).
"""
from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from hbm.analyses.budget import MEMORY_SHARE, machine_memory
from hbm.interface.case import Case, CaseError
from hbm.timedomain.time_march import march
from hbm.timedomain.time_parts import pack_elements
from hbm.timedomain.shooting import MAX_NEWTON, Balance, floquet_verdict, reduced_monodromy, shoot, start_sensitivity
from hbm.timedomain.time_results import History, Run, TimeSimOptions, TimeSimResult, period_amplitudes
from hbm.timedomain.time_state import TimeState, kernel_model

__all__ = ["History", "Run", "TimeSimOptions", "TimeSimResult", "steady_state", "timesim", "transient"]


def _check_supported(case: Case, switch_off_at=None) -> None:
    if case.excitation.base is not None and switch_off_at is not None:
        raise CaseError(f"{case.path}: a switch-off time is not supported with [excitation] base "
                        f"(support motion cannot stop abruptly)")


FREQ_RANGE = (1e-9, 1e12)      # Hz: beyond, 1/(beta h^2) or h itself leaves double precision


def _check_freq(freq_hz):
    try:
        f = float(freq_hz)
    except (TypeError, ValueError):
        raise CaseError(f"frequency must be a number, got {freq_hz!r}") from None
    if not (f > 0 and math.isfinite(f)):
        raise CaseError(f"frequency must be > 0 Hz, got {freq_hz!r}")
    if not FREQ_RANGE[0] <= f <= FREQ_RANGE[1]:
        raise CaseError(f"frequency {f:g} Hz is outside {FREQ_RANGE[0]:g} .. {FREQ_RANGE[1]:g} Hz: its time "
                        f"step would overflow or underflow the integrator's arithmetic")
    return f


def _amplitudes(case: Case, hist: History, N: int, w: float):
    """``h1`` and ``max`` per output over the last ``N + 1`` rows (one period)."""
    return period_amplitudes(case, hist.q[-(N + 1):], hist.t[-(N + 1):], w)


_NO_SENS = np.zeros((0, 0))


def _integrate(case, freq_hz, opts: TimeSimOptions, steps, periods, check, t_off, state,
               progress, period_offset=0, sens=None):
    """Run up to ``periods`` periods from ``state`` (updated in place); returns a :class:`Run`.
    ``sens`` (m, m), if given, is carried through every step (:mod:`hbm.timedomain.time_sensitivity`)."""
    w = 2.0 * np.pi * freq_hz
    N = int(steps)
    n = case.n_dof
    packed = pack_elements(case.elements, n)
    n_f = packed.g_out.shape[0]
    rows = N + 1 if check else periods * N + 1
    need = 8.0 * rows * (n + 3 * n_f) + 8.0 * 4 * n * n
    if need > MEMORY_SHARE * machine_memory():
        raise CaseError(f"the time history of {rows} steps needs about {need / 1e9:.3g} GB "
                        f"(this machine has {machine_memory() / 1e9:.3g} GB): fewer steps or periods")
    rec_q = np.zeros((rows, n))
    rec_f = np.zeros((rows, n_f))
    rec_u = np.zeros((rows, n_f))
    rec_v = np.zeros((rows, n_f))
    model = kernel_model(case)
    laws_opts = (float(opts.alpha), float(opts.newton_tol), int(opts.max_iter), int(opts.max_level),
                 float(opts.jump_tol))
    rec = (0 if check else 1, rec_q, rec_f, rec_u, rec_v) + packed.record_map()
    prev = np.zeros((N if check else 1, n))
    cur = np.zeros_like(prev)
    stats = np.zeros(4, dtype=np.int64)
    t_off = np.inf if t_off is None else float(t_off)
    T = 1.0 / freq_hz
    t0 = time.perf_counter()
    done, status, change, chunk = 0, 0, -1.0, 1
    while done < periods:
        chunk = min(chunk, periods - done)
        tc = time.perf_counter()
        run = (w, t_off, N, done * N, chunk, bool(check), float(opts.tol), done > 0)
        status, pp, ch, t_fail = march(model, packed.laws, laws_opts, run, state.arrays(), rec,
                                       prev, cur, stats, _NO_SENS if sens is None else sens)
        done += pp
        if ch >= 0:
            change = ch
        if status < 0:
            raise RuntimeError(
                f"time integration failed at t = {t_fail:.6g} s (period {period_offset + done + 1}) at "
                f"{freq_hz:.6g} Hz: Newton did not converge even with sub-step dt/{2 ** opts.max_level}")
        if status == 1:
            break
        if progress is not None:
            progress(period_offset + done, change)
        per = (time.perf_counter() - tc) / max(pp, 1)
        chunk = int(max(1, min(1000, 0.5 / max(per, 1e-9))))
    secs = time.perf_counter() - t0
    if check:
        t = (period_offset + done - 1) * T + np.arange(N + 1) * (T / N)
    else:
        t = np.arange(rows) * (T / N)
    hist = History(t, rec_q, rec_f, rec_u, packed.names, rec_v)
    h1, mx = _amplitudes(case, hist, N, w)
    st = {"newton_iterations": int(stats[0]), "substeps": int(stats[1]),
          "refinements": int(stats[2]), "newton_failures": int(stats[3])}
    return Run(freq_hz, N, done, bool(status == 1), float(change), h1, mx, hist, st, secs)


def _one_period(case, f, opts, steps, packed):
    """``one_period(state, Y)`` for :func:`hbm.timedomain.shooting.shoot`: one period in place, ``Y``
    carried through it; returns the period's ``q`` (N + 1, n)."""
    def one_period(state, Y):
        return _integrate(case, f, opts, steps, 1, False, None, state, None, sens=Y).history.q
    return one_period


SHOOT_START = 1e-3     # periodicity change below which shooting gets its full iterations
FAR_ITERATIONS = 4     # shooting iterations tried from further away


def _settle(case, f, opts: TimeSimOptions, steps, state, progress, period_offset=0) -> Run:
    """Periodic steady state from ``state``: plain periods, and shooting when they have not
    repeated after ``opts.shoot_after``.  From a change above ``SHOOT_START`` shooting gets
    ``FAR_ITERATIONS`` (a beating undamped mode converges at once; a stick-slip period map far
    from its orbit makes Newton wander), and if that fails, plain periods bring the change
    below ``SHOOT_START`` for a second attempt.  Plain periods confirm the periodicity test."""
    first = min(opts.shoot_after, opts.max_periods)
    runs = [_integrate(case, f, opts, steps, first, True, None, state, progress, period_offset)]
    if runs[0].converged or first >= opts.max_periods:
        return runs[0]
    packed = pack_elements(case.elements, case.n_dof)
    t0 = time.perf_counter()

    def attempt(change, done):
        iters = MAX_NEWTON if change <= SHOOT_START else FAR_ITERATIONS
        base = _one_period(case, f, opts, steps, packed)
        count = [period_offset + done]

        def one_period(st, Y):          # a shooting period can take seconds: report each
            q = base(st, Y)
            count[0] += 1
            if progress is not None:
                progress(count[0], -1.0)
            return q
        return shoot(one_period, state, kernel_model(case), packed.laws, 2 * np.pi * f, opts.tol, iters)

    shots = [attempt(runs[0].change, first)]
    if not shots[0].converged and runs[0].change > SHOOT_START:
        spent = first + shots[0].iterations
        near = dataclasses.replace(opts, tol=max(SHOOT_START, opts.tol))
        runs.append(_integrate(case, f, near, steps, max(opts.max_periods - spent, 2), True, None, state,
                               progress, period_offset + spent))
        if runs[-1].converged:
            shots.append(attempt(runs[-1].change, spent + runs[-1].periods))
    spent = sum(r.periods for r in runs) + sum(sh.iterations for sh in shots)
    last = _integrate(case, f, opts, steps, max(opts.max_periods - spent, 2), True, None, state,
                      progress, period_offset + spent)
    stats = {k: sum(r.stats[k] for r in runs) + last.stats[k] for k in last.stats}
    return dataclasses.replace(last, periods=spent + last.periods, stats=stats, shooting=shots[-1],
                               seconds=sum(r.seconds for r in runs) + (time.perf_counter() - t0))


def floquet(case: Case, freq_hz: float, state, options: TimeSimOptions, steps: int) -> tuple:
    """``(stable, largest |mu|, multipliers)`` of the periodic solution through ``state``
    (one period with sensitivities, :mod:`hbm.timedomain.shooting`); ``state`` is advanced a period."""
    packed = pack_elements(case.elements, case.n_dof)
    model = kernel_model(case)
    balance = Balance(model, packed.laws, 2 * np.pi * freq_hz)
    Y = start_sensitivity(case.n_dof, state.S.size, model[4], balance.static)
    _one_period(case, freq_hz, options, steps, packed)(state, Y)
    mu = np.linalg.eigvals(reduced_monodromy(Y, balance, case.n_dof))
    stable, big = floquet_verdict(mu)
    return stable, big, mu


def steady_state(case: Case, freq_hz: float, options: TimeSimOptions | None = None,
                 progress=None) -> Run:
    """Periodic steady state at ``freq_hz`` from rest with ``options.steps`` steps per period.

    Parameters
    ----------
    case : Case
    freq_hz : float
        Excitation frequency, Hz (> 0).
    options : TimeSimOptions, optional
    progress : callable, optional
        ``progress(periods_done, relative_change)`` every chunk of periods (about 0.5 s).

    Returns
    -------
    Run
        ``converged`` says whether the periodicity tolerance was met within ``max_periods``.
    """
    opts = options or TimeSimOptions()
    opts.validate()
    f = _check_freq(freq_hz)
    _check_supported(case)
    state = TimeState(case, pack_elements(case.elements, case.n_dof), 2 * np.pi * f)
    return _settle(case, f, opts, opts.steps, state, progress)


def transient(case: Case, freq_hz: float, periods: int, switch_off_at: float | None = None,
              options: TimeSimOptions | None = None, progress=None) -> Run:
    """Response from rest over ``periods`` periods; the force is zero after ``switch_off_at`` s.

    Returns
    -------
    Run
        ``history`` holds every step (``periods * steps + 1`` rows); ``h1``/``max`` are of the
        last period.
    """
    opts = options or TimeSimOptions()
    opts.validate()
    f = _check_freq(freq_hz)
    if not (isinstance(periods, (int, np.integer)) and periods >= 1):
        raise CaseError(f"periods must be an integer >= 1, got {periods!r}")
    if switch_off_at is not None and not (switch_off_at >= 0 and math.isfinite(switch_off_at)):
        raise CaseError(f"switch-off time must be >= 0 s, got {switch_off_at!r}")
    _check_supported(case, switch_off_at)
    state = TimeState(case, pack_elements(case.elements, case.n_dof), 2 * np.pi * f)
    return _integrate(case, f, opts, opts.steps, int(periods), False, switch_off_at, state, progress)


def _relative_changes(coarse: Run, fine: Run):
    errs = {}
    for name in fine.h1:
        e = []
        for key in ("h1", "max"):
            y2, y1 = getattr(fine, key)[name], getattr(coarse, key)[name]
            e.append(abs(y2 - y1) / abs(y2) if y2 != 0 else abs(y1 - y2))
        errs[name] = tuple(e)
    est = max((max(e) for e in errs.values()), default=0.0)
    return errs, float(est)


def timesim(case: Case, freq_hz: float, options: TimeSimOptions | None = None,
            periods: int | None = None, switch_off_at: float | None = None,
            progress=None) -> TimeSimResult:
    """Time-domain reference at one frequency with a step-halving error estimate.

    Steady mode (``periods`` None): steady state with ``n = options.steps`` steps per period
    from rest, then continued with ``2 n`` until periodic again.  Transient mode: two runs
    from rest over ``periods`` periods (force off after ``switch_off_at`` s) with ``n`` and
    ``2 n`` steps.  Values reported are the ``2 n`` run's.

    Raises
    ------
    CaseError
        Bad options (non-positive frequency, steps < 8, ...).
    RuntimeError
        Newton failure at the finest sub-step (message gives the time).
    """
    opts = options or TimeSimOptions()
    opts.validate()
    f = _check_freq(freq_hz)
    _check_supported(case, switch_off_at)
    t0 = time.perf_counter()
    if periods is None:
        packed = pack_elements(case.elements, case.n_dof)
        state = TimeState(case, packed, 2 * np.pi * f)
        coarse = _settle(case, f, opts, opts.steps, state, progress)
        fine = _settle(case, f, opts, 2 * opts.steps, state, progress, period_offset=coarse.periods)
        mode, conv, total = "steady", coarse.converged and fine.converged, coarse.periods + fine.periods
        stability = floquet(case, f, state, opts, 2 * opts.steps) if opts.floquet else None
    else:
        coarse = transient(case, f, periods, switch_off_at, opts, progress)
        fine = transient(case, f, periods, switch_off_at,
                         dataclasses.replace(opts, steps=2 * opts.steps), progress)
        mode, conv, total = "transient", True, int(periods)
        stability = None
    errs, est = _relative_changes(coarse, fine)
    if not all(math.isfinite(v) for v in list(fine.h1.values()) + list(fine.max.values())):
        raise RuntimeError(f"the integration at {f:g} Hz produced non-finite amplitudes (overflow): "
                           f"check the model's units and the frequency")
    return TimeSimResult(f, dict(fine.h1), dict(fine.max), est, errs, int(total), bool(conv), mode,
                         coarse, fine, time.perf_counter() - t0, switch_off_at, stability)
