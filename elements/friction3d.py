"""The friction3d element class: a point contact with friction, normal-load variation and
separation (law in laws/friction3d.py)."""
from __future__ import annotations

import numpy as np

from .base import Element
from .friction2d_events import contact_harmonics
from .jenkins_events import gauss_rules
from .keys import coordinate_rows, require_keys, finite, positive, non_negative
from .law_march import START_PRINCIPAL, CLOSE_NEWTON
from .laws.friction3d import n_states
from .laws.registry import FRICTION3D


class Friction3D(Element):
    """Macroslip point contact on local coordinates (t1, t2, n), or (t1, n) without ``t2``.

    Case keys: ``type``, ``dofs = {t1 = ..., t2 = ..., n = ...}`` (``t2`` optional), ``kt``,
    ``kn`` (> 0), ``mu`` (>= 0), ``normal_preload`` (``N0 >= 0``), optional ``normal_gap``
    (``g``, default 0), ``aft`` (``"sampled"``, default, or on a (t1, n) contact ``"events"``:
    forces from the located events, :mod:`elements.friction2d_events`) and ``name``.

    Each local coordinate is a linear combination of model DOFs, one row of the gather
    matrix (:func:`elements.keys.coordinate_row`):

    - ``a`` or ``[a]``: ``q_a``;  ``[a, b]``: ``q_a - q_b`` (contact between two bodies whose
      DOFs are along the contact axes);
    - ``[[a, ca], [b, cb], ...]`` or a table ``{a = ca, b = cb}``: ``ca q_a + cb q_b + ...``,
      pairs of DOF and coefficient (TOML table keys: DOF names, or indices as strings),
      for contact directions not along the model axes.  A mass with DOFs x (0) and y (1)
      against a wall inclined by 30 degrees::

          dofs = { t1 = [[0, 0.8660254], [1, 0.5]], n = [[0, -0.5], [1, 0.8660254]] }

      The coefficients are taken as given (not normalised): unit direction vectors give
      ``kt``, ``kn`` their physical meaning.  Malformed forms (a pair that is not
      ``[dof, number]``, a DOF twice, all coefficients zero, pairs mixed with bare DOFs)
      are rejected with the coordinate named (``dofs.t1``).

    The normal load is ``N = max(N0 + kn (u_n - g), 0)`` (``u_n > 0`` closes); the element
    force along ``n`` is ``N - N_rest`` with ``N_rest = max(N0 - kn g, 0)`` the load at rest
    (zero at rest, ``-N_rest`` while open).  ``g > 0`` is an initial gap (open at rest, closes
    when ``u_n`` exceeds ``g - N0 / kn``), ``g < 0`` an interference (a static load
    ``-kn g`` added to ``N0``), as Petrov & Ewins (2003) model both.  The law sees only
    ``N0 - kn g`` (``laws/friction3d.py``).  The tangential force obeys Coulomb's law with a
    circular limit ``mu N`` and a stick stiffness ``kt``.

    State layout (``nt`` = 1 or 2 tangential directions): ``[f_t (nt), f_n, u_t,prev (nt), N_p]``
    (:mod:`elements.laws.friction3d`).

    Start of the march (``start_index``): the sample where the tangential motion reverses
    along its principal direction (argmax of the projection of the centred ``u_t`` on the
    leading eigenvector of its covariance).  The rest state reached there from ``q = 0`` is
    then on (1D, constant load: exactly) or close to the steady hysteresis loop, so the march
    closes after one or a few passes.  For 2D loops (elliptical motion) and a varying normal
    load the slider position is only forgotten geometrically, pass after pass: the component
    of the slider offset across a nearly fixed slip direction, and partial slip that shakes
    down towards an elastic loop, contract slowly (up to ~130 passes seen on random ellipses
    to reach 1e-12; near the stick/slip boundary more than 1000).  So this element closes the
    loop by Newton on the start state (:func:`elements.closure.march_newton`: the period map
    and its state derivative come from the same pass), with plain passes as the fallback,
    ``max_passes = 1000`` (reached only by loops that shake down asymptotically) and
    ``closure_tol = 1e-12``.
    """

    kind = FRICTION3D
    velocity = False
    needs_mean = True       # normal-load variation gives mean forces
    keys = ("type", "dofs", "kt", "kn", "mu", "normal_preload", "normal_gap", "aft", "name")
    dof_keys = ("t1", "t2", "n")
    quantities = ("normal_load_min", "normal_load_max", "open_fraction", "slip_fraction",
                  "dissipation")
    max_passes = 1000
    closure_tol = 1e-12
    start_rule = START_PRINCIPAL
    closure = CLOSE_NEWTON
    default_harmonics = 3           # benchmarks/default_harmonics.py
    default_samples_factor = 2

    def __init__(self, gather, kt, kn, mu, normal_preload, name="friction3d", normal_gap=0.0, aft="sampled"):
        G = np.array(gather, dtype=float, ndmin=2)
        if G.shape[0] not in (2, 3):
            raise ValueError(f"{name}: friction3d needs 2 (t1, n) or 3 (t1, t2, n) coordinates, "
                             f"got {G.shape[0]}")
        nt = G.shape[0] - 1
        if aft not in ("sampled", "events") or (aft == "events" and nt == 2):
            raise ValueError(f"{name}: aft must be \"sampled\" or, on a (t1, n) contact, \"events\"; "
                             f"got {aft!r}" + (" with t2" if nt == 2 else ""))
        self.aft = aft
        self.gap = finite("normal_gap", normal_gap)
        kn = positive("kn", kn)
        n_gap = non_negative("normal_preload", normal_preload) - kn * self.gap
        params = np.array([positive("kt", kt), kn, non_negative("mu", mu), n_gap, float(nt)])
        super().__init__(G, params, name)
        self.n_state = n_states(nt)
        self.coord_names = ("t1", "t2", "n") if nt == 2 else ("t1", "n")

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="element"):
        require_keys(spec, cls.keys, ("dofs", "kt", "kn", "mu", "normal_preload"), where)
        dofs = spec["dofs"]
        if not isinstance(dofs, dict):
            raise ValueError(f"{where}: friction3d dofs must be a table {{ t1 = ..., t2 = ..., n = ... }}, "
                             f"got {dofs!r}")
        require_keys(dofs, cls.dof_keys, ("t1", "n"), f"{where}: dofs")
        names = [k for k in cls.dof_keys if k in dofs]
        G = coordinate_rows([dofs[k] for k in names], n_dof, dof_index,
                            [f"{where}: dofs.{k}" for k in names])
        return cls(G, spec["kt"], spec["kn"], spec["mu"], spec["normal_preload"],
                   spec.get("name", "friction3d"), spec.get("normal_gap", 0.0), spec.get("aft", "sampled"))

    @property
    def n_tangential(self) -> int:
        return int(self.params[4])

    @property
    def events_available(self) -> bool:
        """``aft = "events"`` exists for one tangential direction only."""
        return self.n_tangential == 1

    @property
    def kt(self):
        return float(self.params[0])

    @property
    def kn(self):
        return float(self.params[1])

    @property
    def mu(self):
        return float(self.params[2])

    @property
    def normal_preload(self):
        """Normal load at rest, ``N_rest = max(N0 - kn g, 0)``: ``N = f_n + N_rest``."""
        return max(float(self.params[3]), 0.0)

    @property
    def n_start(self) -> int:
        return self.n_tangential

    def linear_stiffness(self):
        """Tangent at rest: ``kn`` along n unless a gap holds the contact open (closing side
        when it just touches), ``kt`` along t1, t2 if ``mu N_rest > 0``."""
        nt = self.n_tangential
        kt = self.kt if self.mu * self.normal_preload > 0.0 else 0.0
        kn = self.kn if self.params[3] >= 0.0 else 0.0
        return np.diag([kt] * nt + [kn])

    def harmonic_forces(self, U, h, is_sin):
        """Exact harmonic forces of a (t1, n) contact from its events (``aft = "events"``,
        :mod:`elements.friction2d_events`).

        Parameters
        ----------
        U : ndarray, shape (nc, 2)
            Coefficients of ``u_t1``, ``u_n``.
        h, is_sin : ndarray, shape (nc,)
            The layout (:func:`elements.jenkins_events.row_kinds`).

        Returns
        -------
        (F, dF) with shapes (nc, 2) and (nc, 2, 2 nc), or None when the law is to be marched
        (a loop stuck with the slider at rest, where the march is exact).
        """
        nc = h.size
        F, J = np.empty((nc, 2)), np.empty((nc, 2, nc, 2))
        h_max = int(h.max())
        gx, gw = gauss_rules(h_max)
        if not contact_harmonics(h, is_sin, np.ascontiguousarray(U, dtype=float), self.params[:4].copy(),
                                 16 * max(h_max, 4), gx, gw, F, J):
            return None
        return F, J.reshape(nc, 2, 2 * nc)

    def static_state(self) -> dict:
        return {"normal_preload": self.normal_preload, "normal_gap": self.gap}

    def summary(self, f, z) -> dict:
        """Per-period quantities from the marched samples.

        Parameters
        ----------
        f : ndarray, shape (N, n_local)
            Forces returned by ``march`` (one closed period).
        z : ndarray, shape (N, n_local)
            The sampled local coordinates that produced them.

        Returns
        -------
        dict
            ``normal_load_min``, ``normal_load_max`` (N over the period), ``open_fraction``
            (fraction of samples with ``N = 0``), ``slip_fraction`` (fraction of samples whose
            step slipped: trial force outside ``mu N``, recomputed exactly from the previous
            sample, re-contact between the samples included), ``dissipation`` (work of the friction force on the slider per period,
            ``sum f_t . (w_j - w_{j-1})`` with the slider position ``w = u_t - f_t / kt``).
        """
        f = np.asarray(f, dtype=float)
        z = np.asarray(z, dtype=float)
        nt = self.n_tangential
        Nload = f[:, nt] + self.normal_preload
        Ntr = self.params[3] + self.kn * z[:, nt]          # trial normal load per sample
        closed = Ntr > 0.0
        Np = np.roll(Ntr, 1)
        recontact = closed & (Np <= 0.0)                   # re-sticks between the samples
        g = np.where(recontact, Ntr / np.where(recontact, Ntr - Np, 1.0), 1.0)    # 1 - theta
        ft = f[:, :nt]
        ut = z[:, :nt]
        trial = np.roll(ft, 1, axis=0) + self.kt * g[:, None] * (ut - np.roll(ut, 1, axis=0))
        slipping = closed & (np.linalg.norm(trial, axis=1) > self.mu * Nload)
        w = ut - ft / self.kt
        dissipation = float(np.sum(ft * (w - np.roll(w, 1, axis=0))))
        return {
            "normal_load_min": float(Nload.min()),
            "normal_load_max": float(Nload.max()),
            "open_fraction": float(np.mean(~closed)),
            "slip_fraction": float(np.mean(slipping)),
            "dissipation": dissipation,
        }
