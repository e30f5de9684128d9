r"""Railcar friction wedge (seed 004) with rigid contacts: the paper's own one-DOF model,
integrated from event to event in closed form.

With both faces of each wedge closed and rigid, the wedges follow the bolster
(:math:`Y_w = \Gamma Y_b`, :math:`X_w = -\tan\gamma\, Y_w`) and the rig has one DOF: the
bolster's displacement :math:`Y` relative to the side-frame, which moves as
:math:`A \cos W t`. The paper's Eq. (1), dimensional, while the bolster slips in the
direction :math:`s = \operatorname{sgn} \dot Y`:

.. math::

    \ddot Y + \omega^2 F^s Y = -g (H^s + G^s) + G^s A W^2 \cos W t,
    \qquad \omega^2 = K_b / M_b,

with :math:`F^\pm, G^\pm, H^\pm` at :math:`\mu_k` (``kaiser_coefficients``, Table 2). While
:math:`\dot Y = 0` it sticks as long as neither direction can start (coefficients at :math:`\mu_s`):

.. math::

    a^+(t) = -\omega^2 F^+ Y - g (H^+ + G^+) + G^+ A W^2 \cos W t \le 0 \le a^-(t).

Every phase has a closed form. A slip phase is an undamped oscillator of frequency
:math:`\omega \sqrt{F^s}` under a constant and a harmonic load; it ends at the first zero of
:math:`\dot Y` (located on a grid of 1/64 of the shorter period, each sign change or
near-zero extremum refined by Brent's method). A stick phase ends where :math:`a^\pm` crosses
zero, a cosine equation solved exactly: no contact stiffness, no time step. A stick is of
type A when the bolster leaves in the direction it came, B when it reverses (paper, Fig. 8).

Steady states: periods marched until the state repeats, or Newton on the period map.
"""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "rigs"))

import make_railcar_wedge_model as mk                        # noqa: E402

W2 = mk.K_B / mk.M_B          # omega^2 of the bolster on its nest, 1/s^2
GRID = 64                     # velocity samples per shorter period in a slip phase


@dataclasses.dataclass(frozen=True)
class Rig:
    """The one-DOF rig at one excitation.

    ``slip[s]`` and ``stick[s]`` hold ``(F, G, H)`` for bolster motion up (``s = 1``) and
    down (``s = -1``) at mu_k and mu_s; ``W`` the excitation's angular frequency (rad/s) and
    ``A`` the side-frame's displacement amplitude (m)."""

    slip: dict
    stick: dict
    W: float
    A: float

    @classmethod
    def at(cls, freq_hz: float, A: float, mu_k: float = mk.MU, mu_s: float | None = None):
        """The rig at ``freq_hz`` with amplitude ``A`` (m) and friction ``mu_k`` / ``mu_s``
        (``mu_s`` defaults to ``mu_k``)."""
        def table(mu):
            c = mk.kaiser_coefficients(mu)
            return {s: (c["F" + k], c["G" + k], c["H" + k]) for s, k in ((1, "+"), (-1, "-"))}
        mu_s = mu_k if mu_s is None else mu_s
        if mu_s < mu_k:
            raise ValueError(f"mu_s = {mu_s} is below mu_k = {mu_k}")
        return cls(table(mu_k), table(mu_s), 2 * np.pi * freq_hz, A)

    @property
    def period(self) -> float:
        return 2 * np.pi / self.W

    @property
    def scale(self) -> np.ndarray:
        """Scales of the state (y, v): ``(A, A W)``."""
        return np.array([self.A, self.A * self.W])

    def stick_test(self, s: int, y: float) -> tuple[float, float]:
        """``(P, Q)`` with ``a(t) = P + Q cos(W t)``: the acceleration the bolster stuck at
        ``y`` would start with in direction ``s`` (static coefficients); it leaves upwards
        where ``a`` of ``s = 1`` is positive, downwards where that of ``s = -1`` is negative."""
        F, G, H = self.stick[s]
        return -W2 * F * y - mk.G_ACC * (H + G), G * self.A * self.W ** 2

    def drive(self, s: int, t, stick: bool = False):
        """Acceleration of the bolster at rest at ``Y = 0`` under the law of direction ``s``
        (the right-hand side of Eq. (1)); (len(t),) or scalar."""
        F, G, H = (self.stick if stick else self.slip)[s]
        return -mk.G_ACC * (H + G) + G * self.A * self.W ** 2 * np.cos(self.W * t)


@dataclasses.dataclass(frozen=True)
class Phase:
    """One phase from ``t0`` to ``t1``: ``s = 0`` stuck at ``y0``; ``s = +-1`` slipping with
    ``Y(t) = Yc + Yh cos(W t) + C1 cos(ws (t - t0)) + C2 sin(ws (t - t0))``."""

    s: int
    t0: float
    t1: float
    y0: float
    ws: float = 0.0
    Yc: float = 0.0
    Yh: float = 0.0
    C1: float = 0.0
    C2: float = 0.0

    def y(self, t, W):
        """Displacement at times ``t`` inside the phase."""
        if self.s == 0:
            return np.full_like(np.asarray(t, float), self.y0)
        tau = self.ws * (t - self.t0)
        return self.Yc + self.Yh * np.cos(W * t) + self.C1 * np.cos(tau) + self.C2 * np.sin(tau)

    def v(self, t, W):
        """Velocity at times ``t`` inside the phase."""
        if self.s == 0:
            return np.zeros_like(np.asarray(t, float))
        tau = self.ws * (t - self.t0)
        return (-self.Yh * W * np.sin(W * t)
                + self.ws * (-self.C1 * np.sin(tau) + self.C2 * np.cos(tau)))

    def a(self, t, W):
        """Acceleration at times ``t`` inside the phase."""
        if self.s == 0:
            return np.zeros_like(np.asarray(t, float))
        tau = self.ws * (t - self.t0)
        return (-self.Yh * W ** 2 * np.cos(W * t)
                - self.ws ** 2 * (self.C1 * np.cos(tau) + self.C2 * np.sin(tau)))


def slip_phase(rig: Rig, s: int, t0: float, y0: float, v0: float, horizon: float) -> Phase:
    """The slip phase in direction ``s`` from ``(t0, y0, v0)`` (``s v0 >= 0``), up to the
    first zero of the velocity or ``horizon`` (s), whichever comes first."""
    F, G, H = rig.slip[s]
    ws = np.sqrt(W2 * F)
    if abs(ws - rig.W) < 1e-6 * ws:
        raise ValueError(f"excitation at the slipping rig's own frequency {ws / 2 / np.pi:.4f} Hz")
    Yc = -mk.G_ACC * (H + G) / (W2 * F)
    Yh = G * rig.A * rig.W ** 2 / (W2 * F - rig.W ** 2)
    C1 = y0 - Yc - Yh * np.cos(rig.W * t0)
    C2 = (v0 + Yh * rig.W * np.sin(rig.W * t0)) / ws
    p = Phase(s, t0, t0 + horizon, y0, ws, Yc, Yh, C1, C2)
    return dataclasses.replace(p, t1=_first_stop(p, rig.W, t0, t0 + horizon))


def _first_stop(p: Phase, W: float, t0: float, t_end: float) -> float:
    """First time after ``t0`` where ``s v`` reaches zero; ``t_end`` if none. The motion
    leaves ``t0`` with ``s v > 0`` (or from ``v = 0``, speeding up). A cell of the grid where
    ``s v`` keeps its sign but has an interior minimum (a zero of the acceleration) is
    checked at that minimum, so that a short reversal is not stepped over."""
    s = p.s
    h = 2 * np.pi / max(W, p.ws) / GRID
    n = max(2, int(np.ceil((t_end - t0) / h)) + 1)
    t = np.linspace(t0, t_end, n)
    g, ga = s * p.v(t, W), s * p.a(t, W)
    from_rest = g[0] <= 0
    for i in range(n - 1):
        ta, tb = t[i], t[i + 1]
        if i == 0 and from_rest:
            if g[1] > 0:
                continue
            # back at zero within the first cell: through a maximum, or it never left
            if not ga[0] > 0 > ga[1]:
                return t0
            tm = _root(lambda x: p.a(x, W), ta, tb)
            return _root(lambda x: p.v(x, W), tm, tb) if s * p.v(tm, W) > 0 else t0
        if g[i + 1] <= 0:
            return _root(lambda x: p.v(x, W), ta, tb)
        if ga[i] < 0 < ga[i + 1]:
            tm = _root(lambda x: p.a(x, W), ta, tb)
            if s * p.v(tm, W) <= 0:                 # the minimum dips to zero
                return _root(lambda x: p.v(x, W), ta, tm)
    return t_end


def _root(f, a: float, b: float) -> float:
    """Brent's root of ``f`` on ``[a, b]`` (the end nearer zero if there is no sign change)."""
    fa, fb = f(a), f(b)
    if fa == 0.0:
        return a
    if fb == 0.0 or np.sign(fa) == np.sign(fb):
        return b if abs(fb) <= abs(fa) else a
    return brentq(f, a, b, xtol=1e-18, rtol=1e-15)


def stick_phase(rig: Rig, t0: float, y0: float, horizon: float,
                graze: bool = False) -> tuple[Phase, int]:
    """The stick phase at ``y0`` from ``t0``: the phase (until ``t0 + horizon`` if it never
    ends) and the direction the bolster leaves in (0 if it does not leave). ``graze``: a
    slip from here just failed to start (the condition only touches zero), so the arc the
    condition is violated on now is passed over."""
    ends = []
    for s in (1, -1):
        P, Q = rig.stick_test(s, y0)
        if s * P > 0:                                # violated whatever the phase
            ends.append((t0, s))
            continue
        if abs(P) >= Q:                              # never violated (Q = 0: no excitation)
            continue
        th = np.arccos(-P / Q)
        entry = 2 * np.pi - th if s == 1 else th     # where the violated arc begins
        phase0 = (rig.W * t0) % (2 * np.pi)
        inside = (phase0 > 2 * np.pi - th or phase0 < th) if s == 1 else (th < phase0 < 2 * np.pi - th)
        if inside and not graze:
            ends.append((t0, s))
            continue
        d = (entry - phase0) % (2 * np.pi) or 2 * np.pi
        ends.append((t0 + d / rig.W, s))
    if not ends or min(ends)[0] > t0 + horizon:
        return Phase(0, t0, t0 + horizon, y0), 0
    t1, s = min(ends)
    return Phase(0, t0, t1, y0), s


def next_direction(rig: Rig, t: float, y: float) -> int:
    """Direction after the velocity reaches zero at ``(t, y)``: 0 to stick, else the sign of
    the motion that starts (with the static coefficients for the stick test)."""
    c = np.cos(rig.W * t)
    for s in (1, -1):
        P, Q = rig.stick_test(s, y)
        if s * (P + Q * c) > 0:
            return s
    return 0


def march(rig: Rig, t0: float, y0: float, v0: float, t_end: float) -> list:
    """The phases from the state ``(y0, v0)`` at ``t0`` to ``t_end`` (s), in order."""
    phases, t, y, v = [], t0, y0, v0
    s = int(np.sign(v)) if v != 0 else next_direction(rig, t, y)
    empty = 0
    while t < t_end:
        if s == 0:
            ph, s = stick_phase(rig, t, y, t_end - t, graze=empty > 0)
            v = 0.0
        else:
            ph = slip_phase(rig, s, t, y, v, t_end - t)
            y, v = float(ph.y(ph.t1, rig.W)), float(ph.v(ph.t1, rig.W))
            if ph.t1 < t_end:
                v, s = 0.0, next_direction(rig, ph.t1, y)
            if ph.t1 == t:                          # it did not start: it grazes, stuck
                v, s = 0.0, 0
        empty = empty + 1 if ph.t1 == t else 0
        if empty > 4:
            raise RuntimeError(f"no phase advances at t = {t:.9g} s (y = {y:.6g} m)")
        if ph.t1 > t:
            phases.append(ph)
        t = ph.t1
    return phases


def sample(phases: list, t: np.ndarray, W: float) -> tuple[np.ndarray, np.ndarray]:
    """Displacement and velocity (each like ``t``) of a marched motion at times ``t``."""
    ends = np.array([p.t1 for p in phases])
    k = np.minimum(np.searchsorted(ends, t, side="left"), len(phases) - 1)
    y, v = np.empty_like(t), np.empty_like(t)
    for i in np.unique(k):
        m = k == i
        y[m], v[m] = phases[i].y(t[m], W), phases[i].v(t[m], W)
    return y, v


def period_map(rig: Rig, y: float, v: float, t0: float = 0.0):
    """The state one period after ``(y, v)`` at ``t0`` and the period's phases."""
    phases = march(rig, t0, y, v, t0 + rig.period)
    last = phases[-1]
    return float(last.y(last.t1, rig.W)), float(last.v(last.t1, rig.W)), phases


Y_STATIC = mk.static_equilibrium()[0]     # bolster at rest, frictionless equilibrium, m


@dataclasses.dataclass(frozen=True)
class Steady:
    """A periodic steady state (or the last period marched): the state ``(y0, v0)`` at
    ``t = 0``, the phases of one period of the motion (``multiple`` excitation periods),
    whether it repeats to the tolerance, how (``method``: "marching" or "shooting"), the
    periods marched and whether it attracts (a marched motion does by construction; a shot
    one is perturbed by 1e-6 of ``A`` and ``A W`` and marched ``settle`` periods: it attracts
    if the perturbation has not doubled, so a neutral stuck state, which any position inside
    the stick band is, counts)."""

    rig: Rig
    y0: float
    v0: float
    phases: list
    converged: bool
    method: str
    periods: int
    stable: bool = True
    multiple: int = 1

    @property
    def period(self) -> float:
        """The motion's period, s."""
        return self.multiple * self.rig.period

    def samples(self, n: int = 1024) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Times (n,), displacement and velocity over one period of the motion."""
        t = np.arange(n) * self.period / n
        return (t, *sample(self.phases, t, self.rig.W))


def _after(rig: Rig, z: np.ndarray) -> np.ndarray:
    """The state (y, v) one period after ``z``."""
    return np.array(period_map(rig, *z)[:2])


def _shoot(rig: Rig, y: float, v: float, tol: float, iters: int = 12):
    """Newton on ``P(z) = z`` for the period map ``P`` from ``z = (y, v)`` (Jacobian by
    finite differences); the solution, or None."""
    z = np.array([y, v])
    for _ in range(iters):
        r = _after(rig, z) - z
        if np.all(np.abs(r) <= tol * rig.scale):
            return z
        J = np.column_stack([(_after(rig, z + dz) - z - dz - r) / dz[j]
                             for j, dz in enumerate(np.diag(1e-7 * rig.scale))])
        try:
            z = z - np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            return None
    return None


def steady_state(rig: Rig, tol: float = 1e-10, settle: int = 200, max_periods: int = 3000,
                 y0: float = Y_STATIC, v0: float = 0.0, longest: int = 8) -> Steady:
    """Periodic steady state from ``(y0, v0)`` at ``t = 0`` (default: at rest, static):
    periods are marched until the state repeats to ``tol`` (of ``A`` and ``A W``) after one
    period, or after ``n <= longest`` (a subharmonic motion); after ``settle`` periods
    without that, Newton on the period map is tried from where the march is, then marching
    goes on up to ``max_periods``."""
    states = [np.array([y0, v0])]
    for k in range(1, max_periods + 1):
        y1, v1, phases = period_map(rig, *states[-1])
        states.append(np.array([y1, v1]))
        for n in range(1, min(longest, k) + 1):
            if np.all(np.abs(states[-1] - states[-1 - n]) <= tol * rig.scale):
                y, v = states[-1 - n]
                if n > 1:
                    phases = march(rig, 0.0, y, v, n * rig.period)
                return Steady(rig, y, v, phases, True, "marching", k, True, n)
        if k == settle:
            z = _shoot(rig, *states[-1], tol)
            if z is not None:
                phases = period_map(rig, *z)[2]
                return Steady(rig, z[0], z[1], phases, True, "shooting", k,
                              _attracts(rig, z, settle))
    y, v = states[-1]
    return Steady(rig, y, v, period_map(rig, y, v)[2], False, "marching", max_periods, False)


def _attracts(rig: Rig, z: np.ndarray, periods: int) -> bool:
    """Whether a perturbation of 1e-6 of ``(A, A W)`` of the periodic state ``z`` = (y, v)
    stays below twice that after ``periods`` periods (a multiplier above about
    ``2 ** (1 / periods)`` fails)."""
    p = z + 1e-6 * rig.scale
    for _ in range(periods):
        p = _after(rig, p)
    return bool(np.max(np.abs(p - z) / rig.scale) <= 2e-6)


@dataclasses.dataclass(frozen=True)
class Stick:
    """A stick event of a steady period: start time and duration (s), and its type, "A" if
    the bolster leaves in the direction it came, "B" if it reverses (the paper's Fig. 8)."""

    start: float
    duration: float
    kind: str


def stick_events(st: Steady) -> list:
    """The stick events of the steady period ``st`` (a stick that runs over the end of the
    period joined to its start), in order of their start; [] when it never sticks or sticks
    throughout."""
    T = st.period
    ph = list(st.phases)
    if all(p.s == 0 for p in ph) or all(p.s != 0 for p in ph):
        return []
    k = next(i for i, p in enumerate(ph) if p.s != 0)
    ph = ph[k:] + [Phase(p.s, p.t0 + T, p.t1 + T, p.y0) for p in ph[:k]]   # starts slipping
    events, i = [], 0
    while i < len(ph):
        if ph[i].s != 0:
            i += 1
            continue
        j = i
        while j + 1 < len(ph) and ph[j + 1].s == 0:
            j += 1
        leaves = ph[j + 1].s if j + 1 < len(ph) else ph[0].s
        kind = "A" if ph[i - 1].s == leaves else "B"
        events.append(Stick(ph[i].t0 % T, ph[j].t1 - ph[i].t0, kind))
        i = j + 1
    return sorted(events, key=lambda e: e.start)
