"""Coulomb friction element classes on one coordinate (laws in laws/coulomb.py)."""
from __future__ import annotations

import numpy as np

from .base import Element, slider_summary
from .keys import coordinate_rows, require_keys, positive, non_negative
from .laws.registry import COULOMB_STATIC_KINETIC, COULOMB_REGULARISED
from .laws.coulomb import LINEAR, ARCTAN, TANH
from .law_march import START_ARGMAX


class CoulombStickSlip(Element):
    """Coulomb friction with a static coefficient above the kinetic one (seed 000).

    Case keys: ``type``, ``dofs`` (``[a]`` or ``[a, b]``), ``kt`` (stick stiffness, > 0),
    ``normal_load`` (N >= 0), ``mu_static`` (>= 0), ``mu_kinetic`` (0 <= mu_k <= mu_s),
    optional ``name``.  State ``[f, u_prev, sliding]``.

    The march starts at the displacement maximum (a reversal), from the rest state reached
    there from ``q = 0``.  With ``mu_s > mu_k`` the law has two periodic states for some
    amplitudes (pure stick, and a stick-slip loop once broken loose); this start picks pure
    stick whenever ``kt max(u) <= mu_s N``, i.e. the state reached by loading from rest.
    """

    kind = COULOMB_STATIC_KINETIC
    start_rule = START_ARGMAX
    n_state = 3
    velocity = False
    needs_mean = False
    coord_names = ("u",)
    keys = ("type", "dofs", "kt", "normal_load", "mu_static", "mu_kinetic", "name")
    quantities = ("slip_fraction", "force_amplitude", "dissipation")
    default_harmonics = 9           # benchmarks/default_harmonics.py
    default_samples_factor = 1

    def __init__(self, gather, kt, normal_load, mu_static, mu_kinetic, name="coulomb_stick_slip"):
        mu_s = non_negative("mu_static", mu_static)
        mu_k = non_negative("mu_kinetic", mu_kinetic)
        if mu_k > mu_s:
            raise ValueError(f"{name}: mu_kinetic ({mu_k}) must not exceed mu_static ({mu_s})")
        super().__init__(gather, np.array([positive("kt", kt), non_negative("normal_load", normal_load),
                                           mu_s, mu_k]), name)

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "kt", "normal_load", "mu_static", "mu_kinetic"), where)
        G = coordinate_rows([spec["dofs"]], n_dof, dof_index, where)
        return cls(G, spec["kt"], spec["normal_load"], spec["mu_static"], spec["mu_kinetic"],
                   spec.get("name", "coulomb_stick_slip"))

    @property
    def slip_limit(self):
        """Sliding carries the kinetic force ``mu_kinetic N``."""
        return float(self.params[1] * self.params[3])

    def linear_stiffness(self):
        stuck = self.params[1] * self.params[2] > 0.0
        return np.array([[self.params[0] if stuck else 0.0]])

    def summary(self, f, z):
        """``slip_fraction``, ``force_amplitude``, ``dissipation`` of one closed period
        (:func:`elements.base.slider_summary`); ``f`` (N, 1), ``z`` (N, 1)."""
        return slider_summary(np.asarray(f)[:, 0], np.asarray(z)[:, 0], float(self.params[0]))


class CoulombRegularised(Element):
    """Velocity-regularised Coulomb friction (seed 001, eq. 2.2), memory-less in ``u``.

    ``f = Ft0 sat(v / v_r)`` (``law = "linear"``), ``f = Ft0 (2/pi) arctan(v / v_r)``
    (``law = "arctan"``) or ``f = Ft0 tanh(v / v_r)`` (``law = "tanh"``).  Case keys: ``type``, ``dofs``, ``slip_force`` (Ft0 >= 0),
    ``v_r`` (> 0), ``law`` (default ``"linear"``), optional ``name``.  Inputs ``[u, v]``;
    state ``[f]``.
    """

    kind = COULOMB_REGULARISED
    n_state = 1
    velocity = True
    needs_mean = False
    coord_names = ("u",)
    keys = ("type", "dofs", "slip_force", "v_r", "law", "name")
    quantities = ("slip_fraction", "force_amplitude", "dissipation")
    default_harmonics = 9           # benchmarks/default_harmonics.py
    default_samples_factor = 2
    laws = {"linear": LINEAR, "arctan": ARCTAN, "tanh": TANH}

    def __init__(self, gather, slip_force, v_r, law="linear", name="coulomb_regularised"):
        if law not in self.laws:
            raise ValueError(f"{name}: law must be one of {', '.join(self.laws)}, got {law!r}")
        super().__init__(gather, np.array([non_negative("slip_force", slip_force), positive("v_r", v_r),
                                           float(self.laws[law])]), name)
        self.law = law

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "slip_force", "v_r"), where)
        G = coordinate_rows([spec["dofs"]], n_dof, dof_index, where)
        return cls(G, spec["slip_force"], spec["v_r"], spec.get("law", "linear"),
                   spec.get("name", "coulomb_regularised"))

    @property
    def slip_limit(self):
        return float(self.params[0])

    def linear_stiffness(self):
        return np.zeros((1, 1))

    def linear_damping(self):
        """Viscous tangent at rest, ``df/dv`` at ``v = 0``: ``Ft0 / v_r`` (linear, tanh) or
        ``2 Ft0 / (pi v_r)`` (arctan)."""
        F0, vr = self.params[0], self.params[1]
        c = 2.0 * F0 / (np.pi * vr) if self.law == "arctan" else F0 / vr
        return np.array([[c]])

    def summary(self, f, z):
        r"""Per-period outputs; ``f`` (N, 1), ``z`` (N, 2) = ``[u, v]``.

        ``slip_fraction``: fraction of samples with ``|v| >= v_r`` (sliding at the full
        force, outside the regularisation zone); ``force_amplitude``: ``max |f|``;
        ``dissipation``: :math:`\oint f\,du` by the trapezoidal rule over the closed
        period, :math:`\sum_j \tfrac12 (f_j + f_{j-1})(u_j - u_{j-1})`.
        """
        f = np.asarray(f, dtype=float)[:, 0]
        z = np.asarray(z, dtype=float)
        u, v = z[:, 0], z[:, 1]
        return {
            "slip_fraction": float(np.mean(np.abs(v) >= self.params[1])),
            "force_amplitude": float(np.abs(f).max()),
            "dissipation": float(np.sum(0.5 * (f + np.roll(f, 1)) * (u - np.roll(u, 1)))),
        }
