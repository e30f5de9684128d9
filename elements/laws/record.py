r"""A constitutive law as data: what a law module declares so that the case format, the AFT
march and the time integrator can use it without code elsewhere.

A law is an incremental update ``s_new = Phi(p, s, z)`` with local Jacobians
``A = dPhi/ds``, ``B = dPhi/dz`` (:mod:`elements.kernels`), a rest state at ``z0`` reached from
``q = 0`` and, optionally, a test that it is linear, ``f_j = f_0 + K z_j``, on every sample of
a period (:mod:`elements.law_march`).  Its module defines these compiled kernels and a
:class:`LawRecord`; :mod:`elements.laws.registry` gives it an id and dispatches to it.  A law
on one coordinate whose record is registered as a case type becomes
``[[element]] type = NAME`` with its parameters as keys, by name (:mod:`elements.law_element`).

The start rule and closure constants are here (not in :mod:`elements.law_march`) so that
law modules can name them without importing the march.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

START_FIRST = 0        # march from sample 0 (memoryless laws)
START_ARGMAX = 1       # from the largest sample of the first coordinate (a reversal)
START_PRINCIPAL = 2    # from the reversal along the principal direction of the motion

CLOSE_PLAIN = 0        # repeat periods until the state closes
CLOSE_NEWTON = 1       # Newton on the start state

CHECKS = ("positive", "non_negative", "finite")


@dataclass(frozen=True)
class LawRecord:
    """A law on one coordinate, by name: the case type, parameters and march settings.

    Attributes
    ----------
    name : str
        Case ``type``.
    params : tuple of (str, str, str)
        ``(key, check, meaning)`` per parameter, in the order of the kernels' ``p``; ``check``
        one of :data:`CHECKS`.
    n_state : int
        State size (the force first).
    rest_tangent : callable
        ``p -> (k, c)``: the tangent stiffness and viscous tangent at rest (``z = 0``), used
        for the stuck start of Newton and the unknowns' scale.
    velocity : bool
        The law reads ``[u, du/dt]``.
    needs_mean : bool
        The force has a mean for a zero-mean motion (harmonic 0 is needed).
    start_rule, closure : int
        :data:`START_FIRST` ... and :data:`CLOSE_PLAIN` / :data:`CLOSE_NEWTON`.
    default_harmonics, default_samples_factor : int
        The discretisation a case gets when it states none (:class:`elements.base.Element`).
    summary : str
        One line for the case reference.
    """

    name: str
    params: tuple
    n_state: int
    rest_tangent: Callable[[np.ndarray], tuple]
    velocity: bool = False
    needs_mean: bool = True
    start_rule: int = START_FIRST
    closure: int = CLOSE_PLAIN
    default_harmonics: int = 5
    default_samples_factor: int = 1
    summary: str = ""

    def __post_init__(self):
        for key, check, _ in self.params:
            if check not in CHECKS:
                raise ValueError(f"law {self.name}: parameter {key} has check {check!r}, not one of {CHECKS}")

    @property
    def keys(self) -> tuple:
        """The parameters' case keys, in kernel order."""
        return tuple(k for k, _, _ in self.params)
