"""The cubic element class: parameters, case keys and coordinates (law in laws/cubic.py)."""
from __future__ import annotations

import numpy as np

from .base import Element, coordinate_rows, require_keys, finite
from .kinds import CUBIC


class Cubic(Element):
    """Cubic spring on one coordinate; key ``k3`` (N/m^3, any sign)."""

    kind = CUBIC
    n_state = 1
    velocity = False
    needs_mean = False
    coord_names = ("u",)
    keys = ("type", "dofs", "k3", "name")
    default_harmonics = 3           # benchmarks/default_harmonics.py
    default_samples_factor = 1

    def __init__(self, gather, k3, name="cubic"):
        super().__init__(gather, np.array([finite("k3", k3)]), name)

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "k3"), where)
        G = coordinate_rows([spec["dofs"]], n_dof, dof_index, where)
        return cls(G, spec["k3"], spec.get("name", "cubic"))

    def linear_stiffness(self):
        return np.zeros((1, 1))
