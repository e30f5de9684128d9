r"""Assemblies of beams, lumped bodies and coupling springs, built from readable case keys.

The structure is the direct sum of its parts (each beam from
:func:`hbm.builders.beam.build_beam_model`, each body a lumped mass) coupled by linear
springs:

.. math::

    M = \mathrm{blockdiag}(M_1, \dots, M_p), \qquad
    K = \mathrm{blockdiag}(K_1, \dots, K_p) + \sum_s \sum_i k_{s,i}\, g_{s,i}^T g_{s,i},
    \qquad g_{s,i} = r_{a,i} - r_{b,i},

where ``r_{a,i}`` is row ``i`` of the coordinates of the spring's first end (a node's
translations ``x, y, z`` then rotations, a rigid-offset point's or a body's translations),
``r_{b,i}`` that of the second end (zero for ground).  A rigid-offset point moves by
``u_p = u_n + theta_n x r`` (see :mod:`hbm.builders.beam`).

Names
-----
A part named ``blade1`` prefixes its names: DOFs ``blade1.n3.ux`` (``ux, uy, uz, rx, ry,
rz``), points ``blade1.platform`` with coordinates ``blade1.platform.x`` / ``.y`` / ``.z``.
A single unnamed beam keeps the plain names ``n3.ux`` and ``platform.x``.  A body ``damper``
has DOFs ``damper.ux, damper.uy, damper.uz`` (and ``damper.rx, ...`` with rotary inertia)
and the point ``damper`` (coordinates ``damper.x`` ...).

Case keys (the ``[model]`` table with ``builder = "beam"``)::

    [[model.beam]]                # or one [model.beam] table
    name = "blade1"               # optional for a single beam
    length = 0.12                 # m
    n_elements = 24
    E = 2.0e11                    # Pa
    rho = 7800.0                  # kg/m^3
    nu = 0.3                      # optional, default 0.3
    width = 0.02                  # solid rectangle (local y), or area, Iy, Iz, J
    height = 0.004                # (local z)
    clamp = [0]                   # nodes fixed to ground (default [0]; [] for a beam held
                                  # by springs, e.g. on a common block)
    origin = [0.0, 0.0, 0.0]      # position of node 0 (default origin)
    axis = [0.0, 0.0, 1.0]        # beam direction (default x)
    up = [1.0, 0.0, 0.0]          # reference for the local z axis (default z)
    lumped_mass = false
    points = { platform = { node = 18, offset = [0.0, 0.012, 0.0] } }
    point_masses = { platform = 0.02, n24 = 0.005 }    # at a point or on a node "n<k>"

    [[model.body]]                # a lumped rigid body (e.g. a damper)
    name = "damper"
    mass = 0.01                   # kg
    inertia = [1e-7, 1e-7, 1e-7]  # optional: adds rotations rx, ry, rz

    [[model.spring]]
    between = ["blade1.platform", "damper"]   # or one end: to ground
    k = 1.0e5                     # translations: a number or [kx, ky, kz]
    k_rot = 10.0                  # optional rotations (node or body ends with rotations)

Every unknown key is an error that names it.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from hbm.builders.beam import DENSE_MAX_DOF, build_beam_model

BEAM_KEYS = ("name", "length", "n_elements", "E", "rho", "nu", "width", "height", "area", "Iy",
             "Iz", "J", "clamp", "origin", "axis", "up", "lumped_mass", "points", "point_masses")
BEAM_REQUIRED = ("length", "n_elements", "E", "rho")
POINT_KEYS = ("node", "offset")
BODY_KEYS = ("name", "mass", "inertia")
SPRING_KEYS = ("between", "k", "k_rot")
TRANSLATIONS = ("x", "y", "z")


@dataclass(frozen=True)
class Assembly:
    """Assembled structure.

    Attributes
    ----------
    M, K : ndarray or scipy.sparse.csr_matrix, shape (n, n)
        Dense up to ``DENSE_MAX_DOF`` DOFs, sparse above (or when ``sparse=True``).
    dof_names : tuple of str
    points : dict
        Point name -> gather rows of its translations, dict ``{dof: coefficient}`` per
        direction ``x, y, z`` (a tuple of three dicts).
    """

    M: object
    K: object
    dof_names: tuple
    points: dict = field(default_factory=dict)

    @property
    def n_dof(self) -> int:
        return len(self.dof_names)

    def point_rows(self, name: str) -> np.ndarray:
        """Dense gather rows (3, n_dof) of a point's translations."""
        if name not in self.points:
            raise ValueError(f"unknown point {name!r}; known: {sorted(self.points)}")
        G = np.zeros((3, self.n_dof))
        for i, row in enumerate(self.points[name]):
            for j, c in row.items():
                G[i, j] = c
        return G

    def coordinates(self) -> dict:
        """Name -> DOF index (``"blade1.n3.ux"``) or ``{dof: coefficient}`` (``"blade1.platform.x"``)."""
        out = {s: i for i, s in enumerate(self.dof_names)}
        for p, rows in self.points.items():
            for lab, row in zip(TRANSLATIONS, rows):
                out[f"{p}.{lab}"] = dict(row)
        return out


def _check(table, allowed, where):
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table")
    for k in table:
        if k not in allowed:
            raise ValueError(f"{where}: unknown key {k!r} (allowed: {', '.join(allowed)})")


def _vector(v, n, what):
    a = np.asarray(v, dtype=float) if not isinstance(v, bool) else None
    if a is None or a.ndim > 1 or (a.ndim == 1 and a.size != n) or not np.all(np.isfinite(a)):
        raise ValueError(f"{what} must be a number or a list of {n} numbers, got {v!r}")
    return np.broadcast_to(a, (n,)).copy()


def _rows_dict(G):
    return tuple({int(j): float(G[i, j]) for j in np.flatnonzero(G[i])} for i in range(G.shape[0]))


def _beam(spec, where, single):
    _check(spec, BEAM_KEYS, where)
    for k in BEAM_REQUIRED:
        if k not in spec:
            raise ValueError(f"{where}: missing key {k!r}")
    name = spec.get("name")
    if name is None and not single:
        raise ValueError(f"{where}: several beams need a 'name' each")
    if name is not None and (not isinstance(name, str) or not name or "." in name):
        raise ValueError(f"{where}: name must be a non-empty string without dots, got {name!r}")
    points = {}
    for pname, p in (spec.get("points") or {}).items():
        _check(p, POINT_KEYS, f"{where}: points.{pname}")
        if "node" not in p:
            raise ValueError(f"{where}: points.{pname}: missing key 'node'")
        points[pname] = (p["node"], p.get("offset", (0.0, 0.0, 0.0)))
    masses = {}
    for key, m in (spec.get("point_masses") or {}).items():
        if key in points:
            masses[key] = m
        elif key.startswith("n") and key[1:].isdigit():
            masses[int(key[1:])] = m
        else:
            raise ValueError(f"{where}: point_masses key {key!r} is neither a point nor a node 'n<k>'")
    keys = {k: v for k, v in spec.items() if k not in ("name", "points", "point_masses")}
    for k in ("origin", "axis", "up"):
        if k in keys:
            keys[k] = tuple(_vector(keys[k], 3, f"{where}: {k}"))
    try:
        model = build_beam_model(**keys, points=points, point_masses=masses, sparse=True, allow_free=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None
    return name, model


def build_assembly(beams=(), bodies=(), springs=(), sparse=None) -> Assembly:
    """Assemble beams, bodies and springs given as case tables (see the module docstring).

    Parameters
    ----------
    beams : dict or list of dict
        ``[model.beam]`` table(s).
    bodies : list of dict
        ``[[model.body]]`` tables.
    springs : list of dict
        ``[[model.spring]]`` tables.
    sparse : bool, optional
        Force sparse or dense matrices; default: sparse above ``DENSE_MAX_DOF`` DOFs.

    Returns
    -------
    Assembly

    Raises
    ------
    ValueError
        Unknown or missing keys, bad values, unknown spring ends (the message names them).
    """
    if isinstance(beams, dict):
        beams = [beams]
    for what, lst in (("beam", beams), ("body", bodies), ("spring", springs)):
        if not isinstance(lst, (list, tuple)) or not all(isinstance(x, dict) for x in lst):
            raise ValueError(f"[[model.{what}]] must be a table or an array of tables")
    if not beams and not bodies:
        raise ValueError("[model] builder = 'beam' needs at least one [[model.beam]]")
    Ms, Ks, names, points, nodes = [], [], [], {}, {}
    offset = 0
    seen = set()
    for i, spec in enumerate(beams):
        where = f"[[model.beam]] #{i}"
        name, m = _beam(spec, where, single=len(beams) == 1 and not bodies)
        if name in seen:
            raise ValueError(f"{where}: duplicate name {name!r}")
        seen.add(name)
        pre = f"{name}." if name else ""
        Ms.append(sp.csr_matrix(m.M)); Ks.append(sp.csr_matrix(m.K))
        names += [pre + s for s in m.dof_names]
        for p in m.points:
            rows = m.point_rows(p)
            points[pre + p] = tuple({j + offset: c for j, c in r.items()} for r in _rows_dict(rows))
        for k in range(len(m.node_coords)):
            nodes[f"{pre}n{k}"] = None     # filled below from the DOF names
        offset += m.n_dof
    for i, spec in enumerate(bodies):
        name, diag, labs = _body(spec, f"[[model.body]] #{i}", seen)
        seen.add(name)
        Ms.append(sp.diags(diag).tocsr()); Ks.append(sp.csr_matrix((len(diag), len(diag))))
        names += [f"{name}.{lab}" for lab in labs]
        points[name] = tuple({offset + j: 1.0} for j in range(3))
        nodes[name] = None
        offset += len(diag)
    n = offset
    index = {s: i for i, s in enumerate(names)}
    M = sp.block_diag(Ms, format="csr")
    K = sp.block_diag(Ks, format="lil")

    end_rows = lambda ref, where: _end_rows(ref, where, points, nodes, index, n)   # noqa: E731
    for i, spec in enumerate(springs):
        nz, Ks_ = _spring(spec, f"[[model.spring]] #{i}", end_rows)
        K[np.ix_(nz, nz)] = K[np.ix_(nz, nz)].toarray() + Ks_
    K = K.tocsr()
    use_sparse = n > DENSE_MAX_DOF if sparse is None else bool(sparse)
    if not use_sparse:
        M, K = M.toarray(), K.toarray()
        M, K = 0.5 * (M + M.T), 0.5 * (K + K.T)
    return Assembly(M, K, tuple(names), points)


def _end_rows(ref, where, points, nodes, index, n):
    """Rows (6, n) of a spring end: translations then rotations (rotations NaN-free zeros),
    and whether the end has rotations."""
    R = np.zeros((6, n))
    has_rot = False
    if ref == "ground":
        return R, True
    if ref in points and ref not in nodes:
        for i, row in enumerate(points[ref]):
            for j, c in row.items():
                R[i, j] = c
        return R, False
    if ref in nodes:
        for i, lab in enumerate(("ux", "uy", "uz", "rx", "ry", "rz")):
            j = index.get(f"{ref}.{lab}")
            if j is not None:
                R[i, j] = 1.0
                has_rot = has_rot or i >= 3
        # a clamped node (all DOFs removed) is ground; a body without inertia has no rotations
        return R, has_rot or not np.any(R)
    raise ValueError(f"{where}: unknown spring end {ref!r} (a node like 'blade1.n3', a point, "
                     f"a body or 'ground')")


def _body(spec: dict, where: str, seen: set):
    """``(name, diagonal masses, DOF labels)`` of a ``[[model.body]]`` table."""
    _check(spec, BODY_KEYS, where)
    for k in ("name", "mass"):
        if k not in spec:
            raise ValueError(f"{where}: missing key {k!r}")
    name = spec["name"]
    if not isinstance(name, str) or not name or "." in name or name in seen or name == "ground":
        raise ValueError(f"{where}: name must be a new non-empty string without dots, got {name!r}")
    mass = _vector(spec["mass"], 1, f"{where}: mass")[0]
    if not mass > 0:
        raise ValueError(f"{where}: mass must be positive, got {spec['mass']!r}")
    diag = [mass] * 3
    labs = ["ux", "uy", "uz"]
    if "inertia" in spec:
        inertia = _vector(spec["inertia"], 3, f"{where}: inertia")
        if np.any(inertia <= 0):
            raise ValueError(f"{where}: inertia must be positive")
        diag += list(inertia)
        labs += ["rx", "ry", "rz"]
    return name, diag, labs


def _spring(spec: dict, where: str, end_rows):
    """The coordinates ``nz`` a ``[[model.spring]]`` couples and its stiffness block there,
    ``G^T diag(k, k_rot) G`` with ``G`` the difference of its ends' rows."""
    _check(spec, SPRING_KEYS, where)
    for k in ("between", "k"):
        if k not in spec:
            raise ValueError(f"{where}: missing key {k!r}")
    ends = spec["between"]
    if not isinstance(ends, list) or len(ends) not in (1, 2) or not all(isinstance(e, str) for e in ends):
        raise ValueError(f"{where}: between must be [a, b] or [a] (to ground) with names")
    a, b = (ends + ["ground"])[:2]
    Ra, rot_a = end_rows(a, where)
    Rb, rot_b = end_rows(b, where)
    kt = _vector(spec["k"], 3, f"{where}: k")
    kr = _vector(spec.get("k_rot", 0.0), 3, f"{where}: k_rot")
    if np.any(kt < 0) or np.any(kr < 0):
        raise ValueError(f"{where}: k and k_rot must be >= 0")
    if np.any(kr > 0) and not (rot_a and rot_b):
        raise ValueError(f"{where}: k_rot needs ends with rotations (nodes, bodies with inertia, ground)")
    G = Ra - Rb
    kk = np.r_[kt, kr]
    if not np.any(G):
        raise ValueError(f"{where}: the spring ends do not move (both clamped or identical)")
    nz = np.flatnonzero(np.any(G != 0, axis=0))
    Gs = G[:, nz]
    return nz, (Gs.T * kk) @ Gs
