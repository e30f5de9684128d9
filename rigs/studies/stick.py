r"""Stick/slip bookkeeping on sampled contact forces (time-domain histories or marched periods).

A friction contact sticks at a sample when its tangential force is strictly inside the slip
limit: ``|f_t| < (1 - eps) mu N`` (friction3d, ``N = N0 + f_n``) or ``|f| < (1 - eps) mu_k N``
(coulomb_stick_slip: sliding sets the force to exactly ``mu_k N``, see :func:`coulomb_sliding`).  The slip fraction of a period
is the fraction of its samples that do not stick.  A stick interval is a maximal run of
consecutive samples (periodic wrap-around) in which all the given contacts stick; its type is
A if the relative velocity keeps its sign across it and B if it reverses (seed 004, Fig. 8);
a contact stuck over the whole period gives one interval of type ``full``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

EPS = 1e-9


def friction3d_stuck(forces, elements, eps=EPS):
    """Per sample: do all these friction3d contacts stick?

    Parameters
    ----------
    forces : ndarray, shape (n_t, sum of n_local)
        Element forces in element order (``[f_t1, f_n]`` per 2D contact).
    elements : sequence of Friction3D
        Two-coordinate (t1, n) contacts, in the order of ``forces``' columns.

    Returns
    -------
    ndarray of bool, shape (n_t,)
    """
    stuck = np.ones(forces.shape[0], dtype=bool)
    c = 0
    for el in elements:
        ft, fn = forces[:, c], forces[:, c + 1]
        c += el.n_local
        stuck &= np.abs(ft) < (1.0 - eps) * el.mu * (el.normal_preload + fn)
    return stuck


def coulomb_sliding(f, normal_load, mu_kinetic, eps=EPS):
    """Per sample: is a coulomb_stick_slip contact sliding?  (n_t,) bool.

    A sliding step sets the force to exactly ``+-mu_k N``; a stuck contact may carry any force
    up to ``mu_s N`` (also above ``mu_k N``), so sliding is ``||f| - mu_k N| <= eps mu_k N``.
    """
    fk = mu_kinetic * normal_load
    return np.abs(np.abs(np.asarray(f)) - fk) <= eps * max(fk, 1e-300)


@dataclass(frozen=True)
class StickInterval:
    """One stick interval: start time (s), duration (s), type ``"A"`` or ``"B"`` (``"full"``:
    stuck over the whole period)."""

    start: float
    duration: float
    kind: str


def stick_intervals(stuck, t, v):
    """Maximal runs of ``stuck`` over one period (wrapping around).

    Parameters
    ----------
    stuck : ndarray of bool, shape (N,)
        One period of samples (without the repeated end point).
    t : ndarray, shape (N,)
        Sample times (equally spaced).
    v : ndarray, shape (N,)
        Relative velocity, to classify the intervals.

    Returns
    -------
    list of StickInterval
    """
    stuck = np.asarray(stuck, dtype=bool)
    n = stuck.size
    dt = t[1] - t[0]
    if stuck.all():
        return [StickInterval(float(t[0]), n * dt, "full")]
    if not stuck.any():
        return []
    k = int(np.argmin(stuck))             # a slipping sample: start there
    m = np.roll(stuck, -k)
    out = []
    i = 0
    while i < n:
        if not m[i]:
            i += 1
            continue
        j = i
        while j < n and m[j]:
            j += 1
        s0, s1 = (i + k) % n, (j + k) % n      # first stuck sample, first slipping after it
        before, after = v[(s0 - 2) % n], v[(s1 + 1) % n]
        out.append(StickInterval(float(t[s0]), (j - i) * dt, "A" if before * after > 0 else "B"))
        i = j
    return out


def peak_to_peak(x):
    """``max - min`` of samples."""
    x = np.asarray(x)
    return float(x.max() - x.min())
