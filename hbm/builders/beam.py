r"""3D Euler-Bernoulli beam (frame) finite elements, assembly, clamps, point masses, rigid offsets.

Each node carries 6 DOFs ``[ux, uy, uz, rx, ry, rz]`` (global axes).  In the element's local
frame (``x`` along the element, ``z`` towards the reference ``up`` vector, ``y = z x x``) a
two-node element of length ``L`` has the classical cubic-Hermite matrices (Przemieniecki):

- axial ``EA/L [[1, -1], [-1, 1]]`` and mass ``rho A L/6 [[2, 1], [1, 2]]`` on ``(ux_a, ux_b)``;
- torsion ``GJ/L [[1, -1], [-1, 1]]`` and mass ``rho I_p L/6 [[2, 1], [1, 2]]``,
  ``I_p = I_y + I_z``, ``G = E / (2 (1 + nu))``, on ``(rx_a, rx_b)``;
- bending in the ``x-y`` plane on ``(uy_a, rz_a, uy_b, rz_b)``:

  .. math::

      k = \frac{E I_z}{L^3}\begin{bmatrix}12 & 6L & -12 & 6L\\ 6L & 4L^2 & -6L & 2L^2\\
          -12 & -6L & 12 & -6L\\ 6L & 2L^2 & -6L & 4L^2\end{bmatrix},\quad
      m = \frac{\rho A L}{420}\begin{bmatrix}156 & 22L & 54 & -13L\\ 22L & 4L^2 & 13L & -3L^2\\
          54 & 13L & 156 & -22L\\ -13L & -3L^2 & -22L & 4L^2\end{bmatrix};

- bending in the ``x-z`` plane on ``(uz_a, ry_a, uz_b, ry_b)``: the same with ``I_y`` and the
  rotation sign flipped (``ry = -duz/dx``), i.e. ``S k S`` with ``S = diag(1, -1, 1, -1)``.

Lumped mass (HRZ diagonal scaling): ``rho A L / 2`` per node on translations,
``rho A L^3 / 78`` on the bending rotations and ``rho I_p L / 2`` on the torsion rotation.
Global matrices are ``T^T k T`` with ``T = blockdiag(R, R, R, R)``, ``R`` the rows of the
local axes.  Clamped nodes' DOFs are removed.

A rigid offset (a platform point ``p`` rigidly attached to node ``n`` at offset ``r``,
small rotations) moves by ``u_p = u_n + theta_n x r = [I, -[r]_x] [u_n; theta_n]``; the
three rows over the model's DOFs are the point's translation coordinates, which contact
elements and :func:`hbm.model.condensed_model.condense` use as gather rows.  A point mass ``m`` at such a
point adds ``m G_p^T G_p`` to ``M``.

The matrices are dense ``ndarray`` up to ``DENSE_MAX_DOF`` free DOFs (dense eigen-solves are
fast there) and ``scipy.sparse`` CSR above (use the shift-invert path of
:func:`hbm.model.reduction.reduce_model`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

DENSE_MAX_DOF = 2000
DOF_LABELS = ("ux", "uy", "uz", "rx", "ry", "rz")


@dataclass(frozen=True)
class Section:
    """Beam cross-section: area ``A``, second moments ``Iy`` (bending in x-z), ``Iz`` (x-y),
    torsion constant ``J``; SI units."""

    area: float
    Iy: float
    Iz: float
    J: float

    def __post_init__(self):
        for name in ("area", "Iy", "Iz", "J"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"section {name} must be a positive number, got {v}")

    @classmethod
    def rectangle(cls, width: float, height: float) -> "Section":
        """Solid rectangle, ``width`` along local y, ``height`` along local z.

        ``J = a c^3 [1/3 - 0.21 (c/a)(1 - c^4 / (12 a^4))]`` with ``a >= c`` the sides (Roark).
        """
        if not (width > 0 and height > 0):
            raise ValueError(f"rectangle width and height must be positive, got {width}, {height}")
        a, c = max(width, height), min(width, height)
        J = a * c**3 * (1.0 / 3.0 - 0.21 * (c / a) * (1.0 - c**4 / (12.0 * a**4)))
        return cls(width * height, width * height**3 / 12.0, height * width**3 / 12.0, J)

    @property
    def Ip(self) -> float:
        """Polar second moment ``Iy + Iz`` (torsional inertia)."""
        return self.Iy + self.Iz


@dataclass(frozen=True)
class Material:
    """Isotropic material: Young's modulus ``E``, Poisson ratio ``nu``, density ``rho``."""

    E: float
    nu: float
    rho: float

    def __post_init__(self):
        if not (self.E > 0):
            raise ValueError(f"Young's modulus E must be positive, got {self.E}")
        if not (self.rho > 0):
            raise ValueError(f"density rho must be positive, got {self.rho}")
        if not (-1.0 < self.nu < 0.5):
            raise ValueError(f"Poisson ratio nu must be in (-1, 0.5), got {self.nu}")

    @property
    def G(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))


def _plane(L, EI, rhoA, lumped):
    k = EI / L**3 * np.array([[12.0, 6 * L, -12.0, 6 * L],
                              [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                              [-12.0, -6 * L, 12.0, -6 * L],
                              [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    if lumped:
        m = np.diag([rhoA * L / 2, rhoA * L**3 / 78, rhoA * L / 2, rhoA * L**3 / 78])
    else:
        m = rhoA * L / 420.0 * np.array([[156.0, 22 * L, 54.0, -13 * L],
                                         [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                                         [54.0, 13 * L, 156.0, -22 * L],
                                         [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    return k, m


def _bar(L, stiff, inertia, lumped):
    k = stiff / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    m = inertia * L * (np.eye(2) / 2 if lumped else np.array([[2.0, 1.0], [1.0, 2.0]]) / 6)
    return k, m


def element_matrices(L: float, section: Section, material: Material, lumped: bool = False):
    """Local stiffness and mass of one frame element, shapes (12, 12) each.

    Parameters
    ----------
    L : float
        Element length.
    section : Section
    material : Material
    lumped : bool
        HRZ lumped (diagonal) mass instead of the consistent one.
    """
    if not L > 0:
        raise ValueError(f"element length must be positive, got {L}")
    E, G, rho = material.E, material.G, material.rho
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    ka, ma = _bar(L, E * section.area, rho * section.area, lumped)
    kt, mt = _bar(L, G * section.J, rho * section.Ip, lumped)
    for idx, (kk, mm) in (([0, 6], (ka, ma)), ([3, 9], (kt, mt))):
        k[np.ix_(idx, idx)] += kk
        m[np.ix_(idx, idx)] += mm
    kxy, mxy = _plane(L, E * section.Iz, rho * section.area, lumped)
    idx = [1, 5, 7, 11]
    k[np.ix_(idx, idx)] += kxy
    m[np.ix_(idx, idx)] += mxy
    kxz, mxz = _plane(L, E * section.Iy, rho * section.area, lumped)
    S = np.diag([1.0, -1.0, 1.0, -1.0])
    idx = [2, 4, 8, 10]
    k[np.ix_(idx, idx)] += S @ kxz @ S
    m[np.ix_(idx, idx)] += S @ mxz @ S
    return k, m


def local_axes(xa, xb, up=(0.0, 0.0, 1.0)) -> np.ndarray:
    """Rows ``[e_x, e_y, e_z]`` of the element frame: ``e_x`` along ``xb - xa``, ``e_z`` towards ``up``."""
    d = np.asarray(xb, dtype=float) - np.asarray(xa, dtype=float)
    L = np.linalg.norm(d)
    if L == 0:
        raise ValueError("element has zero length (coincident nodes)")
    ex = d / L
    u = np.asarray(up, dtype=float)
    ez = u - (u @ ex) * ex
    if np.linalg.norm(ez) < 1e-8 * max(np.linalg.norm(u), 1e-300):
        raise ValueError("the up vector is parallel to the beam axis: choose another one")
    ez /= np.linalg.norm(ez)
    ey = np.cross(ez, ex)
    return np.vstack([ex, ey, ez])


def rigid_offset_rows(offset) -> np.ndarray:
    """Rows mapping a node's 6 DOFs to the translations of a rigidly attached point.

    ``u_p = u_n + theta_n x r = [I, -[r]_x] [u_n; theta_n]``, shape (3, 6).
    """
    r = np.asarray(offset, dtype=float)
    if r.shape != (3,):
        raise ValueError(f"offset must be a 3-vector, got shape {r.shape}")
    skew = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    return np.hstack([np.eye(3), -skew])


@dataclass(frozen=True)
class BeamModel:
    """Assembled beam model.

    Attributes
    ----------
    M, K : ndarray or scipy.sparse.csr_matrix, shape (n, n)
        Mass and stiffness over the free DOFs (dense when n <= DENSE_MAX_DOF).
    dof_names : tuple of str
        ``"n3.ux"`` style names of the free DOFs.
    node_coords : ndarray, shape (n_nodes, 3)
    points : dict
        Named platform points: name -> (node, offset (3,)).
    """

    M: object
    K: object
    dof_names: tuple
    node_coords: np.ndarray
    points: dict = field(default_factory=dict)

    @property
    def n_dof(self) -> int:
        return len(self.dof_names)

    def dof_index(self, name: str) -> int:
        """Index of a DOF by name (``"n3.uy"``)."""
        try:
            return self.dof_names.index(name)
        except ValueError:
            raise ValueError(f"unknown DOF name {name!r} (clamped or not in the model)") from None

    def point_rows(self, name: str) -> np.ndarray:
        """Gather rows (3, n_dof) of a named point's translations ``[ux, uy, uz]``."""
        if name not in self.points:
            raise ValueError(f"unknown point {name!r}; known: {sorted(self.points)}")
        node, offset = self.points[name]
        return _offset_rows(self.dof_names, node, offset)

    def point_dofs(self, name: str) -> np.ndarray:
        """Indices of the free DOFs the point's rows touch (for ``keep_dofs``)."""
        return np.flatnonzero(np.any(self.point_rows(name) != 0.0, axis=0))


def _offset_rows(dof_names, node, offset):
    index = {s: i for i, s in enumerate(dof_names)}
    rows = np.zeros((3, len(dof_names)))
    T = rigid_offset_rows(offset)
    for j, lab in enumerate(DOF_LABELS):
        i = index.get(f"n{node}.{lab}")
        if i is not None:          # clamped DOFs do not move
            rows[:, i] = T[:, j]
    return rows


MAX_ELEMENTS = 20000        # 120,006 DOFs: the dense beam assembly's practical limit


def build_beam_model(*, length, n_elements, E, rho, nu=0.3, area=None, Iy=None, Iz=None, J=None,
                     width=None, height=None, clamp=(0,), lumped_mass=False, axis=(1.0, 0.0, 0.0),
                     up=(0.0, 0.0, 1.0), origin=(0.0, 0.0, 0.0), points=None, point_masses=None,
                     sparse=None, allow_free=False) -> BeamModel:
    """Straight 3D beam of ``n_elements`` equal frame elements, nodes ``0..n_elements``.

    Parameters
    ----------
    length : float
        Beam length, m.
    n_elements : int
        Number of elements.
    E, rho, nu : float
        Young's modulus (Pa), density (kg/m^3), Poisson ratio.
    area, Iy, Iz, J : float, optional
        Section properties (m^2, m^4); or give ``width`` and ``height`` of a solid rectangle
        (``width`` along local y, ``height`` along local z).
    clamp : sequence of int
        Nodes whose 6 DOFs are fixed (removed).  At least one node (K must be non-singular),
        unless ``allow_free`` (a part of an assembly held by springs).
    lumped_mass : bool
        HRZ lumped mass instead of consistent.
    axis, up, origin : 3-vectors
        Beam direction, reference vector for the local z axis, position of node 0.
    points : dict, optional
        Named platform points, ``{name: (node, offset)}`` with a 3-vector offset (m).
    point_masses : dict, optional
        ``{node: mass}`` (on the node's translations) or ``{point_name: mass}`` (at the point).
    sparse : bool, optional
        Force sparse (True) or dense (False) output; default by ``DENSE_MAX_DOF``.
    allow_free : bool
        Accept ``clamp = []`` (the caller holds the beam otherwise).

    Returns
    -------
    BeamModel
    """
    n_el = int(n_elements)
    if n_el < 1 or n_el != n_elements:
        raise ValueError(f"n_elements must be a positive integer, got {n_elements}")
    if n_el > MAX_ELEMENTS:
        raise ValueError(f"n_elements = {n_el} is {6 * (n_el + 1)} DOFs; at most {MAX_ELEMENTS} elements per beam "
                         f"(a finer model belongs in a model file and the condensed solver)")
    if not length > 0:
        raise ValueError(f"length must be positive, got {length}")
    section = _section(area, Iy, Iz, J, width, height)
    material = Material(float(E), float(nu), float(rho))

    ax = np.asarray(axis, dtype=float)
    if ax.shape != (3,) or np.linalg.norm(ax) == 0:
        raise ValueError("axis must be a non-zero 3-vector")
    ax = ax / np.linalg.norm(ax)
    n_nodes = n_el + 1
    coords = np.asarray(origin, dtype=float) + np.outer(np.linspace(0, length, n_nodes), ax)

    clamp = sorted(set(int(c) for c in clamp))
    if not clamp and not allow_free:
        raise ValueError("clamp at least one node (free-free beams are not supported)")
    if clamp and (clamp[0] < 0 or clamp[-1] >= n_nodes):
        raise ValueError(f"clamp nodes must be in 0..{n_nodes - 1}, got {clamp}")

    Kall, Mall = _assembled(coords, up, length / n_el, n_el, section, material, lumped_mass)
    all_names = [f"n{i}.{lab}" for i in range(n_nodes) for lab in DOF_LABELS]
    pts = _named_points(points, n_nodes)
    Mall = (Mall + _point_mass_matrix(point_masses, pts, all_names, n_nodes)).tocsr()
    fixed = np.zeros(6 * n_nodes, dtype=bool)
    for c in clamp:
        fixed[6 * c:6 * c + 6] = True
    free = np.flatnonzero(~fixed)
    K, M = Kall[free][:, free], Mall[free][:, free]
    if (free.size > DENSE_MAX_DOF if sparse is None else bool(sparse)):
        K, M = K.tocsr(), M.tocsr()
    else:
        K, M = K.toarray(), M.toarray()
        K, M = 0.5 * (K + K.T), 0.5 * (M + M.T)
    return BeamModel(M, K, tuple(all_names[i] for i in free), coords, pts)


def _section(area, Iy, Iz, J, width, height) -> Section:
    """The cross-section from ``area, Iy, Iz, J`` or from a solid rectangle ``width x height``."""
    rect = width is not None or height is not None
    props = (area, Iy, Iz, J)
    if rect and any(p is not None for p in props):
        raise ValueError("give either width/height or area/Iy/Iz/J for the section, not both")
    if rect:
        if width is None or height is None:
            raise ValueError("a rectangular section needs both width and height")
        return Section.rectangle(float(width), float(height))
    if any(p is None for p in props):
        raise ValueError("section needs area, Iy, Iz and J (or width and height)")
    return Section(*(float(p) for p in props))


def _assembled(coords, up, le: float, n_el: int, section, material, lumped_mass: bool):
    """Global stiffness and mass ``(K, M)`` (6 (n_el + 1) square, CSR) of the straight beam."""
    n_nodes = n_el + 1
    R = local_axes(coords[0], coords[1], up)
    T = np.kron(np.eye(4), R)
    ke, me = element_matrices(le, section, material, lumped_mass)
    ke, me = T.T @ ke @ T, T.T @ me @ T
    n_all = 6 * n_nodes
    rows, cols, kv, mv = [], [], [], []
    for e in range(n_el):
        dofs = np.arange(6 * e, 6 * e + 12)
        r, c = np.meshgrid(dofs, dofs, indexing="ij")
        rows.append(r.ravel()); cols.append(c.ravel())
        kv.append(ke.ravel()); mv.append(me.ravel())
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    Kall = sp.coo_matrix((np.concatenate(kv), (rows, cols)), shape=(n_all, n_all)).tocsr()
    Mall = sp.coo_matrix((np.concatenate(mv), (rows, cols)), shape=(n_all, n_all)).tocsr()
    return Kall, Mall


def _named_points(points, n_nodes: int) -> dict:
    """``{name: (node, offset (3,))}`` checked against the node range."""
    pts = {}
    for name, spec in (points or {}).items():
        try:
            node, offset = spec
        except (TypeError, ValueError):
            raise ValueError(f"point {name!r} must be (node, offset)") from None
        node = int(node)
        if not 0 <= node < n_nodes:
            raise ValueError(f"point {name!r} node {node} is outside 0..{n_nodes - 1}")
        pts[str(name)] = (node, np.asarray(offset, dtype=float).copy())
        rigid_offset_rows(pts[str(name)][1])   # validates the shape
    return pts


def _point_mass_matrix(point_masses, pts, all_names, n_nodes: int):
    """Mass matrix (CSR, all DOFs) of the point masses on nodes or named points."""
    n_all = 6 * n_nodes
    extra = sp.lil_matrix((n_all, n_all))
    for key, mass in (point_masses or {}).items():
        if not (np.isfinite(mass) and mass > 0):
            raise ValueError(f"point mass at {key!r} must be positive, got {mass}")
        if isinstance(key, str):
            if key not in pts:
                raise ValueError(f"point mass names unknown point {key!r}")
            G = _offset_rows(all_names, *pts[key])
            Gs = sp.csr_matrix(G)                 # 3 rows, 6 non-zeros: keep G^T G sparse
            extra += sp.lil_matrix(mass * (Gs.T @ Gs))
        else:
            node = int(key)
            if not 0 <= node < n_nodes:
                raise ValueError(f"point mass node {node} is outside 0..{n_nodes - 1}")
            for j in range(3):
                extra[6 * node + j, 6 * node + j] += mass
    return extra.tocsr()

