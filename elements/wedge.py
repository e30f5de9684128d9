r"""Wedge (cottage-roof) underplatform damper: a rigid body on two inclined friction flanks.

The damper is a rigid body with its own DOFs ``d = [x, y, (z), (rz)]`` at its centre of
gravity (internal unknowns of the harmonic balance, declared by :meth:`WedgeDamper.internal_dofs`
and added to the linear model with its mass, inertia, wire and anchor stiffness).  Each flank
``s`` carries ``p`` contact points at ``r_{s,j} = c_s + o_j t_s`` from the CG
(``o_j`` from ``-L/2`` to ``L/2``; one point, no rotation, for ``p = 1``).  The relative
displacement of point ``j`` (damper minus platform ``P_s``), for a small rotation ``rz``, is

.. math::

    \Delta = (d_x - r_y\, rz - q_{P_s,x} + o_j t_{s,y} \theta_s,\;
              d_y + r_x\, rz - q_{P_s,y} - o_j t_{s,x} \theta_s,\; d_z - q_{P_s,z}),

and its local coordinates (the friction3d contact's ``t1, t2, n``) are

.. math::

    u_{t1} = t_s \cdot \Delta_{xy} = t_x(d_x - q_x) + t_y(d_y - q_y) + (r \times t_s)\, rz, \quad
    u_{t2} = d_z - q_z, \quad
    u_n = n_s \cdot \Delta_{xy} = \dots + (r \times n_s)\, rz

(frames in :mod:`elements.wedge_statics`; ``u_n > 0`` closes).  ``q_{P_s}`` are the platform's
translations at the flank centre and ``theta_s`` its in-plane rotation (optional coordinate
``rz`` of the side table, same sense as the damper's ``rz``: 0 when not given), so a rotation
of the platform relative to the damper, ``rz - theta_s``, presses one end of the flank and
lifts the other, ``u_n`` changing by ``o_j (t_s x n_s)(rz - theta_s)`` along it; a rigid
rotation of damper and platforms together leaves every contact undeformed.  These are rows
of the gather matrix, so the contact forces act on platforms and damper through ``G^T f``.

Each point is a :class:`elements.friction3d.Friction3D` contact (the friction3d law, not a
copy) with ``kt/p``, ``kn/p``, the flank's ``mu`` and the preload ``N_s/p``, where ``N_s``
are the static normal loads from ``CF`` with friction at the limit
(:func:`elements.wedge_statics.static_normal_loads`).  Design: one element whose ``march``
runs each point's contact on its own rows and concatenates (``n_local = (nt+1) * 2p``),
so the case holds one object per damper, with one summary; only the derivative-seed columns
a point actually depends on are marched.  The static tangential forces (``mu N_s`` at the
limit) are not carried into the dynamic law: as in FORSE's implicit model, each contact
starts unloaded tangentially; only the normal preloads are (dynamic forces about the static
equilibrium, DESIGN.md).  Static moments about the CG are not balanced by this model; the
equal load split over the points of a flank is an assumption (issue 5).
"""
from __future__ import annotations

import numpy as np

from .base import Element
from .keys import coordinate, coordinate_row
from .friction3d import Friction3D
from .laws.registry import FRICTION3D
from .wedge_params import KEYS, WedgeParams, parse_params, _sides
from .wedge_statics import flank_frames

SIDES = ("left", "right")


def _as_row(c) -> dict:
    """A platform coordinate as ``{dof: coefficient}`` (an int is one DOF with coefficient 1)."""
    if isinstance(c, dict):
        return {int(k): float(v) for k, v in c.items()}
    return {int(c): 1.0}


def _sub(g, row, scale):
    """``g -= scale * row`` for a coordinate ``row`` given as ``{dof: coefficient}``."""
    for j, c in row.items():
        g[j] -= scale * c


def _rotation(spec, n_dof, dof_index, where) -> dict:
    """A platform rotation ``rz`` as ``{dof: coefficient}``: a DOF, or weighted DOFs such as
    ``{ "blade1.n8.ry" = -1.0 }`` (an axis of the opposite sense); ``{}`` when not given."""
    if spec is None:
        return {}
    row = coordinate_row(spec, n_dof, dof_index, where)
    return {int(j): float(row[j]) for j in np.flatnonzero(row)}


def _cross(r, v):
    """z component of the plane cross product ``r x v``."""
    return r[0] * v[1] - r[1] * v[0]


class WedgeDamper(Element):
    """Rigid wedge damper on two friction flanks (module docstring); registry key ``wedge_damper``.

    Parameters
    ----------
    params : WedgeParams
    platform : sequence of 2 tuples
        Platform coordinates ``(x, y)`` or ``(x, y, z)`` of the left and right contacts, each
        a DOF index or a combination ``{dof: coefficient}`` (a point coordinate such as
        ``"blade1.platform.x"`` of a beam assembly, ``u_p = u_n + theta_n x r``), taken at the
        flank centre.
    damper : sequence of int
        Model indices of the damper DOFs, in the order ``params.dof_suffixes``.
    n_dof : int
        Size of the (augmented) model.
    name : str
    turns : sequence of 2 dicts, optional
        In-plane rotation ``theta_s`` of each platform as ``{dof: coefficient}`` (none if empty).
    """

    kind = FRICTION3D
    velocity = False
    needs_mean = True
    keys = KEYS
    default_harmonics = 5           # benchmarks/default_harmonics.py
    default_samples_factor = 1

    def __init__(self, params: WedgeParams, platform, damper, n_dof, name="wedge_damper", turns=None):
        self.wedge = params
        self.damper_index = np.array(damper, dtype=int)
        self.damper_index.setflags(write=False)
        if self.damper_index.size != len(params.dof_suffixes):
            raise ValueError(f"{name}: needs {len(params.dof_suffixes)} damper DOFs "
                             f"({', '.join(params.dof_suffixes)}), got {self.damper_index.size}")
        t, n = flank_frames(params.angles)
        N = params.static_normal_loads()
        p = params.points_per_flank
        col = dict(zip(params.dof_suffixes, self.damper_index))
        contacts, flank = [], []
        rows_of = [[_as_row(c) for c in platform[s]] for s in range(2)]
        turns = turns if turns is not None else ({}, {})
        for s in range(2):
            ps = rows_of[s]
            centre = params.centres[s] if params.rotates else np.zeros(2)
            for j, off in enumerate(params.point_offsets()):
                r = centre + off * t[s]
                rows = []
                for v in (t[s], None, n[s]):
                    if v is None:
                        if not params.three_d:
                            continue
                        g = np.zeros(n_dof)
                        g[col["z"]] += 1.0
                        _sub(g, ps[2], 1.0)
                    else:
                        g = np.zeros(n_dof)
                        g[col["x"]] += v[0]
                        g[col["y"]] += v[1]
                        if params.rotates:
                            g[col["rz"]] += _cross(r, v)
                            _sub(g, turns[s], _cross(off * t[s], v))
                        _sub(g, ps[0], v[0])
                        _sub(g, ps[1], v[1])
                    rows.append(g)
                label = f"{name}.{'LR'[s]}{j}"
                contacts.append(Friction3D(np.array(rows), params.kt / p, params.kn / p, params.mu[s],
                                           N[s] / p, name=label))
                flank.append(s)
        self.contacts = tuple(contacts)
        self.flank_of_contact = np.array(flank, dtype=int)
        self.static_loads = N
        self.n_local_contact = contacts[0].n_local
        super().__init__(np.vstack([c.gather for c in contacts]), np.zeros(0), name)
        self.coord_names = tuple(f"{c.name.split('.')[-1]}.{k}" for c in contacts for k in c.coord_names)

    # --- case hooks --------------------------------------------------------------------
    @classmethod
    def internal_dofs(cls, spec, where="wedge_damper"):
        """Damper DOFs this element adds to the model (hook of :mod:`hbm.interface.case`).

        Returns
        -------
        names : tuple of str
            ``"<name>.x", "<name>.y"`` (+ ``".z"``) (+ ``".rz"``).
        M : ndarray, shape (n_int, n_int)
            Mass and in-plane inertia.
        K : ndarray, shape (n_int, n_int)
            Wire and anchor stiffness to ground.
        """
        params = parse_params(spec, where)
        name = spec.get("name", "wedge_damper")
        M, K = params.internal_matrices()
        return tuple(f"{name}.{s}" for s in params.dof_suffixes), M, K

    @classmethod
    def from_spec(cls, spec, n_dof, dof_index=None, where="wedge_damper"):
        """Build from a case table; the damper DOFs ``<name>.x`` ... must already be in the model."""
        params = parse_params(spec, where)
        name = spec.get("name", "wedge_damper")
        platform, turns = [], []
        for side, d in zip(SIDES, _sides(spec, where)):
            keys = ("x", "y", "z") if params.three_d else ("x", "y")
            platform.append(tuple(coordinate(d[k], n_dof, dof_index, f"{where}: {side}.{k}") for k in keys))
            turns.append(_rotation(d.get("rz"), n_dof, dof_index, f"{where}: {side}.rz"))
        damper = []
        for s in params.dof_suffixes:
            dn = f"{name}.{s}"
            if dof_index is None or dn not in dof_index:
                raise ValueError(f"{where}: damper DOF {dn!r} is not in the model (wedge_damper adds "
                                 f"its DOFs when the case is loaded by hbm.interface.case)")
            damper.append(int(dof_index[dn]))
        used = {i for pl in platform for c in pl for i in c} | {i for t in turns for i in t}
        if used & set(damper):
            raise ValueError(f"{where}: platform DOFs must not be damper DOFs")
        return cls(params, platform, damper, n_dof, name, turns)

    # --- element interface -------------------------------------------------------------
    def _rows(self, k):
        m = self.n_local_contact
        return slice(k * m, (k + 1) * m)

    def march(self, z, dz):
        """Each point's friction3d march on its rows; seeds restricted to the columns it uses.

        Parameters
        ----------
        z : ndarray, shape (N, n_local)
        dz : ndarray, shape (N, n_local, P)

        Returns
        -------
        f : ndarray, shape (N, n_local)
        df : ndarray, shape (N, n_local, P)
        """
        z = np.asarray(z, dtype=float)
        dz = np.asarray(dz, dtype=float)
        f = np.zeros(z.shape)
        df = np.zeros(dz.shape)
        for k, c in enumerate(self.contacts):
            r = self._rows(k)
            dzk = dz[:, r, :]
            cols = np.flatnonzero(np.any(dzk != 0.0, axis=(0, 1)))
            fk, dfk = c.march(np.ascontiguousarray(z[:, r]), np.ascontiguousarray(dzk[:, :, cols]))
            f[:, r] = fk
            df[:, r, cols] = dfk
        return f, df

    def start_index(self, u):
        raise NotImplementedError("wedge_damper marches its contacts one by one (see march)")

    def law_spec(self):
        return None

    def law_parts(self):
        """Each contact's rows and friction3d law (the AFT marches them one by one)."""
        return [(np.arange(self._rows(k).start, self._rows(k).stop), c.law_spec())
                for k, c in enumerate(self.contacts)]

    def linear_stiffness(self):
        """Block diagonal of the contacts' stuck, closed tangents, (n_local, n_local)."""
        K = np.zeros((self.n_local, self.n_local))
        for k, c in enumerate(self.contacts):
            r = self._rows(k)
            K[r, r] = c.linear_stiffness()
        return K

    # --- reports -----------------------------------------------------------------------
    def static_state(self) -> dict:
        """Static normal loads per flank and the stated stiffnesses to ground."""
        w = self.wedge
        return {
            "cf": w.cf,
            "angles_deg": [float(np.degrees(a)) for a in w.angles],
            "mu": list(w.mu),
            "normal_load_left": float(self.static_loads[0]),
            "normal_load_right": float(self.static_loads[1]),
            "points_per_flank": w.points_per_flank,
            "normal_preload_per_point": [c.normal_preload for c in self.contacts],
            "wire_stiffness": w.wire_stiffness,
            "anchor_stiffness": w.anchor_stiffness,
            "damper_dofs": [f"{self.name}.{s}" for s in w.dof_suffixes],
        }

    quantities = ("slip_fraction", "open_fraction", "dissipation", "normal_load_min_left",
                  "normal_load_max_left", "normal_load_min_right", "normal_load_max_right")

    def summary(self, f, z) -> dict:
        """Per-period scalar quantities (``quantities``) for ``[analysis] outputs``: slip and
        open fractions (mean over all contact points), dissipation (J per period), and the
        min/max of each flank's resultant normal load."""
        q = np.zeros((np.asarray(f).shape[0], len(self.wedge.dof_suffixes)))
        r = self.report(f, z, q)
        L, R = r["left"], r["right"]
        return {
            "slip_fraction": 0.5 * (L["slip_fraction"] + R["slip_fraction"]),
            "open_fraction": 0.5 * (L["open_fraction"] + R["open_fraction"]),
            "dissipation": L["dissipation"] + R["dissipation"],
            "normal_load_min_left": L["normal_load_min"], "normal_load_max_left": L["normal_load_max"],
            "normal_load_min_right": R["normal_load_min"], "normal_load_max_right": R["normal_load_max"],
        }

    def report(self, f, z, q_damper) -> dict:
        """Per-period quantities of a solution, from its samples, per flank and for the damper.

        Parameters
        ----------
        f : ndarray, shape (N, n_local)
            Forces of ``march`` (one closed period).
        z : ndarray, shape (N, n_local)
            Sampled local coordinates.
        q_damper : ndarray, shape (N, n_int)
            Sampled damper DOFs (order ``dof_suffixes``).

        Returns
        -------
        dict
            ``left`` / ``right``: ``static_normal_load``, ``normal_load_min`` / ``_max`` (flank
            resultant over the period), ``point_normal_load_min`` / ``_max`` (lists over the
            points), ``slip_fraction`` (mean over the points of the fraction of slipping
            samples), ``open_fraction`` (same, open), ``dissipation`` (J per period);
            ``damper``: per DOF suffix ``{"mean", "amplitude"}`` with amplitude
            ``(max - min) / 2`` over the samples; ``rotation_amplitude`` (rad, 0 without rotation).
        """
        f = np.asarray(f, dtype=float)
        z = np.asarray(z, dtype=float)
        q = np.asarray(q_damper, dtype=float)
        nt = self.n_local_contact - 1
        out = {}
        for s, side in enumerate(SIDES):
            ks = np.flatnonzero(self.flank_of_contact == s)
            sums = [self.contacts[k].summary(f[:, self._rows(k)], z[:, self._rows(k)]) for k in ks]
            loads = np.stack([f[:, self._rows(k)][:, nt] + self.contacts[k].normal_preload for k in ks], axis=1)
            resultant = loads.sum(axis=1)
            out[side] = {
                "static_normal_load": float(self.static_loads[s]),
                "normal_load_min": float(resultant.min()),
                "normal_load_max": float(resultant.max()),
                "point_normal_load_min": [d["normal_load_min"] for d in sums],
                "point_normal_load_max": [d["normal_load_max"] for d in sums],
                "slip_fraction": float(np.mean([d["slip_fraction"] for d in sums])),
                "open_fraction": float(np.mean([d["open_fraction"] for d in sums])),
                "dissipation": float(sum(d["dissipation"] for d in sums)),
            }
        amp = 0.5 * (q.max(axis=0) - q.min(axis=0))
        out["damper"] = {s: {"mean": float(q[:, i].mean()), "amplitude": float(amp[i])}
                         for i, s in enumerate(self.wedge.dof_suffixes)}
        out["rotation_amplitude"] = out["damper"]["rz"]["amplitude"] if self.wedge.rotates else 0.0
        return out
