"""The jenkins element class: parameters, case keys and coordinates (law in laws/jenkins.py)."""
from __future__ import annotations

import numpy as np

from .base import Element, slider_summary
from .keys import coordinate_rows, require_keys, positive, non_negative
from .laws.registry import JENKINS
from .law_march import START_ARGMAX
from .jenkins_events import gauss_rules, jenkins_harmonics


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
    aft : {"sampled", "events"}
        How the harmonic-balance forces are computed: by marching the law over the time
        samples (default), or exactly from the reversal and slip events
        (:mod:`elements.jenkins_events`): no sampling error, a smooth ``F(U)``, for stiff
        contacts (large ``kt``) and the Coulomb limit.  Outputs and time integration march
        the same law either way.
    """

    kind = JENKINS
    n_state = 2
    velocity = False
    needs_mean = False
    coord_names = ("u",)
    keys = ("type", "dofs", "kt", "slip_force", "aft", "name")
    quantities = ("slip_fraction", "force_amplitude", "dissipation")
    # a displacement maximum is a reversal point: the loop is closed after one pass
    start_rule = START_ARGMAX
    default_harmonics = 7           # benchmarks/default_harmonics.py
    default_samples_factor = 2
    events_available = True

    def __init__(self, gather, kt, slip_force, name="jenkins", aft="sampled"):
        super().__init__(gather, np.array([positive("kt", kt), non_negative("slip_force", slip_force)]), name)
        if aft not in ("sampled", "events"):
            raise ValueError(f"aft must be \"sampled\" or \"events\", got {aft!r}")
        self.aft = aft

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "kt", "slip_force"), where)
        G = coordinate_rows([spec["dofs"]], n_dof, dof_index, where)
        return cls(G, spec["kt"], spec["slip_force"], spec.get("name", "jenkins"), spec.get("aft", "sampled"))

    @property
    def kt(self):
        return float(self.params[0])

    @property
    def slip_force(self):
        return float(self.params[1])

    @property
    def slip_limit(self):
        return self.slip_force

    def linear_stiffness(self):
        return np.array([[self.kt]])

    def harmonic_forces(self, U, h, is_sin):
        """Exact harmonic forces from the events (``aft = "events"``).

        Parameters
        ----------
        U : ndarray, shape (nc, 1)
            Coefficients of ``u``.
        h, is_sin : ndarray, shape (nc,)
            The layout (:func:`elements.jenkins_events.row_kinds`).

        Returns
        -------
        (F, dF) with shapes (nc, 1) and (nc, 1, nc), or None when the loop does not slip
        (stuck for the whole period: then the sampled march, which is exact there).
        """
        nc = h.size
        F, J = np.empty(nc), np.empty((nc, nc))
        h_max = int(h.max())
        gx, gw = gauss_rules(h_max)
        if not jenkins_harmonics(h, is_sin, np.ascontiguousarray(U[:, 0]), self.kt, self.slip_force,
                                 16 * max(h_max, 4), gx, gw, F, J):
            return None
        return F[:, None], J[:, None, :]

    def summary(self, f, z):
        """``slip_fraction``, ``force_amplitude``, ``dissipation`` of one closed period
        (:func:`elements.base.slider_summary`); ``f`` (N, 1), ``z`` (N, 1)."""
        return slider_summary(np.asarray(f)[:, 0], np.asarray(z)[:, 0], self.kt)
