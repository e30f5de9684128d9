r"""Floquet stability of a harmonic-balance point, from the time integrator's period map.

A balance point (coefficients ``X`` (n_coef, n) at ``w``) gives the start of a period,

.. math::

    q_0 = E_0 X, \qquad v_0 = w\, E'_0 X, \qquad a_0 = w^2 E_0 D^2 X ,

(``E_0`` the synthesis row at ``theta = 0``, ``E'_0`` its derivative, ``D`` the derivative
operator) and the law states that the laws reach along the balance's motion (stepped through
two periods of ``z(t) = G E X`` sampled on the integrator's grid, so a friction state carries
its hysteresis).  Shooting (:func:`hbm.timedomain.shooting.shoot`) then finds the periodic solution of the
discrete time map next to it (Newton converges to unstable solutions as well), and its
monodromy matrix gives the Floquet multipliers: the time-domain check of Hill's verdict.

**Why Hill's unstable verdicts are checked** (:func:`confirm_unstable`).  For stick-slip,
contact and stuck-friction laws the linearised harmonic operator can flag a point whose time
solution is stable (the blade couple at 115.96 Hz: an isolated flag that comes and goes with
H, while the period map's largest multiplier is 0.987).  Short runs of flags are checked
first (an isolated flag is the most suspect); on the railcar rig a check takes 0.1 s, and 40
checks spent on the short runs of 28-30 Hz left 429 points of 32-40 Hz unchecked, hence the
time allowance beyond ``MAX_CONFIRM``.  Long runs are sampled: Hill calls 35.8-37 Hz on the
railcar rig unstable, and Floquet agrees at the middle of that stretch but finds a stable
window at 36.45-36.72 Hz (multipliers 0.69-0.94 at 1024 and 4096 steps alike).  Hill errs
the other way too: in the same stretch it calls 36.00, 36.02-36.03 and 36.06 Hz stable, islands
in an unstable run, where the period map's largest multipliers are 1.50-1.58 (1024 and 4096
steps, the time solution within 0.7 % of the balance point), so short stable islands are
checked as well, in one queue with the unstable runs (on the whole railcar FRF a 30 s cap
was reached before every unstable run was checked: islands queued after them were never
checked, and queued with them they left 325 unstable points unchecked, against 170 before).
Hill's spectra take 262 s there (H = 25, 705 points), so the checks may take a quarter of
that (``CONFIRM_SHARE``) when it is more than ``CONFIRM_SECONDS``.

**Steps per period.**  At 25 points of ``upd_like``, 24 of the UPD flanks rig's (unstable
ones included) and the blade couple's overridden point the verdicts of 256 steps are those of
1024 wherever both converged, the largest multipliers 1e-5 apart on stable points and up to
2 % on unstable ones.  Not so on the railcar rig, whose contacts are 112-338 times stiffer
than the structure along them: there 256 steps gave the opposite verdict at 20 of 24 points
of 36.38-36.81 Hz, where 1024 and 4096 steps agree (and the same verdict at a point of
28-30 Hz, so one trial check does not tell).  Models with stiff contacts
(:func:`hbm.model.contact_stiffness.stiff_contacts`, at least 100 times) are checked at
``FINE_STEPS``.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from elements.kernels import law_init, law_step

from hbm.balance.fourier import FourierBasis, basis_matrix
from hbm.model.contact_stiffness import stiff_contacts
from hbm.timedomain.condensed_twin import time_model
from hbm.timedomain.shooting import floquet_verdict, set_state, shoot
from hbm.timedomain.time_parts import pack_elements
from hbm.timedomain.time_results import TimeSimOptions, period_amplitudes


@dataclass(frozen=True)
class FloquetCheck:
    """Floquet verdict of one balance point.

    Attributes
    ----------
    stable : bool
        Every multiplier within ``1 + FLOQUET_MARGIN`` (meaningful only if ``converged``).
    largest : float
        Largest ``|mu|``.
    converged : bool
        Shooting found the periodic time solution.
    distance : float
        ``max|q_time - q_balance|`` over the period, relative to ``max|q_balance|``: how far
        the time solution is from the balance point (same branch if small).
    message : str
    h1, max : dict
        Per case output, the time solution's first-harmonic amplitude and largest ``|y|``
        over its last period (:func:`hbm.timedomain.time_results.period_amplitudes`).
    periods : int
        Periods integrated.
    X : ndarray, shape (n_coef, n), or None
        The time solution's last period projected on the balance's basis (least squares on
        the step grid), for a full model: the start of a shot at a neighbouring frequency
        (:mod:`hbm.analyses.time_fill`); None for a condensed one.
    """

    stable: bool
    largest: float
    converged: bool
    distance: float
    message: str
    h1: dict
    max: dict
    periods: int
    X: np.ndarray | None = None


def _start_states(packed, G_all_q: np.ndarray):
    """Law states at phase 0 after stepping every part through two periods of its inputs.

    ``G_all_q`` (N, n_rows) are the parts' inputs ``G_p q(t_j)`` on the step grid (no
    velocity laws: those read ``G_p v`` as well, see :func:`start_state`).
    """
    kinds, p_all, p_off, s_off, g_all, g_off, vel, d_off = packed.laws
    S = np.zeros(int(s_off[-1]))
    for p in range(kinds.size):
        rows = slice(g_off[p], g_off[p + 1])
        z = np.ascontiguousarray(G_all_q[:, rows])
        nin = z.shape[1]
        ns = s_off[p + 1] - s_off[p]
        params = p_all[p_off[p]:p_off[p + 1]]
        s = np.zeros(ns)
        s_new = np.zeros(ns)
        law_init(kinds[p], params, np.ascontiguousarray(z[0]), s, np.zeros((ns, nin)))
        A, B = np.zeros((ns, ns)), np.zeros((ns, nin))
        for j in (list(range(1, z.shape[0])) + [0]) * 2:
            law_step(kinds[p], params, s, np.ascontiguousarray(z[j]), s_new, A, B)
            s[:] = s_new
        S[s_off[p]:s_off[p + 1]] = s
    return S


def start_state(packed, basis: FourierBasis, X: np.ndarray, w: float, steps: int) -> np.ndarray:
    """``y = [q, v, a, S]`` at phase 0 of the balance point ``X`` (n_coef, n_dof) of a model
    whose law parts are ``packed`` (:func:`hbm.timedomain.time_parts.pack_elements`)."""
    if np.any(packed.laws[6]):
        raise ValueError("the Floquet check of a balance point does not handle velocity-dependent laws")
    theta = 2.0 * np.pi * np.arange(steps) / steps
    q_t = basis_matrix(basis.h_of_row, theta) @ X
    S = _start_states(packed, q_t @ packed.laws[4].T)
    q0 = basis.E[0] @ X
    v0 = w * (basis.dE[0] @ X)
    a0 = w * w * (basis.E[0] @ (basis.D @ (basis.D @ X)))
    return np.concatenate([q0, v0, a0, S])


VERDICT_TOL = 1e-5    # periodicity (relative to max |q|) that is enough to read the multipliers


def check_point(case, basis: FourierBasis, X: np.ndarray, freq_hz: float, steps: int = 1024,
                tol: float = VERDICT_TOL, max_iter: int = 12, problem=None) -> FloquetCheck:
    """Floquet verdict of the balance point ``X`` (n_coef, n) at ``freq_hz``: ``n`` every DOF of
    a full model, or the contact coordinates of the condensed ``problem`` (:func:`time_model`).

    A verdict needs the orbit, not its last digits: shooting stops at a periodicity of ``tol``
    (the multipliers change continuously with the start state between stick-slip events).
    On the UPD flanks rig's unstable stretch, 1e-7 was reached at 32 of 77 points and 1e-5
    at 58, with the same verdicts where both converged; Newton on that non-smooth period map
    often stalls between 1e-7 and 1e-5.

    A support excitation's DOFs follow their imposed motion in the period map as in
    ``hbm timesim`` (the railcar rig, base-excited: periodic after 3-10 shooting periods of 256
    steps, 0.1 s each).

    Raises
    ------
    ValueError
        Velocity-dependent laws (not handled here).
    """
    from hbm.timedomain.time_state import TimeState, kernel_model
    from hbm.timedomain.timesim import _one_period
    w = 2.0 * np.pi * freq_hz
    model, to_model = time_model(case, problem)
    Xm = to_model(X, w)
    packed = pack_elements(model.elements, model.n_dof)
    state = TimeState(model, packed, w)
    set_state(state, start_state(packed, basis, Xm, w, steps), packed.laws)
    opts = TimeSimOptions(steps=steps)
    periods = []

    def one_period(st, Y):
        q = _one_period(model, freq_hz, opts, steps, packed)(st, Y)
        periods.append(q)
        return q

    shot = shoot(one_period, state, kernel_model(model), packed.laws, w, tol, max_iter)
    stable, big = floquet_verdict(shot.multipliers)
    theta = 2.0 * np.pi * np.arange(steps + 1) / steps
    q_hb = basis_matrix(basis.h_of_row, theta) @ Xm
    q_td = periods[-1]
    h1, mx = period_amplitudes(model, q_td, theta / w, w)
    X_td = None
    if model is not case:           # compare the contact motion u = B y
        q_hb, q_td = q_hb @ model.B.T, q_td @ model.B.T
    else:
        X_td = np.linalg.lstsq(basis_matrix(basis.h_of_row, theta[:-1]), q_td[:-1], rcond=None)[0]
    dist = float(np.abs(q_td - q_hb).max() / max(np.abs(q_hb).max(), 1e-300))
    return FloquetCheck(stable, big, shot.converged, dist, shot.message, h1, mx, len(periods), X_td)


MAX_CONFIRM = 40            # Hill-unstable points checked per FRF at least, if there are so many,
CONFIRM_SECONDS = 30.0      # and more while the checks have taken less than this,
CONFIRM_SHARE = 0.25        # or than this share of the Hill spectra's seconds (settings["stability_seconds"])
MAX_STATE = 400             # 3 n + n_S above which the check is not run (cost ~ m n^2 per step)
CONFIRM_STEPS = 256         # the FRF's own checks: the verdicts of 1024 steps at a quarter of the cost
FINE_STEPS = 1024           # ... on models with stiff contacts (hbm.model.contact_stiffness.stiff_contacts)
LONG_RUN = 8                # runs of more unstable points are sampled, not judged by their middle
RUN_SAMPLES = 9             # checks spread over a long run (then its verdict changes bisected)


def _non_smooth(packed) -> bool:
    from elements.laws.registry import COULOMB_REGULARISED, CUBIC
    return bool(np.any(~np.isin(packed.laws[0], (CUBIC, COULOMB_REGULARISED))))


def confirm_unstable(case, basis: FourierBasis, Xs: np.ndarray, freq_hz: np.ndarray,
                     stable: np.ndarray, settings: dict, problem=None) -> np.ndarray:
    """Hill's unstable verdicts checked by Floquet multipliers where Hill is not exact (module
    doc): on a small model (``3 n + n_S <= MAX_STATE``) with a non-smooth law and no velocity
    law.

    The runs of consecutive points Hill calls unstable are checked with :func:`check_point`,
    the shortest runs first, ``MAX_CONFIRM`` checks and more while they have taken less than
    ``CONFIRM_SECONDS`` or ``CONFIRM_SHARE`` of the time Hill's spectra took
    (``settings["stability_seconds"]`` on entry).  A run of at most ``LONG_RUN`` points is
    judged by its middle point first: if Floquet confirms it (or shooting does not converge),
    Hill's verdict stands for the run; if Floquet calls it stable, every point of the run is
    checked and a converged Floquet verdict replaces Hill's.  A longer run is checked at
    ``RUN_SAMPLES`` points spread over it (:func:`_sampled_run`).  Each *island* of at most
    ``LONG_RUN`` points Hill calls stable between two unstable points is checked as a short
    run, in the same order of length, a converged unstable Floquet verdict replacing Hill's
    (``settings["floquet_unstable_hz"]``).  The checks take ``CONFIRM_STEPS`` steps per
    period, ``FINE_STEPS`` on a model with stiff contacts (``settings["floquet_steps"]``).
    ``settings["floquet_checked"]`` counts the checks, ``settings["floquet_overrides_hz"]``
    lists the points turned stable and ``settings["floquet_unchecked"]`` counts the unstable
    points left unchecked by the cap.

    Parameters
    ----------
    Xs : ndarray, shape (n_points, n_coef, n)
        Every DOF's coefficients (full solver) or the contact coordinates of the condensed
        ``problem`` (checked on its kept modes and residual flexibility, :func:`time_model`).
    stable : ndarray of bool, shape (n_points,)

    Returns
    -------
    ndarray of bool, shape (n_points,)
    """
    bad = np.flatnonzero(~stable)
    if not bad.size:
        return stable
    model, _ = time_model(case, problem)
    packed = pack_elements(model.elements, model.n_dof)
    if (not _non_smooth(packed) or np.any(packed.laws[6]) or 3 * model.n_dof + packed.n_states > MAX_STATE
            or (model is case and Xs.shape[-1] != case.n_dof)):
        return stable
    steps = settings["floquet_steps"] = FINE_STEPS if stiff_contacts(case) else CONFIRM_STEPS
    budget = _Budget(max(CONFIRM_SECONDS, CONFIRM_SHARE * settings.get("stability_seconds", 0.0)))

    def floquet_calls(verdict: bool):
        """``turns(i)``: True where shooting converged and Floquet's verdict at point ``i`` is
        ``verdict`` (True: stable), None past the cap."""
        def turns(i):
            if not budget.take():
                return None
            c = check_point(case, basis, Xs[i], float(freq_hz[i]), steps=steps, problem=problem)
            return bool(c.converged and c.stable == verdict)
        return turns

    stable_at, unstable_at = floquet_calls(True), floquet_calls(False)

    out, turned, lost, unchecked = stable.copy(), [], set(), 0
    runs = [(r, False) for r in _runs(bad)]
    for run, island in sorted(runs + [(r, True) for r in _islands(stable)], key=lambda ri: ri[0].size):
        if budget.spent():
            unchecked += 0 if island else run.size
        elif island:
            lost |= _short_run(run, unstable_at)[0]
        else:
            now, left = _sampled_run(run, stable_at) if run.size > LONG_RUN else _short_run(run, stable_at)
            unchecked += left
            out[sorted(now)] = True
            turned += [round(float(freq_hz[i]), 6) for i in sorted(now)]
    out[sorted(lost)] = False
    settings["floquet_checked"] = budget.checks
    if unchecked:
        settings["floquet_unchecked"] = unchecked
    if turned:
        settings["floquet_overrides_hz"] = sorted(turned)
    if lost:
        settings["floquet_unstable_hz"] = sorted(round(float(freq_hz[i]), 6) for i in lost)
    return out


def _islands(stable: np.ndarray) -> list:
    """Runs (indices) of at most ``LONG_RUN`` points that Hill calls stable (``stable`` (n,))
    with an unstable point on either side (module doc)."""
    return [r for r in _runs(np.flatnonzero(stable))
            if r.size <= LONG_RUN and r[0] > 0 and r[-1] < stable.size - 1]


def _runs(idx: np.ndarray) -> list:
    """The runs of consecutive indices in the sorted ``idx`` (k,), as arrays."""
    return np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []


class _Budget:
    """Checks counted against ``MAX_CONFIRM`` and ``seconds`` (spent when both are)."""

    def __init__(self, seconds: float):
        self.checks, self.seconds, self._t0 = 0, seconds, time.perf_counter()

    def spent(self) -> bool:
        return self.checks >= MAX_CONFIRM and time.perf_counter() - self._t0 >= self.seconds

    def take(self) -> bool:
        """False past the cap; else one more check counted."""
        if self.spent():
            return False
        self.checks += 1
        return True


def _short_run(run: np.ndarray, turns):
    """``(points turned, points left unchecked)`` of a run of at most ``LONG_RUN`` points
    (indices (L,)) by ``turns(i)`` (True: Floquet reverses Hill's verdict, None: past the
    cap): its middle first, the others only if Floquet turns it."""
    mid = int(run[run.size // 2])
    if not turns(mid):
        return set(), 0
    rest = [(int(i), turns(int(i))) for i in run if i != mid]
    return {mid} | {i for i, v in rest if v}, sum(v is None for _, v in rest)


def _sampled_run(run: np.ndarray, stable_at) -> tuple:
    """``(points turned stable, 0)`` of a long unstable run (indices (L,)).

    ``RUN_SAMPLES`` points spread evenly over the run are checked; between two neighbouring
    samples of the same verdict every point takes it (an assumption, as for Hill's verdicts
    between probes, :mod:`hbm.analyses.stability_path`: an island narrower than the samples'
    spacing can be missed); where the verdict changes, the change is bisected to
    neighbouring points.  ``stable_at(i)`` returns True (stable), False, or None (past the cap:
    Hill's verdict stands).
    """
    L = run.size
    pos = np.unique(np.linspace(0, L - 1, min(RUN_SAMPLES, L)).round().astype(int))
    v = {int(p): bool(stable_at(int(run[p]))) for p in pos}
    now = {p for p in v if v[p]}
    for a, b in zip(pos[:-1], pos[1:]):
        a, b = int(a), int(b)
        if v[a] == v[b]:
            now |= set(range(a + 1, b)) if v[a] else set()
            continue
        lo, hi = a, b                       # v[lo] == v[a], v[hi] == v[b]
        while hi - lo > 1:
            m = (lo + hi) // 2
            v[m] = bool(stable_at(int(run[m])))
            lo, hi = (m, hi) if v[m] == v[a] else (lo, m)
        now |= set(range(a + 1, lo + 1)) if v[a] else set(range(hi, b))
    return {int(run[p]) for p in now}, 0
