"""The jenkins element class: parameters, case keys and coordinates (law in laws/jenkins.py)."""
from __future__ import annotations

import numpy as np

from .base import Element, coordinate_rows, require_keys, positive, non_negative, slider_summary
from .laws.registry import JENKINS
from .law_march import START_ARGMAX


class Jenkins(Element):
    """Jenkins (macroslip) element on one coordinate ``u = q_a`` or ``u = q_a - q_b``.

    Parameters
    ----------
    dofs : list of int
        ``[a]`` or ``[a, b]``.
    kt : float
        Tangential (stick) stiffness, N/m, > 0.
    slip_force : float
        Slip limit ``mu N``, N, >= 0.
    """

    kind = JENKINS
    n_state = 2
    velocity = False
    needs_mean = False
    coord_names = ("u",)
    keys = ("type", "dofs", "kt", "slip_force", "name")
    quantities = ("slip_fraction", "force_amplitude", "dissipation")
    # a displacement maximum is a reversal point: the loop is closed after one pass
    start_rule = START_ARGMAX
    default_harmonics = 7           # benchmarks/default_harmonics.py
    default_samples_factor = 2

    def __init__(self, gather, kt, slip_force, name="jenkins"):
        super().__init__(gather, np.array([positive("kt", kt), non_negative("slip_force", slip_force)]), name)

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "kt", "slip_force"), where)
        G = coordinate_rows([spec["dofs"]], n_dof, dof_index, where)
        return cls(G, spec["kt"], spec["slip_force"], spec.get("name", "jenkins"))

    @property
    def kt(self):
        return float(self.params[0])

    @property
    def slip_force(self):
        return float(self.params[1])

    def linear_stiffness(self):
        return np.array([[self.kt]])

    def summary(self, f, z):
        """``slip_fraction``, ``force_amplitude``, ``dissipation`` of one closed period
        (:func:`elements.base.slider_summary`); ``f`` (N, 1), ``z`` (N, 1)."""
        return slider_summary(np.asarray(f)[:, 0], np.asarray(z)[:, 0], self.kt)
